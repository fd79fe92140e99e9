"""All-or-none output: layout.fileio.staged_folder (used by stage furnish, measure,
segment and check)."""
from __future__ import annotations

import pytest

from layout.fileio import staged_folder


def test_a_new_folder_appears_whole(tmp_path):
    out = tmp_path / "new"
    with staged_folder(out) as staging:
        (staging / "a.txt").write_text("a")
        (staging / "b.txt").write_text("b")
    assert sorted(p.name for p in out.iterdir()) == ["a.txt", "b.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["new"]  # no staging folder left


def test_an_existing_folder_gets_the_files_and_keeps_the_others(tmp_path):
    (tmp_path / "a.txt").write_text("old")
    (tmp_path / "mine.txt").write_text("user's")
    with staged_folder(tmp_path) as staging:
        (staging / "a.txt").write_text("new")
    assert (tmp_path / "a.txt").read_text() == "new"
    assert (tmp_path / "mine.txt").read_text() == "user's"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "mine.txt"]


def test_a_failure_in_the_block_changes_nothing(tmp_path):
    (tmp_path / "a.txt").write_text("old")
    with pytest.raises(RuntimeError):
        with staged_folder(tmp_path) as staging:
            (staging / "a.txt").write_text("new")
            raise RuntimeError("encoding failed")
    assert (tmp_path / "a.txt").read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]


def test_stale_files_go_with_the_move_and_come_back_if_it_fails(tmp_path, monkeypatch):
    from layout import fileio

    for name in ("a.txt", "old_3.txt", "mine.txt"):
        (tmp_path / name).write_text(name)
    with staged_folder(tmp_path, stale=["old_3.txt", "a.txt", "gone.txt"]) as staging:
        (staging / "a.txt").write_text("new")
    # Written again beats stale; a stale name that is not there is no error.
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == {"a.txt": "new", "mine.txt": "mine.txt"}

    (tmp_path / "old_3.txt").write_text("old_3.txt")

    def failing(a, b):  # the folders' exchange, the one step that puts the new files in place
        raise OSError(13, "Permission denied")

    monkeypatch.setattr(fileio, "_exchange", failing)
    with pytest.raises(OSError, match="Permission denied"):
        with staged_folder(tmp_path, stale=["old_3.txt"]) as staging:
            (staging / "a.txt").write_text("newer")
            (staging / "b.txt").write_text("b")
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == {
        "a.txt": "new", "mine.txt": "mine.txt", "old_3.txt": "old_3.txt"}


def _folder(path):
    return {p.name: p.read_text() for p in sorted(path.iterdir())}


def _killed_at(out, step, queue):
    """In a child process: replace ``out``'s run (a.txt, b.txt, mine.txt) by another
    (a.txt, c.txt; b.txt stale), SIGKILLed at its ``step``-th file-system step."""
    import os
    import shutil
    import signal

    from layout import fileio

    count = [0]

    def counted(function):
        def call(*args, **kwargs):
            count[0] += 1
            if count[0] == step:
                os.kill(os.getpid(), signal.SIGKILL)
            return function(*args, **kwargs)
        return call

    for name in ("_link_or_copy", "_exchange"):
        setattr(fileio, name, counted(getattr(fileio, name)))
    fileio.os.rename = counted(os.rename)
    fileio.shutil.rmtree = counted(shutil.rmtree)
    with fileio.staged_folder(out, stale=["b.txt"]) as staging:
        for name, text in (("a.txt", "new a"), ("c.txt", "new c")):
            counted(lambda: None)()
            (staging / name).write_text(text)
    queue.put(count[0])


@pytest.mark.parametrize("fallback", [False, True])
def test_a_run_killed_at_any_step_leaves_the_old_folder_or_the_new_one(tmp_path, fallback):
    """SIGKILL at every step of replacing a folder, with the atomic exchange and with the
    two-rename fallback (a system without it): the folder is the old run or the new one,
    never a mix or missing; the next run cleans up what the killed one left."""
    import multiprocessing

    from layout import fileio

    old = {"a.txt": "old a", "b.txt": "old b", "mine.txt": "user's"}
    new = {"a.txt": "new a", "c.txt": "new c", "mine.txt": "user's"}
    context = multiprocessing.get_context("fork")
    seen, step = set(), 1
    while True:
        out = tmp_path / f"run{step}" / "out"
        out.mkdir(parents=True)
        for name, text in old.items():
            (out / name).write_text(text)
        queue = context.Queue()
        if fallback:
            def no_exchange(a, b):
                raise OSError(fileio.errno.ENOSYS, "no renameat2")
            fileio_exchange, fileio._exchange = fileio._exchange, no_exchange
        try:
            child = context.Process(target=_killed_at, args=(out, step, queue))
            child.start()
            child.join(30)
        finally:
            if fallback:
                fileio._exchange = fileio_exchange
        finished = child.exitcode == 0
        if not finished:
            # Until the next run, the folder itself may be the old one set aside (.old)
            # only where the system has no exchange; the next run puts it back first.
            if not out.exists():
                assert fallback
                fileio.clean_leftovers(out)
            assert _folder(out) in (old, new), (step, _folder(out))
            seen.add("old" if _folder(out) == old else "new")
            with fileio.staged_folder(out) as staging:  # the next run
                (staging / "z.txt").write_text("next")
            assert [p.name for p in out.parent.iterdir()] == ["out"], step  # nothing left beside it
        else:
            assert _folder(out) == new
            break
        step += 1
    assert step > 5 and seen == {"old", "new"}


def test_a_folder_link_is_followed(tmp_path):
    """--out naming a link to a folder: the folder it points to gets the run; the link stays."""
    real = tmp_path / "real"
    real.mkdir()
    (real / "a.txt").write_text("old")
    link = tmp_path / "link"
    link.symlink_to(real)
    with staged_folder(link) as staging:
        (staging / "a.txt").write_text("new")
    assert link.is_symlink() and (link / "a.txt").read_text() == "new" and (real / "a.txt").read_text() == "new"
