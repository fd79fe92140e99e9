"""One photo furnished from its files' bytes: the work of a batch or web worker, on any machine.

A :class:`Worker` holds what is slow to make, the floor model's session (one thread)
and a GL context, and reuses both photo after photo. It takes the bytes of the photo
and of the files its options name, and gives back the bytes of the files ``stage
furnish`` writes: so it can run on another machine than the one that has the files (a
Ray node), and the caller alone writes the output folder, all or none
(:func:`augment.pipeline.write_files`). Messages and reports name each input as the
caller named it, never the worker's own copy.
"""
from __future__ import annotations

import ctypes
import gc
import os
import resource
import shutil
import tempfile
import time
from pathlib import Path

from layout.errors import StagerError

# The input files a task may carry, as ``pipeline.furnish`` names them, and how a
# message names one that the caller gave no name for.
INPUT_ROLES = {"photo": "the photo", "camera": "the camera profile", "spec": "the spec file",
               "layout": "the layout file", "floor_mask": "the floor mask"}
# Options passed through to ``pipeline.furnish`` as they are.
OPTIONS = ("room", "suggestions", "seed", "style", "clicks", "doors", "auto_doors", "keep_board", "height_m")


def rss_mb() -> float:
    """This process's resident memory now, MB (Linux's /proc; the peak elsewhere)."""
    try:
        with open("/proc/self/statm") as statm:
            return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _libc():
    try:
        return ctypes.CDLL("libc.so.6")
    except OSError:  # not glibc: nothing to trim
        return None


_LIBC = _libc()


def give_back_memory() -> None:
    """Return the memory a photo freed to the system. glibc keeps freed heap pages, and a
    worker's resident memory crept up by about 1 MB a photo (:mod:`benchmarks.batch`)."""
    gc.collect()
    if _LIBC is not None:
        _LIBC.malloc_trim(0)


def scrub(value, names: dict):
    """``value`` (JSON-like) with each path of ``names`` (path -> shown name) replaced by
    its shown name."""
    if isinstance(value, dict):
        return {k: scrub(v, names) for k, v in value.items()}
    if isinstance(value, list):
        return [scrub(v, names) for v in value]
    if isinstance(value, str):
        for path, shown in names.items():
            value = value.replace(path, shown)
        return value
    return value


class Worker:
    """Furnishes photo after photo with one floor model session and one GL context.

    Parameters
    ----------
    threads : int or None
        Threads for onnxruntime, OpenCV and numba: one per worker when there is a worker
        per core; None leaves each library its own choice.
    """

    def __init__(self, threads: int | None = 1):
        import cv2
        import numba

        from ..floor.model import DEFAULT_MODEL, FloorModel

        if threads is not None:
            cv2.setNumThreads(int(threads))
            numba.set_num_threads(min(int(threads), numba.config.NUMBA_NUM_THREADS))
        self.model = FloorModel(DEFAULT_MODEL, threads=threads)
        self._renderer = None

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def furnish(self, inputs: dict, options: dict, reporter=None) -> dict:
        """Furnish one photo.

        Parameters
        ----------
        inputs : dict
            Role (:data:`INPUT_ROLES`; ``"photo"`` required) -> ``(name, data)`` or
            ``(name, data, file name)``: the file's name as the caller shows it, its
            bytes, and the name of the worker's copy (default the name's last part, so
            that the photo's stem titles the plans).
        options : dict
            ``board``: ``(cols, rows, square_mm, kind)``; optional :data:`OPTIONS`.
        reporter : callable, optional
            ``pipeline.furnish``'s progress reporter.

        Returns
        -------
        dict
            ``status`` ``"done"`` with ``files`` (name -> bytes), ``warnings``,
            ``styles``, ``doubt``, ``timings_s``; or ``"refused"`` with ``error`` (the
            :class:`~layout.errors.StagerError`'s message) and ``kind``. Both with
            ``seconds`` and ``rss_mb``. A bug raises.
        """
        try:
            answer = self._furnish(inputs, options, reporter)
        finally:
            give_back_memory()
        answer["rss_mb"] = rss_mb()
        return answer

    def _furnish(self, inputs: dict, options: dict, reporter) -> dict:
        from .. import pipeline
        from ..camera.board import Board
        from ..render.gl import Renderer

        start = time.perf_counter()
        if self._renderer is None:
            self._renderer = Renderer()
        folder = Path(tempfile.mkdtemp(prefix="stager-task-"))
        try:
            paths, names = {}, {}
            for role, (name, data, *stored) in inputs.items():
                if role not in INPUT_ROLES:
                    raise ValueError(f"input {role!r}: expected one of {', '.join(INPUT_ROLES)}")
                (folder / role).mkdir()
                path = paths[role] = folder / role / (stored[0] if stored else Path(name).name or role)
                path.write_bytes(data)
                shown = name or INPUT_ROLES[role]
                # "floor mask PATH: ..." reads "the floor mask NAME: ...".
                names[f"{INPUT_ROLES[role][4:]} {path}"] = f"{INPUT_ROLES[role]} {name}" if name else INPUT_ROLES[role]
                names[str(path)] = shown
            names[f"{folder}/"] = ""
            names[str(folder)] = "the worker's folder"
            cols, rows, square_mm, kind = options["board"]
            try:
                result = pipeline.furnish(paths["photo"], Board(cols, rows, square_mm, kind=kind),
                                          spec=paths.get("spec"), layout=paths.get("layout"),
                                          camera=paths.get("camera"), floor_mask=paths.get("floor_mask"),
                                          model=None if "floor_mask" in paths else self.model,
                                          reporter=reporter, renderer=self._renderer,
                                          **{k: options[k] for k in OPTIONS if options.get(k) is not None})
            except StagerError as error:
                return {"status": "refused", "kind": error.kind, "error": scrub(str(error), names),
                        "seconds": time.perf_counter() - start}
            result.report = scrub(result.report, names)
            files = pipeline.output_files(result)
            return {"status": "done", "files": files, "warnings": scrub(list(result.warnings), names),
                    "styles": list(result.styles), "doubt": result.segmentation.doubt_json(),
                    "timings_s": {k: round(v, 3) for k, v in result.timings_s.items()},
                    "seconds": time.perf_counter() - start}
        finally:
            shutil.rmtree(folder, ignore_errors=True)
