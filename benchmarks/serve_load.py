"""Load check of the web app (issue 10, item 5): concurrent jobs plus malformed uploads.

Run by hand: ``python benchmarks/serve_load.py [--clients 20] [--malformed 100]
[--suggestions 1] [--workers 2]`` (a few minutes). Prints a table and writes
``results/serve_load.{json,md}``.

What it does:

* starts ``stage serve --host 127.0.0.1 --port P --workers N --jobs DIR`` as a
  subprocess, on a free loopback port, with a temporary jobs folder;
* ``--clients`` threads (httpx), each submits one job (``POST /api/jobs``, ``photo`` =
  samples/photos/room_4.jpg, ``suggestions`` = ``--suggestions``); a 503 (full queue) is
  retried after the ``Retry-After`` it names; then it polls ``GET /api/jobs/{id}`` until
  the job is done or failed;
* at the same time, ``--malformed`` bad uploads from a few other threads, in turn: a
  text file, a truncated JPEG, a PNG whose header claims 8000 x 7000 pixels, a bad
  ``board`` option, no photo at all. Each must get a 4xx (a 503 is tolerated: the queue
  is full; any other 5xx, or no answer, is a failure);
* samples the memory of the server (the sum of the RSS of the server process and all
  its descendants, the worker processes: psutil if installed, else ``/proc``).

Reported: jobs completed / submitted, jobs lost (accepted but never reached ``done``),
p50/p95 latency of the status endpoint while jobs were running, the answers to the
malformed uploads by status code, the server's memory peak, and whether the server was
still alive (and answering) at the end.
"""
from __future__ import annotations

import argparse
import itertools
import os
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import zlib
from collections import Counter
from pathlib import Path

import httpx
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import results_io  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PHOTO = ROOT / "samples" / "photos" / "room_4.jpg"
HTTP_TIMEOUT_S = 60.0


# --------------------------------------------------------------------------------------
# The server and its memory
# --------------------------------------------------------------------------------------

def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _tree_pids(root: int) -> list[int]:
    """``root`` and all its descendants (from /proc)."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                stat = f.read()
        except OSError:
            continue
        ppid = int(stat[stat.rindex(")") + 2:].split()[1])
        children.setdefault(ppid, []).append(int(entry))
    pids, todo = [], [root]
    while todo:
        pid = todo.pop()
        pids.append(pid)
        todo.extend(children.get(pid, []))
    return pids


def _rss_bytes(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def tree_rss(pid: int) -> tuple[int, int]:
    """(sum of RSS in bytes, number of processes) of ``pid`` and its descendants."""
    try:
        import psutil
    except ImportError:
        pids = _tree_pids(pid)
        return sum(_rss_bytes(p) for p in pids), len(pids)
    try:
        proc = psutil.Process(pid)
        procs = [proc] + proc.children(recursive=True)
    except psutil.NoSuchProcess:
        return 0, 0
    total = 0
    for p in procs:
        try:
            total += p.memory_info().rss
        except psutil.NoSuchProcess:
            pass
    return total, len(procs)


class MemorySampler(threading.Thread):
    def __init__(self, pid: int, every_s: float = 0.25):
        super().__init__(daemon=True)
        self.pid, self.every_s = pid, every_s
        self.peak, self.peak_procs, self.samples = 0, 0, 0
        self.stop = threading.Event()

    def run(self):
        while not self.stop.is_set():
            rss, n = tree_rss(self.pid)
            if rss > self.peak:
                self.peak, self.peak_procs = rss, n
            self.samples += 1
            self.stop.wait(self.every_s)


def start_server(port: int, workers: int, jobs_dir: Path, log_path: Path) -> subprocess.Popen:
    code = "import sys\nfrom augment.app.cli import main\nsys.argv[0] = 'stage'\nsys.exit(main())"
    log = open(log_path, "wb")
    proc = subprocess.Popen([sys.executable, "-c", code, "serve", "--host", "127.0.0.1", "--port", str(port),
                             "--workers", str(workers), "--jobs", str(jobs_dir)],
                            cwd=ROOT, stdout=log, stderr=subprocess.STDOUT)
    log.close()
    return proc


def wait_ready(base: str, proc: subprocess.Popen, timeout_s: float = 60) -> float:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        if proc.poll() is not None:
            raise RuntimeError(f"the server exited with status {proc.returncode} before it answered")
        try:
            if httpx.get(base + "/openapi.json", timeout=2).status_code == 200:
                return time.monotonic() - t0
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    raise RuntimeError(f"the server did not answer within {timeout_s:g} s")


def stop_server(proc: subprocess.Popen) -> dict:
    """SIGINT (uvicorn's graceful stop), then SIGKILL the tree if it hangs."""
    pids = _tree_pids(proc.pid)
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    try:
        proc.wait(60)
        graceful = True
    except subprocess.TimeoutExpired:
        graceful = False
        for pid in reversed(pids):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        proc.wait(10)
    return dict(exit_status=proc.returncode, graceful_stop=graceful)


# --------------------------------------------------------------------------------------
# Clients
# --------------------------------------------------------------------------------------

def _png_header(width: int, height: int) -> bytes:
    """A PNG that claims ``width`` x ``height`` pixels but holds almost no data."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64)) \
        + chunk(b"IEND", b"")


def malformed_cases(photo: bytes) -> list[tuple[str, dict, dict, int]]:
    """(name, files, form data, expected status) of each kind of bad upload."""
    return [
        ("text file", {"photo": ("notes.txt", b"plain text, no photo\n" * 20, "text/plain")}, {}, 415),
        ("truncated JPEG", {"photo": ("cut.jpg", photo[:2000], "image/jpeg")}, {}, 415),
        ("PNG header 8000x7000", {"photo": ("bomb.png", _png_header(8000, 7000), "image/png")}, {}, 413),
        ("bad board option", {"photo": ("room.jpg", photo, "image/jpeg")}, {"board": "8"}, 422),
        ("missing photo", {}, {"board": "7x5", "suggestions": "1"}, 422),
    ]


class Stats:
    def __init__(self):
        self.lock = threading.Lock()
        self.jobs: list[dict] = []           # one per client
        self.status_latency_s: list[float] = []
        self.malformed: list[dict] = []
        self.busy_503 = 0
        self.active = 0                      # clients whose job is accepted and not finished

    def add(self, attr, value):
        with self.lock:
            getattr(self, attr).append(value)


def job_client(i: int, base: str, photo: bytes, suggestions: int, stats: Stats, deadline: float,
               poll_s: float, retry_cap_s: float | None) -> None:
    record = dict(client=i, id=None, status=None, attempts=0, retries_503=0, submit_errors=[],
                  t_submit_s=None, t_total_s=None, polls=0, error=None)
    t0 = time.monotonic()
    with httpx.Client(base_url=base, timeout=HTTP_TIMEOUT_S) as client:
        while record["id"] is None and time.monotonic() < deadline:
            record["attempts"] += 1
            try:
                r = client.post("/api/jobs", files={"photo": ("room_4.jpg", photo, "image/jpeg")},
                                data={"suggestions": str(suggestions), "seed": str(i)})
            except httpx.HTTPError as error:
                record["submit_errors"].append(f"{type(error).__name__}: {error}")
                time.sleep(1.0)
                continue
            if r.status_code == 202:
                record["id"] = r.json()["id"]
                record["t_submit_s"] = time.monotonic() - t0
            elif r.status_code == 503:
                record["retries_503"] += 1
                with stats.lock:
                    stats.busy_503 += 1
                wait = float(r.headers.get("retry-after", "5"))
                if retry_cap_s is not None:
                    wait = min(wait, retry_cap_s)
                time.sleep(wait + 0.1 * (i % 7))     # a little jitter: not all at once
            else:
                record["submit_errors"].append(f"HTTP {r.status_code}: {r.text[:200]}")
                break
        if record["id"] is None:
            stats.add("jobs", record)
            return
        with stats.lock:
            stats.active += 1
        try:
            while time.monotonic() < deadline:
                t = time.perf_counter()
                try:
                    r = client.get(f"/api/jobs/{record['id']}")
                except httpx.HTTPError as error:
                    record["error"] = f"{type(error).__name__}: {error}"
                    time.sleep(poll_s)
                    continue
                stats.add("status_latency_s", time.perf_counter() - t)
                record["polls"] += 1
                if r.status_code != 200:
                    record["error"] = f"HTTP {r.status_code}: {r.text[:200]}"
                    break
                state = r.json()
                record["status"] = state["status"]
                if state["status"] in ("done", "failed"):
                    if state["status"] == "failed":
                        record["error"] = state["error"]
                    break
                time.sleep(poll_s)
        finally:
            with stats.lock:
                stats.active -= 1
        record["t_total_s"] = time.monotonic() - t0
    stats.add("jobs", record)


def malformed_client(base: str, work: list, stats: Stats, pause_s: float) -> None:
    with httpx.Client(base_url=base, timeout=HTTP_TIMEOUT_S) as client:
        for name, files, data, expected in work:
            t = time.perf_counter()
            try:
                r = client.post("/api/jobs", files=files or None, data=data)
                code, detail = r.status_code, r.text[:160]
            except httpx.HTTPError as error:
                code, detail = None, f"{type(error).__name__}: {error}"
            stats.add("malformed", dict(kind=name, expected=expected, status=code, detail=detail,
                                        latency_s=time.perf_counter() - t))
            time.sleep(pause_s)


# --------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------

def percentile_ms(values, q):
    return float(np.percentile(np.asarray(values) * 1e3, q)) if values else None


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--clients", type=int, default=20, help="concurrent job submitters (default 20)")
    parser.add_argument("--malformed", type=int, default=100, help="bad uploads to send (default 100)")
    parser.add_argument("--suggestions", type=int, default=1, help="suggestions per job (default 1)")
    parser.add_argument("--workers", type=int, default=2, help="server worker processes (default 2)")
    parser.add_argument("--malformed-threads", type=int, default=4)
    parser.add_argument("--poll", type=float, default=0.5, help="seconds between status polls (default 0.5)")
    parser.add_argument("--timeout", type=float, default=1200, help="give up after this many seconds")
    parser.add_argument("--retry-cap", type=float, default=None,
                        help="wait at most this long after a 503 (default: the Retry-After it names)")
    parser.add_argument("--photo", type=Path, default=PHOTO)
    parser.add_argument("--no-write", action="store_true", help="print only, write no results files")
    args = parser.parse_args(argv)

    photo = args.photo.read_bytes()
    stats = Stats()
    with tempfile.TemporaryDirectory(prefix="serve_load_") as tmp:
        tmp = Path(tmp)
        port = _free_port()
        base = f"http://127.0.0.1:{port}"
        server = start_server(port, args.workers, tmp / "jobs", tmp / "server.log")
        sampler = MemorySampler(server.pid)
        sampler.start()
        try:
            startup_s = wait_ready(base, server)
            idle_rss, _ = tree_rss(server.pid)
            print(f"server pid {server.pid} on {base}, ready in {startup_s:.1f} s "
                  f"({idle_rss / 2**20:.0f} MiB); {args.clients} clients, {args.malformed} malformed uploads",
                  flush=True)
            t0 = time.monotonic()
            deadline = t0 + args.timeout
            threads = [threading.Thread(target=job_client, daemon=True,
                                        args=(i, base, photo, args.suggestions, stats, deadline, args.poll,
                                              args.retry_cap))
                       for i in range(args.clients)]
            cases = malformed_cases(photo)
            work = list(itertools.islice(itertools.cycle(cases), args.malformed))
            n_threads = max(1, args.malformed_threads)
            # Spread the bad uploads over the first part of the run, while jobs are running.
            pause_s = 0.25
            threads += [threading.Thread(target=malformed_client, daemon=True,
                                         args=(base, work[k::n_threads], stats, pause_s))
                        for k in range(n_threads)]
            for thread in threads:
                thread.start()
            last = 0.0
            while any(t.is_alive() for t in threads):
                time.sleep(1.0)
                now = time.monotonic() - t0
                if now - last >= 15:
                    last = now
                    with stats.lock:
                        done = sum(j["status"] == "done" for j in stats.jobs)
                        print(f"  {now:5.0f} s: {len(stats.malformed)}/{args.malformed} malformed answered, "
                              f"{stats.active} jobs in flight, {done} done, {stats.busy_503} x 503, "
                              f"memory peak {sampler.peak / 2**20:.0f} MiB", flush=True)
            wall_s = time.monotonic() - t0
            alive = server.poll() is None
            try:
                answering = httpx.get(base + "/openapi.json", timeout=10).status_code == 200
            except httpx.HTTPError:
                answering = False
        finally:
            sampler.stop.set()
            sampler.join(5)
            stopped = stop_server(server)
        log = (tmp / "server.log").read_text(errors="replace")

    jobs = sorted(stats.jobs, key=lambda j: j["client"])
    accepted = [j for j in jobs if j["id"] is not None]
    done = [j for j in accepted if j["status"] == "done"]
    failed = [j for j in accepted if j["status"] == "failed"]
    lost = [j for j in accepted if j["status"] != "done"]
    by_kind: dict[str, Counter] = {}
    for m in stats.malformed:
        by_kind.setdefault(m["kind"], Counter())[str(m["status"])] += 1
    codes = Counter(str(m["status"]) for m in stats.malformed)
    bad_answers = [m for m in stats.malformed
                   if m["status"] is None or not (400 <= m["status"] < 500 or m["status"] == 503)]
    unexpected = [m for m in stats.malformed if m["status"] != m["expected"]]
    lat = stats.status_latency_s
    result = dict(
        options=vars(args) | {"photo": str(Path(args.photo).resolve().relative_to(ROOT))
                              if Path(args.photo).resolve().is_relative_to(ROOT) else str(args.photo)},
        server=dict(startup_s=round(startup_s, 2), idle_rss_mib=round(idle_rss / 2**20, 1),
                    memory_peak_mib=round(sampler.peak / 2**20, 1), processes_at_peak=sampler.peak_procs,
                    memory_samples=sampler.samples,
                    memory_source="psutil" if _has_psutil() else "/proc VmRSS",
                    alive_at_end=alive, answering_at_end=answering, **stopped,
                    tracebacks_in_log=log.count("Traceback")),
        wall_s=round(wall_s, 1),
        jobs=dict(submitted=len(jobs), accepted=len(accepted), completed=len(done), failed=len(failed),
                  lost=len(lost), busy_503=stats.busy_503,
                  submit_errors=sum(len(j["submit_errors"]) for j in jobs),
                  median_job_s=float(np.median([j["t_total_s"] for j in done])) if done else None,
                  max_job_s=float(max(j["t_total_s"] for j in done)) if done else None,
                  lost_detail=[dict(client=j["client"], id=j["id"], status=j["status"], error=j["error"])
                               for j in lost]),
        status_endpoint=dict(requests=len(lat), p50_ms=percentile_ms(lat, 50), p95_ms=percentile_ms(lat, 95),
                             max_ms=percentile_ms(lat, 100)),
        malformed=dict(sent=args.malformed, answered=sum(m["status"] is not None for m in stats.malformed),
                       by_status=dict(sorted(codes.items())),
                       by_kind={k: dict(sorted(v.items())) for k, v in by_kind.items()},
                       not_4xx=len(bad_answers), not_expected_code=len(unexpected),
                       examples_not_expected=[dict(kind=m["kind"], status=m["status"], detail=m["detail"])
                                              for m in unexpected[:5]],
                       p50_ms=percentile_ms([m["latency_s"] for m in stats.malformed], 50),
                       p95_ms=percentile_ms([m["latency_s"] for m in stats.malformed], 95)),
    )
    ok = (not lost and len(accepted) == len(jobs) and not bad_answers and alive and answering
          and len(stats.malformed) == args.malformed)
    result["ok"] = ok
    lines = table(result)
    print("\n".join(lines))
    if not args.no_write:
        md = ["# Web app under load (`benchmarks/serve_load.py`)", "",
              f"`python benchmarks/serve_load.py --clients {args.clients} --malformed {args.malformed} "
              f"--suggestions {args.suggestions} --workers {args.workers}`: a `stage serve` subprocess on "
              "127.0.0.1; job clients submit samples/photos/room_4.jpg (503 -> wait Retry-After, retry) and poll "
              "`GET /api/jobs/{id}` until done; malformed uploads sent at the same time.", ""] + lines
        result["machine"] = results_io.machine()
        paths = results_io.write("serve_load", result, md)
        print("wrote", *(str(p.relative_to(ROOT)) for p in paths))
    return 0 if ok else 1


def _has_psutil() -> bool:
    try:
        import psutil  # noqa: F401
    except ImportError:
        return False
    return True


def table(r: dict) -> list[str]:
    j, s, m, srv = r["jobs"], r["status_endpoint"], r["malformed"], r["server"]

    def ms(v):
        return "-" if v is None else f"{v:.1f} ms"

    kinds = "; ".join(f"{k}: " + ", ".join(f"{c} x{n}" for c, n in v.items()) for k, v in m["by_kind"].items())
    rows = [
        ("jobs completed / submitted", f"{j['completed']} / {j['submitted']} (accepted {j['accepted']}, "
                                       f"failed {j['failed']})"),
        ("jobs lost (accepted, never done)", str(j["lost"])),
        ("503 busy answers (retried)", str(j["busy_503"])),
        ("job time, median / max (submit to done)",
         "-" if j["median_job_s"] is None else f"{j['median_job_s']:.1f} s / {j['max_job_s']:.1f} s"),
        ("status endpoint while busy, p50 / p95 / max",
         f"{ms(s['p50_ms'])} / {ms(s['p95_ms'])} / {ms(s['max_ms'])} ({s['requests']} requests)"),
        ("malformed uploads answered", f"{m['answered']} / {m['sent']}"),
        ("malformed by status code", ", ".join(f"{c}: {n}" for c, n in m["by_status"].items())),
        ("malformed by kind", kinds),
        ("malformed not 4xx (5xx other than 503 or no answer)", str(m["not_4xx"])),
        ("server memory peak (RSS, server + workers)",
         f"{srv['memory_peak_mib']:.0f} MiB ({srv['processes_at_peak']} processes; idle "
         f"{srv['idle_rss_mib']:.0f} MiB; {srv['memory_source']})"),
        ("server alive and answering at end", f"{srv['alive_at_end']} / {srv['answering_at_end']}"),
        ("tracebacks in server log", str(srv["tracebacks_in_log"])),
        ("wall time", f"{r['wall_s']:.0f} s"),
        ("result", "OK" if r["ok"] else "FAILED"),
    ]
    return ["| measure | value |", "|---|---|"] + [f"| {a} | {b} |" for a, b in rows]


if __name__ == "__main__":
    sys.exit(main())
