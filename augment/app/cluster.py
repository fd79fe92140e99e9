"""Ray for Stager: joining or starting a cluster, and the actor that furnishes photos.

:class:`StageWorker` wraps :class:`augment.app.worker.Worker` (one floor model session,
one GL context, one thread) as a Ray actor, one per CPU; ``stage batch``
(:mod:`augment.app.batch`) and ``stage serve --address`` (:class:`RayPool`) hand it
photos. Ray is imported only here, when one of them runs. Every node of a cluster needs
Stager installed (the actor is imported there by name).
"""
from __future__ import annotations

import logging
import os
import queue
import threading

from layout.errors import UsageError


class StageWorker:
    """A worker's state on a Ray node (made into an actor by :func:`actor_class`)."""

    def __init__(self):
        from augment.app.worker import Worker

        self.worker = Worker(threads=1)

    def where(self) -> str:
        """``node address:process id/node id``, for the results (nodes of one machine
        share the address)."""
        import ray

        return f"{ray.util.get_node_ip_address()}:{os.getpid()}/{ray.get_runtime_context().get_node_id()[:8]}"

    def furnish(self, inputs: dict, options: dict) -> dict:
        return self.worker.furnish(inputs, options)

    def furnish_stages(self, inputs: dict, options: dict):
        """:meth:`furnish`, yielding the progress (``{"stage", "done", "total"}``) as the
        stages finish, then the answer (a Ray streaming generator)."""
        heard = queue.Queue()

        class Reporter:
            def __init__(self, total):
                self.total, self.done, self.current = int(total), 0, None
                self._say()

            def stage(self, name):
                self.current = name
                self._say()

            def step(self, n=1):
                self.done += n
                self._say()

            def grow(self, n):
                self.total += n
                self._say()

            def close(self):
                pass

            def _say(self):
                heard.put({"progress": {"stage": self.current, "done": self.done, "total": self.total}})

        def work():
            try:
                heard.put({"answer": self.worker.furnish(inputs, options, reporter=Reporter)})
            except BaseException as error:  # handed to the caller below
                heard.put({"raise": error})

        threading.Thread(target=work, daemon=True).start()
        while True:
            item = heard.get()
            if "raise" in item:
                raise item["raise"]
            yield item
            if "answer" in item:
                return


_ACTOR = None


def actor_class():
    """:class:`StageWorker` as a Ray actor class: one CPU, not restarted by Ray (the
    caller retries the photo on another)."""
    global _ACTOR
    if _ACTOR is None:
        import ray

        _ACTOR = ray.remote(num_cpus=1, max_restarts=0, max_task_retries=0)(StageWorker)
    return _ACTOR


def connect(address: str | None, workers: int | None) -> int:
    """Join the Ray cluster at ``address`` (``"auto"``, ``host:port`` or
    ``ray://host:port``), or start one on this machine with ``workers`` CPUs (all its
    cores by default). Returns the workers to run: ``workers``, or one per CPU of the
    cluster."""
    import ray

    if address not in (None, "auto"):
        _reachable(address)
    quiet = {"log_to_driver": False, "logging_level": logging.ERROR, "configure_logging": True}
    try:
        if address is None:
            ray.init(num_cpus=workers or os.cpu_count() or 1, include_dashboard=False, **quiet)
        else:
            ray.init(address=address, **quiet)
    except (ConnectionError, RuntimeError, ValueError) as error:
        raise UsageError(f"--address {address}: cannot join a Ray cluster there ({str(error).splitlines()[0]}); "
                         "start one with `ray start --head` and give the address it prints, or leave "
                         "--address out to run on this machine") from None
    return int(workers or max(1, int(ray.cluster_resources().get("CPU", 1))))


def _reachable(address: str) -> None:
    """Refuse at once an address nothing listens on (Ray itself would retry for minutes)."""
    import socket

    host, _, port = address.removeprefix("ray://").rpartition(":")
    try:
        socket.create_connection((host, int(port)), timeout=5).close()
    except (OSError, ValueError) as error:
        reason = "give it as host:port" if isinstance(error, ValueError) else (error.strerror or str(error))
        raise UsageError(f"--address {address}: no Ray cluster answers there ({reason}); start one with "
                         "`ray start --head` and give the address it prints, or leave --address out to run "
                         "on this machine") from None


def start_failure(error) -> UsageError:
    """The error when no worker can start on the cluster (Stager missing on a node...)."""
    cause = str(error).strip().splitlines()
    detail = next((line for line in reversed(cause) if "Error" in line), cause[-1] if cause else repr(error))
    return UsageError(f"the Ray workers cannot start ({detail.strip()}); every node needs Stager installed as "
                      "here (pip install -e . in the same Python), and a free CPU")
