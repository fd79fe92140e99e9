"""The floor model: an ONNX segmentation network's floor probability for a photo.

Stager's own network (``models/floor_segnet.onnx``, trained on synthetic rooms by
``models/train_floor.py``), or any ONNX segmentation model a user points at, described
by a :class:`ModelSpec`. Images are RGB ``(rows, cols, 3)`` uint8.
"""
from __future__ import annotations

import json
import math
import numbers
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np

from layout.fileio import path_problem

from ..errors import SegmentationError
from ..photo.io import size_problem
from .settings import FLOOR

# The repository's trained models (models/README.md has their cards).
MODELS_DIR = Path(__file__).resolve().parents[2] / "models"
DEFAULT_MODEL = MODELS_DIR / "floor_segnet.onnx"


MAX_INPUT_PX = 4096  # a model input side: larger would take seconds and gigabytes on a CPU


# The input element types a model may take (as onnxruntime names them): exports for phones
# often take bytes, or half floats.
INPUT_TYPES = {"tensor(float)": np.float32, "tensor(float16)": np.float16, "tensor(double)": np.float64,
               "tensor(uint8)": np.uint8}


def _numbers(value) -> tuple[float, ...] | None:
    """``value`` (a number or a list of them) as finite floats; None when it is not that."""
    items = tuple(value) if isinstance(value, (list, tuple, np.ndarray)) else (value,)
    if not all(isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) for v in items):
        return None
    return tuple(float(v) for v in items)


@dataclass(frozen=True)
class ModelSpec:
    """How to feed an ONNX segmentation model and read its floor class.

    Attributes
    ----------
    input_size : (rows, cols) or None
        A fixed input size; None for a fully convolutional model, fed the photo scaled so
        its long side is ``input_long_px``, each side a multiple of ``multiple_px``.
    input_long_px : int or tuple of int
        With several long sides the model runs at each and the floor probabilities are
        averaged (the shipped model: its training size and two larger, which find more of
        the floor in dark corners and under tables of real rooms).
    fine_long_px : tuple of int
        Larger long sides, whose mean is the floor probability wherever it is higher than
        the mean over ``input_long_px``: a far strip of floor past a threshold, a few input
        pixels tall at the smaller sizes, reads as floor at these (for a model trained to
        read them, ``models/train_floor.py --read-long-px``), while the smaller sizes see
        the room whole. Empty: none.
    channel_order : "RGB" or "BGR"
    scale, mean, std : float, (3,), (3,)
        Input = (pixel * scale - mean) / std, per channel in ``channel_order``.
    floor_class : tuple of int
        Output channels whose probabilities add up to "floor" (e.g. SUN RGB-D floor = 2,
        or ADE20K floor and rug).
    output : "logits" or "probabilities"
        Whether the model's output still needs a softmax over the class axis (a sigmoid
        for one channel). A model whose output is one integer class per pixel (its
        argmax) is read as such, whatever this says.
    layout : "NCHW" or "NHWC"
    """

    input_size: tuple[int, int] | None = None
    input_long_px: int | tuple[int, ...] = 256
    fine_long_px: tuple[int, ...] = ()
    multiple_px: int = 32
    channel_order: str = "RGB"
    scale: float = 1 / 255
    mean: tuple[float, float, float] = (0.485, 0.456, 0.406)
    std: tuple[float, float, float] = (0.229, 0.224, 0.225)
    floor_class: tuple[int, ...] = (1,)
    output: str = "logits"
    layout: str = "NCHW"

    def __post_init__(self):
        # Fields come from a sidecar JSON or the command line: check each by name, so a
        # wrong one is one clear error rather than a TypeError deep in inference.
        def wholes(name, lo, hi, count=None, example=""):
            values = _numbers(getattr(self, name))
            if (values is None or not values or (count is not None and len(values) != count)
                    or any(v != int(v) or not lo <= v <= hi for v in values)):
                raise SegmentationError(f"model {name} {getattr(self, name)!r}: need "
                                        f"{'one or more' if count is None else count} whole number"
                                        f"{'s' * (count != 1)} from {lo} to {hi}{example}")
            object.__setattr__(self, name, tuple(int(v) for v in values))

        wholes("multiple_px", 1, 1024, 1)
        object.__setattr__(self, "multiple_px", self.multiple_px[0])
        wholes("input_long_px", self.multiple_px, MAX_INPUT_PX, example=", e.g. 256 or [256, 320]")
        if isinstance(self.fine_long_px, (list, tuple)) and len(self.fine_long_px) == 0:
            object.__setattr__(self, "fine_long_px", ())
        else:
            wholes("fine_long_px", self.multiple_px, MAX_INPUT_PX, example=", e.g. [448, 576], or [] for none")
        if self.input_size is not None:
            wholes("input_size", 16, MAX_INPUT_PX, 2, example=" (rows, cols)")
        wholes("floor_class", 0, 100_000, example=", the output channels that are floor, e.g. [1] or [3, 28]")
        # A class named twice would count its probability twice.
        object.__setattr__(self, "floor_class", tuple(dict.fromkeys(self.floor_class)))
        for name, count in (("scale", 1), ("mean", 3), ("std", 3)):
            values = _numbers(getattr(self, name))
            if values is None or len(values) != count or (name != "mean" and min(values) <= 0):
                raise SegmentationError(f"model {name} {getattr(self, name)!r}: need {count} finite number"
                                        f"{'s' * (count > 1)}{'' if name == 'mean' else ' > 0'}; the input is "
                                        "(pixel * scale - mean) / std, e.g. scale 1/255 with ImageNet's mean "
                                        "and std")
            object.__setattr__(self, name, values[0] if count == 1 else values)
        for name, choices in (("channel_order", ("RGB", "BGR")), ("output", ("logits", "probabilities")),
                              ("layout", ("NCHW", "NHWC"))):
            if getattr(self, name) not in choices:
                raise SegmentationError(f"model {name} {getattr(self, name)!r}: use {' or '.join(choices)}")

    @classmethod
    def from_json(cls, path) -> "ModelSpec":
        """Read the spec from a model's sidecar JSON (unknown keys, like training notes, are ignored)."""
        path = Path(path)
        try:
            data = json.loads(path.read_text())
        except (OSError, ValueError, RecursionError) as error:
            raise SegmentationError(f"model spec {path}: cannot read it as JSON ({error})") from None
        if not isinstance(data, dict):
            raise SegmentationError(f"model spec {path}: holds a JSON {type(data).__name__}, not an object of "
                                    "fields (input_size, mean, std, floor_class, ...)")
        try:
            return cls(**{f: data[f] for f in cls.__dataclass_fields__ if f in data})
        except SegmentationError as error:
            raise SegmentationError(f"model spec {path}: {str(error).removeprefix('model ')}") from None


class FloorModel:
    """An ONNX segmentation model loaded in onnxruntime, with its :class:`ModelSpec`.

    Parameters
    ----------
    path : path-like
        The ``.onnx`` file. Its spec is read from ``path`` with suffix ``.json`` when that
        exists, else the defaults; ``spec`` overrides both.
    spec : ModelSpec, optional
    threads : int, optional
        onnxruntime intra-op threads (default: its own choice).
    """

    def __init__(self, path=DEFAULT_MODEL, spec: ModelSpec | None = None, threads: int | None = None):
        import onnxruntime as ort  # loaded lazily: GrabCut-only runs need none of it

        self.path = Path(path)
        if (problem := path_problem(self.path, missing="no such file")) is not None:
            raise SegmentationError(f"model {self.path}: {problem}; train one with models/train_floor.py "
                                    "or use --method grabcut")
        sidecar = self.path.with_suffix(".json")
        self.spec = spec if spec is not None else (ModelSpec.from_json(sidecar) if sidecar.is_file() else ModelSpec())
        options = _session_options()
        if threads is not None:
            options.intra_op_num_threads = threads
        try:
            self.session = ort.InferenceSession(str(self.path), options, providers=["CPUExecutionProvider"])
        except Exception as error:  # onnxruntime raises its own types for a corrupt file
            raise SegmentationError(f"model {self.path}: onnxruntime cannot load it ({error})") from None
        inputs = self.session.get_inputs()
        if len(inputs) != 1:
            raise SegmentationError(f"model {self.path}: expected one input, found {len(inputs)}")
        self.input_name = inputs[0].name
        self.input_dtype = INPUT_TYPES.get(inputs[0].type)
        if self.input_dtype is None:
            raise SegmentationError(f"model {self.path}: its input {self.input_name} is {inputs[0].type}; Stager "
                                    f"feeds images as {', '.join(INPUT_TYPES)}")
        shape = list(inputs[0].shape)
        if len(shape) != 4:
            raise SegmentationError(f"model {self.path}: its input {self.input_name} is {shape}; expected an image "
                                    "batch (1, 3, rows, cols), or (1, rows, cols, 3) with layout NHWC")
        spatial = shape[2:4] if self.spec.layout == "NCHW" else shape[1:3]
        channels = shape[1] if self.spec.layout == "NCHW" else shape[3]
        if isinstance(channels, int) and channels != 3:
            raise SegmentationError(f"model {self.path}: its input is {shape}, {channels} channels where Stager "
                                    f"feeds 3 (RGB or BGR); is its layout not {self.spec.layout}? (the layout "
                                    "field of its JSON)")
        if all(isinstance(v, int) and v > 0 for v in spatial):
            # A model exported for one size says so; fed another, onnxruntime refuses it.
            if self.spec.input_size is None:
                self.spec = replace(self.spec, input_size=tuple(spatial))
            elif tuple(self.spec.input_size) != tuple(spatial):
                raise SegmentationError(f"model {self.path}: takes {spatial[1]}x{spatial[0]} px (its input is "
                                        f"{shape}), not the {self.spec.input_size[1]}x{self.spec.input_size[0]} "
                                        f"asked for; give --input-size {spatial[1]}x{spatial[0]} or leave it out")

    def input_shapes(self, rows: int, cols: int, longs=None) -> list[tuple[int, int]]:
        """The (rows, cols) the model is fed for a photo of ``rows`` x ``cols``, one per
        input size of the spec (or per long side of ``longs``)."""
        s = self.spec
        if s.input_size is not None:
            return [tuple(s.input_size)]
        m = s.multiple_px
        return [(max(m, round(rows * long / max(rows, cols) / m) * m),
                 max(m, round(cols * long / max(rows, cols) / m) * m))
                for long in (s.input_long_px if longs is None else longs)]

    def _fine_longs(self) -> tuple[int, ...]:
        """The fine sizes read: none for a model of one fixed input size."""
        return self.spec.fine_long_px if self.spec.input_size is None else ()

    def inputs_label(self, rows: int, cols: int) -> str:
        """The input shapes for a photo of ``rows`` x ``cols``, as a benchmark names them:
        "256x192+320x256+448x320", then the fine sizes' "448x320+576x416 where higher"."""
        label = "+".join(f"{c}x{r}" for r, c in self.input_shapes(rows, cols))
        if self._fine_longs():
            fine = "+".join(f"{c}x{r}" for r, c in self.input_shapes(rows, cols, self._fine_longs()))
            label += f", {fine} where higher"
        return label

    def floor_probability(self, image: np.ndarray, size_px: tuple[int, int] | None = None) -> np.ndarray:
        """Floor probability float32 in [0, 1], ``(rows, cols)`` of the image or of
        ``size_px = (width, height)`` when given (cheaper than resizing twice): the mean
        over the spec's input sizes, or where higher the mean over its fine sizes (a size in
        both runs once). The model learned rooms upright: give it the photo turned so
        (:mod:`augment.floor.upright`)."""
        image = check_image(image)
        rows, cols = image.shape[:2]
        if size_px is not None:
            cols, rows = int(size_px[0]), int(size_px[1])
        # Shrunk once, before the smaller working sizes are made from it.
        image = shrink_to(image, FLOOR.model.preshrink_long_px)
        runs = {}

        def mean(longs):
            shapes = self.input_shapes(rows, cols, longs)
            for shape in shapes:
                if shape not in runs:
                    runs[shape] = self._probability(image, shape, (cols, rows))
            return np.clip(sum(runs[shape] for shape in shapes) / len(shapes), 0, 1)

        p = mean(None)
        if self._fine_longs():
            p = np.maximum(p, mean(self._fine_longs()))
        return np.ascontiguousarray(p)

    def _probability(self, image: np.ndarray, in_shape: tuple[int, int], size_px: tuple[int, int]) -> np.ndarray:
        s = self.spec
        in_rows, in_cols = in_shape
        x = shrink_area(image, (in_cols, in_rows))
        if s.channel_order == "BGR":
            x = x[..., ::-1]
        if self.input_dtype != np.uint8:
            # A model that takes bytes takes the pixels as they are, and scales them itself.
            x = (x.astype(np.float32) * np.float32(s.scale) - np.float32(s.mean)) / np.float32(s.std)
        x = x.transpose(2, 0, 1)[None] if s.layout == "NCHW" else x[None]
        out = self.session.run(None, {self.input_name: np.ascontiguousarray(x, self.input_dtype)})[0][0]
        if np.issubdtype(out.dtype, np.floating):
            out = out.astype(np.float32)
        if out.ndim == 2 and np.issubdtype(out.dtype, np.integer):
            # A model that gives its argmax, a class per pixel: floor where it is a floor class.
            p = np.isin(out, s.floor_class).astype(np.float32)
            return cv2.resize(p, size_px, interpolation=cv2.INTER_LINEAR)
        if s.layout == "NHWC" and out.ndim == 3:
            out = out.transpose(2, 0, 1)
        if out.ndim != 3 or max(s.floor_class) >= out.shape[0]:
            raise SegmentationError(f"model {self.path}: output shape {out.shape} has no class "
                                    f"{max(s.floor_class)}; check floor_class and layout")
        if s.output == "logits" and out.shape[0] == 1:
            # One channel: a floor-or-not model's logit (a softmax over one class is 1).
            out = 1.0 / (1.0 + np.exp(-out))
        elif s.output == "logits":
            out = np.exp(out - out.max(axis=0, keepdims=True))
            out /= out.sum(axis=0, keepdims=True)
        p = out[list(s.floor_class)].sum(axis=0).astype(np.float32)
        return cv2.resize(p, size_px, interpolation=cv2.INTER_LINEAR)


def _session_options():
    """Quiet, and with worker threads that sleep between runs: spinning ones took a core
    from the threads that erase the board and load the solver meanwhile (a 1280x960
    ``stage furnish``: 6.1 -> 5.7 s, median of 8 side by side)."""
    import onnxruntime as ort

    options = ort.SessionOptions()
    options.log_severity_level = 3
    options.add_session_config_entry("session.intra_op.allow_spinning", "0")
    return options


@lru_cache(maxsize=4)
def shipped_session(path: str):
    """An onnxruntime session of one of the small models that ship in ``models/``, kept."""
    import onnxruntime as ort

    if not Path(path).is_file():
        raise FileNotFoundError(f"the model {path} is missing: it ships with Stager, "
                                f"restore it with `git checkout models/{Path(path).name}`")
    return ort.InferenceSession(path, _session_options(), providers=["CPUExecutionProvider"])


def shrink_to(image: np.ndarray, long_px: int) -> np.ndarray:
    """``image`` shrunk by the least whole factor that brings its long side to ``long_px``
    or less (a whole factor is OpenCV's fast path); as it is when it is that small."""
    rows, cols = image.shape[:2]
    k = math.ceil(max(rows, cols) / long_px)
    if k <= 1:
        return image
    return shrink_area(image, (round(cols / k), round(rows / k)))


def shrink_area(image: np.ndarray, size_px: tuple[int, int], least: int = 4) -> np.ndarray:
    """``cv2.resize(image, size_px, interpolation=cv2.INTER_AREA)`` for a smaller ``size_px =
    (width, height)``, through :func:`shrink_whole` first."""
    image = shrink_whole(image, size_px, least)
    if image.shape[1::-1] == tuple(size_px):
        return image
    return cv2.resize(image, tuple(size_px), interpolation=cv2.INTER_AREA)


def shrink_whole(image: np.ndarray, size_px: tuple[int, int], least: int = 4) -> np.ndarray:
    """``image`` shrunk by a whole factor that divides both its sides, so that the way on to
    ``size_px = (width, height)`` still averages ``least`` x ``least`` pixels or more: OpenCV
    averages whole blocks some 20 times faster than fractional ones (12 MP photos), and
    with 4 the two steps come within a few levels of one."""
    rows, cols = image.shape[:2]
    k = int(min(cols / size_px[0], rows / size_px[1]) / least)
    while k >= 2 and (cols % k or rows % k):
        k -= 1
    return image if k < 2 else cv2.resize(image, (cols // k, rows // k), interpolation=cv2.INTER_AREA)


def check_image(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.ndim == 2:
        image = np.repeat(image[..., None], 3, axis=2)
    if image.ndim != 3 or image.shape[2] not in (3, 4):
        raise SegmentationError(f"image of shape {image.shape}: expected (rows, cols, 3) RGB")
    if image.dtype != np.uint8:
        raise SegmentationError(f"image dtype {image.dtype}: expected uint8")
    if (problem := size_problem(image.shape[1], image.shape[0])) is not None:
        raise SegmentationError(f"the image {problem}")
    return np.ascontiguousarray(image[..., :3])


def working_scale(shape, long_px) -> float:
    return min(1.0, long_px / max(shape))


def load_floor_model(model) -> "FloorModel":
    """``model`` as a :class:`FloorModel`: one already loaded, a path, or Stager's own for None."""
    if isinstance(model, FloorModel):
        return model
    return FloorModel(DEFAULT_MODEL if model is None else Path(model))
