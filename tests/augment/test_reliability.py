"""Bad input, faults and hostile uploads: one clear ``error:`` line and exit 2, never a
traceback, a hang, a modified input, a half-written output folder or a frozen server.
One test per class of failure, each with more cases than the one first seen, and
bounded fuzz tests over photos, arguments, profiles and uploads."""
from __future__ import annotations

import hashlib
import io
import json
import os
import random
import signal
import struct
import subprocess
import sys
import threading
import time
import zlib
from contextlib import contextmanager
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from augment.app import cli
from augment.camera.calibrate import load_profile
from augment.errors import CalibrationError
from augment.photo.io import read_photo

ROOT = Path(__file__).resolve().parents[2]
PHOTO = ROOT / "samples" / "photos" / "room_4.jpg"
# In CI: a fixed set of 60 cases per fuzz test. By hand, STAGER_FUZZ_EXAMPLES=5000 draws that
# many new ones each run.
FUZZ = settings(max_examples=int(os.environ.get("STAGER_FUZZ_EXAMPLES", "60")), deadline=None,
                derandomize="STAGER_FUZZ_EXAMPLES" not in os.environ, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@contextmanager
def within(seconds: int):
    """Fail, rather than hang, past ``seconds`` (a read of a named pipe would block)."""
    def late(signum, frame):
        raise TimeoutError(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, late)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def run(argv, capsys, seconds: int = 60):
    with within(seconds):
        code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def refused(code, err, *needles):
    assert code == 2 and err.startswith("error: ") and "Traceback" not in err, err[-2000:]
    assert all(n in err for n in needles), err
    assert len(err) < 2000, err[:300]


def _png(width: int, height: int) -> bytes:
    """A PNG whose header claims ``width`` x ``height`` but holds almost nothing."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) \
        + chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b"")


def _digest(folder: Path) -> dict:
    return {p.name: hashlib.sha1(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir()) if p.is_file()}


# --------------------------------------------------------------------------------------
# What a path is: named for what it is, never read when it is no file
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("command", ["check", "segment", "measure", "furnish", "calibrate"])
def test_a_path_that_is_no_photo_is_named_for_what_it_is(tmp_path, capsys, command):
    pipe = tmp_path / "pipe.jpg"
    os.mkfifo(pipe)
    loop = tmp_path / "loop.jpg"
    loop.symlink_to(loop)
    cases = {pipe: "named pipe", Path("/dev/zero"): "device", loop: "loop of symbolic links",
             tmp_path / ("x" * 300 + ".jpg"): "304 bytes long", tmp_path / "missing.jpg": "does not exist"}
    out = ["--out", tmp_path / "o" / {"calibrate": "profile.json", "segment": "floor.png"}.get(command, "x")]
    for path, needle in cases.items():
        code, _, err = run([command, path, *out], capsys, seconds=20)
        if command == "calibrate" and needle in ("named pipe", "device", "loop of symbolic links", "does not exist"):
            # A shot that cannot be read is skipped and named; with none left, the run is refused.
            refused(code, err)
        else:
            refused(code, err, needle)
    assert not (tmp_path / "o").exists()


def test_every_path_flag_refuses_a_name_no_file_system_takes(tmp_path, capsys):
    long = tmp_path / ("n" * 256)
    for argv in (["check", PHOTO, "--out", long], ["check", PHOTO, "--camera", long],
                 ["segment", PHOTO, "--out", long / "m.png"], ["segment", PHOTO, "--model", long],
                 ["measure", PHOTO, "--floor-mask", long], ["furnish", PHOTO, "--spec", long],
                 ["furnish", PHOTO, "--asset", f"sofa={long}"], ["board", "--out", long / "b.pdf"],
                 ["serve", "--jobs", long], ["furnish", PHOTO, "--out", ""], ["check", ""]):
        code, _, err = run(argv, capsys)
        refused(code, err, "give a path" if "" in argv else "256 bytes long")


@pytest.mark.parametrize("out", ["/", ".", ".."])
def test_an_output_folder_that_cannot_be_replaced_whole_is_refused(tmp_path, capsys, monkeypatch, out):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(["furnish", PHOTO, "--out", out], capsys)
    refused(code, err, f"--out {out}")
    layout_code = subprocess.run([sys.executable, "-m", "layout.cli", "solve", ROOT / "samples" / "bedroom.toml",
                                  "--out", out], capture_output=True, text=True, cwd=tmp_path,
                                 env=dict(os.environ, PYTHONPATH=str(ROOT)))
    refused(layout_code.returncode, layout_code.stderr, f"--out {out}")


# --------------------------------------------------------------------------------------
# Values past any limit, and values that look like flags
# --------------------------------------------------------------------------------------

def test_values_past_any_limit_are_refused_by_name(tmp_path, capsys):
    huge = tmp_path / "huge.png"
    huge.write_bytes(_png(100_000, 100_000))
    code, _, err = run(["check", huge], capsys)
    refused(code, err, "100000 x 100000", "megapixels")
    for board, needle in (("9999999999999999999999x5", "at most 100 inner corners"), ("-3x5", "'-3x5'"),
                          ("7x" + "9" * 5000, "(5000 digits)")):
        code, _, err = run(["check", PHOTO, "--board", board], capsys)
        refused(code, err, "--board", needle)
    code, _, err = run(["check", PHOTO, "--square", "-inf"], capsys)
    refused(code, err, "--square", "'-inf'")
    code, _, err = run(["segment", PHOTO, "--floor-at", "-5,-5", "--out", tmp_path / "m.png"], capsys)
    refused(code, err, "floor at -5,-5: outside the photo")
    base = {"K": [[1000, 0, 640], [0, 1000, 480], [0, 0, 1]], "distortion": [0.0] * 5, "size_px": [1280, 960]}
    for name, profile, needle in (("f", dict(base, K=[[1e308, 0, 640], [0, 1e308, 480], [0, 0, 1]]), "focal lengths"),
                                  ("d", dict(base, distortion=[0.1] * 100), "100 coefficients"),
                                  ("s", dict(base, size_px=[10 ** 30, 5]), "size_px"),
                                  ("n", dict(base, K=[[float("nan")] * 3] * 3), "not finite")):
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps(profile))
        code, _, err = run(["check", PHOTO, "--camera", path], capsys)
        refused(code, err, "camera profile", needle)


def test_a_damaged_or_foreign_image_is_said_to_be_that(tmp_path, capsys):
    ok, png = cv2.imencode(".png", np.full((200, 300, 3), 120, np.uint8))
    data = bytearray(png.tobytes())
    at = data.find(b"IDAT")
    data[at + 4 + int.from_bytes(data[at - 4:at], "big")] ^= 0xFF  # the chunk's checksum
    (tmp_path / "damaged.png").write_bytes(bytes(data))
    from PIL import Image

    Image.new("RGB", (300, 200)).save(tmp_path / "room.gif")
    for name, needle in (("damaged.png", "damaged PNG file (a checksum does not match"), ("room.gif", "GIF file")):
        code, _, err = run(["check", tmp_path / name], capsys)
        refused(code, err, needle)


# --------------------------------------------------------------------------------------
# A run killed at a random moment: the old complete run or the new complete run
# --------------------------------------------------------------------------------------

def _furnish(out: Path, suggestions: int, seed: int) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "augment.app.cli", "furnish", str(PHOTO), "--suggestions",
                             str(suggestions), "--seed", str(seed), "--out", str(out), "--quiet"],
                            cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def _run_of(out: Path):
    """The run the folder holds, by the images and scenes it holds, and whether it is whole:
    every file its report lists is there, and nothing of another run."""
    report = json.loads((out / "report.json").read_text())
    listed = {"report.json", "staged_all.jpg", "energy.png", *report["files"]["overlays"]}
    for s in report["suggestions"]:
        listed |= {s["files"]["staged"], s["files"]["layout"], s["files"]["plan"], s["files"]["scene"]}
    assert {p.name for p in out.iterdir()} == listed
    return {n: d for n, d in _digest(out).items() if n.endswith((".jpg", ".glb"))}


def test_stage_furnish_killed_at_random_moments_leaves_one_whole_run(tmp_path):
    out = tmp_path / "out"
    t0 = time.perf_counter()
    assert _furnish(out, 1, 0).wait(180) == 0
    duration = time.perf_counter() - t0
    first, seen, rng = _run_of(out), [], random.Random(7)
    # A moment at random in each quarter of 0.5-1.4 runs' time: from the work before any
    # file is written to past the last rename, each time.
    for k in range(4):
        run = _furnish(out, 2, 1)
        time.sleep((0.5 + 0.225 * (k + rng.random())) * duration)
        run.kill()
        run.wait()
        seen.append(_run_of(out))
    assert _furnish(out, 2, 1).wait(180) == 0
    second = _run_of(out)
    assert all(s in (first, second) for s in seen) and first != second
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # the last run cleaned up what the killed ones left


# --------------------------------------------------------------------------------------
# The web app: never frozen, never echoing, one list of formats, no server paths
# --------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def client(tmp_path_factory):
    import warnings

    with warnings.catch_warnings():  # as in test_web.py: httpx is what the app's tests use
        warnings.filterwarnings("ignore", "Using `httpx` with `starlette.testclient` is deprecated")
        from fastapi.testclient import TestClient

    from augment.app.web import create_app

    jobs = tmp_path_factory.mktemp("jobs")
    with TestClient(create_app(jobs, workers=1, max_queued=4, max_upload_mb=2)) as c:
        yield c


def test_an_upload_past_the_limit_is_stopped_as_it_streams(client, tmp_path):
    """No Content-Length (chunked), to a real server: it answers 413 once the limit is
    passed, and the client is stopped long before it has sent its 60 MB."""
    import select
    import socket

    import uvicorn

    from augment.app.web import create_app

    listening = socket.socket()
    listening.bind(("127.0.0.1", 0))
    server = uvicorn.Server(uvicorn.Config(create_app(tmp_path / "jobs", workers=1, max_upload_mb=2),
                                           log_level="warning"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [listening]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 10
    while not server.started and time.monotonic() < deadline:
        time.sleep(0.05)
    try:
        sock = socket.create_connection(listening.getsockname(), timeout=10)
        sock.sendall(b"POST /api/jobs HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n"
                     b"Content-Type: multipart/form-data; boundary=b\r\n\r\n")
        part = b'--b\r\nContent-Disposition: form-data; name="photo"; filename="a.jpg"\r\n\r\n'
        sock.sendall(b"%x\r\n%s\r\n" % (len(part), part))
        sent_mb, answer = 0, b""
        for sent_mb in range(1, 61):
            try:
                sock.sendall(b"%x\r\n%s\r\n" % (1_000_000, b"\0" * 1_000_000))
            except OSError:  # the server closed the connection
                break
            if select.select([sock], [], [], 0.05)[0]:
                break
        sock.settimeout(10)
        while b"\r\n\r\n" not in answer or not answer.rstrip().endswith(b"}"):
            chunk = sock.recv(65536)
            if not chunk:
                break
            answer += chunk
        sock.close()
    finally:
        server.should_exit = True
        thread.join(20)
        listening.close()
    assert answer.startswith(b"HTTP/1.1 413") and b"at most 2 MB" in answer, answer[:300]
    assert sent_mb < 20, sent_mb


def test_a_refused_upload_never_echoes_what_was_sent(client):
    big = b"x" * 900_000
    response = client.post("/api/jobs", files={"photo": ("", big, "image/jpeg")})
    assert response.status_code == 422 and len(response.content) < 2000, response.content[:300]
    response = client.post("/api/jobs", files={"photo": ("a.jpg", PHOTO.read_bytes(), "image/jpeg")},
                           data={"clicks": "[" + "9" * 100_000 + "]", "suggestions": "x" * 100_000})
    assert response.status_code == 422 and len(response.content) < 2000


def test_the_command_line_and_the_web_app_take_the_same_formats(client, tmp_path, capsys):
    from PIL import Image

    buffer = io.BytesIO()
    Image.open(PHOTO).save(buffer, "GIF")
    (tmp_path / "room.gif").write_bytes(buffer.getvalue())
    code, _, err = run(["check", tmp_path / "room.gif"], capsys)
    refused(code, err, "is a GIF file")
    response = client.post("/api/jobs", files={"photo": ("room.gif", buffer.getvalue(), "image/gif")})
    assert response.status_code == 415 and "GIF" in response.json()["detail"]


def test_a_slow_check_does_not_hold_up_other_requests(client, monkeypatch):
    """Checking an upload runs off the server's event loop: a status request is answered
    while a spec is still being checked."""
    from augment.app import web

    real = web._check_spec

    def slow(data):
        time.sleep(3)
        return real(data)

    monkeypatch.setattr(web, "_check_spec", slow)
    answered = []

    def post():
        answered.append(("post", client.post("/api/jobs", files={
            "photo": ("a.jpg", PHOTO.read_bytes(), "image/jpeg"),
            "spec": ("s.toml", b"[room]\npolygon = 1\n", "text/plain")}).status_code, time.perf_counter()))

    thread = threading.Thread(target=post)
    t0 = time.perf_counter()
    thread.start()
    time.sleep(0.5)
    status = client.get("/api/jobs/00000000-0000-4000-8000-000000000000")
    waited = time.perf_counter() - t0
    thread.join(30)
    assert status.status_code == 404 and waited < 2.0, waited
    assert answered and answered[0][1] == 422 and answered[0][2] - t0 >= 3


def test_a_spec_past_the_limits_is_refused_at_once(client):
    """The 100 KB spec whose outline had 5,000 corners kept the server from answering
    anything for 30 s."""
    corners = [[round(5 * float(np.cos(a)), 3), round(5 * float(np.sin(a)), 3)]
               for a in np.linspace(0, 6.28, 5000, endpoint=False)]
    spec = f"[room]\npolygon = {corners}\npreset = \"bedroom\"\n".encode()
    assert 50_000 < len(spec) < 256_000
    t0 = time.perf_counter()
    response = client.post("/api/jobs", files={"photo": ("a.jpg", PHOTO.read_bytes(), "image/jpeg"),
                                               "spec": ("s.toml", spec, "text/plain")})
    assert response.status_code == 422 and "at most 1,000" in response.json()["detail"]
    assert time.perf_counter() - t0 < 3.0


def test_the_report_names_the_upload_not_the_servers_path(client):
    response = client.post("/api/jobs", files={"photo": ("my room.jpg", PHOTO.read_bytes(), "image/jpeg")},
                           data={"suggestions": "1"})
    job_id = response.json()["id"]
    deadline = time.monotonic() + 120
    while (state := client.get(f"/api/jobs/{job_id}").json())["status"] not in ("done", "failed"):
        assert time.monotonic() < deadline
        time.sleep(0.3)
    assert state["status"] == "done", state
    report = client.get(f"/api/jobs/{job_id}/files/report.json").text
    assert json.loads(report)["photo"] == "my room.jpg"
    assert "/input/" not in report and job_id not in report and "/tmp" not in report
    assert not any("/tmp" in w or "/input/" in w for w in state["warnings"])


def test_a_job_whose_worker_dies_is_tried_again(client):
    """The worker is killed under the job, as the kernel's out-of-memory killer would: the
    job is tried once more on a fresh worker and done; killed twice, it fails saying why."""
    from augment.app import jobs

    queue = client.app.state.queue

    def submit():
        r = client.post("/api/jobs", files={"photo": ("a.jpg", PHOTO.read_bytes(), "image/jpeg")},
                        data={"suggestions": "1"})
        return queue.jobs[r.json()["id"]]

    def kill_its_worker(job, attempt):
        deadline = time.monotonic() + 120
        while not (job.attempts == attempt and (job.folder / "progress.json").exists() and queue._pool._processes):
            assert time.monotonic() < deadline and job.result is None
            time.sleep(0.05)
        for pid in list(queue._pool._processes):
            os.kill(pid, signal.SIGKILL)

    def wait(job):
        deadline = time.monotonic() + 180
        while job.result is None:
            assert time.monotonic() < deadline
            time.sleep(0.2)
        return client.get(f"/api/jobs/{job.id}").json()

    job = submit()
    kill_its_worker(job, 1)
    state = wait(job)
    assert state["status"] == "done" and job.attempts == 2, state
    job = submit()
    kill_its_worker(job, 1)
    (job.folder / "progress.json").unlink()  # so that the second attempt's progress is waited for
    kill_its_worker(job, 2)
    state = wait(job)
    assert state["status"] == "failed" and state["error"]["kind"] == "worker", state
    assert "stopped, 2 times" in state["error"]["message"] and jobs.MAX_ATTEMPTS == 2


def test_deleting_a_job_that_waits_deletes_it(client):
    ids = []
    for _ in range(3):
        r = client.post("/api/jobs", files={"photo": ("a.jpg", PHOTO.read_bytes(), "image/jpeg")},
                        data={"suggestions": "1"})
        ids.append(r.json()["id"])
    # With one worker: the first runs, the second waits handed to the worker's queue (it
    # could not be cancelled, and was answered "the photo is being furnished"), the third
    # waits in the server's.
    for waiting in ids[1:]:
        response = client.delete(f"/api/jobs/{waiting}")
        assert response.status_code == 200 and response.json()["deleted"] is True, response.json()
        assert client.get(f"/api/jobs/{waiting}").status_code == 404
    client.delete(f"/api/jobs/{ids[0]}")


# --------------------------------------------------------------------------------------
# Fuzz: no traceback, no hang, nothing modified
# --------------------------------------------------------------------------------------

_NUMBERS = st.one_of(st.integers(-10 ** 30, 10 ** 30).map(str), st.floats(allow_nan=True).map(repr),
                     st.sampled_from(["", "-", "--", "0x10", "1e999", "-inf", "nan", "7x5", "-3x5", "charuco:7x5",
                                      "1,2", "-5,-5", "1,2,3,4", "a=b", "ü", "\u202e", "x" * 5000]))
_FLAGS = {"check": ["--board", "--square", "--camera", "--out"],
          "segment": ["--board", "--square", "--camera", "--method", "--floor-at", "--not-floor-at", "--input-size",
                      "--mean", "--floor-class", "--out"],
          "furnish": ["--board", "--square", "--room", "--suggestions", "--seed", "--door", "--asset", "--floor-at",
                      "--out"],
          "board": ["--paper", "--board", "--square", "--out"]}


@FUZZ
@given(data=st.data())
def test_fuzz_the_command_line(tmp_path_factory, capsys, data):
    """Arguments of every kind on photos that cannot be furnished fast (none, junk, a
    thumbnail): exit 0 or 2, one error line, never a traceback; the inputs unchanged."""
    folder = tmp_path_factory.mktemp("fuzz")
    junk = folder / "junk.jpg"
    junk.write_bytes(data.draw(st.binary(max_size=2000)))
    small = folder / "small.png"
    cv2.imwrite(str(small), np.zeros((40, 40, 3), np.uint8))
    before = _digest(folder)
    command = data.draw(st.sampled_from(sorted(_FLAGS)))
    argv = [command] if command == "board" else [command, data.draw(st.sampled_from([junk, small, folder / "none"]))]
    for flag in data.draw(st.lists(st.sampled_from(_FLAGS[command]), max_size=4)):
        value = data.draw(_NUMBERS)
        argv += [flag, folder / "out" / value[:50] if flag == "--out" else value]
    here = os.getcwd()
    os.chdir(folder)  # `stage board` writes board.pdf here by default
    try:
        code, _, err = run(argv, capsys, seconds=60)
    finally:
        os.chdir(here)
    assert code in (0, 2) and "Traceback" not in err and "a bug in stage" not in err, (argv, err[-1500:])
    assert len(err) < 4000
    assert {n: d for n, d in _digest(folder).items() if n in before} == before


@FUZZ
@given(data=st.binary(max_size=4000), prefix=st.sampled_from([b"", b"\xff\xd8\xff", b"\x89PNG\r\n\x1a\n", b"GIF89a",
                                                               b"II*\0", b"RIFF\0\0\0\0WEBP", b"\0\0\0\x18ftypheic"]))
def test_fuzz_photo_bytes(tmp_path_factory, data, prefix):
    path = tmp_path_factory.mktemp("photo") / "p.jpg"
    path.write_bytes(prefix + data)
    with within(30):
        try:
            read_photo(path)
        except CalibrationError as error:
            assert str(error).startswith(f"photo {path} ") and len(str(error)) < 600


_SCALAR = st.none() | st.booleans() | st.floats() | st.integers(-10 ** 20, 10 ** 20) | st.text(max_size=20)
_ROW = st.lists(_SCALAR, max_size=5)
_JSON = _SCALAR | _ROW | st.lists(_ROW, max_size=4) | st.dictionaries(st.text(max_size=8), _SCALAR, max_size=4)


@FUZZ
@given(K=_JSON, distortion=_JSON, size=_JSON, extra=st.dictionaries(st.sampled_from(["rms_px", "focal_uncertainty"]),
                                                                      _JSON))
def test_fuzz_camera_profiles(tmp_path_factory, K, distortion, size, extra):
    path = tmp_path_factory.mktemp("profile") / "p.json"
    path.write_text(json.dumps({"K": K, "distortion": distortion, "size_px": size, **extra}))
    try:
        intrinsics = load_profile(path, (1280, 960))
    except CalibrationError as error:
        assert len(str(error)) < 800
    else:
        assert np.isfinite(intrinsics.K).all() and intrinsics.K[0, 0] > 0


@FUZZ
@given(fields=st.dictionaries(st.sampled_from(["board", "square", "room", "suggestions", "seed", "clicks", "doors",
                                               "keep_board"]), _NUMBERS, max_size=6),
       photo=st.binary(max_size=3000))
def test_fuzz_uploads(client, fields, photo):
    """Refused with 4xx and a short reason, never 5xx, never an echo of what was sent."""
    response = client.post("/api/jobs", files={"photo": ("p.jpg", photo, "image/jpeg")}, data=fields)
    assert 400 <= response.status_code < 500 and len(response.content) < 3000, (response.status_code,
                                                                               response.content[:300])
