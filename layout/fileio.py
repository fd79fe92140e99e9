"""Atomic file output: readers never see a half-written file, and a failed write leaves
the previous file (or none) in place; :func:`staged_folder` does the same for a set of
files."""
from __future__ import annotations

import ctypes
import errno
import os
import re
import shutil
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path

# What the file system says of a path, worded to follow the path in a message.
_OS_PROBLEMS = {
    errno.ENOENT: "does not exist; check the path",
    errno.ENAMETOOLONG: "has a name too long for the file system; give a shorter path",
    errno.ELOOP: "is a loop of symbolic links; give the file itself",
    errno.ENOTDIR: "is not reachable: a part of the path before it is a file, not a folder",
    errno.EACCES: "cannot be reached (permission denied); check that you may read it",
}


def path_problem(path, kind: str = "file", missing: str | None = None, folder: str | None = None) -> str | None:
    """What keeps ``path`` from being read as a ``kind`` (``"file"`` or ``"folder"``),
    worded to follow the path in a message ("photo x.jpg is a named pipe, not a file"),
    or None. ``missing`` and ``folder`` reword a path that does not exist and, for a
    file, a folder. Never reads the file: a named pipe or a device would block or never end."""
    text = os.fspath(path)
    if not text:
        return f"is empty; give the {kind}'s name"
    try:
        mode = os.stat(text).st_mode
    except OSError as error:
        if error.errno == errno.ENOENT and missing is not None:
            return missing
        return _OS_PROBLEMS.get(error.errno, f"cannot be reached ({error.strerror or error})")
    except ValueError:  # a NUL character
        return "is not a path (it holds a NUL character)"
    if kind == "folder":
        return None if stat.S_ISDIR(mode) else "is a file, not a folder"
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return folder or "is a folder, not a file"
    if stat.S_ISFIFO(mode):
        return "is a named pipe, not a file"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "is a device, not a file"
    return "is not a regular file"


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


def folder_problem(out_dir) -> str | None:
    """What keeps ``out_dir`` from being an output folder that runs replace whole, worded
    to follow its name in a message, or None."""
    out = Path(out_dir)
    if not os.fspath(out_dir):
        return "is empty; give a folder for the outputs, e.g. out/room"
    resolved = out.resolve()
    if resolved.parent == resolved:
        return "is the file system's root; give a folder of its own for the outputs, e.g. /tmp/out"
    cwd = Path.cwd().resolve()
    if resolved == cwd or resolved in cwd.parents:
        return ("is the current folder, or holds it: a run replaces its output folder as a whole; give a "
                "folder of its own, e.g. out/room")
    if resolved.exists() and not resolved.is_dir():
        return "exists and is not a folder; give a folder for the outputs"
    for parent in resolved.parents:
        if parent.exists():
            return None if parent.is_dir() else f"{parent} is a file, not a folder"
    return None


@contextmanager
def staged_folder(out_dir, stale=(), whole: bool = True):
    """Yield a temporary folder beside ``out_dir``; what is written there replaces
    ``out_dir``'s files all or none when the block ends without an exception.

    With ``whole`` (an output folder of Stager's own), the new folder is made complete
    beside the old one: the files written, and hard links to the files of ``out_dir``
    that the block did not write (but for the names in ``stale``, an earlier run's
    outputs this run replaces). One atomic exchange of the two folders then puts it in
    place (``renameat2(RENAME_EXCHANGE)``), and the old one is deleted: killed at any
    moment, ``out_dir`` is the old complete folder or the new one. A killed run's
    temporary folder is deleted by the next run into ``out_dir``. Without ``whole``
    (files put into a folder of the user's), each file is renamed in, atomically each.

    Errors are ``OSError``; the temporary folder never outlives the block.
    """
    out = Path(out_dir)
    if out.is_symlink():
        out = out.resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    clean_leftovers(out)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.{_TAG}-{os.getpid()}-", suffix=".tmp", dir=out.parent))
    try:
        yield staging
        names = sorted(p.name for p in staging.iterdir())
        if not out.exists():
            staging.chmod(0o755)  # mkdtemp makes it private; outputs are meant to be shared
            os.rename(staging, out)
        elif whole:
            _keep_the_others(out, staging, set(names) | set(stale))
            staging.chmod(stat.S_IMODE(out.stat().st_mode))
            _swap(staging, out)
        else:
            _move_in(staging, names, out, [n for n in stale if n not in names and (out / n).is_file()])
    finally:
        shutil.rmtree(staging, ignore_errors=True)


# Temporary folders are named .<out's name>.stager-<pid>-<random>.tmp (and .old): the
# next run into the folder knows a killed run's by its process being gone.
_TAG = "stager"
_LEFTOVER = re.compile(rf"^\.(?P<name>.+)\.{_TAG}-(?P<pid>\d+)-[^.]*\.(?P<kind>tmp|old)$")


def clean_leftovers(out_dir) -> list[Path]:
    """Delete what killed runs into ``out_dir`` left beside it; when a run was killed
    while ``out_dir`` was away (the two-rename fallback), put the old folder back first.
    Returns the paths deleted."""
    out = Path(out_dir)
    gone = []
    try:
        siblings = list(out.parent.iterdir())
    except OSError:
        return gone
    for path in sorted(siblings):
        match = _LEFTOVER.match(path.name)
        if match is None or match["name"] != out.name or _alive(int(match["pid"])):
            continue
        if match["kind"] == "old" and not out.exists():
            os.rename(path, out)
            continue
        shutil.rmtree(path, ignore_errors=True)
        gone.append(path)
    return gone


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # another user's process
    return True


def _keep_the_others(out: Path, staging: Path, replaced: set) -> None:
    """Hard links (copies where the file system has none) in ``staging`` to what ``out``
    holds besides the names ``replaced``."""
    for path in out.iterdir():
        if path.name in replaced:
            continue
        target = staging / path.name
        if path.is_dir() and not path.is_symlink():
            shutil.copytree(path, target, symlinks=True, copy_function=_link_or_copy)
        else:
            _link_or_copy(path, target)


def _link_or_copy(source, target) -> None:
    if os.path.islink(source):
        os.symlink(os.readlink(source), target)
        return
    try:
        os.link(source, target)
    except OSError:
        shutil.copy2(source, target)


def _swap(staging: Path, out: Path) -> None:
    """Put ``staging`` where ``out`` is, in one step where the system allows it; then
    delete the old folder."""
    try:
        _exchange(staging, out)
    except OSError as error:
        if error.errno not in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP, errno.EOPNOTSUPP):
            raise
        # No atomic exchange here: two renames; a run killed between them leaves the old
        # folder as .old, which the next run puts back (clean_leftovers).
        old = staging.with_suffix(".old")
        os.rename(out, old)
        os.rename(staging, out)
        shutil.rmtree(old, ignore_errors=True)
        return
    shutil.rmtree(staging, ignore_errors=True)  # now the old folder


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def _exchange(a: Path, b: Path) -> None:
    """Swap two paths atomically (Linux ``renameat2`` with ``RENAME_EXCHANGE``)."""
    libc = ctypes.CDLL(None, use_errno=True)
    renameat2 = getattr(libc, "renameat2", None)
    if renameat2 is None:
        raise OSError(errno.ENOSYS, "renameat2 is not available")
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) != 0:
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code), str(b))


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
