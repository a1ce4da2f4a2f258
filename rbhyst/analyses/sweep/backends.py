"""Where a sweep's batches run: local worker processes, or an existing Dask cluster.

Both take batches of (key, deck values), run them with :func:`.worker.run_batch` and give
back one dict per case, so that the results are the same bits wherever they ran.
"""

from __future__ import annotations

import os
import time
from concurrent import futures as cf

from rbhyst.errors import InputError
from rbhyst.analyses.sweep.worker import init_local_worker, run_batch


class WorkerLost(Exception):
    """A batch's worker died (or the cluster was lost) before it answered."""


def default_workers() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


class LocalPool:
    """``workers`` processes started with 'spawn' (a fresh interpreter each: no copy of this
    process's threads or locks, which numba and the progress bar hold), each loading the
    compiled kernels once. A pool whose worker is killed cannot go on: it is started anew
    and the batches it held are run again, at most ``MAX_RESTARTS`` times."""

    MAX_RESTARTS = 3

    def __init__(self, workers: int, base, histories: bool):
        import multiprocessing

        self.workers = workers
        self.slots = 2 * workers  # a batch waiting for each worker: no worker idles between batches
        self.where = f"{workers} local worker{'s' * (workers != 1)}"
        self._base, self._histories = base, histories
        self._ctx = multiprocessing.get_context("spawn")
        self.restarts = 0
        self._start()

    def _start(self) -> None:
        self._pool = cf.ProcessPoolExecutor(self.workers, mp_context=self._ctx, initializer=init_local_worker)

    def submit(self, cases):
        return self._pool.submit(run_batch, self._base, cases, self._histories)

    def wait(self, fs, timeout: float):
        done, _ = cf.wait(fs, timeout=timeout, return_when=cf.FIRST_COMPLETED)
        return done

    def result(self, f) -> list[dict]:
        try:
            return f.result()
        except cf.process.BrokenProcessPool as err:
            raise WorkerLost(f"a worker process died ({err})") from None

    def recover(self) -> str:
        """After a lost worker: "requeue" (a new pool: every batch in flight runs again), or
        "stop" when the pool has died too often (a case that kills its worker every time)."""
        self.close(kill=True)
        if self.restarts >= self.MAX_RESTARTS:
            return "stop"
        self.restarts += 1
        self._start()
        return "requeue"

    def close(self, kill: bool = False, pending=()) -> None:
        import gc

        pool, self._pool = self._pool, None
        if pool is None:
            return
        if kill:
            # ProcessPoolExecutor (before Python 3.14) cannot end its workers: a running case
            # would finish first. Ctrl-C must not wait for that.
            procs = list((getattr(pool, "_processes", None) or {}).values())
            for p in procs:
                if p.is_alive():
                    p.terminate()
            for p in procs:
                p.join(2.0)
        pool.shutdown(wait=True, cancel_futures=True)
        del pool
        # the pool's queues hold semaphores that only their finalizers release; the command
        # ends without the interpreter's teardown, and multiprocessing's resource tracker would
        # warn about them
        gc.collect()


class DaskCluster:
    """The batches as tasks on an existing Dask distributed cluster (``dask scheduler`` and
    ``dask worker``). Dask reruns a task whose worker died on another worker; a batch that
    keeps killing workers, or a cluster that is gone, is lost: its cases stay missing."""

    #: seconds without a connection to the scheduler before the cluster counts as lost
    LOST_AFTER_S = 30.0

    def __init__(self, address: str, base, histories: bool):
        try:
            from distributed import Client
        except ImportError:
            raise InputError('--scheduler: needs Dask distributed: pip install "rbhyst[dask]"') from None
        try:
            self.client = Client(address, timeout="15s", set_as_default=False)
        except (OSError, TimeoutError, ValueError) as err:
            raise InputError(f"--scheduler: cannot reach {address} ({err.__class__.__name__}: {err})") from None
        try:
            self.client.wait_for_workers(1, timeout=30)
        except (TimeoutError, OSError):
            self.client.close()
            raise InputError(f"--scheduler: {address} has no workers (start them with "
                             f"`dask worker {address} --nthreads 1`)") from None
        threads = sum(w.get("nthreads", 1) for w in self.client.scheduler_info()["workers"].values())
        self.workers = max(1, threads)
        self.slots = 2 * self.workers
        self.where = f"{address} ({self.workers} worker thread{'s' * (self.workers != 1)})"
        self._base, self._histories = base, histories
        self._unreachable_since: float | None = None

    def submit(self, cases):
        return self.client.submit(run_batch, self._base, cases, self._histories, pure=False)

    def wait(self, fs, timeout: float):
        # (distributed.wait needs a default client, which a library should not set)
        self._check_connected()
        end = time.monotonic() + timeout
        while True:
            done = {f for f in fs if f.done()}
            if done or time.monotonic() >= end:
                return done
            time.sleep(0.005)

    def _check_connected(self) -> None:
        if self.client.status == "running":
            self._unreachable_since = None
            return
        now = time.monotonic()
        self._unreachable_since = self._unreachable_since or now
        if now - self._unreachable_since > self.LOST_AFTER_S:
            raise WorkerLost(f"lost the Dask scheduler (client {self.client.status})")

    def result(self, f) -> list[dict]:
        try:
            return f.result()
        except Exception as err:  # KilledWorker, CancelledError, a closed connection ...
            raise WorkerLost(f"{err.__class__.__name__}: {err}".strip().rstrip(":")) from None

    def recover(self) -> str:
        return "drop"  # dask has rerun the batch on other workers already; the rest goes on

    def close(self, kill: bool = False, pending=()) -> None:
        try:
            if kill and pending:
                self.client.cancel(list(pending))
        except Exception:  # a cluster that is gone has nothing left to cancel
            pass
        finally:
            self.client.close()
