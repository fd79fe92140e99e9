"""The GL renderer: what it returns does not depend on the framebuffers it reuses.

A module of its own: closing a context ends the EGL display for every other context of
the process, so no renderer may live beside the ones made here."""
from __future__ import annotations

import numpy as np

from augment.render.gl import Renderer

from tests.augment.test_render import _render_box, _truth_calibration


def test_a_render_into_a_larger_framebuffer_is_the_render_of_a_fresh_context():
    """The renderer draws into the corner of a framebuffer made for a somewhat larger view
    (it reuses them); what it returns is pixel for pixel what a fresh context draws."""
    image, _, calibration = _truth_calibration("room_1", 0.5)
    with Renderer() as fresh:
        alone = _render_box(fresh, image, calibration, (0.5, 1.0), (0.3, 0.3, 0.45), supersample=1.0)
    with Renderer() as used:
        larger = _render_box(used, image, calibration, (0.5, 1.0), (0.35, 0.35, 0.6), supersample=1.0)
        again = _render_box(used, image, calibration, (0.5, 1.0), (0.3, 0.3, 0.45), supersample=1.0)
    (x0, y0, x1, y1), (a0, b0, a1, b1) = alone.roi_px, larger.roi_px
    assert a1 - a0 > x1 - x0 and b1 - b0 > y1 - y0, "the first view must be the larger one"
    assert again.roi_px == alone.roi_px
    assert np.array_equal(again.image, alone.image)


def test_the_read_back_is_pyrenders_own_read_of_the_viewport():
    """The renderer reads back the viewport alone, and no depth when told: the colour and
    depth are, to the bit, pyrender's own read of the (larger, reused) framebuffer's corner."""
    import pyrender
    import trimesh
    from pyrender.renderer import Renderer as PyrenderRenderer

    scene = pyrender.Scene(bg_color=[0.0, 0.0, 0.0, 0.0], ambient_light=[0.3, 0.3, 0.3])
    scene.add(pyrender.Mesh.from_trimesh(trimesh.creation.box((1.0, 0.8, 0.6))), pose=np.eye(4))
    pose = np.eye(4)
    pose[:3, 3] = (0.3, 0.2, 3.0)
    scene.add(pyrender.IntrinsicsCamera(300.0, 300.0, 160.0, 120.0, znear=0.1, zfar=20.0), pose=pose)
    flags = pyrender.RenderFlags.RGBA | pyrender.RenderFlags.FLAT
    with Renderer() as gl:
        gl.render(scene, 400, 300, flags=flags)  # a larger framebuffer, reused below
        color, depth = gl.render(scene, 320, 240, flags=flags)
        only_color, no_depth = gl.render(scene, 320, 240, flags=flags, depth=False)
        assert gl._offscreen._renderer._main_fb_dims == (400, 300)
        offscreen = gl._offscreen
        offscreen._platform.make_current()
        try:
            whole_color, whole_depth = PyrenderRenderer._read_main_framebuffer(
                offscreen._renderer, scene, flags | pyrender.RenderFlags.OFFSCREEN)
        finally:
            offscreen._platform.make_uncurrent()
    assert color.shape == (240, 320, 4) and depth.shape == (240, 320) and no_depth is None
    corner = np.s_[300 - 240:, :320]
    np.testing.assert_array_equal(color, whole_color[corner])
    np.testing.assert_array_equal(only_color, color)
    np.testing.assert_array_equal(depth, whole_depth[corner])
    assert (depth == 0).any() and (depth > 2.0).any()  # background and the box both in view


def test_a_closed_renderer_leaves_nothing_for_the_garbage_collector():
    """Closing frees pyrender's renderer at once: were it left to the collector, its
    ``__del__`` would free framebuffers of whatever context is current then by this
    one's ids (a later render then fails with GL_INVALID_OPERATION)."""
    import gc
    import weakref

    gl = Renderer()
    gl.render(_small_scene(), 64, 48)
    inner = weakref.ref(gl._offscreen._renderer)
    gc.disable()
    try:
        gl.close()
        assert inner() is None
    finally:
        gc.enable()


def _small_scene():
    import pyrender
    import trimesh

    scene = pyrender.Scene()
    scene.add(pyrender.Mesh.from_trimesh(trimesh.creation.box((1.0, 1.0, 1.0))))
    pose = np.eye(4)
    pose[2, 3] = 3.0
    scene.add(pyrender.IntrinsicsCamera(60.0, 60.0, 32.0, 24.0), pose=pose)
    scene.add(pyrender.DirectionalLight(intensity=2.0), pose=pose)
    return scene
