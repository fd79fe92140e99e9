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
