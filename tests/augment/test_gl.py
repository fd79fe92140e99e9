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
        alone = _render_box(fresh, image, calibration, (0.5, 1.0), (0.45, 0.45, 0.7), supersample=1.0)
    with Renderer() as used:
        larger = _render_box(used, image, calibration, (0.5, 1.0), (0.5, 0.5, 0.9), supersample=1.0)
        again = _render_box(used, image, calibration, (0.5, 1.0), (0.45, 0.45, 0.7), supersample=1.0)
    (x0, y0, x1, y1), (a0, b0, a1, b1) = alone.roi_px, larger.roi_px
    assert a1 - a0 > x1 - x0 and b1 - b0 > y1 - y0, "the first view must be the larger one"
    assert again.roi_px == alone.roi_px
    assert np.array_equal(again.image, alone.image)
