"""The web app's job queue: photos furnished in a pool of worker processes.

:class:`JobQueue` keeps the jobs, hands them to the workers (``spawn``: a fresh
interpreter each, no GL or numba state forked), and deletes finished jobs and their
files after ``keep_minutes``. Each worker holds one GL context for all its jobs and
writes a job's progress to ``<job>/progress.json`` as its stages finish; the routes of
:mod:`augment.app.web` read it from there.

Layout of ``jobs_dir``: one folder per job, ``<id>/input/`` (the photo, the camera
profile, the spec, the layout), ``<id>/out/`` (the files of :func:`augment.pipeline.write_outputs`),
``<id>/progress.json``.
"""
from __future__ import annotations

import functools
import json
import math
import multiprocessing
import os
import shutil
import statistics
import threading
import time
import uuid
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path

from layout.errors import StagerError

# A busy server says when to come back: about when a worker frees up, from the recent
# jobs' times (this default until one is done), within these bounds.
DEFAULT_JOB_S = 20.0
RETRY_AFTER_BOUNDS_S = (2, 60)
MAX_ATTEMPTS = 2  # a job whose worker died is tried once more
STAGES = ("calibrate", "segment", "floor", "height", "furniture", "layout", "render", "scene", "overlays",
          "plans", "write")


# --------------------------------------------------------------------------------------
# The worker process
# --------------------------------------------------------------------------------------

_worker = None            # the worker process's Worker: one GL context, one floor model, all its jobs


class _FileProgress:
    """``furnish``'s progress reporter for a job: the current stage and the steps done,
    written to the job's ``progress.json`` (replaced atomically)."""

    def __init__(self, total: int, path: Path):
        self.path = path
        self.total, self.done, self.current, self.finished = int(total), 0, None, []
        self._write()

    def stage(self, name: str) -> None:
        if self.current is not None and self.current != name and self.current not in self.finished:
            self.finished.append(self.current)
        self.current = name
        self._write()

    def step(self, n: int = 1) -> None:
        self.done += n
        self._write()

    def grow(self, n: int) -> None:
        self.total += n
        self._write()

    def close(self) -> None:
        pass

    def heard(self, progress: dict) -> None:
        """A remote worker's report (``{"stage", "done", "total"}``)."""
        if progress["stage"] is not None:
            self.stage(progress["stage"])
        self.done, self.total = progress["done"], progress["total"]
        self._write()

    def _write(self) -> None:
        _write_progress(self.path, {"stage": self.current, "finished": self.finished, "done": self.done,
                                    "total": self.total + 1})  # + 1: writing the files


def _write_progress(path: Path, state: dict) -> None:
    tmp = path.with_suffix(".tmp")
    try:
        tmp.write_text(json.dumps(state))
        os.replace(tmp, path)
    except FileNotFoundError:
        pass  # the job was deleted while it ran: nobody waits for its progress


def job_work(job_dir, options: dict) -> tuple[dict, dict] | None:
    """What a worker needs for a job: its input files (role -> (name shown, bytes, file
    name), :meth:`augment.app.worker.Worker.furnish`) and options; None when the job was
    deleted before it started."""
    job = Path(job_dir)
    if not (job / "input").is_dir():
        return None
    names = options.get("names") or {}
    inputs = {}
    for role, default in (("photo", "the photo"), ("camera", "the camera profile"), ("spec", "the spec file"),
                          ("layout", "the layout file"), ("floor_mask", "the floor mask")):
        if options.get(role):
            inputs[role] = (names.get(role, default), (job / "input" / options[role]).read_bytes(), options[role])
    work = {"board": (*options["board"], options["square"], options["kind"]),
            **{k: options.get(k) for k in ("room", "suggestions", "seed", "style", "clicks", "doors", "keep_board",
                                           "height_m")}}
    return inputs, work


def finish_job(job_dir, answer: dict) -> dict:
    """A worker's answer for a job: its files written to ``<job>/out``, and what
    ``Job.result`` keeps (``files``, ``warnings``, ``styles``, ``doubt``, ``seconds``;
    or ``error`` with ``kind`` and ``message``)."""
    from ..pipeline import write_files

    job = Path(job_dir)
    if answer["status"] == "refused":
        return {"error": {"kind": answer["kind"], "message": answer["error"]}, "seconds": answer["seconds"]}
    progress = job / "progress.json"
    try:
        state = json.loads(progress.read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        state = {"done": 0, "total": 1}
    _write_progress(progress, dict(state, stage="write", finished=list(STAGES[:-1])))
    try:
        paths = write_files(answer["files"], job / "out")
    except StagerError as error:
        return {"error": {"kind": error.kind, "message": str(error).replace(str(job), "the job")},
                "seconds": answer["seconds"]}
    _write_progress(progress, dict(state, stage=None, finished=list(STAGES), done=state["total"]))
    return {"files": [p.name for p in paths], "warnings": answer["warnings"], "styles": answer["styles"],
            "doubt": answer["doubt"], "seconds": answer["seconds"]}


def _run_job(job_dir: str, options: dict) -> dict:
    """Furnish one job's photo into ``job_dir/out`` (in a worker process); returns
    :func:`finish_job`'s result. A bug raises."""
    global _worker
    from .worker import Worker

    work = job_work(job_dir, options)
    if work is None:
        return {"error": {"kind": "cancelled", "message": "the job was deleted before it started"}, "seconds": 0.0}
    if _worker is None:
        _worker = Worker(threads=None)
    return finish_job(job_dir, _worker.furnish(*work, reporter=functools.partial(
        _FileProgress, path=Path(job_dir) / "progress.json")))


# --------------------------------------------------------------------------------------
# The queue (in the server process)
# --------------------------------------------------------------------------------------

class RayPool:
    """Jobs run on Ray actors (:class:`augment.app.cluster.StageWorker`) instead of
    worker processes, with the ``submit`` and ``shutdown`` of a ProcessPoolExecutor.

    The inputs travel to the actor as bytes and the files come back, so the actors may
    be on other machines; the progress streams back stage by stage. An actor that dies
    under a job is replaced here (``heals``), and the job fails with
    ``BrokenProcessPool`` for the queue to try it again.
    """

    heals = True

    def __init__(self, workers: int):
        import queue as queues

        from .cluster import actor_class

        self._actors = queues.Queue()
        for _ in range(workers):
            self._actors.put(actor_class().remote())
        self._all = list(self._actors.queue)
        self._threads = ThreadPoolExecutor(workers, thread_name_prefix="ray-job")

    def submit(self, fn, job_dir: str, options: dict) -> Future:
        assert fn is _run_job  # the one kind of work the queue hands out
        return self._threads.submit(self._run, job_dir, options)

    def _run(self, job_dir: str, options: dict) -> dict:
        import ray

        from .cluster import actor_class

        work = job_work(job_dir, options)
        if work is None:
            return {"error": {"kind": "cancelled", "message": "the job was deleted before it started"},
                    "seconds": 0.0}
        actor = self._actors.get()
        progress, answer = None, None
        try:
            for ref in actor.furnish_stages.options(num_returns="streaming").remote(*work):
                item = ray.get(ref)
                if "progress" in item:
                    if progress is None:
                        progress = _FileProgress(item["progress"]["total"], Path(job_dir) / "progress.json")
                    progress.heard(item["progress"])
                else:
                    answer = item["answer"]
        except ray.exceptions.RayActorError:
            ray.kill(actor, no_restart=True)
            self._all.remove(actor)
            actor = actor_class().remote()
            self._all.append(actor)
            raise BrokenProcessPool("the Ray worker furnishing the photo stopped") from None
        finally:
            self._actors.put(actor)
        return finish_job(job_dir, answer)

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        import ray

        self._threads.shutdown(wait=wait, cancel_futures=cancel_futures)
        for actor in self._all:
            ray.kill(actor, no_restart=True)
        ray.shutdown()


def retry_after_s(job_seconds, workers: int) -> int:
    """Seconds until a worker is likely free: the median of the last (up to 10) job
    times over the worker count, within ``RETRY_AFTER_BOUNDS_S``."""
    recent = list(job_seconds)[-10:]
    typical = statistics.median(recent) if recent else DEFAULT_JOB_S
    lo, hi = RETRY_AFTER_BOUNDS_S
    return int(min(hi, max(lo, math.ceil(typical / max(1, workers)))))


@dataclass
class Job:
    """One photo to furnish: its folder, options and, once done, its result."""

    id: str
    folder: Path
    options: dict
    created: float = field(default_factory=time.time)
    future: Future | None = None
    finished: float | None = None
    result: dict | None = None
    delete_when_done: bool = False
    attempts: int = 0


def job_state(job: Job) -> dict:
    """What ``GET /api/jobs/{id}`` answers: status, per-stage progress, error, files."""
    board = f"{job.options['board'][0]}x{job.options['board'][1]}"
    if job.options["kind"] != "chessboard":
        board = f"{job.options['kind']}:{board}"
    state = {"id": job.id, "status": "queued", "stage": None, "stages": {s: "pending" for s in STAGES},
             "progress": 0.0, "error": None, "files": [], "styles": [], "warnings": [], "doubt": None,
             "options": {"board": board, "square": job.options["square"], "room": job.options["room"],
                         "spec": job.options.get("spec") is not None,
                         "layout": job.options.get("layout") is not None,
                         "floor_mask": job.options.get("floor_mask") is not None,
                         "clicks": len(job.options.get("clicks") or ()),
                         "doors": len(job.options.get("doors") or ()),
                         "keep_board": job.options["keep_board"], "style": job.options.get("style"),
                         "suggestions": job.options["suggestions"], "seed": job.options["seed"],
                         "height_m": job.options.get("height_m")}}
    try:
        progress = json.loads((job.folder / "progress.json").read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        progress = None
    if progress is not None:
        state["status"] = "running"
        for name in progress["finished"]:
            state["stages"][name] = "done"
        if progress["stage"] is not None:
            state["stages"][progress["stage"]] = "running"
        state["stage"] = progress["stage"]
        state["progress"] = round(min(1.0, progress["done"] / max(progress["total"], 1)), 3)
    if job.result is not None:
        if "error" in job.result:
            state["status"] = "failed"
            state["error"] = job.result["error"]
            if state["stage"] is not None:
                state["stages"][state["stage"]] = "failed"
        else:
            state.update(status="done", progress=1.0, stage=None, files=job.result["files"],
                         styles=job.result.get("styles", []),
                         warnings=job.result["warnings"], doubt=job.result["doubt"],
                         stages={s: "done" for s in STAGES})
    return state


class JobQueue:
    """The server's jobs and the worker pool that runs them.

    Parameters
    ----------
    jobs_dir : Path
        Where jobs keep their files (exists).
    workers : int
        Worker processes.
    keep_minutes : float
        Finished jobs and their files are deleted this long after they finish.
    max_queued : int
        Jobs that may wait for a free worker; beyond, :meth:`busy_s` says how long to wait.
    ray : bool
        Run the jobs on the Ray cluster joined (:func:`augment.app.cluster.connect`),
        ``workers`` actors, instead of worker processes of this machine.
    """

    def __init__(self, jobs_dir: Path, workers: int, keep_minutes: float, max_queued: int, ray: bool = False):
        self.jobs_dir = Path(jobs_dir)
        self.workers = int(workers)
        self.keep_s = float(keep_minutes) * 60
        self.max_queued = int(max_queued)
        self.ray = bool(ray)
        self.jobs: dict[str, Job] = {}
        self._pool: ProcessPoolExecutor | None = None
        self._lock = threading.RLock()

    def start(self) -> None:
        self._pool = self._new_pool()

    def close(self) -> None:
        """Stop the workers; queued jobs are cancelled, running ones finish first."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def _new_pool(self):
        if self.ray:
            return RayPool(self.workers)
        return ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context("spawn"))

    def busy_s(self) -> int | None:
        """Seconds to wait before submitting when every worker and queue place is taken,
        else None."""
        active = sum(j.result is None for j in self.jobs.values())
        if active < self.workers + self.max_queued:
            return None
        done = sorted((j for j in self.jobs.values() if j.result is not None and "seconds" in j.result),
                      key=lambda j: j.finished or 0)
        return retry_after_s([j.result["seconds"] for j in done], self.workers)

    def new_folder(self) -> tuple[str, Path]:
        """A fresh job id and its folder, with ``input/`` made."""
        job_id = str(uuid.uuid4())
        folder = self.jobs_dir / job_id
        (folder / "input").mkdir(parents=True)
        return job_id, folder

    def submit(self, job_id: str, folder: Path, options: dict, on_done) -> Job:
        """Queue a job whose inputs are in ``folder/input``; ``on_done(job)`` is called
        from a pool thread when it finishes."""
        job = self.jobs[job_id] = Job(job_id, folder, options)
        self._run(job, on_done)
        return job

    def _run(self, job: Job, on_done) -> None:
        """Hand ``job`` to a worker; a worker that dies under it (killed, out of memory)
        gets the job tried once more on a fresh pool, then failed saying so."""
        job.attempts += 1
        with self._lock:
            try:
                job.future = self._pool.submit(_run_job, str(job.folder), job.options)
            except BrokenProcessPool:
                self._replace_pool(self._pool)
                job.future = self._pool.submit(_run_job, str(job.folder), job.options)
            pool = self._pool

        def done(future: Future) -> None:
            died = not future.cancelled() and isinstance(future.exception(), BrokenProcessPool)
            if died and job.attempts < MAX_ATTEMPTS and not job.delete_when_done and self._pool is not None:
                if not getattr(pool, "heals", False):
                    self._replace_pool(pool)
                self._run(job, on_done)
                return
            _finish(job, future)
            on_done(job)

        job.future.add_done_callback(done)

    def _replace_pool(self, broken: ProcessPoolExecutor) -> None:
        """A fresh pool in place of ``broken`` (once, however many of its jobs ask)."""
        with self._lock:
            if self._pool is broken and broken is not None:
                broken.shutdown(wait=False)
                self._pool = self._new_pool()

    def cancel(self, job: Job) -> bool:
        """Whether the job is deleted at once: it was waiting, or is done. A job handed to
        a worker that has not begun it loses its inputs now, and its worker stops at once.
        A running job is marked to be deleted when it finishes."""
        if job.result is not None or job.future.cancel() or job.future.done():
            return True
        job.delete_when_done = True
        if not (job.folder / "progress.json").exists():
            shutil.rmtree(job.folder / "input", ignore_errors=True)
            return True
        return False

    def forget(self, job: Job) -> None:
        """The job, and its folder with the photo and every file made from it, deleted."""
        self.jobs.pop(job.id, None)
        shutil.rmtree(job.folder, ignore_errors=True)

    def sweep(self, now: float | None = None) -> list[str]:
        """Delete finished jobs older than ``keep_minutes``, and leftover job folders."""
        now = time.time() if now is None else now
        gone = [j.id for j in self.jobs.values() if j.finished is not None and now - j.finished > self.keep_s]
        for job_id in gone:
            self.forget(self.jobs[job_id])
        for folder in self.jobs_dir.iterdir():
            if folder.name not in self.jobs and is_uuid(folder.name) and now - folder.stat().st_mtime > self.keep_s:
                shutil.rmtree(folder, ignore_errors=True)
                gone.append(folder.name)
        return gone


def is_uuid(name: str) -> bool:
    try:
        return str(uuid.UUID(name)) == name
    except ValueError:
        return False


def _finish(job: Job, future: Future) -> None:
    """A worker is done with ``job`` (a pool thread): keep its result, or the bug."""
    job.finished = time.time()
    error = future.exception() if not future.cancelled() else None
    if future.cancelled():
        job.result = {"error": {"kind": "cancelled", "message": "the server stopped before this photo was done"}}
    elif isinstance(error, BrokenProcessPool):
        job.result = {"error": {"kind": "worker", "message": f"the worker furnishing this photo stopped, "
                                f"{job.attempts} time{'s' * (job.attempts > 1)} (killed, or out of memory); try "
                                "again later, or send a smaller photo"}}
    elif error is not None:
        import traceback

        traceback.print_exception(error)
        job.result = {"error": {"kind": "internal", "message": f"internal error ({type(error).__name__}: "
                                                               f"{error}); this is a bug in Stager"}}
    else:
        job.result = future.result()
