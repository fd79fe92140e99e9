"""``stage batch`` on a real two-node Ray cluster on this machine (two raylets on
loopback, made and stopped here): photos done across nodes exactly as ``stage furnish``
writes them, refusals recorded while the rest is done, a worker killed mid-photo, and a
run interrupted and resumed."""
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import cv2
import pytest

from augment.app.batch import MANIFEST_FIELDS, RESULTS, read_tasks, run_batch
from augment.app.cli import main
from layout.errors import UsageError

SAMPLES = Path(__file__).resolve().parents[2] / "samples" / "photos"
SIZE_PX = (800, 600)  # the samples made smaller: a photo takes a worker about 2 s
DEFAULTS = {"board": (7, 5, "chessboard"), "square": 45.0, "room": None, "spec": None, "camera": None,
            "suggestions": 1, "seed": 0, "style": None, "height": None, "auto_doors": True}


@pytest.fixture(scope="module")
def cluster():
    from ray.cluster_utils import Cluster

    made = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
    made.add_node(num_cpus=1)
    made.wait_for_nodes()
    yield made
    made.shutdown()


@pytest.fixture(scope="module")
def photos(tmp_path_factory):
    """A folder of three photos (the samples room_2 ... room_4, smaller)."""
    folder = tmp_path_factory.mktemp("photos")
    for name, sample in (("hall", 4), ("den", 2), ("loft", 3)):
        image = cv2.resize(cv2.imread(str(SAMPLES / f"room_{sample}.jpg")), SIZE_PX, interpolation=cv2.INTER_AREA)
        cv2.imwrite(str(folder / f"{name}.jpg"), image, [cv2.IMWRITE_JPEG_QUALITY, 92])
    return folder


def results(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / RESULTS).read_text().splitlines()]


def leftovers(out: Path) -> list[str]:
    return [p.name for p in out.iterdir() if p.name.startswith(".")]


def test_a_folder_is_done_across_nodes_as_stage_furnish_does_it(cluster, photos, tmp_path):
    from augment import pipeline
    from augment.camera.board import Board

    out = tmp_path / "out"
    summary = run_batch(photos, out, DEFAULTS, address=cluster.address, workers=2)
    assert (summary.done, summary.refused, summary.failed) == (3, 0, 0)
    lines = results(out)
    assert sorted(r["photo"] for r in lines) == sorted(str(p) for p in photos.iterdir())
    assert {r["status"] for r in lines} == {"done"} and all(r["attempt"] == 1 for r in lines)
    nodes = {r["worker"].split("/")[1] for r in lines}
    assert len(nodes) == 2, lines  # both nodes furnished photos
    assert sorted(p.name for p in out.iterdir()) == ["den", "hall", "loft", RESULTS]
    # The same files, byte for byte (but for the seconds in the reports), as furnishing here.
    result = pipeline.furnish(photos / "den.jpg", Board(), suggestions=1)
    here = pipeline.output_files(result)
    assert sorted(here) == sorted(p.name for p in (out / "den").iterdir())
    for name in ("staged_1.jpg", "overlay_floor.png", "scene_1.glb"):
        assert (out / "den" / name).read_bytes() == here[name], name
    report = json.loads((out / "den" / "report.json").read_text())
    assert report["photo"] == str(photos / "den.jpg")  # never the worker's copy
    assert report["suggestions"] == json.loads(here["report.json"])["suggestions"]


def test_a_manifest_with_bad_rows_refuses_them_and_does_the_rest(cluster, photos, tmp_path, capsys):
    grey = tmp_path / "no_board.png"
    cv2.imwrite(str(grey), cv2.resize(cv2.imread(str(photos / "den.jpg")), (8, 6))
                .repeat(100, axis=0).repeat(100, axis=1))
    (tmp_path / "broken.jpg").write_text("not a photo")
    manifest = tmp_path / "shoot.csv"
    manifest.write_text("photo,room,suggestions\n"
                        f"{photos / 'hall.jpg'},bedroom,1\n"
                        "broken.jpg,,\n"
                        "no_board.png,,\n"
                        "missing.jpg,,\n"
                        f"{photos / 'den.jpg'},kitchen,\n")
    out = tmp_path / "out"
    # A bound every worker is past after a photo: each photo gets a fresh worker.
    status = main(["batch", str(manifest), "--out", str(out), "--address", cluster.address, "-n", "2", "-q",
                   "--worker-memory", "256"])
    assert status == 2
    by_photo = {Path(r["photo"]).name: r for r in results(out)}
    assert by_photo["hall.jpg"]["status"] == "done"
    report = json.loads((out / "hall" / "report.json").read_text())
    assert len(report["suggestions"]) == 1 and any(k.endswith("bed") for k in report["furniture"]["kinds"])
    for name, words in (("broken.jpg", "line 3"), ("no_board.png", "board"), ("missing.jpg", "no such file"),
                        ("den.jpg", "kitchen")):
        assert by_photo[name]["status"] == "refused", name
        assert words in by_photo[name]["error"], by_photo[name]["error"]
        assert str(manifest) in by_photo[name]["error"]
    assert sorted(p.name for p in out.iterdir()) == ["hall", RESULTS]
    by_worker = [r for r in by_photo.values() if "worker" in r]  # those the driver did not refuse itself
    assert len(by_worker) == 3 and all(r["worker_mb"] > 256 for r in by_worker)
    assert len({r["worker"] for r in by_worker}) == 3
    err = capsys.readouterr().err
    assert err.count("refused: ") == 0  # quiet: the lines are in results.jsonl


def test_manifest_rows_are_read_with_their_own_options(tmp_path):
    (tmp_path / "specs").mkdir()
    manifest = tmp_path / "m.jsonl"
    manifest.write_text('{"photo": "a.jpg", "board": "charuco:9x6", "square": 30, "seed": 7, "height": 2.7}\n'
                        '\n'
                        '{"photo": "/abs/b.jpg", "spec": "specs/s.toml", "style": "industrial"}\n'
                        '["c.jpg"]\n'
                        '{"photo": "d.jpg", "suggestions": 0}\n'
                        '{"photo": "e.jpg", "colour": "red"}\n'
                        '{"photo": "f.jpg", "height": "27"}\n')
    tasks = list(read_tasks(manifest, dict(DEFAULTS, room="bedroom")))
    a, b, c, d, e, f = tasks
    assert a.error is None and a.photo == tmp_path / "a.jpg"
    assert (a.options["board"], a.options["square"], a.options["seed"], a.options["room"]) == \
        ((9, 6, "charuco"), 30.0, 7, "bedroom")
    assert b.photo == Path("/abs/b.jpg") and b.options["spec"] == tmp_path / "specs" / "s.toml"
    assert b.options["room"] is None and b.options["style"] == "industrial"
    assert "line 4" in c.error and "JSON object" in c.error
    assert "line 5" in d.error and "suggestions" in d.error and "from 1 to 100" in d.error
    assert "line 6" in e.error and "'colour'" in e.error
    assert a.options["height"] == 2.7 and b.options["height"] is None
    assert "line 7: height '27': expected the wall height in meters, 1.8 to 6, e.g. 2.6" in f.error
    bad = tmp_path / "bad.csv"
    bad.write_text("image,room\na.jpg,bedroom\n")
    with pytest.raises(UsageError, match="column 'image'.*" + ", ".join(MANIFEST_FIELDS)):
        next(read_tasks(bad, DEFAULTS))


def _parent(pid: int) -> int:
    """The parent of process ``pid`` (0 once it is gone)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return 0
    return int(stat[stat.rindex(")") + 2:].split()[1])  # after the name, which may hold spaces


def _worker_pids(name: str) -> list[int]:
    """This test process's descendants whose title (Ray's ``ray::Class.method``) contains
    ``name``: another suite's Ray workers on the machine are not this cluster's."""
    pids, me = [], os.getpid()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if name not in (entry / "cmdline").read_bytes().decode(errors="replace"):
                    continue
            except OSError:
                continue
            pid = int(entry.name)
            while pid > 1 and pid != me:
                pid = _parent(pid)
            if pid == me:
                pids.append(int(entry.name))
    return pids


def test_a_worker_killed_mid_photo_has_the_photo_done_again_once(cluster, photos, tmp_path):
    killed = []

    def kill_one():
        deadline = time.monotonic() + 120
        while not killed and time.monotonic() < deadline:
            busy = _worker_pids("StageWorker.furnish")
            if busy:
                time.sleep(0.5)  # into the photo
                os.kill(busy[0], signal.SIGKILL)
                killed.append(busy[0])
            time.sleep(0.05)

    killer = threading.Thread(target=kill_one)
    killer.start()
    out = tmp_path / "out"
    summary = run_batch(photos, out, DEFAULTS, address=cluster.address, workers=2)
    killer.join()
    assert killed
    assert (summary.done, summary.failed) == (3, 0)
    lines = results(out)
    assert sorted(Path(r["photo"]).name for r in lines) == ["den.jpg", "hall.jpg", "loft.jpg"]
    assert max(r["attempt"] for r in lines) == 2  # the killed worker's photo, on another
    assert str(killed[0]) not in {r["worker"].split(":")[1].split("/")[0] for r in lines if r["attempt"] == 2}
    assert leftovers(out) == []
    for stem in ("den", "hall", "loft"):
        assert json.loads((out / stem / "report.json").read_text())["suggestions"][0]["k"] == 1


def test_a_run_interrupted_is_resumed_where_it_stopped(cluster, photos, tmp_path):
    out = tmp_path / "out"
    command = [sys.executable, "-m", "augment.app.cli", "batch", str(photos), "--out", str(out), "-n", "1",
               "--address", cluster.address, "--workers", "1"]
    # Ctrl-C as a terminal sends it, even where this suite runs in a shell's background,
    # which starts it with SIGINT ignored: a child inherits an ignored signal, but not a handler.
    inherited = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        run = subprocess.Popen(command, stderr=subprocess.PIPE, text=True)
    finally:
        signal.signal(signal.SIGINT, inherited)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not ((out / RESULTS).is_file() and (out / RESULTS).read_text()):
        time.sleep(0.1)
    run.send_signal(signal.SIGINT)
    _, err = run.communicate(timeout=60)
    assert run.returncode == 130, err
    assert "run the same command again" in err
    first = {r["photo"] for r in results(out)}
    done_first = sorted(p.name for p in out.iterdir() if p.is_dir())
    assert 1 <= len(first) < 3 and len(done_first) == len(first)
    stamps = {name: (out / name / "report.json").stat().st_mtime_ns for name in done_first}
    assert leftovers(out) == []
    # Again: only the rest is done, once each.
    again = subprocess.run(command + ["-q"], capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    lines = results(out)
    assert sorted(r["photo"] for r in lines) == sorted(str(p) for p in photos.iterdir())
    assert {name: (out / name / "report.json").stat().st_mtime_ns for name in done_first} == stamps
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == ["den", "hall", "loft"]


def test_the_web_app_hands_its_jobs_to_the_cluster(cluster, photos, tmp_path):
    import warnings

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "Using `httpx` with `starlette.testclient` is deprecated")
        from fastapi.testclient import TestClient

    from augment.app.web import create_app

    app = create_app(tmp_path / "jobs", address=cluster.address)
    with TestClient(app) as client:
        ids = []
        for data in ({"suggestions": "2"}, {"board": "9x6", "suggestions": "1"}):
            response = client.post("/api/jobs", files={"photo": ("hall.jpg", (photos / "hall.jpg").read_bytes(),
                                                                 "image/jpeg")}, data=data)
            assert response.status_code == 202, response.text
            ids.append(response.json()["id"])
        stages, deadline = set(), time.monotonic() + 120
        while time.monotonic() < deadline:
            states = [client.get(f"/api/jobs/{i}").json() for i in ids]
            stages |= {s["stage"] for s in states if s["status"] == "running"}
            if all(s["status"] in ("done", "failed") for s in states):
                break
            time.sleep(0.05)
        done, refused = states
        assert done["status"] == "done" and done["progress"] == 1.0, done
        assert {"render", "write"} & stages  # the stages streamed back from the worker
        report = client.get(f"/api/jobs/{ids[0]}/files/report.json").json()
        assert report["photo"] == "hall.jpg" and len(report["suggestions"]) == 2
        assert client.get(f"/api/jobs/{ids[0]}/files/staged_2.jpg").content[:2] == b"\xff\xd8"
        assert refused["status"] == "failed" and refused["error"]["kind"] == "calibration"
        assert "no 9x6 checkerboard found in hall.jpg" in refused["error"]["message"]
        assert str(tmp_path) not in json.dumps(states)


def test_input_that_will_not_do_is_one_error_before_anything_is_made(tmp_path, capsys):
    out = tmp_path / "out"
    (tmp_path / "m.csv").write_text("img,room\na.jpg,bedroom\n")
    (tmp_path / "empty").mkdir()
    for given, words in ((tmp_path / "nope", "no such file or folder"), (tmp_path / "m.csv", "column 'img'"),
                         (tmp_path / "empty", "holds no photos")):
        assert main(["batch", str(given), "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("error: ") and words in err and err.count("\n") == 1, err
        assert not out.exists()


def test_an_address_where_no_cluster_answers_is_one_error_at_once(photos, tmp_path, capsys):
    t0 = time.monotonic()
    for address in ("127.0.0.1:1", "127.0.0.1:port"):
        assert main(["batch", str(photos), "--out", str(tmp_path / "out"), "--address", address]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: --address {address}: no Ray cluster answers there") and err.count("\n") == 1
    assert time.monotonic() - t0 < 30  # Ray alone would retry for minutes
