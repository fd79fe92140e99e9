"""Images to and from file bytes: one encoder for every picture Stager writes, one
decoder for every photo it reads.

Images are RGB ``(h, w, 3)``, RGBA ``(h, w, 4)`` or grey ``(h, w)`` uint8 arrays.
"""
from __future__ import annotations

import io
import threading
from contextlib import contextmanager
from pathlib import Path

import cv2
import numpy as np

from ..errors import CalibrationError

# The ISO base-media brands of HEIF stills: HEIC is what iPhones save by default.
_HEIF_BRANDS = (b"heic", b"heix", b"heim", b"heis", b"hevc", b"hevx", b"mif1", b"msf1")

# What decode_image reads, as error messages name it.
PHOTO_FORMATS = "JPEG, PNG, HEIC, TIFF, WebP or BMP"
# The names photos of those formats go by, as a folder of shots is searched for them.
PHOTO_SUFFIXES = (".jpg", ".jpeg", ".png", ".heic", ".heif", ".tif", ".tiff", ".webp", ".bmp")
JPEG_QUALITY = 92  # staged photos: no visible loss, about a third of the PNG's size
MIN_PHOTO_PX = 64  # a side: a thumbnail; a board in it would be a few pixels across
# Long side over short. Phones take 4:3 to 21:9; wider is a panorama (not one pinhole
# view, which the calibration assumes) or a strip, whose board search copy would be a few
# pixels high.
MAX_ASPECT = 4.0


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


def read_user_file(path) -> tuple[bytes | None, str | None]:
    """The bytes of a file the user named and None, or None and why it cannot be read,
    worded to follow the file's name in an error ("... cannot be read (Permission
    denied); check that you may read it")."""
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


def decode_problem(data: bytes) -> str:
    """Why an image did not decode, worded to follow its name ("photo room.jpg is cut
    short: ..."): empty, cut short (a copy or upload that stopped), samples of 32 bits
    or floats, or not an image at all."""
    if len(data) == 0:
        return "is empty (0 bytes); copy it again from the camera"
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
    if len(data) == 0:
        return None
    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
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
    if path.is_dir():
        raise CalibrationError(f"photo {path} is a folder; give a photo file, e.g. {path / 'room.jpg'}")
    if not path.is_file():
        raise CalibrationError(f"photo {path} does not exist; check the path")
    data, problem = read_user_file(path)
    if problem is not None:
        raise CalibrationError(f"photo {path} {problem}")
    image = decode_image(data)
    if image is None:
        raise CalibrationError(f"photo {path} {decode_problem(data)}")
    if (problem := size_problem(image.shape[1], image.shape[0])) is not None:
        raise CalibrationError(f"photo {path} {problem}")
    return image
