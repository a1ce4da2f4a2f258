"""Where a sweep's batches run: local worker processes, or an existing Dask cluster.

Both take batches of (key, deck values), run them with :func:`.worker.run_batch` and give
back one dict per case, so that the results are the same bits wherever they ran.
"""

from __future__ import annotations

import itertools
import signal
import time
from concurrent import futures as cf
from dataclasses import dataclass, field
from pathlib import Path

from rbhyst._version import __version__
from rbhyst.errors import InputError
from rbhyst.analyses.sweep.worker import init_local_worker, run_batch, run_tracked


class WorkerLost(Exception):
    """A batch's worker died (or the cluster was lost) before it answered.

    ``killed``: the workers Dask saw die running the batch (KilledWorker); ``again``: the
    batch was lost with the connection, not by its cases (run it again); ``rest``: how the
    cases not computed can be, when the same command alone would not do."""

    def __init__(self, message: str, killed: int = 0, again: bool = False, rest: str | None = None):
        super().__init__(message)
        self.killed, self.again, self.rest = killed, again, rest


@dataclass
class Recovery:
    """What a backend says to do with the cases of a lost batch (and, for a local pool, of
    every batch in flight)."""

    again: list = field(default_factory=list)  # run again in batches, first
    alone: list = field(default_factory=list)  # run again one at a time, with nothing else in flight
    failed: list[dict] = field(default_factory=list)  # results: cases that killed their worker every time
    lost: list = field(default_factory=list)  # not computed (a later command computes them)
    reason: str | None = None  # why, when it is not the error's own message
    all_inflight: bool = False  # covers every batch in flight: none of them will answer
    stop: bool = False  # give up: nothing more runs


def killed_result(key: str, message: str) -> dict:
    """A case that killed the workers it ran on: failed in cases.csv, but not kept in the store:
    the sweep counts as incomplete, and the same command (after a fix: more memory per worker)
    tries the case again, within the same bound."""
    return {"key": key, "rbhyst_version": __version__, "status": "failed", "message": message, "killed": True}


#: the TLS files: the command line's option and the sweep file's key for each
TLS_FILES = {"ca_file": ("--tls-ca-file", "cluster.tls_ca_file"), "cert": ("--tls-cert", "cluster.tls_cert"),
             "key": ("--tls-key", "cluster.tls_key")}


def cluster_settings(cluster, workers: int | None, scheduler: str | None, tls_ca_file=None, tls_cert=None,
                     tls_key=None) -> tuple[str | None, dict | None]:
    """The Dask scheduler a sweep runs on (None: local workers) and its TLS files (None: plain
    tcp://): the command line's (``--scheduler``, ``--tls-*``, each paths relative to the
    working folder), else the sweep file's ``[cluster]`` (``cluster``, paths made absolute);
    ``--workers`` runs locally whatever the file says. Every problem at once (InputError)."""
    problems = []
    given = {"ca_file": tls_ca_file, "cert": tls_cert, "key": tls_key}
    if workers is not None and workers < 1:
        problems.append(f"--workers: {workers} must be at least 1")
    if workers is not None and scheduler is not None:
        problems.append("--workers: not with --scheduler (the cluster's workers run the cases)")
    address, place = (scheduler, "--scheduler") if scheduler is not None else \
        (getattr(cluster, "scheduler", None), "cluster.scheduler")
    if workers is not None or address is None:
        problems.extend(f"{TLS_FILES[k][0]}: only with --scheduler (a Dask scheduler that wants TLS)"
                        for k, v in given.items() if v is not None)
        if problems:
            raise InputError(problems)
        return None, None
    tls: dict[str, Path] = {}
    names: dict[str, str] = {}
    for k, (option, key) in TLS_FILES.items():
        if given[k] is not None:
            tls[k], names[k] = Path(given[k]).absolute(), option
        elif getattr(cluster, f"tls_{k}", None) is not None:
            tls[k], names[k] = Path(getattr(cluster, f"tls_{k}")), key
    for k, p in tls.items():
        if not p.is_file():
            problems.append(f"{names[k]}: {p}: no such file")
    if tls:
        side = 0 if any(v is not None for v in given.values()) else 1
        what = {"ca_file": "the certificate of the CA that signed the scheduler's",
                "cert": "this client's certificate, signed by that CA"}
        problems.extend(f"{TLS_FILES[k][side]}: missing: TLS needs {what[k]}" for k in ("ca_file", "cert")
                        if k not in tls)
        if not address.startswith("tls://"):
            problems.append(f"{place}: {address}: with TLS certificates the address is tls://host:port")
    elif address.startswith("tls://"):
        problems.append(f"{place}: {address}: needs its TLS files: --tls-ca-file, --tls-cert and --tls-key (or "
                        "tls_ca_file, tls_cert and tls_key in the sweep file's [cluster])")
    if problems:
        raise InputError(problems)
    return address, tls or None


def default_workers() -> int:
    from rbhyst.cores import usable_cores

    return usable_cores()


class LocalPool:
    """``workers`` processes started with 'spawn' (a fresh interpreter each: no copy of this
    process's threads or locks, which numba and the progress bar hold), each loading the
    compiled kernels once.

    A pool whose worker dies cannot go on: it is started anew and every batch in flight runs
    again. Each worker shows on a board which batch it runs, so a death is pinned on its batch
    (a worker that ended by itself, not by the pool's SIGTERM). A case whose worker died twice
    runs again alone (one case, nothing else in flight); a case that kills its worker ``KILLS``
    times alone is failed. Deaths pinned on no batch end the sweep after ``MAX_RESTARTS``."""

    KILLS = 3
    MAX_RESTARTS = 3

    def __init__(self, workers: int, base, histories: bool):
        import multiprocessing

        self.workers = workers
        self.slots = 2 * workers  # a batch waiting for each worker: no worker idles between batches
        self.where = f"{workers} local worker{'s' * (workers != 1)}"
        self._base, self._histories = base, histories
        self._ctx = multiprocessing.get_context("spawn")
        self._ids = itertools.count(1)
        self._batch: dict[object, int] = {}  # future -> batch number on the board
        self.deaths: dict[str, int] = {}  # case key -> deaths of a worker running it
        self.alone_deaths: dict[str, int] = {}  # case key -> deaths while it ran alone
        self.restarts = 0  # deaths pinned on no batch
        self._start()

    def _start(self) -> None:
        self._board = self._ctx.Array("q", 2 * self.workers, lock=False)
        self._taken = self._ctx.Value("i", 0)
        self._pool = cf.ProcessPoolExecutor(self.workers, mp_context=self._ctx, initializer=init_local_worker,
                                            initargs=(self._board, self._taken))

    def submit(self, cases):
        n = next(self._ids)
        try:
            f = self._pool.submit(run_tracked, n, run_batch, self._base, cases, self._histories)
        except cf.process.BrokenProcessPool as err:
            # a worker died since the last wait (the pool learns it in a thread of its own): the
            # batch is lost with those in flight, and recover() sorts them out together (raised
            # here, it ended the sweep with a traceback)
            f = cf.Future()
            f.set_exception(err)
        self._batch[f] = n
        return f

    def wait(self, fs, timeout: float):
        done, _ = cf.wait(fs, timeout=timeout, return_when=cf.FIRST_COMPLETED)
        return done

    def result(self, f) -> list[dict]:
        try:
            results = f.result()
        except cf.process.BrokenProcessPool as err:
            raise WorkerLost(f"a worker process died ({err})") from None
        self._batch.pop(f, None)
        return results

    def recover(self, err: WorkerLost, f, batch, inflight: dict, alone: bool) -> Recovery:
        """After a death: a new pool, and every batch in flight run again, but the cases of the
        batch the dead worker ran, as the class says."""
        procs = dict(getattr(self._pool, "_processes", None) or {})
        early = {pid for pid, p in procs.items() if p.exitcode is not None}
        self.close(kill=True)
        codes = {pid: p.exitcode for pid, p in procs.items()}
        dead = {pid: c for pid, c in codes.items() if c is not None and c != -signal.SIGTERM}
        if not dead and len(early) == 1:  # a worker SIGTERMed from outside, before the pool ended the rest
            dead = {pid: codes[pid] for pid in early}
        board = list(self._board)
        running = {board[i + 1]: board[i] for i in range(0, len(board), 2) if board[i + 1]}
        ids = {f: self._batch.pop(f, None), **{g: self._batch.pop(g, None) for g in inflight}}
        r = Recovery(all_inflight=True)
        pinned = False
        for g, cases in [(f, batch), *inflight.items()]:
            pid = running.get(ids[g])
            if pid not in dead:
                r.again.extend(cases)
                continue
            pinned = True
            for case in cases:
                key = case[0]
                self.deaths[key] = self.deaths.get(key, 0) + 1
                if alone and len(cases) == 1:
                    self.alone_deaths[key] = n = self.alone_deaths.get(key, 0) + 1
                    if n >= self.KILLS:
                        r.failed.append(killed_result(key, f"killed its worker process {n} times "
                                                           f"({_how(dead[pid])})"))
                        continue
                (r.alone if self.deaths[key] >= 2 else r.again).append(case)
        if not pinned:
            self.restarts += 1
            if self.restarts > self.MAX_RESTARTS:
                r.stop = True
                r.lost = [c for _, cases in [(f, batch), *inflight.items()] for c in cases]
                r.again = []
                r.reason = f"worker processes died {self.restarts} times, none of them running a case"
                return r
        self._start()
        return r

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
            # a worker ended while it sent a result leaves part of a message in the result pipe,
            # and the pool's manager thread waits for the rest forever (shutdown would join it
            # forever): with every worker gone, closing this process's end of the pipe gives
            # the reader end-of-file instead, and the manager ends as for a broken pool
            if all(not p.is_alive() for p in procs):
                writer = getattr(getattr(pool, "_result_queue", None), "_writer", None)
                if writer is not None:
                    writer.close()
        pool.shutdown(wait=True, cancel_futures=True)
        del pool
        # the pool's queues hold semaphores that only their finalizers release, and so does
        # the lock of the workers' count (taken): the command ends without the interpreter's
        # teardown, and multiprocessing's resource tracker warned about what was left at its
        # end ("1 leaked semaphore", after every sweep that drew its plots)
        self._taken = None
        gc.collect()


def _how(code: int) -> str:
    """How a worker process ended, from its exit code."""
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        return f"{name}: out of memory?" if -code == signal.SIGKILL else name
    return f"exit code {code}"


class DaskCluster:
    """The batches as tasks on an existing Dask distributed cluster (``dask scheduler`` and
    ``dask worker``), over TLS when ``tls`` gives the certificates (ca_file, cert, key).

    Dask reruns a task whose worker died on other workers, and gives up after its
    ``distributed.scheduler.allowed-failures`` (KilledWorker): the batch's cases then run
    again alone (one case, nothing else in flight), and a case that kills its workers alone
    is failed. Batches lost with the connection to the scheduler run again once the client
    has reconnected; a scheduler that stays unreachable for ``LOST_AFTER_S`` ends the sweep
    (the cases not computed are missing)."""

    #: seconds the client tries to reach the scheduler, at the start and after losing it; None:
    #: Dask's own distributed.comm.timeouts.connect (30 s unless configured)
    LOST_AFTER_S: float | None = None

    def __init__(self, address: str, base, histories: bool, tls: dict | None = None):
        try:
            import dask
            from distributed import Client
            from dask.utils import parse_timedelta
        except ImportError:
            raise InputError('--scheduler: needs Dask distributed: pip install "rbhyst[dask]"') from None
        lost = self.LOST_AFTER_S
        if lost is None:
            lost = parse_timedelta(dask.config.get("distributed.comm.timeouts.connect"), default="s")
        self.lost_after = float(lost)
        security = None
        if tls:
            from distributed.security import Security

            security = Security(tls_ca_file=str(tls["ca_file"]), tls_client_cert=str(tls["cert"]),
                                tls_client_key=str(tls["key"]) if tls.get("key") else None,
                                require_encryption=True)
        self.address = address
        try:
            self.client = Client(address, timeout=self.lost_after, security=security, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as err:
            raise InputError(f"--scheduler: cannot reach {address} ({_plain(err)})"
                             + ("" if tls or not address.startswith("tcp://") else
                                "; a scheduler that wants TLS needs tls:// and --tls-ca-file, --tls-cert, --tls-key")
                             ) from None
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
        if self.client.status != "running":  # it would never reach the scheduler
            return _Unsent()
        return self.client.submit(run_batch, self._base, cases, self._histories, pure=False)

    def wait(self, fs, timeout: float):
        # (distributed.wait needs a default client, which a library should not set)
        end = time.monotonic() + timeout
        while True:
            self._check_connected()
            if self.client.status == "running":
                done = {f for f in fs if f.done()}
                # while the client reconnects its futures are cancelled: they are run again
                # once it is back (or the sweep ends), not taken for lost cases now
                if done and self.client.status == "running":
                    return done
            if time.monotonic() >= end:
                return set()
            time.sleep(0.005)

    def _check_connected(self) -> None:
        status = self.client.status
        if status == "running":
            self._unreachable_since = None
            return
        now = time.monotonic()
        self._unreachable_since = self._unreachable_since or now
        # the client gives up reconnecting after lost_after and closes; a margin for its own timing
        if status not in ("connecting", "newly-created") or now - self._unreachable_since > self.lost_after + 5:
            raise WorkerLost(f"lost the Dask scheduler (no connection for {self.lost_after:g} s)",
                             rest="the same command with a running scheduler (--scheduler) computes the rest")

    def result(self, f) -> list[dict]:
        if isinstance(f, _Unsent):
            raise WorkerLost("the connection to the scheduler was lost", again=True)
        try:
            return f.result()
        except Exception as err:  # KilledWorker, CancelledError, a closed connection ...
            killed = getattr(err, "allowed_failures", None) if type(err).__name__ == "KilledWorker" else None
            if killed is not None:
                raise WorkerLost(f"KilledWorker: the batch killed {killed + 1} workers", killed=killed + 1) from None
            if getattr(err, "reason", None) == "scheduler-connection-lost" or self.client.status != "running":
                raise WorkerLost("the connection to the scheduler was lost", again=True) from None
            if type(err).__name__ == "CommClosedError":  # (distributed.comm): the result's connection
                # reset as the scheduler or a worker went, between the wait and the gather
                raise WorkerLost(f"a connection of the cluster was lost ({_plain(err)})", again=True) from None
            raise WorkerLost(_plain(err)) from None

    def recover(self, err: WorkerLost, f, batch, inflight: dict, alone: bool) -> Recovery:
        if err.again:
            return Recovery(again=list(batch))
        if err.killed:
            if alone and len(batch) == 1:
                return Recovery(failed=[killed_result(batch[0][0], f"killed its worker {err.killed} times "
                                                      "(Dask KilledWorker: out of memory? see the workers' logs)")])
            return Recovery(alone=list(batch))  # which of its cases? each alone says
        return Recovery(lost=list(batch))

    def close(self, kill: bool = False, pending=()) -> None:
        try:
            pending = [f for f in pending if not isinstance(f, _Unsent)]
            if kill and pending:
                self.client.cancel(pending)
        except Exception:  # a cluster that is gone has nothing left to cancel
            pass
        finally:
            self.client.close()


class _Unsent:
    """A batch submitted while the client was reconnecting: run it again once it is back."""

    def done(self) -> bool:
        return True


def _plain(err: BaseException) -> str:
    """An exception as one line: its class and its first line."""
    text = str(err).strip().splitlines()
    return f"{err.__class__.__name__}: {text[0]}" if text else err.__class__.__name__
