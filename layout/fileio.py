"""Atomic file output: readers never see a half-written file, and a failed write leaves
the previous file (or none) in place; :func:`staged_folder` does the same for a set of
files."""
from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path


def replaced_input(outputs, inputs) -> tuple[Path, Path] | None:
    """The first of ``outputs`` (paths) that is one of the files ``inputs`` (paths or None),
    by any name, and that input; None when writing the outputs leaves every input alone."""
    existing = [Path(p) for p in inputs if p is not None and Path(p).is_file()]
    for out in map(Path, outputs):
        if out.is_file():
            for given in existing:
                if os.path.samefile(out, given):
                    return out, given
    return None


@contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; on success it is renamed onto ``path``.

    The temporary file shares the folder so the rename is atomic; it is made readable by
    all (``mkstemp`` creates it private) because outputs are meant to be shared.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_atomic(path, data: bytes | str) -> Path:
    """Write ``data`` (text as UTF-8) to ``path`` atomically; returns the path."""
    if isinstance(data, str):
        data = data.encode("utf-8")
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


@contextmanager
def staged_folder(out_dir, stale=()):
    """Yield a temporary folder beside ``out_dir``; what is written there is moved into
    ``out_dir`` all or none when the block ends without an exception.

    A new ``out_dir`` is the staging folder renamed into place whole; into an existing one
    each file is renamed in, and if one move fails those already moved are put back as
    they were. Files in ``out_dir`` that the block did not write are left alone, but for
    the names in ``stale`` (an earlier run's outputs this run replaces): those are taken
    away with the move, and put back if it fails. Errors are ``OSError``; the temporary
    folder never outlives the block.
    """
    out = Path(out_dir)
    out.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent))
    try:
        yield staging
        names = sorted(p.name for p in staging.iterdir())
        if not out.exists():
            staging.chmod(0o755)  # mkdtemp makes it private; outputs are meant to be shared
            os.rename(staging, out)
        else:
            _move_in(staging, names, out, [n for n in stale if n not in names and (out / n).is_file()])
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _move_in(staging: Path, names: list[str], out: Path, stale: list[str]) -> None:
    """Move the files ``names`` from ``staging`` into ``out`` and the files ``stale`` out of
    it: each an atomic rename; when one fails, the files already moved are put back as
    they were."""
    backup = staging / ".previous"
    backup.mkdir()
    done = []  # (name, had an older file)
    try:
        for name in names:
            old = (out / name).exists()
            if old:
                os.replace(out / name, backup / name)
            done.append((name, old))
            os.replace(staging / name, out / name)
        for name in stale:
            os.replace(out / name, backup / name)
            done.append((name, True))
    except OSError:
        for name, old in reversed(done):
            try:
                if old:
                    os.replace(backup / name, out / name)
                else:
                    (out / name).unlink(missing_ok=True)
            except OSError:
                pass  # best effort: the first error is the one reported
        raise
