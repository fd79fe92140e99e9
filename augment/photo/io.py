"""Images to and from file bytes: one encoder for every picture Stager writes, one
decoder for every photo it reads.

Images are RGB ``(h, w, 3)``, RGBA ``(h, w, 4)`` or grey ``(h, w)`` uint8 arrays.
"""
from __future__ import annotations

import io
import threading
import warnings
from contextlib import contextmanager
from pathlib import Path

import cv2
import numpy as np

from layout.fileio import path_problem

from ..errors import CalibrationError

# The ISO base-media brands of HEIF stills: HEIC is what iPhones save by default.
_HEIF_BRANDS = (b"heic", b"heix", b"heim", b"heis", b"hevc", b"hevx", b"mif1", b"msf1")

# The photo formats Stager reads, the command line and the web app alike: the format's
# name as Pillow reads it from the header -> the suffix a photo of it is stored under.
ACCEPTED_FORMATS = {"JPEG": ".jpg", "MPO": ".jpg", "PNG": ".png", "TIFF": ".tif", "WEBP": ".webp", "BMP": ".bmp",
                    "HEIF": ".heic"}
# The same, as error messages name them.
PHOTO_FORMATS = "JPEG, PNG, HEIC, TIFF, WebP or BMP"
# The names photos of those formats go by, as a folder of shots is searched for them.
PHOTO_SUFFIXES = (".jpg", ".jpeg", ".png", ".heic", ".heif", ".tif", ".tiff", ".webp", ".bmp")
JPEG_QUALITY = 92  # staged photos: no visible loss, about a third of the PNG's size
MIN_PHOTO_PX = 64  # a side: a thumbnail; a board in it would be a few pixels across
# Long side over short. Phones take 4:3 to 21:9; wider is a panorama (not one pinhole
# view, which the calibration assumes) or a strip, whose board search copy would be a few
# pixels high.
MAX_ASPECT = 4.0
# The most pixels a photo may have: above the 200 MP phones take, below what decoding
# a file that only claims its size would cost (100,000 x 100,000 asks for 30 GB).
MAX_PHOTO_PIXELS = 250_000_000


def size_problem(width: int, height: int) -> str | None:
    """What is wrong with a photo of ``width`` x ``height`` for Stager, said for an
    error message ("... is 30 x 20 px: ..."), or None when its size will do."""
    short, long = sorted((width, height))
    if short < MIN_PHOTO_PX:
        return (f"is {width} x {height} px: too small, Stager needs at least {MIN_PHOTO_PX} px a side "
                "(give the photo as the camera took it)")
    if long > MAX_ASPECT * short:
        return (f"is {width} x {height} px, {long / short:.0f} times as {'wide' if width > height else 'tall'} "
                f"as it is {'high' if width > height else 'wide'}: Stager needs one ordinary photo, at most "
                f"{MAX_ASPECT:g} to 1 (not a panorama or a strip cut from one)")
    return None


def header(data: bytes) -> tuple[str | None, tuple[int, int]] | None:
    """The format (Pillow's name) and ``(width, height)`` an encoded image's header
    claims, read without decoding its pixels; None when it is no image Pillow can open."""
    try:
        with pillow_open(io.BytesIO(bytes(data))) as image:
            return image.format, image.size
    except (OSError, ValueError, SyntaxError):
        return None


def pixels_problem(width: int, height: int, limit: int = MAX_PHOTO_PIXELS) -> str | None:
    """What is wrong with a photo of ``width`` x ``height`` pixels for its pixel count,
    worded to follow its name, or None."""
    if width * height <= limit:
        return None
    return (f"is {width} x {height} = {width * height / 1e6:,.0f} megapixels; at most {limit / 1e6:g} megapixels "
            "are read: give the photo as a phone takes it (12 to 200 megapixels)")


def read_user_file(path) -> tuple[bytes | None, str | None]:
    """The bytes of a file the user named and None, or None and why it cannot be read,
    worded to follow the file's name in an error ("... cannot be read (Permission
    denied); check that you may read it"). A named pipe or a device is refused unread."""
    if (problem := path_problem(path)) is not None:
        return None, problem
    try:
        return Path(path).read_bytes(), None
    except OSError as error:
        return None, f"cannot be read ({error.strerror or error}); check that you may read it"


def encode_image(image: np.ndarray, ext: str, quality: int = JPEG_QUALITY) -> bytes:
    """The bytes of a ``.jpg`` (at ``quality``) or ``.png`` file of ``image``."""
    a = np.asarray(image)
    if a.dtype != np.uint8 or not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (3, 4))):
        raise ValueError(f"image must be (h, w), (h, w, 3) or (h, w, 4) uint8, got shape {a.shape} dtype {a.dtype}")
    if a.ndim == 3:
        a = cv2.cvtColor(a, cv2.COLOR_RGBA2BGRA if a.shape[2] == 4 else cv2.COLOR_RGB2BGR)
    params = [cv2.IMWRITE_JPEG_QUALITY, int(quality)] if ext == ".jpg" else []
    ok, data = cv2.imencode(ext, a, params)
    if not ok:
        raise RuntimeError(f"OpenCV could not encode an image as {ext}")
    return data.tobytes()


def is_heif(data: bytes) -> bool:
    """Whether ``data`` starts like a HEIF/HEIC file."""
    return len(data) >= 12 and data[4:8] == b"ftyp" and bytes(data[8:12]) in _HEIF_BRANDS


def register_heif() -> None:
    """Let Pillow open HEIF/HEIC files (for their size and EXIF); idempotent."""
    import pillow_heif

    pillow_heif.register_heif_opener()


_UNGUARDED = threading.Lock()


@contextmanager
def pillow_open(source):
    """``PIL.Image.open(source)`` (a path or a binary file), HEIC too, without Pillow's
    decompression-bomb guard.

    Pillow warns above 89 MP and refuses above 179 MP, where phones take 108 and 200 MP
    photos. Stager decodes photos with OpenCV, which has no such guard, and the web app
    refuses large uploads by their header itself (:func:`augment.app.web.check_photo`), so
    here the guard would only stop a real photo's EXIF or a mask drawn at its size.
    """
    from PIL import Image

    register_heif()
    # Pillow reads its guard, a global, when it opens a file: lifted for this open only,
    # one thread at a time, so that the web app's threads never leave it lifted.
    # Pillow warns of what it reads past in a damaged file (corrupt EXIF, a truncated
    # tag); Stager says what is wrong with the file itself, once.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        with _UNGUARDED:
            limit, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
            try:
                image = Image.open(source)
            finally:
                Image.MAX_IMAGE_PIXELS = limit
        with image:
            yield image


def decode_grey(data: bytes) -> np.ndarray | None:
    """An encoded image as grey levels ``(h, w)`` float32 in [0, 255], upright as its EXIF
    says (as :func:`decode_image` turns photos), with what is transparent taken as black;
    None when it cannot be decoded.

    For masks: a layer painted on transparency says "not here" where it is transparent,
    whatever colour it hides there (editors often keep white). 16-bit grey is scaled to
    255. Pillow decodes it once, alpha and all; OpenCV turns only its colour decode
    upright, not the one that keeps the alpha.
    """
    from PIL import ImageOps

    try:
        with pillow_open(io.BytesIO(bytes(data))) as opened:
            image = ImageOps.exif_transpose(opened)
            if image.mode.startswith("I;16") or image.mode == "I":
                return np.asarray(image, np.float32) * np.float32(255 / 65535)
            if image.mode == "P" and "transparency" in image.info:
                image = image.convert("RGBA")
            grey = np.asarray(image.convert("L"), np.float32)
            if "A" in image.getbands():
                grey *= np.asarray(image.getchannel("A"), np.float32) / np.float32(255)
            return grey
    except (OSError, ValueError, SyntaxError):
        return None


def _other_format(data: bytes) -> str | None:
    """The format of an image Pillow can open but Stager does not take (a GIF), or None."""
    head = header(data)
    return head[0] if head is not None and head[0] is not None and head[0] not in ACCEPTED_FORMATS else None


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _png_damage(data: bytes) -> str | None:
    """Why a PNG file is damaged (a chunk's checksum does not match), or None. Checked
    before OpenCV sees it: libpng prints its own error lines for such a file."""
    if not bytes(data[:8]) == _PNG_SIGNATURE:
        return None
    try:
        with pillow_open(io.BytesIO(bytes(data))) as image:
            image.verify()
    except SyntaxError as error:
        said = " ".join(str(error).split())
        return "a checksum does not match" if "checksum" in said or "CRC" in said else said[:120]
    except (OSError, ValueError):
        return "its header is damaged"
    return None


def decode_problem(data: bytes) -> str:
    """Why an image did not decode, worded to follow its name ("photo room.jpg is cut
    short: ..."): empty, cut short (a copy or upload that stopped), samples of 32 bits
    or floats, or not an image at all."""
    if len(data) == 0:
        return "is empty (0 bytes); copy it again from the camera"
    if (kind := _other_format(data)) is not None:
        return f"is a {kind} file; Stager reads {PHOTO_FORMATS} photos: save it as one of those"
    if (damage := _png_damage(data)) is not None:
        return (f"is a damaged PNG file ({damage}: it was changed or cut after it was saved); save or copy it "
                "again")
    try:
        with pillow_open(io.BytesIO(bytes(data))) as image:
            kind, mode = image.format, image.mode
            try:
                image.load()
            except (OSError, ValueError, SyntaxError) as error:
                said = " ".join(str(error).split())
                if any(w in said.lower() for w in ("truncated", "incomplete", "broken", "end of file")):
                    return (f"is cut short: a {kind} file that ends before its picture does (a copy or upload "
                            "that stopped?); copy it again from the camera")
                return f"is a {kind} file that cannot be decoded ({said[:120]}); save it again as JPEG or PNG"
    except (OSError, ValueError, SyntaxError):
        return f"is not an image Stager can read ({PHOTO_FORMATS})"
    if mode in ("I", "F") or mode.startswith(("I;32", "F;")):
        return f"is a {kind} of {'floating-point' if mode.startswith('F') else '32-bit'} samples; save it as an " \
               "8- or 16-bit image (JPEG, PNG or TIFF)"
    return f"is a {kind} image ({mode}) Stager cannot decode; save it again as JPEG or PNG"


def decode_image(data: bytes) -> np.ndarray | None:
    """An encoded photo as RGB ``(h, w, 3)`` uint8, turned upright as it says, or None
    when it cannot be decoded.

    JPEG, PNG, TIFF, WebP and BMP go through OpenCV (which applies the EXIF
    orientation); HEIC/HEIF, what iPhones save, through pillow-heif (which applies the
    file's rotation).
    """
    if len(data) == 0 or _png_damage(data) is not None or _other_format(data) is not None:
        return None
    try:
        image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    except cv2.error:  # a header OpenCV refuses (a size past its limits)
        image = None
    if image is not None:
        return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
    if not is_heif(data):
        return None
    import pillow_heif

    try:
        heif = pillow_heif.open_heif(io.BytesIO(bytes(data)), convert_hdr_to_8bit=True)
        return np.asarray(heif.to_pillow().convert("RGB"))
    except (ValueError, RuntimeError, OSError, SyntaxError):
        return None


def read_photo(path) -> np.ndarray:
    """An RGB photo (h, w, 3) uint8 from ``path``.

    Raises
    ------
    CalibrationError
        When the file is missing, not an image Stager can decode, or of a size that will not
        do (too small, or a panorama).
    """
    path = Path(path)
    if path_problem(path, "folder") is None:
        raise CalibrationError(f"photo {path} is a folder; give a photo file, e.g. {path / 'room.jpg'}")
    data, problem = read_user_file(path)
    if problem is not None:
        raise CalibrationError(f"photo {path} {problem}")
    if (head := header(data)) is not None and (problem := pixels_problem(*head[1])) is not None:
        raise CalibrationError(f"photo {path} {problem}")
    image = decode_image(data)
    if image is None:
        raise CalibrationError(f"photo {path} {decode_problem(data)}")
    if (problem := size_problem(image.shape[1], image.shape[0])) is not None:
        raise CalibrationError(f"photo {path} {problem}")
    return image
