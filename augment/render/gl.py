"""The one place that loads pyrender (the maintained fork ``pyrender2``): headless GL backend,
camera conventions.

Backend selection. ``PYOPENGL_PLATFORM`` is respected when set. Otherwise EGL is used when
its libraries are installed (Mesa's llvmpipe renders on a CPU, and EGL draws about twice
as fast as OSMesa here), then OSMesa. PyOpenGL reads the variable once, on first import,
so it is settled here before anything imports ``pyrender`` or ``OpenGL``.

Camera conventions. Stager's cameras follow OpenCV: x right, y down, z forward, pixel
centers at integer coordinates. OpenGL cameras look down -z with y up and put pixel
centers at half-integers; :func:`pyrender_camera` and :func:`gl_from_cv_pose` convert,
so a point projected with ``K`` lands exactly where the renderer draws it.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import os
from pathlib import Path

import numpy as np

from .settings import RENDER

# Debian packages behind each backend, for the error message when none loads.
_EGL_PACKAGES = "libegl1 libegl-mesa0 libgl1-mesa-dri"
_OSMESA_PACKAGES = "libosmesa6"
# libglvnd's EGL finds Mesa through this vendor file (package libegl-mesa0).
_MESA_EGL_VENDOR = Path("/usr/share/glvnd/egl_vendor.d/50_mesa.json")


def _loads(name: str) -> bool:
    try:
        ctypes.CDLL(name)
    except OSError:
        return False
    return True


def select_platform() -> str:
    """Pick and export the headless GL backend (``egl`` or ``osmesa``).

    Returns
    -------
    platform : str
        The value now in ``os.environ["PYOPENGL_PLATFORM"]``.

    Raises
    ------
    ImportError
        When neither backend's libraries are installed; names the Debian packages.
    """
    chosen = os.environ.get("PYOPENGL_PLATFORM")
    if chosen:
        return chosen
    if _loads("libEGL.so.1") and _MESA_EGL_VENDOR.exists():
        chosen = "egl"
    elif _loads("libOSMesa.so.8") or ctypes.util.find_library("OSMesa"):
        chosen = "osmesa"
    else:
        raise ImportError(
            "no headless OpenGL found: install the Debian packages "
            f"`{_EGL_PACKAGES}` (EGL) or `{_OSMESA_PACKAGES}` (OSMesa), "
            "e.g. `sudo apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6`"
        )
    os.environ["PYOPENGL_PLATFORM"] = chosen
    return chosen


def _import_pyrender():
    select_platform()
    import pyrender

    return pyrender


pyrender = _import_pyrender()


def _by_name(node):
    return node.name or ""


class Scene(pyrender.Scene):
    """A pyrender scene that draws its meshes and sums its lights in node-name order.

    pyrender keeps nodes in sets and iterates them in memory-address order, so two renders
    of one scene can differ where surfaces meet (the first drawn wins a tie) and in the
    last bit of summed light. Name every node uniquely and the render is repeatable.
    """

    @property
    def mesh_nodes(self):
        return sorted(self._mesh_nodes, key=_by_name)

    @property
    def light_nodes(self):
        return sorted(self._point_light_nodes | self._spot_light_nodes | self._directional_light_nodes,
                      key=_by_name)


def pyrender_camera(K: np.ndarray) -> "pyrender.IntrinsicsCamera":
    """An OpenGL camera that draws exactly what ``K`` (OpenCV convention) projects.

    Parameters
    ----------
    K : (3, 3) float
        Intrinsics in pixels, pixel centers at integer coordinates.
    """
    K = np.asarray(K, dtype=np.float64)
    # OpenGL's pixel (i, j) covers [i, i+1): its center is i + 0.5, OpenCV's is i.
    return pyrender.IntrinsicsCamera(
        fx=K[0, 0], fy=K[1, 1], cx=K[0, 2] + 0.5, cy=K[1, 2] + 0.5,
        znear=RENDER.gl.znear_m, zfar=RENDER.gl.zfar_m,
    )


# Flips y and z: OpenCV camera axes (x right, y down, z forward) to OpenGL's (y up, -z forward).
_CV_TO_GL = np.diag([1.0, -1.0, -1.0, 1.0])


def gl_from_cv_pose(world_from_camera: np.ndarray) -> np.ndarray:
    """The pyrender camera pose for an OpenCV-convention ``world_from_camera`` (4, 4)."""
    return np.asarray(world_from_camera, dtype=np.float64) @ _CV_TO_GL


def far_camera(center_m, radius_m: float, forward, size_px: int, distance_m: float):
    """A camera ``distance_m`` away looking along ``forward`` (3,) at a sphere (``center_m``
    (3,), ``radius_m``) that fills its ``size_px`` square image: nearly parallel rays, yet
    pyrender's depth stays exact. The image's x axis is horizontal where it can be.

    Returns
    -------
    camera_from_world : (4, 4) float64, OpenCV axes
    K : (3, 3) float64, pixels
    camera : pyrender.IntrinsicsCamera, near and far planes around the sphere
    """
    d = np.asarray(forward, dtype=np.float64)
    d = d / np.linalg.norm(d)
    x = np.cross(d, [0.0, 0.0, 1.0]) if abs(d[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(d, x), d])
    eye = np.asarray(center_m, dtype=np.float64) - d * distance_m
    camera_from_world = np.eye(4)
    camera_from_world[:3, :3], camera_from_world[:3, 3] = R, -R @ eye
    f = 0.5 * size_px * distance_m / radius_m
    c = 0.5 * size_px - 0.5
    K = np.array([[f, 0.0, c], [0.0, f, c], [0.0, 0.0, 1.0]])
    camera = pyrender.IntrinsicsCamera(fx=f, fy=f, cx=c + 0.5, cy=c + 0.5, znear=distance_m - 2.0 * radius_m,
                                       zfar=distance_m + 2.0 * radius_m)
    return camera_from_world, K, camera


def _with_shadow_offset(shadow_pass):
    """Wrap one renderer's shadow pass so it writes depths pushed back by
    ``RENDER.gl.shadow_offset`` (slope-scaled, so grazing surfaces get more): pyrender's own
    bias is too small for walls lit at a grazing angle and leaves stripes of "shadow acne"."""
    from OpenGL import GL

    def offset_pass(*args, **kwargs):
        GL.glEnable(GL.GL_POLYGON_OFFSET_FILL)
        GL.glPolygonOffset(*RENDER.gl.shadow_offset)
        try:
            return shadow_pass(*args, **kwargs)
        finally:
            GL.glDisable(GL.GL_POLYGON_OFFSET_FILL)

    return offset_pass


# What pyrender's renderer holds of its offscreen framebuffer, the size last.
_FRAMEBUFFER_FIELDS = ("_main_fb", "_main_cb", "_main_db", "_main_fb_ms", "_main_cb_ms", "_main_db_ms",
                       "_main_fb_dims")
_NO_FRAMEBUFFER = (None,) * 6 + ((None, None),)


def _reuse_framebuffers(renderer, spares: int = 2, slack: float = 1.6) -> None:
    """Make one pyrender renderer draw into a framebuffer it has whenever one is large enough.

    pyrender makes a new framebuffer (4x multisampled) whenever the viewport's size
    changes, and each staged photo has sizes of its own: the region its furniture
    covers, then the light's and the lamps' square depth views. On llvmpipe a new one
    costs 30-100 ms at a few megapixels. A framebuffer of at most ``slack`` times the
    viewport's area is drawn into from its corner instead (:meth:`Renderer.render` crops
    the read); the last ``spares`` others are kept for later, and go with the context."""
    configure, delete = renderer._configure_main_framebuffer, renderer._delete_main_framebuffer
    kept: dict = {}  # size -> the fields' values, oldest first

    def fits(size, want):
        return (size[0] >= want[0] and size[1] >= want[1]
                and size[0] * size[1] <= slack * want[0] * want[1])

    def fields():
        return tuple(getattr(renderer, name) for name in _FRAMEBUFFER_FIELDS)

    def put(values):
        for name, value in zip(_FRAMEBUFFER_FIELDS, values):
            setattr(renderer, name, value)

    def configure_reusing():
        want = (renderer.viewport_width, renderer.viewport_height)
        if renderer._main_fb is not None and fits(renderer._main_fb_dims, want):
            return
        if renderer._main_fb is not None:
            kept[renderer._main_fb_dims] = fields()
        put(_NO_FRAMEBUFFER)
        usable = [size for size in kept if fits(size, want)]
        if usable:
            put(kept.pop(min(usable, key=lambda size: size[0] * size[1])))
        else:
            configure()
        while len(kept) > spares:
            current = fields()
            put(kept.pop(next(iter(kept))))
            delete()
            put(current)

    renderer._configure_main_framebuffer = configure_reusing


def _read_viewport(renderer, depth_wanted) -> None:
    """Make one pyrender renderer read back the viewport alone, and its depth only when
    ``depth_wanted()``. pyrender resolves and reads its whole framebuffer, which
    :func:`_reuse_framebuffers` may have made larger, and linearizes the depth with
    boolean indexing: a third of a staged photo's GL time on llvmpipe. The values are
    pyrender's, to the bit."""
    from OpenGL import GL

    def read(scene, flags):
        w, h = int(renderer.viewport_width), int(renderer.viewport_height)
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, renderer._main_fb_ms)
        GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, renderer._main_fb)
        GL.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL.GL_COLOR_BUFFER_BIT, GL.GL_LINEAR)
        GL.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL.GL_DEPTH_BUFFER_BIT, GL.GL_NEAREST)
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, renderer._main_fb)
        depth = None
        if flags & pyrender.RenderFlags.DEPTH_ONLY or depth_wanted():
            raw = np.frombuffer(GL.glReadPixels(0, 0, w, h, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT),
                                np.float32).reshape(h, w)[::-1]
            ndc = 2.0 * raw - 1.0
            camera = scene.main_camera_node.camera
            near, far = camera.znear, camera.zfar
            with np.errstate(divide="ignore"):
                if far is None:
                    linear = 2 * near / (1.0 - ndc)
                else:
                    linear = (2.0 * near * far) / (far + near - ndc * (far - near))
            depth = np.where(raw == 1.0, np.float32(0.0), linear).astype(np.float32, copy=False)
            if flags & pyrender.RenderFlags.DEPTH_ONLY:
                return depth
        rgba = bool(flags & pyrender.RenderFlags.RGBA)
        color = np.frombuffer(GL.glReadPixels(0, 0, w, h, GL.GL_RGBA if rgba else GL.GL_RGB, GL.GL_UNSIGNED_BYTE),
                              np.uint8).reshape(h, w, 4 if rgba else 3)[::-1]
        return color, depth

    renderer._read_main_framebuffer = read


# The methods of pyrender's renderer that :meth:`Renderer._prepare` replaces.
_PATCHED = ("_shadow_mapping_pass", "_configure_main_framebuffer", "_read_main_framebuffer")


class Renderer:
    """One offscreen GL context, reused for every image (contexts are costly and some
    drivers fail when they are re-created). Use as a context manager.

    Parameters
    ----------
    width_px, height_px : int
        Initial viewport; :meth:`render` resizes as needed.
    """

    def __init__(self, width_px: int = 640, height_px: int = 480):
        self._depth_wanted = True
        try:
            self._offscreen = pyrender.OffscreenRenderer(width_px, height_px)
        except Exception as error:  # the GL stack raises many types; all mean "no context"
            platform = os.environ.get("PYOPENGL_PLATFORM")
            other = "osmesa" if platform == "egl" else "egl"
            raise ImportError(
                f"could not create an offscreen OpenGL context with PYOPENGL_PLATFORM={platform} "
                f"({type(error).__name__}: {error}). Install `{_EGL_PACKAGES}` and "
                f"`{_OSMESA_PACKAGES}`, or try PYOPENGL_PLATFORM={other}."
            ) from error
        self._prepare()

    def _prepare(self) -> None:
        """Stager's changes to a new context's renderer (pyrender's context is current)."""
        self._offscreen._renderer._shadow_mapping_pass = _with_shadow_offset(
            self._offscreen._renderer._shadow_mapping_pass)
        _reuse_framebuffers(self._offscreen._renderer)
        _read_viewport(self._offscreen._renderer, lambda: self._depth_wanted)
        # pyrender uploads textures as tightly packed rows; GL's default assumes rows padded
        # to 4 bytes, which skews any RGB texture whose width is not a multiple of 4 and
        # reads past the end of its buffer.
        from OpenGL import GL

        GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)

    def render(self, scene, width_px: int, height_px: int, flags=None, seg_node_map=None,
               shadow_map_px: int = 2048, depth: bool = True):
        """Render ``scene`` from its main camera.

        ``shadow_map_px`` (a power of two) sizes the shadow maps of lights rendered for
        the first time: pyrender fixes it at 2048, which is most of the cost of a small
        image on a CPU and more detail than a 320 x 240 frame can show.

        Returns
        -------
        color : (height_px, width_px, 3) uint8, or (height_px, width_px, 4) with ``RenderFlags.RGBA``
            (premultiplied over a transparent black background).
        depth_m : (height_px, width_px) float32
            Distance along the optical axis, 0 where nothing was drawn; with
            ``depth=False`` None where skipping it saves the read (framebuffers).
        """
        if flags is None:
            flags = pyrender.RenderFlags.NONE
        # pyrender reads this module constant when it makes a light's shadow texture and
        # when it sets the shadow pass viewport; both happen inside this call.
        pyrender.light.SHADOW_TEX_SZ = pyrender.renderer.SHADOW_TEX_SZ = int(shadow_map_px)
        self._offscreen.viewport_width = int(width_px)
        self._offscreen.viewport_height = int(height_px)
        platform = self._offscreen._platform
        if platform.supports_framebuffers():
            self._depth_wanted = depth
            try:  # the viewport alone is read back (:func:`_read_viewport`)
                out = self._offscreen.render(scene, flags=flags, seg_node_map=seg_node_map)
            finally:
                self._depth_wanted = True
            if isinstance(out, tuple):
                return tuple(None if a is None else np.ascontiguousarray(a) for a in out)
            return np.ascontiguousarray(out)
        # OSMesa draws into a buffer of fixed size, read back as RGB. For another size
        # pyrender makes a new context, which would lose the changes above: made here.
        if (platform.viewport_width, platform.viewport_height) != (int(width_px), int(height_px)):
            self._offscreen.delete()
            self._offscreen._create()
            self._prepare()
        if not flags & pyrender.RenderFlags.RGBA:
            return self._offscreen.render(scene, flags=flags, seg_node_map=seg_node_map)
        # Alpha from two renders, over black and over white: a pixel shows the background
        # as much as it is transparent.
        flags &= ~pyrender.RenderFlags.RGBA
        background = scene.bg_color.copy()
        try:
            scene.bg_color = [0.0, 0.0, 0.0, 1.0]
            over_black, depth = self._offscreen.render(scene, flags=flags, seg_node_map=seg_node_map)
            scene.bg_color = [1.0, 1.0, 1.0, 1.0]
            over_white, _ = self._offscreen.render(scene, flags=flags, seg_node_map=seg_node_map)
        finally:
            scene.bg_color = background
        seen = (over_white.astype(np.int16) - over_black).max(axis=2)
        alpha = (255 - np.clip(seen, 0, 255)).astype(np.uint8)
        return np.dstack([over_black, alpha]), depth

    def close(self) -> None:
        """Free the context's GL objects and the context. As pyrender's ``delete`` does,
        without its full garbage collection (0.1 s at the end of each staged photo): the
        changes of :meth:`_prepare` close over pyrender's renderer, a cycle that only the
        collector would free, and its ``__del__`` would then free a framebuffer of whatever
        context is current by the id this one had. Dropped here, it goes at once."""
        if self._offscreen is not None:
            offscreen, self._offscreen = self._offscreen, None
            renderer = offscreen._renderer
            offscreen._platform.make_current()
            renderer.delete()
            renderer._shadow_fb = None  # pyrender's delete leaves the id, a second delete frees it again
            offscreen._platform.delete_context()
            for name in _PATCHED:
                renderer.__dict__.pop(name, None)
            offscreen._renderer = offscreen._platform = None

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
