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
    import os

    from layout import fileio

    for name in ("a.txt", "old_3.txt", "mine.txt"):
        (tmp_path / name).write_text(name)
    with staged_folder(tmp_path, stale=["old_3.txt", "a.txt", "gone.txt"]) as staging:
        (staging / "a.txt").write_text("new")
    # Written again beats stale; a stale name that is not there is no error.
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == {"a.txt": "new", "mine.txt": "mine.txt"}

    (tmp_path / "old_3.txt").write_text("old_3.txt")
    real = os.replace

    def failing(src, dst):
        if os.fspath(src).endswith("old_3.txt") and ".previous" in os.fspath(dst):
            raise OSError(13, "Permission denied")
        return real(src, dst)

    monkeypatch.setattr(fileio.os, "replace", failing)
    with pytest.raises(OSError, match="Permission denied"):
        with staged_folder(tmp_path, stale=["old_3.txt"]) as staging:
            (staging / "a.txt").write_text("newer")
            (staging / "b.txt").write_text("b")
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == {
        "a.txt": "new", "mine.txt": "mine.txt", "old_3.txt": "old_3.txt"}
