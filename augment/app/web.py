"""The web app: upload a photo of an empty room in a browser, get staged images.

:func:`create_app` builds a FastAPI app over :func:`augment.pipeline.furnish`;
``stage serve`` runs it with uvicorn (bound to 127.0.0.1 by default). The API, also
described on the app's OpenAPI page (``/docs``):

=================================== ==================================================
``POST /api/jobs``                  multipart: ``photo`` and the options of ``stage
                                    furnish`` (``board``, ``square``, ``room``,
                                    ``suggestions``, ``seed``, an optional ``camera``
                                    profile file, an optional ``spec`` file instead of
                                    the room preset or ``layout`` (a ``layout_K.json``
                                    to render again, e.g. in another ``style``), an
                                    optional ``floor_mask`` file or
                                    ``clicks`` correcting the floor, ``doors`` to keep
                                    clear, ``height`` of the walls where the photo
                                    does not show it) -> 202 ``{"id": ...}``
``GET /api/jobs/{id}``              ``status`` (queued, running, done, failed), per-stage
                                    progress, ``error`` (what went wrong, in words),
                                    ``files``, ``warnings``, ``doubt`` (where an
                                    uncertain floor is most in doubt, or a
                                    skirting board may be left in it)
``GET /api/jobs/{id}/files/{name}`` one output file; only names in the job's ``files``
``GET /api/jobs/{id}/photo``        the photo the job was sent
``GET /api/jobs/{id}/download.zip`` every output file in one zip
``DELETE /api/jobs/{id}``           delete the job and its files now (a running job's as it ends)
``GET /api/board.pdf``              the board to print (``board``, ``square``, ``paper``)
=================================== ==================================================

``GET /jobs/{id}`` is the job's page: the upload page showing that job's stages, then its
results, as after an upload (a job sent through the API can be watched in a browser), with
its options and photo loaded so that it can be corrected and furnished again.

Jobs run in a pool of worker processes (one per core by default), or on the actors of
a Ray cluster (``stage serve --address``, :class:`augment.app.jobs.RayPool`), each with
one GL context reused for all its jobs (:class:`augment.render.gl.Renderer`); at most ``workers +
max_queued`` jobs are waiting or running, beyond that ``POST /api/jobs`` answers 503 with
``Retry-After``. Safety: the upload's size is limited (413); its header is read before it
is decoded, so more than :data:`MAX_PIXELS` pixels (a decompression bomb) is refused
(413); anything Stager cannot decode is refused (415); job ids are random UUIDs; files
are served only by name from the job's own output listing; finished jobs are deleted
after ``keep_minutes``. Nothing the user sends is used as a path: the photo is stored
as ``photo.<type>`` with the type found by decoding it, a spec as ``spec.toml`` once it
has been checked as ``stage furnish --spec`` would check it (422 with the reason
otherwise; it is data, read by :mod:`tomllib`, and names no files), a layout likewise
as ``layout.json``.

The jobs and their worker processes: :mod:`augment.app.jobs`.
"""
from __future__ import annotations

import asyncio
import io
import json
import math
import os
import warnings
import zipfile
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Annotated

from fastapi import FastAPI, File, Form, HTTPException, UploadFile
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, Response

from layout.errors import shorten
from layout.spec import MAX_LAYOUT_BYTES, MAX_SPEC_BYTES

from ..camera.calibrate import MAX_PROFILE_BYTES
from ..errors import UploadError
from ..floor.segment import MAX_CLICKS
from ..render.styles import STYLES
from ..room.doors import MAX_DOORS
from .jobs import STAGES, Job, JobQueue, job_state
from .values import HEIGHT_RANGE_M

MAX_PIXELS = 50_000_000
MAX_SUGGESTIONS = 12
DEFAULT_JOBS_DIR = Path("out") / "jobs"
STATIC_DIR = Path(__file__).with_name("web_static")


# --------------------------------------------------------------------------------------
# Upload checks
# --------------------------------------------------------------------------------------

def check_photo(data: bytes, max_pixels: int = MAX_PIXELS) -> str:
    """Check an uploaded photo; returns the suffix to store it under (``".jpg"``, ...).

    The header's size is read first (PIL, without decoding the pixels), so a small file
    that claims a huge image is refused before it can fill the memory; then it is
    decoded as the pipeline will (:func:`augment.photo.io.decode_image`).

    Raises
    ------
    UploadError
        415 when it is not an image Stager can decode, 413 when it has more than
        ``max_pixels`` pixels, 422 when its size will not do (:func:`augment.photo.io.size_problem`).
    """
    from PIL import Image, UnidentifiedImageError

    from ..photo.io import (
        ACCEPTED_FORMATS,
        PHOTO_FORMATS,
        decode_image,
        decode_problem,
        register_heif,
        size_problem,
    )

    register_heif()

    with warnings.catch_warnings():
        # PIL warns above its own (larger) limit; this check refuses those anyway.
        warnings.simplefilter("ignore", Image.DecompressionBombWarning)
        try:
            with Image.open(io.BytesIO(data)) as image:
                (width, height), kind = image.size, image.format
        except Image.DecompressionBombError:
            raise UploadError(413, f"the photo has too many pixels (at most {max_pixels / 1e6:g} megapixels)") \
                from None
        except (UnidentifiedImageError, OSError, ValueError):
            raise UploadError(415, f"the file {decode_problem(data)}") from None
    if (problem := size_problem(width, height)) is not None:
        raise UploadError(422, f"the photo {problem}")
    if width * height > max_pixels:
        raise UploadError(413, f"the photo is {width} x {height} = {width * height / 1e6:.0f} megapixels; at "
                               f"most {max_pixels / 1e6:g} megapixels are accepted: send a smaller photo")
    if kind not in ACCEPTED_FORMATS:
        raise UploadError(415, f"the photo is a {kind or 'unknown'} file; send a {PHOTO_FORMATS} photo")
    if decode_image(data) is None:
        raise UploadError(415, f"the photo {decode_problem(data)}")
    return ACCEPTED_FORMATS[kind]


def _check_spec(data: bytes) -> None:
    """Refuse (422) a layout spec that ``stage furnish --spec`` would refuse."""
    from layout.errors import LayoutError
    from layout.spec import spec_from_bytes

    try:
        spec_from_bytes(data, "the spec file")
    except LayoutError as error:
        raise UploadError(422, str(error)) from None


def _check_layout(data: bytes) -> None:
    """Refuse (422) a layout that ``stage furnish --layout`` would refuse."""
    from layout.errors import LayoutError
    from layout.spec import spec_of_layout

    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise UploadError(422, "the layout is not JSON; send a layout_K.json that Stager wrote") from None
    try:
        spec_of_layout(doc, "the layout file")
    except LayoutError as error:
        raise UploadError(422, str(error)) from None


def _number_rows(text: str, width: int) -> list[list[float]] | None:
    """``text`` as a JSON list of lists of ``width`` finite numbers each (``[]`` for
    blank text), or None when it is not that."""
    if not text.strip():
        return []
    try:
        rows = json.loads(text)
    except (json.JSONDecodeError, RecursionError):
        return None
    ok = isinstance(rows, list) and all(
        isinstance(r, list) and len(r) == width and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                        and math.isfinite(v) for v in r) for r in rows)
    return [[float(v) for v in r] for r in rows] if ok else None


def _check_clicks(text: str) -> list[list[float]]:
    """The ``clicks`` field: a JSON list of ``[x, y, 1 or 0]`` (photo pixels; 1 floor left
    out, 0 something taken for floor), at most ``MAX_CLICKS``; 422 otherwise."""
    clicks = _number_rows(text, 3)
    if clicks is None or any(c[2] not in (0, 1) for c in clicks):
        raise UploadError(422, f"clicks {text[:80]!r}: give a JSON list of [x, y, 1] for floor left out and "
                               "[x, y, 0] for something taken for floor, x and y in the photo's pixels, "
                               "e.g. [[640, 900, 1]]")
    if len(clicks) > MAX_CLICKS:
        raise UploadError(422, f"clicks: {len(clicks)} given, at most {MAX_CLICKS}; for larger corrections "
                               "upload a floor mask")
    return clicks


def _check_doors(text: str) -> list[list[float]]:
    """The ``doors`` field: a JSON list of ``[x1, y1, x2, y2]`` (photo pixels of the feet
    of a door's two sides), at most ``MAX_DOORS``; 422 otherwise."""
    doors = _number_rows(text, 4)
    if doors is None or len(doors) > MAX_DOORS:
        raise UploadError(422, f"doors {text[:80]!r}: give a JSON list of at most {MAX_DOORS} [x1, y1, x2, y2], "
                               "the photo pixels of the feet of each door's two sides, e.g. [[980, 220, 1190, 280]]")
    return doors


def _check_options(board: str, square: float, room: str, suggestions: int, seed: int = 0) -> tuple:

    from layout.presets import PRESETS

    from ..camera.board import MIN_SQUARE_MM, Board, parse_board

    try:
        spec = parse_board(board)
    except ValueError as error:
        raise UploadError(422, f"board {error}") from None
    if not MIN_SQUARE_MM <= square < 1000:
        raise UploadError(422, f"square {square:g}: the side of one printed square in millimeters, "
                               f"{MIN_SQUARE_MM:g} to 1000, e.g. 45")
    try:
        Board(spec.cols, spec.rows, square, kind=spec.kind)
    except ValueError as error:
        raise UploadError(422, f"board {board}: {error}") from None
    if room not in PRESETS:
        raise UploadError(422, f"room {room!r}: choose one of {', '.join(PRESETS)}")
    if not 1 <= suggestions <= MAX_SUGGESTIONS:
        raise UploadError(422, f"suggestions {suggestions}: choose from 1 to {MAX_SUGGESTIONS}")
    if seed < 0:
        raise UploadError(422, f"seed {seed}: a whole number from 0 (the same seed gives the same layouts)")
    return spec


# --------------------------------------------------------------------------------------
# Jobs
# --------------------------------------------------------------------------------------

def _board_hint(job: Job) -> dict:
    """What to print when the board was not found: the board asked for and its PDF."""
    cols, rows = job.options["board"]
    spec = f"{cols}x{rows}" if job.options["kind"] == "chessboard" else f"{job.options['kind']}:{cols}x{rows}"
    square = job.options["square"]
    return {"board": spec, "square": square,
            "pdf": f"/api/board.pdf?board={spec}&square={square:g}"}


def _page() -> str:
    """The one page, its room and style lists filled as ``stage furnish --room`` and ``--style`` take them."""
    import html

    from layout.presets import DEFAULT_ROOM, PRESETS

    options = "".join(f'<option value="{name}"{" selected" if name == DEFAULT_ROOM else ""}>'
                      f'{html.escape(name.replace("_", " "))}</option>' for name in PRESETS)
    styles = '<option value="" selected>different per suggestion</option>' + "".join(
        f'<option value="{name}">{html.escape(name.replace("_", " "))}</option>' for name in STYLES)
    return (STATIC_DIR / "index.html").read_text(encoding="utf-8").replace("<!-- PRESETS -->", options).replace(
        "<!-- STYLES -->", styles)


def create_app(jobs_dir=DEFAULT_JOBS_DIR, max_upload_mb: float = 25, workers: int | None = None,
               keep_minutes: float = 60, max_queued: int | None = None, address: str | None = None):
    """The web app.

    Parameters
    ----------
    jobs_dir : path-like
        Where jobs keep their files (created).
    max_upload_mb : float
        Largest request accepted, megabytes (413 beyond).
    workers : int, optional
        Worker processes; default one per core (with ``address``: Ray actors, one per
        CPU of the cluster).
    keep_minutes : float
        Finished jobs and their files are deleted this long after they finish.
    max_queued : int, optional
        Jobs that may wait for a free worker (default ``2 * workers``); beyond that,
        ``POST /api/jobs`` answers 503 with ``Retry-After``.
    address : str, optional
        A Ray cluster (:func:`augment.app.cluster.connect`) whose actors run the jobs,
        instead of worker processes of this machine.

    Returns
    -------
    fastapi.FastAPI
    """
    jobs_dir = Path(jobs_dir)
    jobs_dir.mkdir(parents=True, exist_ok=True)
    if workers is not None and int(workers) < 1:
        raise ValueError(f"workers = {workers}: at least 1")
    if address is not None:
        from .cluster import connect

        workers = connect(address, workers)
    workers = (os.cpu_count() or 1) if workers is None else int(workers)
    max_queued = 2 * workers if max_queued is None else int(max_queued)
    max_bytes = int(max_upload_mb * 1e6)
    queue = JobQueue(jobs_dir, workers, keep_minutes, max_queued, ray=address is not None)

    async def sweeper():
        while True:
            await asyncio.sleep(max(1.0, min(60.0, queue.keep_s / 4)))
            queue.sweep()

    @asynccontextmanager
    async def lifespan(app):
        queue.start()
        task = asyncio.create_task(sweeper())
        try:
            yield
        finally:
            task.cancel()
            queue.close()

    app = FastAPI(title="Stager", version=_version(), lifespan=lifespan,
                  description="Furnish a photo of an empty room. Upload a photo with the printed board on its "
                              "floor to POST /api/jobs, poll GET /api/jobs/{id}, then fetch its files.")
    app.state.queue = queue
    app.state.sweep = queue.sweep
    app.state.jobs = queue.jobs

    @app.exception_handler(UploadError)
    async def upload_error(request, error: UploadError):
        return JSONResponse({"detail": str(error)}, status_code=error.status)

    @app.exception_handler(RequestValidationError)
    async def invalid_request(request, error: RequestValidationError):
        # Where and what, never the value sent (it may be a whole photo).
        return JSONResponse({"detail": [{"loc": list(e.get("loc", ())), "msg": shorten(str(e.get("msg", ""))),
                                         "type": e.get("type")} for e in error.errors()]}, status_code=422)

    app.add_middleware(_BodyLimit, max_bytes=max_bytes)

    page = _page()

    @app.get("/", include_in_schema=False)
    async def index():
        return HTMLResponse(page)

    @app.get("/jobs/{job_id}", include_in_schema=False)
    async def job_page(job_id: str):
        # The page finds the job in its address and shows it; for a job that is not
        # there it says so, as the API's 404 does.
        return HTMLResponse(page, status_code=200 if job_id in queue.jobs else 404)

    @app.post("/api/jobs", status_code=202)
    async def submit(photo: Annotated[UploadFile, File(description="photo of the empty room, the board on "
                                                                   "its floor")],
                     board: Annotated[str, Form(description="inner corners, COLSxROWS or charuco:COLSxROWS")]
                     = "7x5",
                     square: Annotated[float, Form(description="side of one printed square, mm")] = 45.0,
                     room: Annotated[str, Form(description="room preset")] = "living_room",
                     suggestions: Annotated[int, Form()] = 4,
                     seed: Annotated[int, Form()] = 0,
                     camera: Annotated[UploadFile | None, File(description="camera profile from "
                                                                           "`stage calibrate`")] = None,
                     spec: Annotated[UploadFile | None, File(description="a layout spec (TOML, see `layout "
                                                                         "solve`) instead of the room preset")]
                     = None,
                     floor_mask: Annotated[UploadFile | None, File(description="your own floor mask (white = "
                                                                               "floor, the photo's shape) instead "
                                                                               "of the floor Stager finds")]
                     = None,
                     clicks: Annotated[str, Form(description="corrections of the floor found: a JSON list of "
                                                             "[x, y, 1] (floor left out) and [x, y, 0] (taken "
                                                             "for floor), photo pixels, in order")] = "",
                     doors: Annotated[str, Form(description="doors to keep clear: a JSON list of [x1, y1, x2, "
                                                            "y2], the photo pixels of the feet of each door's "
                                                            "two sides")] = "",
                     layout: Annotated[UploadFile | None, File(description="a layout_K.json made before for "
                                                                           "this photo, rendered again as it "
                                                                           "stands (one suggestion; room and "
                                                                           "suggestions do not apply)")] = None,
                     style: Annotated[str, Form(description="the furniture's look (" + ", ".join(STYLES) + "); "
                                                            "empty: each suggestion another")] = "",
                     keep_board: Annotated[bool, Form(description="leave the board in the staged photos (by "
                                                                  "default its sheet is filled with the floor "
                                                                  "around it)")] = False,
                     height: Annotated[float | None, Form(description="the wall height in meters, used when the "
                                                                      "photo does not show it")] = None):
        """Start furnishing a photo; answers the job's id."""
        board_spec = _check_options(board, square, room, suggestions, seed)
        if height is not None and not HEIGHT_RANGE_M[0] <= height <= HEIGHT_RANGE_M[1]:
            raise UploadError(422, f"height {height:g}: the wall height in meters, {HEIGHT_RANGE_M[0]:g} to "
                                   f"{HEIGHT_RANGE_M[1]:g}, e.g. 2.6; leave it empty to measure it from the photo")
        if style and style not in STYLES:
            raise UploadError(422, f"style {style[:40]!r}: choose one of {', '.join(STYLES)}")
        corrections = _check_clicks(clicks)
        door_feet = _check_doors(doors)
        data = await photo.read(max_bytes + 1)
        if len(data) > max_bytes:
            raise UploadError(413, _too_large(len(data), max_bytes))
        if not data:
            raise UploadError(422, "no photo: choose a photo of the empty room with the board on its floor")
        suffix = await asyncio.to_thread(check_photo, data)  # decoding takes a while: off the event loop
        profile = None
        if camera is not None and camera.filename:
            profile = await camera.read(MAX_PROFILE_BYTES + 1)
            if len(profile) > MAX_PROFILE_BYTES:
                raise UploadError(413, "the camera profile is larger than 1 MB; it is not a profile from "
                                       "`stage calibrate`")
            try:
                json.loads(profile)
            except (UnicodeDecodeError, json.JSONDecodeError, RecursionError):
                raise UploadError(422, "the camera profile is not JSON; make one with `stage calibrate`") from None
        layout_spec = None
        if spec is not None and spec.filename:
            layout_spec = await spec.read(MAX_SPEC_BYTES + 1)
            if len(layout_spec) > MAX_SPEC_BYTES:
                raise UploadError(413, f"the spec file is larger than {MAX_SPEC_BYTES >> 10} KB; a layout spec "
                                       "is a short TOML text")
            await asyncio.to_thread(_check_spec, layout_spec)
        made = None
        if layout is not None and layout.filename:
            if layout_spec is not None:
                raise UploadError(422, "a layout holds its own furniture: send a layout or a spec, not both")
            made = await layout.read(MAX_LAYOUT_BYTES + 1)
            if len(made) > MAX_LAYOUT_BYTES:
                raise UploadError(413, f"the layout is larger than {MAX_LAYOUT_BYTES >> 20} MB; it is not a "
                                       "layout_K.json that Stager wrote")
            await asyncio.to_thread(_check_layout, made)
        mask, mask_suffix = None, None
        if floor_mask is not None and floor_mask.filename:
            mask = await floor_mask.read(max_bytes + 1)
            if len(mask) > max_bytes:
                raise UploadError(413, f"the floor mask is larger than {max_bytes / 1e6:g} MB; save it as a "
                                       "black-and-white PNG (white = floor)")
            try:
                mask_suffix = await asyncio.to_thread(check_photo, mask)
            except UploadError as error:
                raise UploadError(error.status, f"the floor mask: {error}") from None
            if corrections:
                raise UploadError(422, "clicks correct the floor Stager finds, and a floor mask is used as it "
                                       "is: paint the correction into the mask, or leave the mask out")
        wait = queue.busy_s()
        if wait is not None:
            active = sum(j.result is None for j in queue.jobs.values())
            raise HTTPException(503, f"the server is busy ({active} photos in progress); try again in "
                                     f"{wait} s", headers={"Retry-After": str(wait)})
        job_id, folder = queue.new_folder()
        (folder / "input" / f"photo{suffix}").write_bytes(data)
        if profile is not None:
            (folder / "input" / "camera.json").write_bytes(profile)
        if layout_spec is not None:
            (folder / "input" / "spec.toml").write_bytes(layout_spec)
        if made is not None:
            (folder / "input" / "layout.json").write_bytes(made)
        if mask is not None:
            (folder / "input" / f"floor_mask{mask_suffix}").write_bytes(mask)
        options = {"photo": f"photo{suffix}", "camera": "camera.json" if profile is not None else None,
                   "spec": "spec.toml" if layout_spec is not None else None,
                   "layout": "layout.json" if made is not None else None,
                   "floor_mask": f"floor_mask{mask_suffix}" if mask is not None else None,
                   "clicks": corrections, "doors": door_feet,
                   "board": (board_spec.cols, board_spec.rows), "kind": board_spec.kind, "square": float(square),
                   "room": None if layout_spec is not None or made is not None else room,
                   "suggestions": 1 if made is not None else int(suggestions),
                   "seed": int(seed), "keep_board": bool(keep_board), "style": style or None,
                   "height_m": None if height is None else float(height),
                   "names": {"photo": _sent_name(photo.filename, "photo"),
                             **({"camera": _sent_name(camera.filename, "camera profile")} if profile else {}),
                             **({"spec": _sent_name(spec.filename, "spec file")} if layout_spec else {}),
                             **({"layout": _sent_name(layout.filename, "layout file")} if made else {}),
                             **({"floor_mask": _sent_name(floor_mask.filename, "floor mask")} if mask else {})}}
        loop = asyncio.get_running_loop()

        def done(job: Job) -> None:
            if job.delete_when_done:
                # A pool thread: the jobs dict is the event loop's to change.
                loop.call_soon_threadsafe(queue.forget, job)

        queue.submit(job_id, folder, options, done)
        return {"id": job_id}

    def get_job(job_id: str) -> Job:
        job = queue.jobs.get(job_id)
        if job is None:
            raise HTTPException(404, f"no job {job_id[:60]!r}: it never existed or was deleted (finished jobs are "
                                     f"kept {keep_minutes:g} minutes)")
        return job

    @app.get("/api/jobs/{job_id}")
    async def status(job_id: str):
        """The job's status, per-stage progress, error, files and warnings, and where the
        floor is most in doubt (``doubt``: x_px, y_px and whether it is now floor) when it
        is uncertain, or where a skirting board may be left in it."""
        job = get_job(job_id)
        state = job_state(job)
        if state["error"] is not None and state["error"]["kind"] == "calibration" \
                and state["error"]["message"].startswith("no "):
            state["error"]["board"] = _board_hint(job)
        return state

    @app.delete("/api/jobs/{job_id}")
    async def delete(job_id: str):
        """Delete the job and every file of it (the photo too) now, rather than
        ``keep_minutes`` after it finishes; a running job's are deleted as it finishes."""
        job = get_job(job_id)
        if not queue.cancel(job):
            return JSONResponse({"id": job_id, "deleted": False,
                                 "detail": "the photo is being furnished; it and its files are deleted as soon "
                                           "as that is done"}, status_code=202)
        queue.forget(job)
        return {"id": job_id, "deleted": True}

    @app.get("/api/jobs/{job_id}/files/{name}")
    async def file(job_id: str, name: str):
        """One output file, by its name in the job's ``files``."""
        job = get_job(job_id)
        names = job.result.get("files", []) if job.result is not None else []
        if name not in names:
            raise HTTPException(404, f"job {job_id} has no file {name!r}; its files are listed by "
                                     f"GET /api/jobs/{job_id}")
        return FileResponse(job.folder / "out" / name)

    @app.get("/api/jobs/{job_id}/photo")
    async def photo_file(job_id: str):
        """The photo the job was sent (its page loads it, to furnish it again)."""
        job = get_job(job_id)
        return FileResponse(job.folder / "input" / job.options["photo"])

    @app.get("/api/jobs/{job_id}/download.zip")
    async def download(job_id: str):
        """Every output file of a finished job, in one zip."""
        job = get_job(job_id)
        if job.result is None or "files" not in job.result:
            raise HTTPException(409, f"job {job_id} has no files: it is {job_state(job)['status']}")
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
            for name in job.result["files"]:
                archive.write(job.folder / "out" / name, name)
        return Response(buffer.getvalue(), media_type="application/zip",
                        headers={"Content-Disposition": f'attachment; filename="stager-{job_id[:8]}.zip"'})

    @app.get("/api/board.pdf")
    async def board_pdf(board: str = "7x5", square: float | None = None, paper: str = "A3"):
        """The board to print, as `stage board` writes it."""
        return Response(await asyncio.to_thread(_board_pdf, board, square, paper), media_type="application/pdf",
                        headers={"Content-Disposition": 'inline; filename="board.pdf"'})

    return app


def _board_pdf(board: str, square: float | None, paper: str) -> bytes:
    import tempfile

    from ..camera.board import parse_board
    from ..camera.printable import board_for_paper, write_board_pdf

    try:
        cols, rows, kind = parse_board(board)
        printed = board_for_paper(paper, cols, rows, square, kind)
    except ValueError as error:
        raise UploadError(422, f"board {board}, square {square}, paper {paper}: {error}") from None
    with tempfile.TemporaryDirectory() as folder:
        path = write_board_pdf(Path(folder) / "board.pdf", printed, paper.upper())
        return path.read_bytes()


class _BodyLimit:
    """Refuse (413) a request whose body is larger than ``max_bytes``: by its header before
    it is read, and as it arrives when it says no length (chunked), reading no further."""

    def __init__(self, app, max_bytes: int):
        self.app, self.max_bytes = app, max_bytes

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        length = dict(scope.get("headers") or ()).get(b"content-length", b"")
        if length.isdigit() and int(length) > self.max_bytes:
            response = JSONResponse({"detail": _too_large(int(length), self.max_bytes)}, status_code=413)
            return await response(scope, receive, send)
        seen = 0

        async def counted():
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > self.max_bytes:
                    # An HTTPException passes through the body's parser as it is.
                    raise HTTPException(413, _too_large(None, self.max_bytes))
            return message

        await self.app(scope, counted, send)


def _sent_name(filename: str | None, default: str) -> str:
    """An uploaded file's name as the reports give it: its last part, printable, short."""
    name = "".join(c for c in Path(str(filename or "").replace("\\", "/")).name if c.isprintable())[:100]
    return name or default


def _too_large(n_bytes: int | None, max_bytes: int) -> str:
    size = "larger than that" if n_bytes is None else f"{n_bytes / 1e6:.1f} MB"
    return f"the upload is {size}; at most {max_bytes / 1e6:g} MB are accepted: send a smaller photo"


def _version() -> str:
    from .. import __version__

    return __version__


def serve(host: str = "127.0.0.1", port: int = 8000, workers: int | None = None, jobs_dir=DEFAULT_JOBS_DIR,
          address: str | None = None) -> None:
    """Run the app with uvicorn until interrupted."""
    import uvicorn

    # The workers say what is wrong with a photo themselves; OpenCV's lines would only crowd the log.
    os.environ.setdefault("OPENCV_LOG_LEVEL", "SILENT")

    uvicorn.run(create_app(jobs_dir, workers=workers, address=address), host=host, port=port)


__all__ = ["create_app", "check_photo", "serve", "UploadError", "MAX_PIXELS", "STAGES"]
