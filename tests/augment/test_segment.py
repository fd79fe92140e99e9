"""Floor segmentation and the floor polygon against known answers: synthetic renders the
model never saw (its training seeds were 100 to 103), a hand-built ONNX model, and
floors drawn from known polygons through a real calibration."""
from __future__ import annotations

import dataclasses
import json
import re

import cv2
import numpy as np
import pytest
from skimage.measure import points_in_poly

from augment.camera.board import Board
from augment.camera.calibrate import calibrate_photo, exif_intrinsics
from augment.camera.calibration import turn_points
from augment.draw.floor import floor_overlay
from augment.draw.settings import DRAW
from augment.errors import SegmentationError
from augment.floor import segment
from augment.floor.model import DEFAULT_MODEL, FloorModel, ModelSpec, shrink_area, shrink_to
from augment.floor.polygon import _bridge, floor_area_m2, floor_polygon
from augment.floor.segment import below_horizon, disputed_floor, floor_parts, segment_floor
from augment.floor.settings import FLOOR
from augment.floor.upright import Upright
from augment.render.gl import Renderer
from augment.synth import OTHER, render_sample
from layout.geometry import polygon_area, self_intersection


def iou(a, b):
    return np.logical_and(a, b).sum() / np.logical_or(a, b).sum()


@pytest.fixture(scope="module")
def held_out():
    """Renders from seeds the model was not trained on, calibrated with their true focal
    length (these tests are about the floor, not the focal estimate)."""
    out = []
    with Renderer() as renderer:
        for i in range(6):
            sample = render_sample([7100, i], renderer, size_px=(640, 480))
            f = sample.truth["K"][0][0]
            try:
                cal = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(f, (640, 480)))
            except ValueError:
                continue
            out.append((sample, cal))
    assert len(out) >= 4
    return out


@pytest.fixture(scope="module")
def model():
    return FloorModel(DEFAULT_MODEL)


def test_shipped_model_finds_the_floor_of_unseen_rooms(held_out, model):
    ious = []
    for sample, cal in held_out:
        image = sample.image.copy()
        seg = segment_floor(image, model, cal)
        assert np.array_equal(image, sample.image)  # input untouched
        assert seg.method == "onnx+grabcut" and seg.mask.shape == image.shape[:2]
        ious.append(iou(seg.mask, sample.floor_mask))
    assert min(ious) > 0.9 and np.mean(ious) > 0.95, ious


def test_grabcut_alone_from_the_calibration(held_out):
    """Without the model GrabCut finds most of the floor, but where a band of sun splits
    it (render 3: 41 % of the floor in view sunlit, the board in the sun) it keeps the
    board's side only: IoU 0.50. The model's path finds all of it (above)."""
    ious = [iou(segment_floor(s.image, calibration=c, method="grabcut").mask, s.floor_mask) for s, c in held_out]
    assert np.mean(ious) > 0.8 and sorted(ious)[1] > 0.75, ious


def test_the_board_is_floor_and_nothing_above_the_horizon_is(held_out, model):
    sample, cal = held_out[0]
    mask = segment_floor(sample.image, model, cal).mask
    rows, cols = mask.shape
    y, x = np.mgrid[0:rows, 0:cols]
    above = cal.horizon[0] * x + cal.horizon[1] * y + cal.horizon[2] < 0
    assert not (mask & above).any()
    board = np.zeros_like(mask, np.uint8)
    cv2.fillPoly(board, [cal.pixels_from_floor(Board().outline_m()[:, :2] * 0.9).round().astype(np.int32)], 1)
    assert mask[board > 0].all()


class _Doubting:
    """The shipped model, but doubting the floor near things standing on it (probability
    0.06 within 10 working pixels of them): the base model of commit ed2f93e gave the floor
    behind and between cartons 0.02; below ``FLOOR.segment.veto_p`` (0.05) the model now
    overrules GrabCut there, and the doubt tested here is GrabCut's to settle."""

    def __init__(self, model, labels, floor):
        self.model, self.labels, self.floor = model, labels, floor

    def __getattr__(self, name):
        return getattr(self.model, name)

    def floor_probability(self, image, size=None):
        p = self.model.floor_probability(image, size).copy()
        rows, cols = p.shape
        floor = cv2.resize(self.floor.astype(np.uint8), (cols, rows), interpolation=cv2.INTER_NEAREST) > 0
        things = cv2.resize((self.labels == OTHER).astype(np.uint8), (cols, rows), interpolation=cv2.INTER_NEAREST)
        p[floor & (cv2.dilate(things, np.ones((21, 21), np.uint8)) > 0)] = 0.06
        return p


def test_floor_the_model_nearly_rules_out_is_left_to_grabcut(model, monkeypatch):
    """A render of the synthetic photographer (seed 907, render 77: a dark wooden floor
    with cartons along the far wall), the model doubting the floor by the cartons (0.06).
    Taken as sure "not floor", that floor is lost, 2 % of the floor's pixels (the model read
    at 448 and 576 px is sure of less there); GrabCut, left to judge it, keeps it. The truth
    is the render's floor mask."""

    with Renderer() as renderer:
        sample = render_sample([907, 77], renderer)
    w, h = sample.truth["size_px"]
    cal = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(sample.truth["K"][0][0], (w, h)))
    truth = sample.floor_mask
    doubting = _Doubting(model, sample.labels, truth)

    def missed_and_extra():
        mask = segment_floor(sample.image, doubting, cal).mask
        return (truth & ~mask).sum() / truth.sum(), (mask & ~truth).sum() / truth.sum()

    missed, extra = missed_and_extra()
    assert missed < 0.01 and extra < 0.01, (missed, extra)
    monkeypatch.setattr(FLOOR.segment, "sure_other", 0.07)
    assert missed_and_extra()[0] > 0.015


# Class 2's logit is 20 (R - B), the others 0: "floor" is where the photo is red.
RED_IS_CLASS_2 = [[0, 0, 0], [0, 0, 0], [20, 0, -20]]


def _conv_model(path, weights, shape_in, layout="NCHW", input_type=None):
    """A 1x1 convolution of the image by ``weights`` (classes, 3), input ``shape_in``. An
    NHWC model (as exported from TensorFlow) takes and gives channels last; one of
    another ``input_type`` (onnx.TensorProto's) casts its input to floats first."""
    import onnx
    from onnx import TensorProto, helper

    w = np.asarray(weights, np.float32)[..., None, None]
    nodes, inp = [], "image"
    if input_type is not None:
        nodes.append(helper.make_node("Cast", ["image"], ["floats"], to=TensorProto.FLOAT))
        inp = "floats"
    if layout == "NHWC":
        nodes.append(helper.make_node("Transpose", [inp], ["nchw"], perm=[0, 3, 1, 2]))
        inp = "nchw"
    nodes.append(helper.make_node("Conv", [inp, "w"], ["logits" if layout == "NCHW" else "conv"]))
    if layout == "NHWC":
        nodes.append(helper.make_node("Transpose", ["conv"], ["logits"], perm=[0, 2, 3, 1]))
    shape_out = [1, len(w)] + list(shape_in[2:]) if layout == "NCHW" else list(shape_in[:3]) + [len(w)]
    graph = helper.make_graph(
        nodes, "conv", [helper.make_tensor_value_info("image", input_type or TensorProto.FLOAT, shape_in)],
        [helper.make_tensor_value_info("logits", TensorProto.FLOAT, shape_out)],
        [helper.make_tensor("w", TensorProto.FLOAT, w.shape, w.ravel())])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.save(model, str(path))
    return path


def _tiny_model(path, layout="NCHW"):
    """Red is class 2 (fed BGR by mistake, blue is), any input size."""
    shape_in = [1, "rows", "cols", 3] if layout == "NHWC" else [1, 3, "rows", "cols"]
    return _conv_model(path, RED_IS_CLASS_2, shape_in, layout)


def test_fixed_size_and_one_channel_models(tmp_path):
    """A model exported for one input size is fed that size (onnxruntime refused the
    photo's, a traceback); a model of one output channel is read as a logit (a softmax
    over one class made every pixel floor); one that gives class labels, as labels."""
    image = np.zeros((96, 128, 3), np.uint8)
    image[:, :64] = (200, 30, 30)   # red left half
    image[:, 64:] = (30, 30, 200)   # blue right half
    left = np.zeros((96, 128), bool)
    left[:, :64] = True
    fixed = _conv_model(tmp_path / "fixed.onnx", RED_IS_CLASS_2, [1, 3, 48, 64])
    model = FloorModel(fixed, spec=ModelSpec(mean=(0, 0, 0), std=(1, 1, 1), floor_class=(2,)))
    assert model.spec.input_size == (48, 64) and iou(model.floor_probability(image) > 0.5, left) > 0.95
    with pytest.raises(SegmentationError, match=re.escape("takes 64x48 px (its input is [1, 3, 48, 64]), not "
                                                          "the 128x96 asked for")):
        FloorModel(fixed, spec=ModelSpec(input_size=(96, 128), floor_class=(2,)))
    one = _conv_model(tmp_path / "one.onnx", [[20, 0, -20]], [1, 3, "rows", "cols"])
    p = FloorModel(one, spec=ModelSpec(mean=(0, 0, 0), std=(1, 1, 1), floor_class=(0,))).floor_probability(image)
    assert iou(p > 0.5, left) > 0.95 and p[:, 100:].max() < 0.01
    # A model that gives its argmax (int64, a class per pixel): floor where it is class 2.
    import onnx
    from onnx import helper

    graph = onnx.load(str(_tiny_model(tmp_path / "argmax.onnx"))).graph
    graph.node[0].output[0] = "scores"
    graph.node.append(helper.make_node("ArgMax", ["scores"], ["labels"], axis=1, keepdims=0))
    graph.output[0].CopyFrom(helper.make_tensor_value_info("labels", onnx.TensorProto.INT64, [1, "rows", "cols"]))
    labels = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    labels.ir_version = 8
    onnx.save(labels, str(tmp_path / "argmax.onnx"))
    p = FloorModel(tmp_path / "argmax.onnx", spec=ModelSpec(mean=(0, 0, 0), std=(1, 1, 1), floor_class=(2,))
                   ).floor_probability(image)
    assert iou(p > 0.5, left) > 0.95
    flat = _conv_model(tmp_path / "flat.onnx", [[1, 2, 3, 4]], [1, 4, "rows", "cols"])
    with pytest.raises(SegmentationError, match=re.escape("its input is [1, 4, 'rows', 'cols'], 4 channels")):
        FloorModel(flat)  # a traceback from onnxruntime at the first photo


def test_a_users_onnx_model_is_fed_as_its_spec_says(tmp_path):
    image = np.zeros((96, 128, 3), np.uint8)
    image[:, :64] = (200, 30, 30)   # red left half
    image[:, 64:] = (30, 30, 200)   # blue right half
    left = np.zeros((96, 128), bool)
    left[:, :64] = True
    for layout in ("NCHW", "NHWC"):
        path = _tiny_model(tmp_path / f"tiny_{layout}.onnx", layout)
        spec = ModelSpec(input_size=(48, 64), mean=(0, 0, 0), std=(1, 1, 1), floor_class=(2,), layout=layout)
        p = FloorModel(path, spec=spec).floor_probability(image)
        assert p.shape == (96, 128) and iou(p > 0.5, left) > 0.95
        bgr = FloorModel(path, spec=ModelSpec(**{**spec.__dict__, "channel_order": "BGR"}))
        assert iou(bgr.floor_probability(image) > 0.5, ~left) > 0.95
    # The sidecar JSON is read when present; CLI-style overrides win over it.
    (tmp_path / "tiny_NCHW.json").write_text(json.dumps({"input_size": [48, 64], "mean": [0, 0, 0],
                                                         "std": [1, 1, 1], "floor_class": 2, "note": "x"}))
    assert FloorModel(tmp_path / "tiny_NCHW.onnx").spec.floor_class == (2,)


def test_models_that_take_bytes_or_half_floats(tmp_path):
    """Exports for phones often take uint8 pixels (and scale them themselves) or float16:
    each is fed its type (both crashed in onnxruntime, "Unexpected input data type"); an
    input no image can be is one clear error."""
    from onnx import TensorProto

    image = np.zeros((96, 128, 3), np.uint8)
    image[:, :64] = (200, 30, 30)   # red left half
    image[:, 64:] = (30, 30, 200)
    left = np.zeros((96, 128), bool)
    left[:, :64] = True
    shape = [1, 3, "rows", "cols"]
    # With ImageNet's mean and std, the default: bytes go in as they are all the same.
    for name, kind, spec in (("bytes", TensorProto.UINT8, ModelSpec(floor_class=(2,))),
                             ("half", TensorProto.FLOAT16, ModelSpec(mean=(0, 0, 0), std=(1, 1, 1),
                                                                     floor_class=(2,)))):
        model = FloorModel(_conv_model(tmp_path / f"{name}.onnx", RED_IS_CLASS_2, shape, input_type=kind), spec=spec)
        p = model.floor_probability(image)
        assert p.dtype == np.float32 and iou(p > 0.5, left) > 0.95, name
    with pytest.raises(SegmentationError, match=re.escape("its input image is tensor(int64); Stager feeds images "
                                                          "as tensor(float), tensor(float16)")):
        FloorModel(_conv_model(tmp_path / "ints.onnx", RED_IS_CLASS_2, shape, input_type=TensorProto.INT64))


def test_several_input_sizes_average_the_floor_probability(held_out, model):
    """A spec with two long sides runs the model at both; the probability is their mean."""
    sample, _ = held_out[0]
    single = [FloorModel(model.path, spec=dataclasses.replace(model.spec, input_long_px=long, fine_long_px=()))
              for long in (256, 320)]
    p256, p320 = (m.floor_probability(sample.image) for m in single)
    assert np.abs(p256 - p320).max() > 0.1  # the two scales see the photo differently
    both = FloorModel(model.path, spec=dataclasses.replace(model.spec, input_long_px=[256, 320], fine_long_px=()))
    assert both.spec.input_long_px == (256, 320)
    np.testing.assert_allclose(both.floor_probability(sample.image), (p256 + p320) / 2, atol=1e-5)
    with pytest.raises(SegmentationError, match="input_long_px"):
        ModelSpec(input_long_px=[])
    for bad in (16, [256, "big"]):
        with pytest.raises(SegmentationError, match="input_long_px"):
            ModelSpec(input_long_px=bad)


def test_the_fine_sizes_read_the_floor_where_they_see_more(held_out, model):
    """A spec's fine sizes give a second read, taken wherever it is higher than the
    averaged sizes' (a size in both runs once)."""
    sample, _ = held_out[0]
    at = {long: FloorModel(model.path, spec=dataclasses.replace(model.spec, input_long_px=long, fine_long_px=()))
          .floor_probability(sample.image) for long in (256, 320, 448, 576)}
    base, fine = (at[256] + at[320] + at[448]) / 3, (at[448] + at[576]) / 2
    assert (fine > base + 0.1).any() and (fine < base - 0.1).any()  # each sees floor the other doubts
    both = FloorModel(model.path, spec=dataclasses.replace(model.spec, input_long_px=[256, 320, 448],
                                                           fine_long_px=[448, 576]))
    np.testing.assert_allclose(both.floor_probability(sample.image), np.maximum(base, fine), atol=1e-5)
    assert model.spec.fine_long_px == (448, 576)  # the shipped model's sidecar
    none = FloorModel(model.path, spec=dataclasses.replace(model.spec, fine_long_px=[]))
    assert none.spec.fine_long_px == ()
    np.testing.assert_allclose(none.floor_probability(sample.image), base, atol=1e-5)
    # As the benchmarks name them, for a 1008x756 photo (576 * 756 / 1008 = 432: 448 rows).
    assert model.inputs_label(756, 1008) == "256x192+320x256+448x320, 448x320+576x448 where higher"
    assert none.inputs_label(756, 1008) == "256x192+320x256+448x320"
    for bad in (16, [448, "big"], 448.5):
        with pytest.raises(SegmentationError, match="fine_long_px"):
            ModelSpec(fine_long_px=bad)


@pytest.mark.parametrize("seed", [[985, 22], [986, 17]])
def test_a_far_strip_of_a_second_floor_is_floor(model, seed):
    """Threshold renders (tuning sets 985, 986) whose second floor is a strip along the far
    wall, a few pixels tall at the training size: read at 256, 320 and 448 px the model
    gives it 0.2-0.4 and GrabCut drops it (-20 % and -27 % of the area with the model
    before). Read also at 448 and 576 px (the fine sizes) by the model fine-tuned for
    them, it is floor: the polygon is within 5 % of the one from the true mask."""
    with Renderer() as renderer:
        sample = render_sample(seed, renderer, two_floors=1.0)
    w, h = sample.truth["size_px"]
    cal = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(sample.truth["K"][0][0], (w, h)))
    truth_m2 = floor_polygon(sample.floor_mask, cal).area_m2
    seg = segment_floor(sample.image, model, cal)
    assert abs(floor_polygon(seg.mask, cal).area_m2 / truth_m2 - 1) < 0.05


def test_bad_models_and_images_get_clear_errors(tmp_path):
    with pytest.raises(SegmentationError, match="no such file"):
        FloorModel(tmp_path / "missing.onnx")
    (tmp_path / "junk.onnx").write_bytes(b"not a model")
    with pytest.raises(SegmentationError, match="cannot load"):
        FloorModel(tmp_path / "junk.onnx")
    with pytest.raises(SegmentationError, match="channel_order"):
        ModelSpec(channel_order="RGBA")
    # Options that used to pass: a NaN mean fed the model NaNs (every pixel "disputed"),
    # and a 100000 px input asked OpenCV for 30 GB.
    for bad, words in ((dict(mean=(float("nan"), 0, 0)), "mean (nan, 0, 0): need 3 finite numbers"),
                       (dict(std=(1, float("inf"), 1)), "std (1, inf, 1): need 3 finite numbers > 0"),
                       (dict(scale=0.0), "scale 0.0: need 1 finite number > 0"),
                       (dict(input_size=(100_000, 100_000)), "to 4096"),
                       (dict(input_size=(8, 8)), "from 16"), (dict(input_long_px=(256, 9000)), "to 4096")):
        with pytest.raises(SegmentationError, match=re.escape(words)):
            ModelSpec(**bad)
    assert ModelSpec(floor_class=(3, 28, 3)).floor_class == (3, 28)  # counted once
    # A user's sidecar JSON: each wrong field named (these were TypeErrors and
    # ValueErrors, or a class 1.5 or true taken as is).
    sidecar = tmp_path / "user.json"
    for text, words in (("[]", "holds a JSON list, not an object"), ('{"mean": 5}', "mean 5: need 3 finite"),
                        ('{"floor_class": "abc"}', "floor_class 'abc': need one or more whole numbers"),
                        ('{"floor_class": [1.5]}', "floor_class [1.5]"), ('{"floor_class": [true]}', "floor_class [True]"),
                        ('{"scale": "x"}', "scale 'x': need 1 finite number"), ('{"multiple_px": 0}', "multiple_px 0"),
                        ("[" * 100_000 + "]" * 100_000, "cannot read it as JSON")):
        sidecar.write_text(text)
        with pytest.raises(SegmentationError, match=re.escape(f"model spec {sidecar}: {words}")):
            ModelSpec.from_json(sidecar)
    sidecar.write_text('{"floor_class": 3, "input_long_px": [256, 320], "std": [1, 1, 1], "notes": "ignored"}')
    read = ModelSpec.from_json(sidecar)
    assert (read.floor_class, read.input_long_px, read.std) == ((3,), (256, 320), (1.0, 1.0, 1.0))
    with pytest.raises(SegmentationError, match="too small"):
        segment_floor(np.zeros((20, 30, 3), np.uint8), method="grabcut")
    with pytest.raises(SegmentationError, match="uint8"):
        segment_floor(np.zeros((100, 100, 3), np.float32), method="grabcut")
    with pytest.raises(SegmentationError, match="calibration"):
        segment_floor(np.zeros((100, 100, 3), np.uint8), method="grabcut")


def test_grey_photo_is_accepted(held_out, model):
    sample, cal = held_out[0]
    grey = cv2.cvtColor(sample.image, cv2.COLOR_RGB2GRAY)
    assert iou(segment_floor(grey, model, cal).mask, sample.floor_mask) > 0.85


def _floor_mask(cal, polygon_m):
    """Rasterize a floor polygon through the calibration as a camera does: a pixel is
    floor when its center sees the floor (below the horizon, inside the polygon)."""
    cols, rows = cal.size_px
    y, x = np.mgrid[:rows, :cols]
    centers = np.column_stack([x.ravel(), y.ravel()]).astype(np.float64)
    H = np.linalg.inv(cal.image_from_floor)
    below_horizon = (np.column_stack([centers, np.ones(len(centers))]) @ H.T)[:, 2] > 0
    inside = points_in_poly(cal.floor_from_pixels(centers), polygon_m)
    return (inside & below_horizon).reshape(rows, cols)


def test_polygon_recovers_a_known_floor(held_out):
    """An L-shaped floor around the board, fully in view: its corners come back within
    3 cm, its area within 1 %, and every edge is a real boundary."""
    _, cal = held_out[0]
    cam = np.linalg.inv(cal.camera_from_floor)[:2, 3]
    toward = -cam / np.linalg.norm(cam)  # from the camera through the board
    side = np.array([-toward[1], toward[0]])
    local = np.array([[-0.8, -0.3], [0.8, -0.3], [0.8, 0.5], [0.2, 0.5], [0.2, 1.1], [-0.8, 1.1]])
    for scale in (1.0, 0.7, 0.5):  # as large as the view allows, with the board inside
        truth = scale * (local[:, :1] * side + local[:, 1:] * toward)
        mask = _floor_mask(cal, truth)
        if not (mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any()):
            break
    else:
        pytest.fail("no L-shaped floor fits the view")
    poly = floor_polygon(mask, cal)
    assert len(poly.polygon_m) == 6 and set(poly.edge_kind) == {"boundary"} and poly.caveat == ""
    for v in truth:
        assert np.min(np.linalg.norm(poly.polygon_m - v, axis=1)) < 0.03
    area = 0.5 * abs(np.dot(truth[:, 0], np.roll(truth[:, 1], -1)) - np.dot(truth[:, 1], np.roll(truth[:, 0], -1)))
    assert abs(poly.area_m2 - area) / area < 0.005
    # Pixel by pixel, the raster is unbiased: boundary pixels half in and half out even out.
    assert abs(floor_area_m2(mask, cal) - area) / area < 0.005
    # Counter-clockwise seen from above.
    p = poly.polygon_m
    assert np.dot(p[:, 0], np.roll(p[:, 1], -1)) - np.dot(p[:, 1], np.roll(p[:, 0], -1)) > 0


def test_a_far_wall_of_a_segmented_render_is_one_edge(monkeypatch):
    """Render 9900/38 of the synthetic photographer (1280 x 960, as the staging benchmark
    makes it): GrabCut decides the floor at 400 px, and its mask's steps of a pixel or
    two are centimeters deep along the far wall, 6 m away. Straightened on the floor
    alone they stayed as teeth (21 vertices, 13 of them on that wall); straightened in
    the photo first, the floor has a vertex per corner of the room in view, and its
    area stays that of the straightening on the floor alone and of the true mask."""
    with Renderer() as renderer:
        sample = render_sample([9900, 38], renderer, (1280, 960), clutter=False)
    f = sample.truth["K"][0][0]
    cal = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(f, (1280, 960)))
    mask = segment_floor(sample.image, FloorModel(DEFAULT_MODEL), cal).mask
    poly = floor_polygon(mask, cal)
    assert len(poly.polygon_m) <= 6, poly.polygon_m
    assert poly.area_m2 == pytest.approx(floor_polygon(sample.floor_mask, cal).area_m2, rel=0.02)
    monkeypatch.setattr(FLOOR.polygon, "simplify_share", 0.0)
    toothed = floor_polygon(mask, cal)
    assert len(toothed.polygon_m) > 12
    assert poly.area_m2 == pytest.approx(toothed.area_m2, rel=0.005)


def test_carton_behind_a_thin_rim_of_floor_stays_inside_the_outline(held_out):
    """A floor with a carton's hole cut out just below its far edge, leaving a rim of floor
    one pixel thin behind it: the outline is the floor's own (area within 1 % of the
    whole floor's), not a bay running round the carton (8 % less without filling holes first)."""
    _, cal = held_out[0]
    cam = np.linalg.inv(cal.camera_from_floor)[:2, 3]
    toward = -cam / np.linalg.norm(cam)
    side = np.array([-toward[1], toward[0]])
    truth = np.array([-0.6 * side - 0.3 * toward, 0.6 * side - 0.3 * toward, 0.6 * side + 0.8 * toward,
                      -0.6 * side + 0.8 * toward])
    whole = _floor_mask(cal, truth)
    mask = whole.copy()
    cols = np.flatnonzero(mask.any(axis=0))
    top = mask.argmax(axis=0)
    for c in cols[len(cols) // 3: len(cols) // 2]:
        mask[top[c] + 1: top[c] + 40, c] = False
    expected = floor_polygon(whole, cal).area_m2
    assert abs(floor_polygon(mask, cal).area_m2 - expected) / expected < 0.01


def test_floor_cut_by_the_photo_edge_is_labelled(held_out):
    """A floor running out of the photo at the bottom: those edges are the photo's, and
    the caveat says the room goes on."""
    _, cal = held_out[0]
    cam = np.linalg.inv(cal.camera_from_floor)[:2, 3]
    toward = -cam / np.linalg.norm(cam)
    side = np.array([-toward[1], toward[0]])
    # From just ahead of the camera's feet (below the photo's bottom edge) to 1 m past the board.
    near, far = cam + 0.3 * toward, toward
    truth = np.array([near - 0.6 * side, near + 0.6 * side, far + 0.6 * side, far - 0.6 * side])
    mask = _floor_mask(cal, truth)
    poly = floor_polygon(mask, cal)
    assert "image" in poly.edge_kind and "boundary" in poly.edge_kind
    assert "visible floor only" in poly.caveat
    picture = floor_overlay(np.zeros((*mask.shape, 3), np.uint8), mask, poly, cal)
    assert picture.shape == (mask.shape[0], mask.shape[1] + mask.shape[0], 3)


def test_mask_of_the_wrong_size_is_refused(held_out):
    _, cal = held_out[0]
    with pytest.raises(ValueError, match="does not match"):
        floor_polygon(np.ones((10, 10), bool), cal)


def _split_floor(cal):
    """A floor running out of the photo at the bottom, cut in two by a wall corner 15 cm
    thick that also runs out of it, plus a patch of 'floor' beyond the far wall that
    touches nothing. Returns the mask and the two parts' and the island's masks."""
    cam = np.linalg.inv(cal.camera_from_floor)[:2, 3]
    toward = -cam / np.linalg.norm(cam)
    side = np.array([-toward[1], toward[0]])
    near, far = cam + 0.3 * toward, toward

    def band(s0, s1, a=near, b=far):
        return _floor_mask(cal, np.array([a + s0 * side, a + s1 * side, b + s1 * side, b + s0 * side]))

    left, right = band(-0.6, -0.3), band(-0.15, 0.6)
    island = band(-0.2, 0.2, far + 0.3 * toward, far + 0.6 * toward)
    assert not (island[0].any() or island[-1].any() or island[:, 0].any() or island[:, -1].any())
    return left | right | island, left, right, island


def test_floor_cut_in_two_at_the_photo_edge_is_one_polygon(held_out):
    """Both parts of a floor split by a wall corner at the photo's edge are in the polygon
    (area within 1 % of theirs, where the board's part alone is over 10 % short), joined
    by a corridor that counts as the photo's edge, the polygon simple; the clean-up's rule
    leaves out a patch touching neither the edge nor the floor."""
    _, cal = held_out[0]
    mask, left, right, island = _split_floor(cal)
    both = floor_area_m2(left | right, cal)
    assert floor_area_m2(left, cal) > 0.1 * both
    poly = floor_polygon(left | right, cal)
    assert abs(poly.area_m2 - both) / both < 0.01
    # The parts meet beyond the photo's edge, where the floor goes on.
    assert "image" in poly.edge_kind
    assert self_intersection(poly.polygon_m) is None
    labels, main, parts = floor_parts(mask, cal)
    assert np.all(labels[right] == main) and [np.unique(labels[left])[-1]] == parts


def test_a_part_kept_inside_the_photo_is_in_the_polygon(held_out):
    """A part of the mask cut off inside the photo (floor behind a carton the user clicked,
    or painted in a mask) is kept by the clean-up only when clicked, and then counts in
    the polygon: bridged on by a narrow corridor labelled a boundary (it crosses the thing
    between), the polygon still simple, the area within 1 % of the three parts'."""
    from augment.floor.segment import _clean

    _, cal = held_out[0]
    mask, left, right, island = _split_floor(cal)
    kept = _clean(mask, cal, 1.0, np.where(mask, 0.9, 0.05), clicked=island)
    assert kept[island].mean() > 0.95
    all_three = floor_area_m2(mask, cal)
    assert floor_area_m2(island, cal) > 0.05 * all_three
    poly = floor_polygon(kept, cal)
    assert abs(poly.area_m2 - all_three) / all_three < 0.01
    assert poly.edge_kind.count("boundary") > floor_polygon(left | right, cal).edge_kind.count("boundary")
    assert self_intersection(poly.polygon_m) is None


def test_floors_in_many_parts_give_simple_polygons_of_their_area(held_out):
    """Thirty floors made of a patch round the board and two to six other patches
    scattered around it, seen through a real calibration (most come out in several
    parts, some reaching the photo's edge, some not): every polygon is simple, the floor
    mesh triangulated from it covers exactly its area, and the area is the mask's
    within 6 % (the median within 0.2 %). Traced with the parts as one outline joined by
    pixel seams, 2 of these 30 polygons crossed themselves, one mesh 43 % over, and the
    median was 0.3 %."""
    from augment.render.gltf import _floor_mesh

    _, cal = held_out[0]
    errors, several = [], 0
    for seed in range(30):
        rng = np.random.default_rng(seed)
        mask = _floor_mask(cal, np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
                           * rng.uniform(0.4, 1.2, 2) + rng.uniform(-0.2, 0.2, 2))
        for _ in range(rng.integers(2, 7)):
            half = rng.uniform(0.15, 1.25, 2)
            a = rng.uniform(0, np.pi)
            turn = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
            corners = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]) * half
            mask |= _floor_mask(cal, corners @ turn.T + rng.uniform(-4, 4, 2))
        several += len(floor_parts(mask, cal, reach_edge=False)[2]) > 0
        poly = floor_polygon(mask, cal)
        assert self_intersection(poly.polygon_m) is None, seed
        assert abs(_floor_mesh(poly.polygon_m).area - poly.area_m2) < 1e-9 * poly.area_m2, seed
        errors.append(poly.area_m2 / floor_area_m2(mask, cal) - 1)
    assert several >= 15
    assert np.max(np.abs(errors)) < 0.06 and np.median(np.abs(errors)) < 0.002


def test_a_floor_with_narrow_necks_gives_simple_polygons(held_out):
    """Two hundred floors of two or three blobs joined by strips 2-4 px wide below the
    horizon: every polygon is simple and its mesh covers exactly its area, or, where the
    floor is only a strip that straightens to a line, it is refused. Three things made
    such polygons cross themselves: the refitted corners on the two sides of a neck
    passing each other, a corner dropped as a notch, and Douglas-Peucker's own chords
    across a long strip (seeds 83 and 178 here, after the first was mended)."""
    from augment.render.gltf import _floor_mesh

    _, cal = held_out[0]
    cols, rows = cal.size_px
    below = segment.below_horizon((rows, cols), cal.horizon, 1.0)
    refused = 0
    for seed in range(200):
        rng = np.random.default_rng(seed)
        drawn = np.zeros((rows, cols), np.uint8)
        centers = []
        for _ in range(rng.integers(2, 4)):
            center = rng.uniform([0, 0.45 * rows], [cols, rows])
            radius = rng.uniform(30, 140)
            angle = np.sort(rng.uniform(0, 2 * np.pi, rng.integers(3, 7)))
            blob = center + radius * np.column_stack([np.cos(angle), 0.6 * np.sin(angle)])
            cv2.fillPoly(drawn, [blob.astype(np.int32)], 1)
            centers.append(center)
        for a, b in zip(centers, centers[1:]):
            cv2.line(drawn, tuple(a.astype(int).tolist()), tuple(b.astype(int).tolist()), 1,
                     int(rng.integers(2, 5)))
        try:
            poly = floor_polygon((drawn > 0) & below, cal)
        except ValueError as error:
            assert "too thin" in str(error)
            refused += 1
            continue
        assert len(poly.polygon_m) >= 3 and self_intersection(poly.polygon_m) is None, seed
        assert abs(_floor_mesh(poly.polygon_m).area - poly.area_m2) < 1e-9 * poly.area_m2, seed
    assert refused < 10


def test_a_corridor_joins_two_polygons_into_one_simple_polygon():
    """Two unit squares 1 m apart: the corridor (``FLOOR.polygon.bridge_m`` wide,
    centered on the line between the nearest corners) adds its own area and two
    half-width triangles where it leaves the corners, 2 + 0.001 + 2 * 0.00025 m^2 by
    hand; the squares' edge kinds are kept and the corridor's two sides are boundaries.
    A part that overlaps the polygon cannot be joined without crossing."""
    assert FLOOR.polygon.bridge_m == 0.001
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    kinds = ["boundary", "image", "far", "boundary"]
    poly, out_kinds = _bridge(square, kinds, square + [2.0, 0.0], ["far"] * 4)
    assert self_intersection(poly) is None
    assert abs(abs(polygon_area(poly)) - 2.0015) < 1e-12 and polygon_area(poly) > 0
    assert len(out_kinds) == len(poly) == 10
    assert out_kinds.count("boundary") == 4 and out_kinds.count("far") == 5 and out_kinds.count("image") == 1
    assert _bridge(square, kinds, square + [0.5, 0.5], ["far"] * 4) is None


def test_a_small_far_part_clicked_as_floor_is_in_the_polygon(held_out):
    """A far patch of floor behind a carton covers too few pixels to count in the
    polygon on its own (under ``FLOOR.segment.min_part_share`` of the main region's), but
    the user who clicks it sees it green in the overlay: with the click's pixel given, it
    counts, the area within 1 % of both parts'; a click on the main region changes
    nothing."""
    _, cal = held_out[0]
    cam = np.linalg.inv(cal.camera_from_floor)[:2, 3]
    toward = -cam / np.linalg.norm(cam)
    side = np.array([-toward[1], toward[0]])
    near, far = cam + 0.3 * toward, toward

    def patch(s0, s1, a, b):
        return _floor_mask(cal, np.array([a + s0 * side, a + s1 * side, b + s1 * side, b + s0 * side]))

    main = patch(-1.0, 1.0, near, far)
    island = patch(-0.25, 0.25, far + 5.0 * toward, far + 5.6 * toward)
    assert 0 < island.sum() < FLOOR.segment.min_part_share * main.sum()
    mask = main | island
    both = floor_area_m2(mask, cal)
    alone = floor_polygon(mask, cal).area_m2
    assert alone < 0.9 * both
    ys, xs = np.nonzero(island)
    click = [[xs.mean(), ys.mean()]]
    assert abs(floor_polygon(mask, cal, np.array(click)).area_m2 - both) < 0.01 * both
    ys, xs = np.nonzero(main)
    assert floor_polygon(mask, cal, np.array([[xs.mean(), ys.mean()]])).area_m2 == alone


def test_a_part_the_model_calls_no_floor_is_left_out(held_out):
    """A part cut off at the photo's edge stays only where the model calls it floor on
    average; GrabCut's colour alone does not keep it."""
    _, cal = held_out[0]
    mask, left, right, _ = _split_floor(cal)
    p = np.where(mask, 0.9, 0.05)
    assert len(floor_parts(mask, cal, p)[2]) == 1
    p[left] = 0.3
    assert floor_parts(mask, cal, p)[2] == []
    # A part too small to hold anything is a leak more often than floor.
    speck = np.zeros_like(mask)
    speck[-3:, :3] = True
    assert floor_parts(right | speck, cal)[2] == []


def test_thin_spurs_far_from_the_models_floor_are_dropped():
    """The clean-up drops lines GrabCut took in far from the model's floor (a shadow's
    edge up a wall), and keeps what GrabCut rightly adds past the model: a sliver near its
    floor's edge (behind a carton at a far wall), a region (shade), and any line the user
    clicked as floor."""
    from augment.floor.segment import _clean

    reach_px, width_px = FLOOR.segment.spur_reach_px, FLOOR.segment.spur_width_px

    floor = np.zeros((480, 640), bool)
    floor[300:] = True
    p = np.where(floor, 0.95, 0.02)
    thin = width_px - 2
    spur = np.zeros_like(floor)
    spur[300 - 3 * reach_px:300, 100:100 + thin] = True  # up the wall ...
    spur[300 - 3 * reach_px:300 - 3 * reach_px + thin, 100:300] = True  # ... and along it
    sliver = np.zeros_like(floor)
    top = 300 - reach_px // 2
    sliver[top:top + thin, 400:500] = True
    sliver[top:300, 400:400 + thin] = True
    region = np.zeros_like(floor)
    region[300 - 3 * reach_px:300, 540:600] = True
    mask = floor | spur | sliver | region
    kept = _clean(mask, None, 1.0, p)
    # (A region's sharp corners far out lose a pixel each.)
    assert kept[floor].all() and kept[sliver].all() and kept[region].mean() > 0.999
    far = spur.copy()
    far[300 - reach_px:] = False
    assert not kept[far].any()
    # A line the user clicked as floor is floor.
    assert _clean(mask, None, 1.0, p, clicked=spur)[spur].all()


def test_a_windows_shadow_on_a_wall_is_not_floor(model):
    """Render 15 of seed 930: a window's shadow falls on a cream wall in lines of the
    tiled floor's colour, one reaching down to the floor. GrabCut took the lines in with
    the floor, a spur up the wall and along it that put the polygon 19 % over the true
    floor's; now the polygon is within 5 % of the one outlined from the true mask. (Checked
    before the skirting step, which the spur rule does not touch: the floor-line gap model
    adds 364 px along a wall here, 294 of them not floor, +4.54 -> +5.01 %.)"""
    with Renderer() as renderer:
        sample = render_sample([930, 15], renderer)
    w, h = sample.truth["size_px"]
    cal = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(sample.truth["K"][0][0], (w, h)))
    seg = segment_floor(sample.image, model, cal, skirting=False)
    truth_m2 = floor_polygon(sample.floor_mask, cal).area_m2
    assert abs(floor_polygon(seg.mask, cal).area_m2 / truth_m2 - 1) < 0.05
    assert iou(seg.mask, sample.floor_mask) > 0.98


def test_grabcut_alone_keeps_only_the_boards_region(held_out):
    """The clean-up keeps a part cut off at the photo's edge only on the model's word:
    with GrabCut alone (no probabilities) the board's region is the floor."""
    from augment.floor.segment import _clean

    _, cal = held_out[0]
    mask, left, right, island = _split_floor(cal)
    alone = _clean(mask, cal, 1.0)
    assert alone[right].mean() > 0.99 and not alone[left].any() and not alone[island].any()
    with_model = _clean(mask, cal, 1.0, np.where(mask, 0.9, 0.05))
    assert with_model[left].mean() > 0.95 and not with_model[island].any()


def test_disputed_floor_is_the_area_the_model_and_the_mask_disagree_on(held_out):
    """The mask holds a 1 m square of floor beyond the board's center; the model (at the
    working size) calls a 0.4 x 0.35 m patch of it not floor: 0.14 m² disputed, 14 %."""
    _, cal = held_out[0]
    cam = np.linalg.inv(cal.camera_from_floor)[:2, 3]
    toward = -cam / np.linalg.norm(cam)
    side = np.array([-toward[1], toward[0]])

    def square(x0, x1, y0, y1):
        return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]) @ np.array([side, toward])

    floor = square(-0.5, 0.5, 0.0, 1.0)
    mask = _floor_mask(cal, floor)
    assert not (mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any())
    cols, rows = cal.size_px

    def model_says(floor_mask):  # at GrabCut's working size, as segment_floor has it
        long_px = FLOOR.segment.grabcut_long_px
        size = (long_px, round(rows * long_px / cols))
        return cv2.resize(floor_mask.astype(np.float32), size, interpolation=cv2.INTER_AREA)

    patch = _floor_mask(cal, square(0.0, 0.4, 0.4, 0.75))
    region, disputed_m2, share = disputed_floor(mask, model_says(mask & ~patch), cal)
    assert abs(disputed_m2 - 0.14) < 0.005, disputed_m2
    assert abs(share - 0.14) < 0.005, share
    assert iou(region, model_says(patch) > 0.5) > 0.95
    # Where they agree nothing is disputed.
    assert disputed_floor(mask, model_says(mask), cal)[1] < 0.001
    # The floor overlay hatches the disputed patch, and nothing else.
    hatched = np.all(floor_overlay(np.zeros((rows, cols, 3), np.uint8), mask, disputed=region)
                     == DRAW.floor.disputed_color, axis=2)
    assert 0.25 < hatched.sum() / patch.sum() < 0.45 and not (hatched & ~cv2.dilate(patch.astype(np.uint8),
                                                                                     np.ones((5, 5)))).any()


def test_an_uncertain_floor_is_said(held_out, model, monkeypatch):
    sample, cal = held_out[0]
    seg = segment_floor(sample.image, model, cal)
    region, m2, share = disputed_floor(seg.mask, seg.probability, cal)
    assert np.array_equal(seg.disputed, region) and (seg.disputed_m2, seg.disputed_share) == (m2, share)
    for threshold, said in ((share * 0.9, True), (share * 1.1, False)):
        monkeypatch.setattr(FLOOR.segment, "disputed_share_warn", threshold)
        again = segment_floor(sample.image, model, cal)
        assert again.uncertain == said and (again.doubted is not None) == said
        assert any("floor found is uncertain" in w and f"{m2:.1f} m² ({100 * share:.0f} % of the floor found"
                   in w for w in again.warnings) == said
        assert (again.doubt_px is not None) == said and (again.doubt_json() is not None) == said
    # The warning names a pixel in the largest patch in doubt and what the mask says
    # there; the overlay rings it.
    monkeypatch.setattr(FLOOR.segment, "disputed_share_warn", share * 0.9)
    doubted = segment_floor(sample.image, model, cal)
    warning = next(w for w in doubted.warnings if "uncertain" in w)
    x, y = map(int, re.search(r"around (\d+),(\d+)", warning).groups())
    assert doubted.doubt_px == (x, y)
    r, c = region.shape
    assert region[int(y * r / seg.mask.shape[0]), int(x * c / seg.mask.shape[1])]
    now = bool(seg.mask[y, x])
    assert f"now {'floor' if now else 'not floor'}" in warning and doubted.doubt_json() == {
        "x_px": x, "y_px": y, "floor": now}
    plain = floor_overlay(sample.image, doubted.mask, disputed=doubted.doubted)
    ringed = floor_overlay(sample.image, doubted.mask, disputed=doubted.doubted, doubt_px=doubted.doubt_px)
    changed = np.argwhere(np.any(plain != ringed, axis=2))
    radius = np.hypot(*(changed - [y, x]).T)
    # A ring around the pixel (12 thicknesses across, 2-3 px thick here), with the pixel
    # itself left to see.
    thick = max(2, round(max(seg.mask.shape) / 500))
    assert abs(np.median(radius) - 12 * thick) < 1.5 * thick and radius.min() > 9 * thick, radius
    assert np.array_equal(plain[y, x], ringed[y, x])
    assert segment_floor(sample.image, model, None).disputed_m2 is None  # no calibration, no m²
    # Patches in doubt larger than the floor found (a model calling floor where the mask has
    # none) are said as a multiple, not as "250 % of it".
    monkeypatch.setattr(segment, "disputed_floor", lambda *args, **kwargs: (region, 2.5 * m2 / share, 2.5))
    assert "(2.5 times the floor found," in segment_floor(sample.image, model, cal).warnings[-1]


class _Blind:
    """The shipped model made wrong on purpose in one patch of the photo: it says
    ``p`` there (0: sure not floor; 1: sure floor)."""

    def __init__(self, model, patch, p):
        self.model, self.patch, self.p, self.spec = model, patch, p, model.spec

    def floor_probability(self, image, size_px=None):
        prob = self.model.floor_probability(image, size_px)
        patch = cv2.resize(self.patch.astype(np.float32), prob.shape[::-1], interpolation=cv2.INTER_AREA) > 0.5
        return np.where(patch, np.float32(self.p), prob)


def _centroid(region):
    y, x = np.nonzero(region)
    return float(x.mean()), float(y.mean())


def test_a_floor_click_brings_back_floor_the_model_missed(held_out, model):
    """The model calls a 0.8 x 0.8 m square of floor beyond the board sure "not floor";
    GrabCut cannot bring back what it is told is sure. One click in the square does."""
    sample, cal = held_out[0]
    truth = sample.floor_mask
    cam = np.linalg.inv(cal.camera_from_floor)[:2, 3]
    toward = -cam / np.linalg.norm(cam)
    side = np.array([-toward[1], toward[0]])
    square = np.array([[-0.4, 0.4], [0.4, 0.4], [0.4, 1.2], [-0.4, 1.2]]) @ np.array([side, toward])
    patch = _floor_mask(cal, square) & truth
    assert patch.sum() > 2000
    blind = _Blind(model, patch, 0.0)
    before = segment_floor(sample.image, blind, cal)
    assert (patch & ~before.mask).sum() / patch.sum() > 0.5
    x, y = _centroid(patch)
    after = segment_floor(sample.image, blind, cal, clicks=[(x, y, 1)])
    assert (patch & ~after.mask).sum() / patch.sum() < 0.05
    # Nothing else was taken for floor with it.
    unblind = segment_floor(sample.image, model, cal).mask
    assert (after.mask & ~truth).sum() <= (unblind & ~truth).sum() + 0.005 * truth.sum()
    assert after.clicks.tolist() == [[x, y, 1.0]]
    assert after.clicks_json() == [{"x_px": x, "y_px": y, "floor": True}]
    # Within the click's reach the user settled it: no longer in dispute with the model.
    r, c = after.disputed.shape
    scale = c / truth.shape[1]
    yy, xx = np.mgrid[:r, :c]
    reach = (xx - x * scale) ** 2 + (yy - y * scale) ** 2 < (0.95 * FLOOR.segment.click_reach * c) ** 2
    assert before.disputed[reach].sum() > 100 and after.disputed[reach].sum() == 0


def test_a_clicks_region_reaches_half_a_meter_over_the_floor(held_out):
    """On a photo of one flat grey (no edges, so only the reach bounds the region), a
    floor click's region is every pixel that sees the floor within click_region_reach_m
    of the clicked one and lies within click_region_max_reach of the long side: far away
    a wide, flat ellipse, running along a far wall rather than up it as a disc of
    click_region_reach of the long side would; near, the disc of the larger share."""
    settings = FLOOR.segment
    long_px = settings.grabcut_long_px
    sample, cal = held_out[0]
    rows, cols = sample.floor_mask.shape
    scale = long_px / cols
    small = np.full((round(rows * scale), long_px, 3), 128, np.uint8)
    working = cal.scaled(scale)
    cam = np.linalg.inv(cal.camera_from_floor)[:2, 3]
    old_disc_px = 2 * round(settings.click_region_reach * long_px) + 1
    max_px = settings.click_region_max_reach * long_px
    for distance_m in (2.0, 6.0):
        x, y = cal.pixels_from_floor((cam - distance_m * cam / np.linalg.norm(cam))[None])[0]
        floor, other, _ = segment._click_regions(small, scale, cal, np.array([[x, y, 1.0, x, y]]))
        assert not other.any()
        ys, xs = np.nonzero(floor)
        col, row = round(x * scale), round(y * scale)
        at = working.floor_from_pixels(np.array([[col + 0.5, row + 0.5]]))[0]
        reach_m = np.linalg.norm(working.floor_from_pixels(np.column_stack([xs + 0.5, ys + 0.5])) - at, axis=1)
        reach_px = np.hypot(xs - col, ys - row)
        assert reach_m.max() < settings.click_region_reach_m and reach_px.max() <= max_px + 0.5
        width, height = np.ptp(xs) + 1, np.ptp(ys) + 1
        assert width > old_disc_px and height < width, (distance_m, width, height)
        if distance_m == 2.0:  # near: the disc binds, and is filled
            assert reach_px.max() > max_px - 1.5 and floor.sum() > 0.9 * np.pi * max_px ** 2
        else:  # far: the half meter binds, most of all upward
            assert reach_m.max() > 0.45 and height < old_disc_px, (reach_m.max(), height)


def test_a_not_floor_click_takes_away_what_was_taken_for_floor(held_out, model, monkeypatch):
    """The model calls a patch of wall at the foot of the far wall sure floor; one click
    on it takes it away again, and the floor around it stays. (Rising past the wall's foot
    between two stretches of its board, the patch is cut along the foot anyway, as a thing
    against the wall: that cut is off here, for what the click does alone.)"""
    monkeypatch.setattr(FLOOR.wall_foot, "rise_m", 10.0)
    sample, cal = held_out[0]
    truth = sample.floor_mask
    rows, cols = truth.shape
    col = cols // 2
    top = int(np.argmax(truth[:, col]))  # the floor's far edge in the middle column
    radius = rows // 12
    y, x = np.mgrid[:rows, :cols]
    patch = ((x - col) ** 2 + (y - (top - radius // 2)) ** 2 < radius ** 2) & ~truth
    blind = _Blind(model, patch, 1.0)
    before = segment_floor(sample.image, blind, cal)
    assert (patch & before.mask).sum() / patch.sum() > 0.5
    click = (float(col), float(top - radius // 2), 0)
    after = segment_floor(sample.image, blind, cal, clicks=[click])
    assert (patch & after.mask).sum() / patch.sum() < 0.05
    unblind = segment_floor(sample.image, model, cal).mask
    assert (truth & ~after.mask).sum() <= (truth & ~unblind).sum() + 0.005 * truth.sum()


def test_a_patch_of_wall_called_floor_at_the_walls_foot_is_cut_along_the_foot(held_out, model):
    """The same patch of wall the model calls sure floor, without a click: the mask rises
    past the wall's foot, which the board either side shows, and comes back down to it;
    it is cut along the foot, and the floor below stays."""
    sample, cal = held_out[0]
    truth = sample.floor_mask
    rows, cols = truth.shape
    col = cols // 2
    top = int(np.argmax(truth[:, col]))
    radius = rows // 12
    y, x = np.mgrid[:rows, :cols]
    patch = ((x - col) ** 2 + (y - (top - radius // 2)) ** 2 < radius ** 2) & ~truth
    mask = segment_floor(sample.image, _Blind(model, patch, 1.0), cal).mask
    assert (patch & mask).sum() < 0.05 * patch.sum()
    unblind = segment_floor(sample.image, model, cal).mask
    assert (truth & ~mask).sum() <= (truth & ~unblind).sum() + 0.005 * truth.sum()


def test_clicks_apply_in_order_and_contradictions_are_refused(held_out, model):
    sample, cal = held_out[0]
    rows, cols = sample.floor_mask.shape
    center = cal.pixels_from_floor(np.zeros((1, 2)))[0]
    floor_pixel = tuple(np.argwhere(sample.floor_mask & ~_floor_mask(cal, Board().outline_m()[:, :2] * 1.5))[0][::-1])
    x, y = float(floor_pixel[0]), float(floor_pixel[1])
    # The same floor said to be floor, then not: the later click wins.
    seg = segment_floor(sample.image, model, cal, clicks=[(x, y, 1), (x, y, 0)])
    assert not seg.mask[int(y), int(x)]
    seg = segment_floor(sample.image, model, cal, clicks=[(x, y, 0), (x, y, 1)])
    assert seg.mask[int(y), int(x)]
    with pytest.raises(SegmentationError, match=rf"floor at {cols + 5}.*outside the photo \({cols} x {rows} px\)"):
        segment_floor(sample.image, model, cal, clicks=[(cols + 5, 10, 1)])
    above = np.argwhere(~below_horizon((rows, cols), cal.horizon))
    assert len(above)
    ay, ax = above[0]
    with pytest.raises(SegmentationError, match="above the horizon"):
        segment_floor(sample.image, model, cal, clicks=[(ax, ay, 1)])
    with pytest.raises(SegmentationError, match="on the board"):
        segment_floor(sample.image, model, cal, clicks=[(*center, 0)])
    with pytest.raises(SegmentationError, match="rows of x, y"):
        segment_floor(sample.image, model, cal, clicks=[(1, 2)])


def test_a_click_outranks_the_skirting_trim(held_out, model, monkeypatch):
    """Where the trim cuts floor it took for a board, a floor click there gives it back."""
    sample, cal = held_out[0]
    truth = sample.floor_mask
    board = _floor_mask(cal, Board().outline_m()[:, :2] * 2.0)
    y, x = np.argwhere(truth & ~board)[len(np.argwhere(truth & ~board)) // 3]
    cut = np.zeros_like(truth)
    cut[max(0, y - 20):y + 20, max(0, x - 20):x + 20] = True

    def over_cut(image, mask, calibration, board_at=None, extend=False):  # a trim gone too deep, around (x, y)
        return mask & ~cut, 0.2, None

    monkeypatch.setattr(segment, "trim_skirting", over_cut)
    assert not segment_floor(sample.image, model, cal).mask[y, x]
    seg = segment_floor(sample.image, model, cal, clicks=[(float(x), float(y), 1)])
    assert seg.mask[y, x] and seg.mask[cut & truth].mean() > 0.5


def test_not_floor_clicks_are_handed_to_the_skirting_trim(held_out, model, monkeypatch):
    """The trim hears where the user said "not floor" (a click on a board it left makes
    that wall's strip a board), and not the floor clicks."""
    sample, cal = held_out[0]
    heard = []

    def trim(image, mask, calibration, board_at=None, extend=False):
        heard.append(np.asarray(board_at, float))
        return mask.copy(), None, None

    monkeypatch.setattr(segment, "trim_skirting", trim)
    rows, cols = sample.floor_mask.shape
    floor_y, floor_x = np.argwhere(sample.floor_mask)[len(np.argwhere(sample.floor_mask)) // 2]
    segment_floor(sample.image, model, cal, clicks=[(float(floor_x), float(floor_y), 1), (5.0, rows - 6.0, 0)])
    assert len(heard) == 1 and heard[0].shape == (1, 3) and tuple(heard[0][0, :2]) == (5.0, rows - 6.0)


def test_a_not_floor_click_on_a_board_marks_no_colour_region(held_out, model, monkeypatch):
    """A "not floor" click the trim takes for a board click (on the strip at a wall's
    foot) goes to the trim only: its colour region, which on a board of the floor's colour
    runs into the floor below, is not carved. Other clicks keep their regions."""
    sample, cal = held_out[0]
    rows, cols = sample.floor_mask.shape
    board, carton, floor = (10.0, 20.0, 0), (30.0, 40.0, 0), (float(cols // 2), float(rows - 5), 1)
    monkeypatch.setattr(segment, "board_clicks", lambda image, mask, calibration, points: np.array(
        [tuple(p) == board[:2] for p in np.asarray(points)]))
    given = []
    regions = segment._click_regions

    def recorded(small, scale, calibration, clicks):
        given.append(np.asarray(clicks, float))
        return regions(small, scale, calibration, clicks)

    monkeypatch.setattr(segment, "_click_regions", recorded)
    heard = []

    def trim(image, mask, calibration, board_at=None, extend=False):
        heard.append(np.asarray(board_at, float))
        return mask.copy(), None, None

    monkeypatch.setattr(segment, "trim_skirting", trim)
    segment_floor(sample.image, model, cal, clicks=[board, carton, floor])
    # the first pass (floor clicks only, to find the walls' strips), then the segmentation
    assert [g[:, :2].tolist() for g in given] == [[list(floor[:2])], [list(carton[:2]), list(floor[:2])]]
    assert heard[0][:, :2].tolist() == [list(board[:2]), list(carton[:2])]
    given.clear()
    segment_floor(sample.image, model, cal, clicks=[floor], skirting=False)
    assert len(given) == 1  # no first pass without a "not floor" click


def test_the_first_pass_shares_the_model_and_is_the_floor_when_every_not_floor_click_is_a_board(
        held_out, model, monkeypatch):
    """With "not floor" clicks the floor is found twice (without them, to tell board clicks,
    then with the clicks that mark regions), but the model runs once; and when every "not
    floor" click is on a board the two passes have the same clicks, so GrabCut runs once."""
    sample, cal = held_out[0]
    rows, cols = sample.floor_mask.shape
    board, carton, floor = (10.0, 20.0, 0), (30.0, 40.0, 0), (float(cols // 2), float(rows - 5), 1)
    monkeypatch.setattr(segment, "board_clicks", lambda image, mask, calibration, points: np.array(
        [tuple(p) == board[:2] for p in np.asarray(points)]))
    calls = {"model": 0, "grabcut": 0}

    def counted(name, function):
        def call(*args, **kwargs):
            calls[name] += 1
            return function(*args, **kwargs)
        return call

    monkeypatch.setattr(model, "floor_probability", counted("model", model.floor_probability))
    monkeypatch.setattr(segment, "_grabcut", counted("grabcut", segment._grabcut))
    for clicks, grabcuts in (([board, floor], 1), ([board, carton, floor], 2), ([floor], 1)):
        calls.update(model=0, grabcut=0)
        segment_floor(sample.image, model, cal, clicks=clicks)
        assert calls == {"model": 1, "grabcut": grabcuts}, clicks


def test_a_board_click_settles_the_band_the_trim_cut_above_it():
    """Two bands the trim cut, along two walls; a board click on the strip of the first
    (a few rows below its cut, in its column) settles that band alone, so the model, which
    calls the board floor, does not put it back in dispute."""
    cut = np.zeros((100, 200), bool)
    cut[20:26, 10:90] = True
    cut[30:35, 110:190] = True
    settled = segment._cut_clicked(cut, np.array([[50.0, 28.0, 0.0]]))
    np.testing.assert_array_equal(settled, cut & (np.arange(200) < 100)[None])
    assert not segment._cut_clicked(cut, np.array([[100.0, 50.0, 0.0]])).any()  # between the bands
    # In a photo that shows the room turned, the column runs up the room's way, as the
    # trim cut: the same band, turned.
    for k in (1, 2, 3):
        click = np.column_stack([turn_points([[50.0, 28.0]], k, (200, 100)), [0.0]])
        up = Upright((-k) % 4, (200, 100) if k % 2 == 0 else (100, 200), None)
        np.testing.assert_array_equal(up.back(segment._cut_clicked(up.image(np.rot90(cut, k)), up.points(click))),
                                      np.rot90(settled, k))


def test_a_photo_of_the_room_turned_finds_the_same_floor(held_out, model):
    """A photo whose orientation was lost (or taken with the phone held sideways) shows
    the room turned. The model learned rooms upright, and the skirting trim reads columns
    up from the floor: both now see the room turned upright (``upright_turns``), and the
    mask, turned back, is the upright photo's. Before, the model saw the room on its side
    and the floor found was another."""
    for sample, cal in held_out[:3]:
        upright = segment_floor(sample.image, model, cal).mask
        for k in (1, 2, 3):
            seg = segment_floor(np.ascontiguousarray(np.rot90(sample.image, k)), model, cal.turned(k))
            # (GrabCut's colour clusters start from the pixels in another order.)
            assert iou(np.rot90(seg.mask, -k), upright) > 0.95, k
            assert iou(np.rot90(seg.mask, -k), sample.floor_mask) > 0.95, k


def test_the_middle_of_a_patch_by_hand():
    """A 9 x 9 square's middle is its center pixel, the one pixel 5 px from its edge; cut
    off at the photo's top-left corner it is still the center (the photo's edge counts as
    the patch's); with a long thin arm attached, the middle stays in the square."""
    image = np.zeros((20, 40), bool)
    image[6:15, 10:19] = True
    assert segment.patch_middle(image) == (14, 10)
    corner = np.zeros((20, 40), bool)
    corner[:9, :9] = True
    assert segment.patch_middle(corner) == (4, 4)
    image[10:12, 19:40] = True
    assert segment.patch_middle(image) == (14, 10)


def _working_floor(held_out):
    """The first held-out render's true floor at GrabCut's working size (400 px wide):
    its calibration, the scale, the mask and the rows that hold floor."""
    sample, cal = held_out[0]
    rows, cols = sample.floor_mask.shape
    scale = 400 / cols
    small = cv2.resize(sample.floor_mask.astype(np.uint8), (400, round(rows * scale)),
                       interpolation=cv2.INTER_NEAREST) > 0
    return cal, scale, small, np.flatnonzero(small.any(axis=1))


def test_floor_the_model_calls_floor_and_grabcut_dropped_whole_is_given_back(held_out):
    """A second floor material past a threshold fits GrabCut's colour model badly and is
    dropped whole, though the model calls it floor: a far band of the true floor, taken
    out of the mask, comes back; a band one pixel thick along the edge (GrabCut's own
    correction of the model's soft edge), a patch not touching the floor, anything above
    the horizon and a region clicked as not floor stay out."""
    from augment.floor.segment import _restore_dropped

    cal, scale, small, floor_rows = _working_floor(held_out)
    band = np.zeros_like(small)
    band[floor_rows[0]:floor_rows[0] + (floor_rows[-1] - floor_rows[0]) // 3] = True
    band &= small
    p = np.where(small, 0.8, 0.02).astype(np.float32)
    nothing = np.zeros_like(small)
    back = _restore_dropped(small & ~band, p, cal, scale, nothing)
    assert back[band].mean() > 0.99 and not back[~small].any()
    # The user's "not floor" outranks the model.
    assert not _restore_dropped(small & ~band, p, cal, scale, band)[band].any()
    # GrabCut's thin edge corrections stand.
    eroded = cv2.erode(small.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    assert np.array_equal(_restore_dropped(eroded, p, cal, scale, nothing), eroded)
    # A patch the model calls floor, apart from the floor kept, stays out.
    kept = small.copy()
    kept[:floor_rows[0] + 2 * (floor_rows[-1] - floor_rows[0]) // 3] = False
    assert not _restore_dropped(kept, np.where(band | kept, 0.8, 0.02), cal, scale, nothing)[band].any()
    # Above the horizon nothing is floor, whatever the model says.
    sky = ~below_horizon(small.shape, cal.scaled(scale).horizon, 0.0)
    assert not _restore_dropped(small & ~band, np.where(sky | small, 0.8, 0.02), cal, scale, nothing)[sky].any()


def test_a_dropped_floor_is_judged_by_its_whole_area_not_its_core(held_out, monkeypatch):
    """The size rule weighs the dropped region, not the core left after peeling its
    edge: a far strip of tiles lost a third of its area to that peel (render 981/20 of
    the threshold stress set: 0.28 of 0.37 m², under the 0.3 m² rule). With the
    rule set between the band's core and its whole area, the band comes back."""
    from augment.floor.segment import _restore_dropped

    cal, scale, small, floor_rows = _working_floor(held_out)
    band = np.zeros_like(small)
    band[floor_rows[0]:floor_rows[0] + 12] = True
    band &= small
    edge = FLOOR.segment.restore_edge_px
    core = cv2.erode(band.astype(np.uint8), cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * edge + 1,) * 2)) > 0
    small_cal = cal.scaled(scale)
    whole_m2, core_m2 = floor_area_m2(band, small_cal), floor_area_m2(core, small_cal)
    assert core_m2 < 0.8 * whole_m2
    p = np.where(small, 0.8, 0.02).astype(np.float32)
    nothing = np.zeros_like(small)
    monkeypatch.setattr(FLOOR.segment, "restore_min_m2", (whole_m2 + core_m2) / 2)
    assert _restore_dropped(small & ~band, p, cal, scale, nothing)[band].mean() > 0.99
    monkeypatch.setattr(FLOOR.segment, "restore_min_m2", 1.05 * whole_m2)
    assert not _restore_dropped(small & ~band, p, cal, scale, nothing)[band].any()


def test_a_far_strip_with_the_floor_right_below_comes_back_however_few_its_pixels(held_out, monkeypatch):
    """GrabCut cuts a few pixels off the floor's far edge (a second material along the far
    wall: render 991/27 of a threshold set, 1.5 m² in three strips of 126-286 working
    pixels, under the 0.5 % pixel rule's 474): such a strip, whose lower edge goes on into
    the floor kept, comes back below the pixel rule, and so does one past a gap that spans
    half of ``restore_gap_m`` on the floor (a threshold bar); a patch of as many pixels
    above a gap that spans twice that (a carton's top above its face) does not."""
    from augment.floor.segment import _restore_dropped

    cal, scale, small, floor_rows = _working_floor(held_out)
    top = floor_rows[0]
    band = np.zeros_like(small)
    band[top:top + 10] = True
    band &= small
    p = np.where(small, 0.8, 0.02).astype(np.float32)
    nothing = np.zeros_like(small)
    monkeypatch.setattr(FLOOR.segment, "restore_min_m2", 0.0)
    # The pixel rule alone would keep them all out.
    monkeypatch.setattr(FLOOR.segment, "min_part_share", 2.0 * band.sum() / small.sum())
    assert _restore_dropped(small & ~band, p, cal, scale, nothing)[band].mean() > 0.99
    # A patch 10 rows tall, 30 rows below the far edge, with the floor kept beside it and
    # a gap below it that spans ``span_m`` of floor, then the floor kept again.
    cols = np.flatnonzero(small[top + 80])
    x0 = cols[len(cols) // 3]
    small_cal = cal.scaled(scale)

    def floor_gap_rows(span_m):
        y0 = top + 39
        for rows in range(1, 60):
            a, b = small_cal.floor_from_pixels(np.array([[x0 + 12.0, y0], [x0 + 12.0, y0 + rows + 1]]))
            if np.hypot(*(b - a)) >= span_m:
                return rows
        raise AssertionError("no such gap")

    gap = FLOOR.segment.restore_gap_m
    for span_m, comes_back in ((2.0 * gap, False), (0.5 * gap, True)):
        patch = np.zeros_like(small)
        patch[top + 30:top + 40, x0:x0 + 25] = True
        face = np.zeros_like(small)
        face[top + 40:top + 40 + floor_gap_rows(span_m), x0:x0 + 25] = True
        assert small[patch | face].all()
        back = _restore_dropped(small & ~patch & ~face, np.where(face, 0.02, p).astype(np.float32), cal, scale,
                                nothing)
        if comes_back:
            assert back[patch].mean() > 0.95  # its corners: the peeled core grows back round
        else:
            assert not back[patch].any()


def test_regions_grabcut_added_where_the_model_sees_no_floor_are_taken_back():
    """GrabCut takes in a carton's face of the floor's colour whole, where the model gives
    a few percent: such a region goes. GrabCut's thin corrections of the model's soft edge
    stand, and so do regions the model only doubts (floor in shade) and the floor the user
    clicked."""
    from augment.floor.segment import _vetoed

    def _veto_added(mask, p, clicked):
        return mask & ~_vetoed(mask, p, clicked)

    floor = np.zeros((120, 160), bool)
    floor[60:] = True
    p = np.where(floor, 0.95, 0.01).astype(np.float32)
    face = np.zeros_like(floor)
    face[30:60, 100:140] = True                      # a carton's face on the floor's far edge
    edge = np.zeros_like(floor)
    edge[58:60, :90] = True                          # two rows along the model's edge
    mask = floor | face | edge
    nothing = np.zeros_like(floor)
    kept = _veto_added(mask, p, nothing)
    assert kept[face].mean() < 0.01                  # (the peel rounds the region's corners)
    assert kept[floor].all() and kept[edge].all()
    doubted = np.where(face, np.float32(0.2), p)     # the model doubts: floor in shade
    assert np.array_equal(_veto_added(mask, doubted, nothing), mask)
    # Per pixel: the part of a region the model doubts stays, the part it is sure of goes.
    half = np.where(face & (np.arange(160) < 120), np.float32(0.2), p)
    kept = _veto_added(mask, half, nothing)
    assert kept[30:60, 100:120].all() and kept[30:60, 120:140].mean() < 0.01
    assert np.array_equal(_veto_added(mask, p, face), mask)


def _found_on_render(seed, model, **options):
    """A render of the synthetic photographer (``options`` for :func:`render_sample`),
    calibrated with its true focal length, segmented with ``model``: the floor polygon's
    area error against the polygon of the true mask, and the mask's IoU with the truth."""
    with Renderer() as renderer:
        sample = render_sample(seed, renderer, **options)
    w, h = sample.truth["size_px"]
    cal = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(sample.truth["K"][0][0], (w, h)))
    seg = segment_floor(sample.image, model, cal)
    truth_m2 = floor_polygon(sample.floor_mask, cal).area_m2
    return floor_polygon(seg.mask, cal).area_m2 / truth_m2 - 1, iou(seg.mask, sample.floor_mask)


def test_a_carton_of_the_floors_colour_is_not_floor(model):
    """Render 28 of the clean tuning set 992: two faces of a grey carton by the photo's
    edge fit GrabCut's colour model of a grey concrete floor, and were taken in whole
    (+8 % of the area, IoU 0.944) though the model gave them 0.03. Now the polygon is
    within 2 % of the one from the true mask, and only the carton's rim is left in."""
    area_error, overlap = _found_on_render([992, 28], model)
    assert abs(area_error) < 0.02 and overlap > 0.97


def test_two_floors_apart_by_a_thin_line_are_one_floor(held_out):
    """A threshold bar GrabCut leaves out parts the floor in two: the far floor, which the
    model is unsure of and which reaches no photo edge, was dropped with the line (render
    981/38: -17 % of the area). Now both floors and the line between are kept; a sliver
    beyond the far floor (a line along a skirting board's top) still goes, and a part
    farther off than the line's width stays apart."""
    from augment.floor.segment import _clean

    sample, cal = held_out[0]
    floor = sample.floor_mask.copy()
    rows = np.flatnonzero(floor.any(axis=1))
    top, bottom = rows[0], rows[-1]
    cut = top + (bottom - top) // 3
    far = floor.copy()
    far[cut:] = False
    far[:, :40] = far[:, -40:] = False               # the far floor reaches no photo edge
    line = floor.copy()
    line[:cut] = False
    line[cut + 3:] = False
    near = floor & ~far & ~line
    near[:cut + 3] = False
    line[:, :40] = line[:, -40:] = False             # the line between the two floors
    assert far.sum() > 2000 and line.any() and not (far & near).any()
    sliver = np.zeros_like(floor)
    sliver[top - 4, 100:300] = True                  # 3 px above the far floor's top row
    mask = far | near | sliver
    p = np.where(near, 0.9, 0.3).astype(np.float32)  # the model doubts the far floor
    kept = _clean(mask, cal, 1.0, p)
    # (The clean-up's opening takes a pixel off a region's sharp corners.)
    assert kept[far].mean() > 0.99 and kept[near].mean() > 0.99 and kept[line].mean() > 0.95
    assert not kept[sliver].any()
    # A gap wider than the bridge parts them as before.
    wide = far.copy()
    wide[cut - 8:cut] = False
    assert not _clean(wide | near, cal, 1.0, np.where(near, 0.9, 0.3).astype(np.float32))[wide].any()


@pytest.mark.parametrize("index", [pytest.param(20, marks=pytest.mark.xfail(strict=True, reason=(
    "the model fine-tuned for 448-576 px drops a strip of pale tiles along the right wall and takes a "
    "sliver of that wall: the area is within 1 %, the overlap 0.936"))), 38])
def test_a_second_floor_past_a_threshold_is_in_the_polygon(model, index):
    """Renders of the threshold stress set (seed 981) where the second floor was left out:
    on 20 GrabCut dropped a far strip of pale tiles and the size rule judged only its core
    (-13 % of the area); on 38 a threshold bar cut the far tiles off (-17 %). Both
    polygons were brought within 5 % of the one from the true mask."""
    area_error, overlap = _found_on_render([981, index], model, two_floors=1.0)
    assert abs(area_error) < 0.05 and overlap > 0.98


@pytest.mark.parametrize("index", [2, 6])
def test_a_second_floor_past_a_threshold_is_floor(model, index):
    """Tiles past carpet, planks past vinyl: the second material is floor, not dropped
    because it looks unlike the floor around the board (the model of commit ed2f93e gave
    0.963 and 0.789 on these two renders)."""
    with Renderer() as renderer:
        sample = render_sample([7200, index], renderer, size_px=(640, 480), two_floors=1.0)
    assert sample.truth["render"]["second_floor"]["area_m2"] > 10
    cal = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(sample.truth["K"][0][0], (640, 480)))
    assert iou(segment_floor(sample.image, model, cal).mask, sample.floor_mask) > 0.98


def test_shrinking_by_whole_blocks_first_keeps_the_area_average():
    """Large photos are shrunk by a whole factor first (OpenCV's fast path): exactly by
    two for the model's working copy, and within a few levels of a one-step area filter
    on the way to a much smaller size."""
    blocks = np.array([[10, 20, 30], [40, 50, 60]], np.uint8)
    image = np.kron(blocks, np.ones((3, 3), np.uint8)).repeat(2, axis=0).repeat(2, axis=1)  # (12, 18)
    image[0, 0], image[1, 1] = 8, 12  # the first 6 x 6 block still averages 10
    np.testing.assert_array_equal(shrink_area(image, (3, 2)), blocks)
    photo = np.zeros((3024, 4032, 3), np.uint8)
    photo[1::2, 1::2] = 200  # a pattern only a whole 2 x 2 average turns into one flat grey
    assert np.all(shrink_to(photo, 2048) == 50) and shrink_to(photo, 2048).shape == (1512, 2016, 3)
    assert shrink_to(photo[:960, :1280], 2048).shape == (960, 1280, 3)
    # A photo's detail at a few output pixels: piecewise linear over 32 px.
    rng = np.random.default_rng(0)
    photo = cv2.resize(rng.integers(0, 256, (94, 126, 3), dtype=np.uint8), (4032, 3024), interpolation=cv2.INTER_LINEAR)
    for size in ((400, 300), (448, 320), (1280, 960)):
        ours = shrink_area(photo, size).astype(int)
        theirs = cv2.resize(photo, size, interpolation=cv2.INTER_AREA).astype(int)
        assert ours.shape == theirs.shape and np.abs(ours - theirs).max() <= 2
        assert np.abs(ours - theirs).mean() < 0.3
