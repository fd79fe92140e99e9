"""The ``layout`` command line (layout.cli)."""
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from layout import cli, spec

SPEC = """
[room]
polygon = [[0, 0], [4, 0], [4, 3], [0, 3]]
height = 2.5
doors = [{ at = [3.4, 0.0], width = 0.8 }]

[solver]
max_iterations = 200

[[items]]
id = "bed"
kind = "single_bed"

[[items]]
id = "nightstand"
kind = "nightstand"

[[items]]
id = "wardrobe"
kind = "wardrobe"
"""


@pytest.fixture
def spec_file(tmp_path):
    path = tmp_path / "room.toml"
    path.write_text(textwrap.dedent(SPEC))
    return path


def test_solve_writes_outputs_and_prints_a_summary(spec_file, tmp_path, capsys):
    before = spec_file.read_bytes()
    out = tmp_path / "out"
    rc = cli.main(["solve", str(spec_file), "--suggestions", "3", "--seed", "5", "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    assert captured.err == ""  # no progress bar when stderr is not a terminal
    assert spec_file.read_bytes() == before  # the input is never touched
    files = sorted(p.name for p in out.iterdir())
    assert files == ["energy.png", "layout_1.json", "layout_2.json", "layout_3.json",
                     "plan_1.png", "plan_2.png", "plan_3.png"]
    data = json.loads((out / "layout_3.json").read_text())
    assert data["seed"] == 7  # suggestion K uses seed + K - 1, as Solver.suggest
    assert {i["id"] for i in data["items"]} == {"bed", "nightstand", "wardrobe"}
    assert "traversable" in data["metrics"]
    lines = captured.out.splitlines()
    assert lines[0].split() == ["K", "energy", "iters", "overlaps", "outside", "m²", "walkable", "time", "ms"]
    assert [ln.split()[0] for ln in lines[1:4]] == ["1", "2", "3"]
    assert lines[4].startswith("diversity: ")
    assert str(out) in lines[5]


def test_layouts_that_are_not_clean_or_repeat_are_warned(tmp_path, capsys):
    """A living room's sofa, TV stand and coffee table in an L of 1 m wide arms: they
    cannot face each other on that floor. The table's columns were the only sign."""
    path = tmp_path / "narrow.toml"
    path.write_text('[room]\npolygon = [[0, 0], [6, 0], [6, 1], [1, 1], [1, 6], [0, 6]]\nheight = 2.6\n'
                    'preset = "living_room"\n')
    assert cli.main(["solve", str(path), "-n", "2", "--out", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2, err
    for k in (1, 2):
        assert err[k - 1].startswith(f"warning: suggestion {k}: ") and "m² of sofa" in err[k - 1], err
        assert "off the floor" in err[k - 1] and "too small or narrow" in err[k - 1]


def test_quiet_prints_nothing(spec_file, tmp_path, capsys):
    assert cli.main(["solve", str(spec_file), "-n", "1", "--out", str(tmp_path / "o"), "--quiet"]) == 0
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""
    assert (tmp_path / "o" / "plan_1.png").exists()


def test_default_out_dir_is_named_after_the_spec(spec_file, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["solve", str(spec_file), "-n", "1", "-q"]) == 0
    assert (tmp_path / "out" / "room" / "layout_1.json").exists()


def test_kinds_and_presets(capsys):
    assert cli.main(["kinds"]) == 0
    out = capsys.readouterr().out
    assert "sofa" in out and "2.10" in out and "arcade_cabinet" in out
    assert cli.main(["presets"]) == 0
    out = capsys.readouterr().out
    for name in ("living_room", "bedroom", "dining_room", "office", "game_room", "outdoor_yard"):
        assert name in out


def _error(capsys, argv):
    rc = cli.main(argv)
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("error: ") and "Traceback" not in err
    assert err.count("\n") == 1
    return err


def test_bad_input_exits_2_with_one_line(spec_file, tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(SPEC.replace('kind = "wardrobe"', 'kind = "wardrobee"'))
    err = _error(capsys, ["solve", str(bad), "--out", str(tmp_path / "o")])
    assert str(bad) in err and "'wardrobe'" in err
    assert not (tmp_path / "o").exists()

    broken = tmp_path / "broken.toml"
    broken.write_text("[room\npolygon = 1\n")
    err = _error(capsys, ["solve", str(broken)])
    assert "invalid TOML" in err and "line 1" in err

    err = _error(capsys, ["solve", str(tmp_path / "missing.toml")])
    assert "no such file" in err

    clash = tmp_path / "clash"
    clash.write_text("a file, not a folder")
    err = _error(capsys, ["solve", str(spec_file), "--out", str(clash)])
    assert "not a folder" in err and clash.read_text() == "a file, not a folder"

    for n in ("0", "101"):  # 10**6 suggestions ran for hours, writing a plan each
        err = _error(capsys, ["solve", str(spec_file), "--suggestions", n])
        assert f"--suggestions {n}: choose from 1 to 100" in err

    # numpy takes no negative seed: refused as a usage error, not a traceback.
    err = _error(capsys, ["solve", str(spec_file), "--seed", "-5"])
    assert "argument --seed: '-5': expected a whole number from 0" in err


def test_usage_errors_exit_2(capsys):
    _error(capsys, [])
    _error(capsys, ["solve"])
    _error(capsys, ["solve", "x.toml", "--seed", "abc"])
    _error(capsys, ["frobnicate"])


def test_help_exits_0(capsys):
    assert cli.main(["--help"]) == 0
    assert "solve" in capsys.readouterr().out


def test_unexpected_failure_exits_1(spec_file, tmp_path, capsys, monkeypatch):
    def boom(*args, **kwargs):
        raise RuntimeError("kaboom")

    monkeypatch.setattr(spec, "build", boom)
    assert cli.main(["solve", str(spec_file), "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err
    assert "kaboom" in err and "unexpected" in err


def test_module_entry_point_reports_bad_input(tmp_path):
    # The console script runs layout.cli:main; run the same through the module.
    proc = subprocess.run(
        [sys.executable, "-m", "layout.cli", "solve", str(tmp_path / "nope.toml")],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 2
    assert proc.stderr.startswith("error: ") and "no such file" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_ctrl_c_reads_as_an_interruption_whatever_it_turns_into(capsys):
    """Ctrl-C lands wherever the program is; inside PyOpenGL's wrappers it came out as a
    TypeError and was reported as a bug in Stager (seen once in ten interrupted runs)."""
    import os
    import signal
    import time

    from layout.command import dispatch

    def command(args):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        except KeyboardInterrupt:
            raise TypeError("'NoneType' object cannot be interpreted as an integer") from None
        return 0

    # A shell starts background jobs (`make test &`) with Ctrl-C ignored, and Python then
    # leaves it ignored: give the test the handler an interactive run has.
    inherited = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        assert dispatch(command, None, "stage") == 130
        assert capsys.readouterr().err.startswith("error: interrupted after ")
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # put back
    finally:
        signal.signal(signal.SIGINT, inherited)

    def broken(args):
        raise TypeError("a real bug")

    assert dispatch(broken, None, "stage") == 1
    assert "unexpected failure (a bug in stage)" in capsys.readouterr().err


def test_solve_says_when_the_first_run_compiles(spec_file, tmp_path, capsys, monkeypatch):
    import layout.solver

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)  # a terminal, as the note is for one
    for ready in (False, True):
        monkeypatch.setattr(layout.solver, "compiled", lambda: ready)
        assert cli.main(["solve", str(spec_file), "--suggestions", "1", "--out", str(tmp_path / "o")]) == 0
        err = capsys.readouterr().err
        assert ("note: the first run on this machine compiles the layout solver" in err) is not ready, err
    # Not on a terminal (tests, CI, a pipe), or with --quiet: not a word.
    monkeypatch.setattr(layout.solver, "compiled", lambda: False)
    assert cli.main(["solve", str(spec_file), "--out", str(tmp_path / "o"), "-q"]) == 0
    assert capsys.readouterr().err == ""


def test_compiled_reads_a_cold_cache_without_compiling(spec_file, tmp_path):
    # An empty numba cache: the solver would compile, and asking does not start it.
    code = "from layout.solver import compiled; import layout._kernels as K; print(compiled(), K.solve_loop.signatures)"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                          cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "[]"]
    # Once compiled or loaded in a process, it is ready.
    from layout.solver import compiled

    model, solver = spec.build(spec.load_spec(spec_file))
    solver.solve(model, seed=0)
    assert compiled()
