"""``stage batch``: many photos furnished on Ray, on this machine or a cluster.

The driver (this process) reads the photos one at a time, from a folder or a manifest
(:func:`read_tasks`), and hands each to a Ray actor (:class:`augment.app.worker.Worker`:
one floor model session and one GL context, reused photo after photo). The actor sends
back the files' bytes and the driver writes ``DIR/<photo stem>/`` all or none, so only
the driver writes the output: a photo whose worker is killed mid-way leaves nothing and
is done again on another worker, and a second run into ``DIR`` skips the photos whose
folders are there (:func:`done_before`). ``DIR/results.jsonl`` gets one line per photo
as it finishes.
"""
from __future__ import annotations

import csv
import json
import os
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

from layout.errors import UsageError

from ..photo.io import PHOTO_SUFFIXES
from .cluster import actor_class, connect, start_failure

RESULTS = "results.jsonl"
# The fields a manifest row may give; paths in it are read from the manifest's folder.
MANIFEST_FIELDS = ("photo", "board", "square", "room", "spec", "camera", "suggestions", "seed", "style", "height")
DEFAULT_RETRIES = 2
# A worker past this resident memory after a photo is replaced by a fresh one.
DEFAULT_WORKER_MB = 4096


@dataclass
class Task:
    """One photo to furnish: where it came from and the options it is furnished with."""

    photo: Path
    where: str                          # how messages name it: the path, or "manifest line N"
    options: dict = field(default_factory=dict)  # worker options, and "spec"/"camera" paths
    error: str | None = None            # why it is refused before any work

    @property
    def stem(self) -> str:
        return self.photo.stem

    def said(self, message: str) -> str:
        """``message`` prefixed by where the photo is named, unless it is its path alone."""
        return message if self.where == str(self.photo) else f"{self.where}: {message}"


# --------------------------------------------------------------------------------------
# Reading the input
# --------------------------------------------------------------------------------------

def _photos_in(folder: Path):
    """The photos in ``folder`` (not below), by name."""
    with os.scandir(folder) as entries:
        names = sorted(e.name for e in entries if Path(e.name).suffix.lower() in PHOTO_SUFFIXES and e.is_file())
    if not names:
        raise UsageError(f"folder {folder} holds no photos ({', '.join(PHOTO_SUFFIXES)}); give a folder of "
                         f"photos or a manifest (.csv or .jsonl with a 'photo' field)")
    return (folder / name for name in names)


def _rows(manifest: Path):
    """(line number, {field: text or value}) of each row of a CSV or JSONL manifest."""
    text = manifest.suffix.lower()
    if text == ".csv":
        with open(manifest, newline="", encoding="utf-8-sig") as f:
            reader = csv.DictReader(f)
            header = [h.strip() for h in (reader.fieldnames or [])]
            unknown = [h for h in header if h not in MANIFEST_FIELDS]
            if "photo" not in header or unknown:
                what = f"column {unknown[0]!r} is not one Stager knows" if unknown else "it has no 'photo' column"
                raise UsageError(f"manifest {manifest}: {what}; its first line names the columns, from "
                                 f"{', '.join(MANIFEST_FIELDS)} (photo is needed)")
            reader.fieldnames = header
            for row in reader:
                if any(v and v.strip() for v in row.values() if isinstance(v, str)):
                    yield reader.line_num, {k: v.strip() for k, v in row.items() if isinstance(v, str) and v.strip()}
        return
    with open(manifest, encoding="utf-8") as f:
        for n, line in enumerate(f, start=1):
            if not line.strip():
                continue
            try:
                row = json.loads(line)
            except json.JSONDecodeError as error:
                yield n, {"": f"not a JSON object ({error.msg}, column {error.colno})"}
                continue
            yield n, row if isinstance(row, dict) else {"": f"not a JSON object but {type(row).__name__}"}


def _field(name: str, value, base: Path):
    """A manifest field's value, checked as ``stage furnish`` checks its flag; raises
    ValueError saying what would work."""
    import argparse

    from layout.command import seed_arg
    from layout.presets import PRESETS

    from ..camera.board import parse_board
    from ..render.styles import STYLES
    from .values import count, height_m, square_mm

    text = str(value).strip()
    try:
        if name == "board":
            return parse_board(text)
        if name == "square":
            return square_mm(text)
        if name == "height":
            return height_m(text)
        if name in ("suggestions",):
            return count(text)
        if name == "seed":
            return seed_arg(text)
    except (argparse.ArgumentTypeError, ValueError) as error:
        raise ValueError(str(error)) from None
    if name == "room" and text not in PRESETS:
        raise ValueError(f"{text!r}: choose one of {', '.join(PRESETS)}")
    if name == "style" and text not in STYLES:
        raise ValueError(f"{text!r}: choose one of {', '.join(STYLES)}")
    if name in ("photo", "spec", "camera"):
        if not text:
            raise ValueError("empty: give a path")
        path = Path(text).expanduser()
        return path if path.is_absolute() else base / path
    return text


def read_tasks(source: Path, defaults: dict):
    """The photos of ``source`` (a folder of photos, or a CSV/JSONL manifest), one
    :class:`Task` at a time, in order.

    ``defaults``: the command's options (``board`` (cols, rows, kind), ``square``,
    ``room``, ``spec``, ``camera``, ``suggestions``, ``seed``, ``style``, ``height``,
    ``auto_doors``), which a manifest row's fields replace. A row that will not do
    becomes a task with its ``error``; a manifest whose columns will not do raises
    :class:`UsageError`, before anything is done.
    """
    source = Path(source)
    if source.is_dir():
        for photo in _photos_in(source):
            yield Task(photo, str(photo), _options(defaults, {}))
        return
    for n, row in _rows(source):
        where = f"manifest {source} line {n}"
        if "" in row:
            yield Task(Path(f"line-{n}"), where, {}, f"{where}: {row['']}; each line is one object like "
                                                     '{"photo": "a.jpg", "room": "bedroom"}')
            continue
        given, error = {}, None
        for name, value in row.items():
            if name not in MANIFEST_FIELDS:
                error = f"{where}: field {name!r} is not one Stager knows; use {', '.join(MANIFEST_FIELDS)}"
                break
            if value is None or str(value).strip() == "":
                continue
            try:
                given[name] = _field(name, value, source.parent)
            except ValueError as problem:
                error = f"{where}: {name} {problem}"
                break
        if error is None and "photo" not in given:
            error = f"{where}: no photo; every row names its photo (the 'photo' field)"
        if error is None and "room" in given and "spec" in given:
            error = f"{where}: both a room ({given['room']}) and a spec; give one of them"
        photo = given.get("photo", Path(f"line-{n}"))
        yield Task(photo, where, _options(defaults, given) if error is None else {}, error)


def _options(defaults: dict, given: dict) -> dict:
    """The options a photo is furnished with: the command's, a row's in their place."""
    options = {k: defaults.get(k) for k in ("board", "square", "room", "spec", "camera", "suggestions", "seed",
                                            "style", "height", "auto_doors")}
    options.update({k: v for k, v in given.items() if k != "photo"})
    if "room" in given:
        options["spec"] = None
    if "spec" in given:
        options["room"] = None
    return options


def done_before(out_dir: Path, stem: str) -> bool:
    """Whether a photo's folder is complete: its report is written last into a folder
    that appears whole (:func:`layout.fileio.staged_folder`)."""
    return (out_dir / stem / "report.json").is_file()


def _read_inputs(task: Task) -> dict:
    """The task's files as the worker takes them (role -> (name, bytes)); raises
    UsageError naming a file that cannot be read."""
    from layout.fileio import path_problem

    inputs = {}
    for role, path in (("photo", task.photo), ("spec", task.options.get("spec")),
                       ("camera", task.options.get("camera"))):
        if path is None:
            continue
        if (problem := path_problem(path, missing="no such file")) is not None:
            raise UsageError(f"{'photo' if role == 'photo' else role} {path}: {problem}")
        try:
            inputs[role] = (str(path), Path(path).read_bytes())
        except OSError as error:
            raise UsageError(f"{role} {path}: cannot read it ({error.strerror or error})") from None
    return inputs


def _worker_options(task: Task) -> dict:
    from ..camera.board import DEFAULT_SQUARE_MM

    o = task.options
    cols, rows, kind = o["board"]
    square = o["square"] if o.get("square") is not None else DEFAULT_SQUARE_MM
    return {"board": (cols, rows, square, kind), "room": o.get("room"), "suggestions": o.get("suggestions") or 4,
            "seed": o.get("seed") or 0, "style": o.get("style"), "auto_doors": o.get("auto_doors", True),
            "height_m": o.get("height")}


# --------------------------------------------------------------------------------------
# Ray
# --------------------------------------------------------------------------------------

@dataclass
class Summary:
    """What a batch run did: photo counts by status, and where it stopped."""

    done: int = 0
    refused: int = 0
    failed: int = 0
    skipped: int = 0        # done by an earlier run into the same folder
    left: int = 0           # not done when the run was interrupted
    interrupted: bool = False
    seconds: float = 0.0
    driver_s: float = 0.0   # the driver's own time: reading the input, handing out, writing


class _Results:
    """``results.jsonl``, one line per photo as it finishes, flushed at once."""

    def __init__(self, path: Path):
        self.file = open(path, "a", encoding="utf-8")

    def write(self, record: dict) -> None:
        self.file.write(json.dumps(record, allow_nan=False) + "\n")
        self.file.flush()

    def close(self) -> None:
        self.file.close()


def run_batch(source: Path, out_dir: Path, defaults: dict, *, address: str | None = None,
              workers: int | None = None, retries: int = DEFAULT_RETRIES, worker_mb: float = DEFAULT_WORKER_MB,
              progress: bool = False, say=print) -> Summary:
    """Furnish every photo of ``source`` (:func:`read_tasks`) into ``out_dir/<stem>/``
    on Ray actors; see the module docstring. ``say`` hears one line per refused or
    failed photo. Ctrl-C stops the run (``Summary.interrupted``); run again to go on.
    """
    import ray
    from tqdm import tqdm

    from ..pipeline import write_files

    start = time.perf_counter()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    # A first pass over the input (names and folders only, no photo read): the count
    # for the progress bar, and the manifest's header checked before anything runs.
    total = skipped = 0
    for task in read_tasks(source, defaults):
        total += 1
        skipped += task.error is None and done_before(out_dir, task.stem)
    summary = Summary(skipped=skipped)
    n_workers = connect(address, workers)
    results = _Results(out_dir / RESULTS)
    Actor = actor_class()
    bar = tqdm(total=total - skipped, unit="photo", disable=not progress, dynamic_ncols=True, smoothing=0.1)

    # The actors: each starts with a probe (``where``); one is given a photo only once it
    # answers, so an actor that cannot be placed (its node gone) holds none.
    probes, idle, where = {}, deque(), {}
    busy = {}   # ObjectRef -> (actor, task, inputs, attempt)
    redo = deque()  # (task, attempt) whose worker died

    def new_actor():
        actor = Actor.remote()
        probes[actor.where.remote()] = actor

    starts_failed = 0

    def record(task, status, attempt, **extra):
        results.write({"photo": str(task.photo), "out": task.stem if status == "done" else None,
                       "status": status, "attempt": attempt, "finished": time.strftime("%Y-%m-%dT%H:%M:%S"),
                       "run_s": round(time.perf_counter() - start, 3),
                       **extra})
        if status in ("refused", "failed"):
            say(f"{status}: {extra.get('error')}")
        setattr(summary, status, getattr(summary, status) + 1)
        bar.update()
        minutes = (time.perf_counter() - start) / 60
        bar.set_postfix_str(f"{summary.done / max(minutes, 1e-9):.1f} photos/min, {summary.refused} refused, "
                            f"{summary.failed} failed", refresh=False)

    tasks = read_tasks(source, defaults)
    stems = {}
    exhausted = False

    def next_task():
        """The next photo to hand out with its inputs, or None; refusals found on the
        way are recorded."""
        nonlocal exhausted
        while redo:
            return redo.popleft()
        while not exhausted:
            task = next(tasks, None)
            if task is None:
                exhausted = True
                return None
            if task.error is None and done_before(out_dir, task.stem):
                continue
            if task.error is None and task.stem in stems:
                task.error = task.said(f"another photo named {task.stem} comes first ({stems[task.stem]}); "
                              f"both would go to {out_dir / task.stem}/: rename one")
            if task.error is not None:
                record(task, "refused", 1, error=task.error)
                continue
            stems[task.stem] = task.where
            try:
                inputs = _read_inputs(task)
            except UsageError as error:
                record(task, "refused", 1, error=task.said(str(error)))
                continue
            return task, inputs, 1
        return None

    try:
        for _ in range(n_workers):
            new_actor()
        while True:
            while idle:
                t0 = time.perf_counter()
                item = next_task()
                if item is None:
                    break
                task, inputs, attempt = item
                actor = idle.popleft()
                busy[actor.furnish.remote(inputs, _worker_options(task))] = (actor, task, inputs, attempt)
                summary.driver_s += time.perf_counter() - t0
            if not busy and (exhausted and not redo):
                break
            if not busy and not probes:
                new_actor()
            ready, _ = ray.wait(list(busy) + list(probes), num_returns=1, timeout=1.0)
            for ref in ready:
                t0 = time.perf_counter()
                if ref in probes:
                    actor = probes.pop(ref)
                    try:
                        where[actor] = ray.get(ref)
                        idle.append(actor)
                    except ray.exceptions.RayError as error:
                        # It died starting: another in its place, unless none can start.
                        starts_failed += 1
                        if starts_failed > 2 * n_workers + 1:
                            raise start_failure(error) from None
                        new_actor()
                    continue
                actor, task, inputs, attempt = busy.pop(ref)
                try:
                    answer = ray.get(ref)
                except ray.exceptions.RayActorError:
                    # The worker died under the photo (killed, out of memory, node lost).
                    ray.kill(actor, no_restart=True)
                    new_actor()
                    if attempt <= retries:
                        redo.append((task, inputs, attempt + 1))
                    else:
                        record(task, "failed", attempt, worker=where.get(actor),
                               error=task.said(f"photo {task.photo}: the worker furnishing it stopped {attempt} times "
                                                 "(killed, out of memory, or its node lost)"))
                    continue
                except ray.exceptions.RayTaskError as error:
                    idle.append(actor)
                    cause = error.cause if getattr(error, "cause", None) is not None else error
                    record(task, "failed", attempt, worker=where.get(actor),
                           error=task.said(f"photo {task.photo}: internal error ({type(cause).__name__}: "
                                           f"{str(cause).splitlines()[0] if str(cause) else ''}); this is a bug "
                                           "in Stager"))
                    continue
                if answer["rss_mb"] > worker_mb:
                    ray.kill(actor, no_restart=True)
                    new_actor()
                else:
                    idle.append(actor)
                common = {"worker": where.get(actor), "seconds": round(answer["seconds"], 3),
                          "worker_mb": round(answer["rss_mb"])}
                if answer["status"] == "refused":
                    record(task, "refused", attempt, error=task.said(answer["error"]), **common)
                    continue
                try:
                    write_files(answer["files"], out_dir / task.stem,
                                inputs=[task.photo, task.options.get("spec"), task.options.get("camera")])
                except Exception as error:  # a folder that cannot be written: said, and the run goes on
                    record(task, "refused", attempt, error=task.said(str(error)), **common)
                    continue
                record(task, "done", attempt, warnings=answer["warnings"], styles=answer["styles"],
                       timings_s=answer["timings_s"], **common)
                summary.driver_s += time.perf_counter() - t0
    except KeyboardInterrupt:
        summary.interrupted = True
    finally:
        summary.left = max(0, total - skipped - summary.done - summary.refused - summary.failed)
        bar.close()
        results.close()
        for actor in list(where) + list(probes.values()):
            try:
                ray.kill(actor, no_restart=True)
            except Exception:  # already gone
                pass
        ray.shutdown()
        summary.seconds = time.perf_counter() - start
    return summary


