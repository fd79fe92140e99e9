import matplotlib.image
import numpy as np
import pytest
from matplotlib.figure import Figure

from layout import geometry, plot

FLOOR = np.array([[0, 0], [5, 0], [5, 3], [2.5, 3], [2.5, 4.5], [0, 4.5]], dtype=np.float64)
CENTER = np.array([[1.0, 1.0], [3.5, 1.5], [1.2, 3.5], [4.0, 2.6]])
YAW = np.array([np.pi / 2, np.pi, 0.3, -np.pi / 2])
WIDTH = np.array([2.0, 1.8, 0.6, 1.0])
DEPTH = np.array([0.9, 0.6, 0.6, 0.5])
ACCESS = np.array([[0, 0, 0.8, 0], [0, 0, 0.6, 0], [0, 0, 0.5, 0], [0, 0, 0, 0]], float)
LABELS = ["sofa", "bed", "chair", "tv stand"]


def plan_inputs():
    """Every array input of a plan, read-only so that any in-place write raises."""
    arrays = {
        "polygon_m": FLOOR,
        "corners_m": geometry.box_corners(CENTER, YAW, WIDTH, DEPTH),
        "yaw_rad": YAW,
        "door_zones_m": np.array([[[3, 0], [4, 0], [4, 0.9], [3, 0.9]]], float),
        "door_segments_m": np.array([[[3, 0], [4, 0]]], float),
        "window_segments_m": np.array([[[0, 1], [0, 2.5]]], float),
        "lanes_m": np.array([[[3.5, 0.9], [2.0, 2.5]]]),
        "access_corners_m": geometry.access_box_corners(CENTER, YAW, WIDTH, DEPTH, ACCESS),
        "access_depth_m": ACCESS,
    }
    for a in arrays.values():
        a.setflags(write=False)
    return arrays


def read_rgb(path):
    image = matplotlib.image.imread(path)
    assert image.ndim == 3 and image.shape[2] in (3, 4)
    return image[..., :3]


def n_colors(rgb):
    q = (rgb * 255).round().astype(np.int32)
    return len(np.unique((q[..., 0] << 16) | (q[..., 1] << 8) | q[..., 2]))


def red_pixels(rgb):
    return int(np.sum((rgb[..., 0] > 0.75) & (rgb[..., 1] < 0.3) & (rgb[..., 2] < 0.3)))


def test_plot_plan_writes_readable_picture(tmp_path):
    inputs = plan_inputs()
    copies = {k: v.copy() for k, v in inputs.items()}
    path = tmp_path / "plan.png"
    plot.plot_plan(
        path,
        inputs["polygon_m"],
        inputs["corners_m"],
        LABELS,
        inputs["yaw_rad"],
        door_zones_m=inputs["door_zones_m"],
        door_segments_m=inputs["door_segments_m"],
        window_segments_m=inputs["window_segments_m"],
        lanes_m=inputs["lanes_m"],
        overlap_pairs=np.array([[1, 3]]),
        title="living room",
        access_corners_m=inputs["access_corners_m"],
        access_depth_m=inputs["access_depth_m"],
        kinds=["sofa", "bed", "chair", "tv"],
    )
    assert path.stat().st_size > 0
    rgb = read_rgb(path)
    # Sized to the room: about 10 in at 120 dpi, wider than tall like the 5 x 4.5 m floor.
    assert 800 < rgb.shape[1] < 1300 and 700 < rgb.shape[0] < rgb.shape[1]
    assert n_colors(rgb) > 20
    # The overlapping pair is drawn in red.
    assert red_pixels(rgb) > 500
    # Atomic write: nothing but the image is left in the folder.
    assert [p.name for p in tmp_path.iterdir()] == ["plan.png"]
    for key, value in inputs.items():
        np.testing.assert_array_equal(value, copies[key], err_msg=key)


def test_plot_plan_minimal_and_overwrites(tmp_path):
    path = tmp_path / "plan.png"
    path.write_bytes(b"stale")
    corners = geometry.box_corners(CENTER, YAW, WIDTH, DEPTH)
    plot.plot_plan(path, FLOOR, corners, LABELS, YAW)
    rgb = read_rgb(path)
    assert n_colors(rgb) > 10
    assert red_pixels(rgb) < 50


def test_plan_figure_skips_labels_that_do_not_fit():
    corners = geometry.box_corners([[1.0, 1.0], [3.0, 1.0]], [0.0, 0.0], [0.02, 1.0], [0.02, 1.0])
    fig = plot.plan_figure(FLOOR, corners, ["tiny", "table"], [0.0, 0.0])
    assert isinstance(fig, Figure)
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert "table" in texts and "tiny" not in texts and "1 m" in texts


def test_plan_figure_rejects_bad_shapes():
    corners = geometry.box_corners(CENTER, YAW, WIDTH, DEPTH)
    with pytest.raises(ValueError):
        plot.plan_figure(FLOOR, corners, LABELS[:2], YAW)
    with pytest.raises(ValueError):
        plot.plan_figure(FLOOR, corners, LABELS, YAW, overlap_pairs=[[0, 9]])
    with pytest.raises(ValueError):
        plot.plan_figure(FLOOR, corners, LABELS, YAW, access_depth_m=ACCESS)


def test_plot_energy(tmp_path):
    t = np.arange(200, dtype=np.float64)
    traces = {"PBD": 10 * np.exp(-t / 30) + 0.1, "MCMC": 10 * np.exp(-t[:150] / 80) + 0.5}
    for v in traces.values():
        v.setflags(write=False)
    copies = {k: v.copy() for k, v in traces.items()}
    path = tmp_path / "energy.png"
    plot.plot_energy(path, traces, title="energy", log=True)
    rgb = read_rgb(path)
    assert n_colors(rgb) > 10
    # Both curves are drawn in their own color (matplotlib's default blue and orange).
    blue = np.all(np.abs(rgb - [0.12, 0.47, 0.71]) < 0.08, axis=-1).sum()
    orange = np.all(np.abs(rgb - [1.0, 0.5, 0.05]) < 0.08, axis=-1).sum()
    assert blue > 100 and orange > 100
    assert [p.name for p in tmp_path.iterdir()] == ["energy.png"]
    for key, value in traces.items():
        np.testing.assert_array_equal(value, copies[key])


def test_plot_energy_rejects_what_it_cannot_draw(tmp_path):
    with pytest.raises(ValueError):
        plot.plot_energy(tmp_path / "e.png", {})
    with pytest.raises(ValueError):
        plot.plot_energy(tmp_path / "e.png", {"a": [1.0, 0.0]}, log=True)
    assert list(tmp_path.iterdir()) == []
