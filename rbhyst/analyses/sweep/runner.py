"""run_sweep: the cases a results folder does not hold yet, in batches on local workers or a
Dask cluster, each batch kept as it comes back; then cases.csv, stats.csv, sweep.json, plots
and (optionally) histories.parquet, written together under the rules of rbhyst.files.outdir."""

from __future__ import annotations

import json
import math
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from rbhyst._version import __version__
from rbhyst.errors import DiskFull, InputError
from rbhyst.files.outdir import MANIFEST, read_manifest, staged_directory
from rbhyst.analyses.sweep.backends import WorkerLost
from rbhyst.analyses.sweep.cases import Sweep
from rbhyst.analyses.sweep.store import Journal
from rbhyst.analyses.sweep.tables import (PERCENTILE, CaseRows, cases_table, peak_cells, write_case_rows,
                                          write_stats)
from rbhyst.analyses.sweep.uptodate import OUTPUT_FILES, OUTPUTS_SUM, outputs_sum, standing

#: the files a sweep writes into its folder (beside its own .rbhyst-sweep/)
CASES_CSV, STATS_CSV, SWEEP_JSON, HISTORIES_FILE = "cases.csv", "stats.csv", "sweep.json", "histories.parquet"
#: a batch is sized to take about this long on a worker (once a case's cost is known)
BATCH_S = 0.5


class SweepIncomplete(Exception):
    """Some cases could not be computed (a worker or the cluster lost); the rest are kept."""

    def __init__(self, message: str, outcome: "Outcome"):
        super().__init__(message)
        self.outcome = outcome


@dataclass
class Outcome:
    """What a sweep did: the results by key, and how long it took."""

    sweep: Sweep
    out: Path
    results: dict[str, dict] = field(default_factory=dict)
    computed: int = 0  # cases run by this call
    reused: int = 0  # cases the folder held already
    missing: list[str] = field(default_factory=list)  # keys lost with a worker
    missing_reason: str = ""
    notes: list[str] = field(default_factory=list)  # said before the cases run
    missing_rest: str = "the same command computes the rest"  # how they can be computed
    where: str = ""
    t_start: float = 0.0
    t_first: float | None = None  # when the first batch came back (a worker started and ran it)
    t_end: float = 0.0
    n_first: int = 0  # cases in that batch
    elapsed_s: list[float] = field(default_factory=list)  # per computed case, in its worker
    wall_s: list[float] = field(default_factory=list)  # per computed case: analysis.wall_s
    written: bool = False  # the files written by this call (not: they stood as an earlier call wrote them)

    @property
    def failed(self) -> int:
        return sum(1 for c in self.sweep.cases if c.problem or self.results.get(c.key, {}).get("status") == "failed")

    @property
    def ok(self) -> int:
        return sum(1 for c in self.sweep.cases if not c.problem and self.results.get(c.key, {}).get("status") == "ok")

    @property
    def killed(self) -> list[int]:
        """The numbers of the cases that killed their workers (failed, not kept: incomplete)."""
        return [c.number for c in self.sweep.cases if self.results.get(c.key, {}).get("killed")]

    def table(self) -> tuple[list[str], list[list]]:
        """cases.csv's header and rows (each a list of its cells)."""
        header, rows = self.case_rows()
        return header, list(rows)

    def case_rows(self) -> tuple[list[str], CaseRows]:
        """cases.csv's header and rows, each row held as its line of text (tables.CaseRows)."""
        return cases_table(self.sweep.cases, self.sweep.vary_keys, self.results)


Progress = Callable[[int, int, int], None]  # (cases done, of which failed, cases to compute)


def final_files(save_histories: bool, plotter=None, fragility: bool = False) -> list[str]:
    names = [CASES_CSV, STATS_CSV, SWEEP_JSON]
    if save_histories:
        names.append(HISTORIES_FILE)
    if plotter is not None:
        names.extend(plotter.PLOT_FILES)
    if fragility:
        from rbhyst.analyses.fragility import files

        names.extend(files(plotter is not None))
    return names


def check_out(out: Path, names: list[str]) -> None:
    """Before anything runs: the folder's files rbhyst would write are rbhyst's or absent."""
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: exists and is not a folder; choose another output folder")
    if not out.exists():
        return
    owned = read_manifest(out)
    problems = [f"{out}: {n} exists and rbhyst did not write it (not listed in {MANIFEST}); rbhyst will not "
                "overwrite it: move it away or choose another output folder"
                for n in names if ((out / n).exists() or (out / n).is_symlink()) and n not in owned.files]
    if problems:
        raise InputError(problems)


def run_sweep(sweep: Sweep, out: str | Path | None = None, workers: int | None = None,
              scheduler: str | None = None, fresh: bool = False, save_histories: bool = False,
              plots: bool = True, progress: Progress | None = None,
              started: Callable[["Outcome", int], None] | None = None, tls_ca_file: str | Path | None = None,
              tls_cert: str | Path | None = None, tls_key: str | Path | None = None, plotter=None,
              redraw: bool = False) -> Outcome:
    """Compute what ``out`` (default results/<sweep stem>/ beside the sweep file) does not hold
    yet and write the sweep's files. Raises SweepIncomplete when cases were lost with a worker
    or the cluster (what finished is kept: the same call computes the rest).

    ``started(outcome, n)`` is called once the folder is checked and the workers are ready
    to compute ``n`` cases (0: the folder holds them all); ``progress(done, failed, n)`` as
    batches come back. ``plots`` are drawn by ``plotter`` (``PLOT_FILES``, ``write_plots``:
    rbhyst.report.sweep, which rbhyst.sweep.run_sweep gives).

    ``scheduler`` and the ``tls_*`` files (a scheduler that wants TLS) default to the sweep
    file's ``[cluster]``; ``workers`` runs locally whatever the file says. A call that computes
    nothing leaves the files as they are where they stand as an earlier call wrote them from the
    same cases (rbhyst.analyses.sweep.uptodate), unless ``redraw``."""
    if plots and plotter is None:
        raise TypeError("plots need a plotter (rbhyst.report.sweep): call rbhyst.sweep.run_sweep")
    plotter = plotter if plots else None
    from rbhyst.analyses.sweep.backends import DaskCluster, LocalPool, cluster_settings, default_workers

    out = Path(out) if out is not None else sweep.default_out()
    scheduler, tls = cluster_settings(sweep.cluster, workers, scheduler, tls_ca_file, tls_cert, tls_key)
    if save_histories:
        from rbhyst.analyses.sweep.histories import require_pyarrow

        require_pyarrow()
    check_out(out, final_files(save_histories, plotter, sweep.fragility is not None))
    journal = Journal(out, fresh=fresh)
    outcome = Outcome(sweep, out, t_start=time.perf_counter())
    todo = _still_to_compute(sweep, journal, save_histories, outcome)
    outcome.reused = sum(1 for c in sweep.cases if c.key in outcome.results)
    # a scheduler that cannot be reached (or refuses the certificates) is an input error: before
    # the journal is made, so that nothing is written
    backend = DaskCluster(scheduler, sweep.base, save_histories, tls=tls) if todo and scheduler is not None else None
    try:
        try:
            journal.open()
        except BaseException:
            if backend is not None:
                backend.close()
            raise
        if not todo and started:
            started(outcome, 0)
        if todo:
            if backend is None:
                backend = LocalPool(min(workers or default_workers(), len(todo)), sweep.base, save_histories)
            outcome.where = backend.where
            if started:
                started(outcome, len(todo))
            _compute(backend, list(todo.items()), journal, outcome, save_histories, progress)
        outcome.t_end = time.perf_counter()
        if outcome.missing:
            n = len(outcome.missing)
            raise SweepIncomplete(f"{n} case{'s' * (n != 1)} could not be computed on {outcome.where}: "
                                  f"{outcome.missing_reason}; the {len(outcome.results)} finished are kept in "
                                  f"{journal.folder}: {outcome.missing_rest}", outcome)
        made = _made_from(outcome, save_histories, plotter)
        if todo or redraw or not standing(out, journal.path, made[0]):
            _write(outcome, journal, save_histories, plotter, made)
            outcome.written = True
    finally:
        journal.close()
    return outcome


def _still_to_compute(sweep: Sweep, journal: Journal, save_histories: bool, outcome: Outcome) -> dict[str, dict]:
    """The cases the store does not vouch for (key -> values); those it does go into
    ``outcome.results``, and a note names those it could not vouch for."""
    todo: dict[str, dict] = {}
    untrusted = list(journal.damaged)  # (key, why); the key None where too little of a line is left
    for c in sweep.cases:
        if c.problem is not None or c.key in todo:
            continue
        e = journal.entries.get(c.key)
        if e is not None and save_histories and e.get("status") == "ok":
            why = journal.history_problem(c.key)
            if why not in (None, "not kept"):
                untrusted.append((c.key, why))
            if why is not None:
                e = None
        if e is not None:
            outcome.results[c.key] = e
        else:
            todo[c.key] = c.values
    outcome.notes.extend(damage_notes(sweep, untrusted))
    return todo


def _made_from(outcome: Outcome, save_histories: bool, plotter) -> tuple[str, tuple, dict]:
    """(the sha256 of what the files are made from, cases.csv's header and rows, the varied
    keys' units): what a finished sweep compares with its sweep.json before writing again."""
    table = outcome.case_rows()
    units = _vary_units(outcome.sweep)
    return outputs_sum(outcome, table, units, save_histories, plotter is not None), table, units


def _compute(backend, todo: list[tuple[str, dict]], journal: Journal, outcome: Outcome,
             save_histories: bool, progress: Progress | None) -> None:
    """Run the cases in batches on the backend, keeping each as it comes back. Long because it
    is one scheduling loop: its queue, the batches in flight and the recovery after a lost
    worker share their state."""
    queue = deque(todo)
    solo: deque = deque()  # cases whose worker died: each runs alone, so that a death names its case
    inflight: dict[object, list[tuple[str, dict]]] = {}
    alone: set = set()  # the future of a case running alone
    done = failed = 0
    per_case: float | None = None  # seconds a case takes in a worker
    killed = False
    if progress:
        progress(0, 0, len(todo))

    def lose(err: WorkerLost, reason: str | None = None) -> None:
        outcome.missing_reason = reason or str(err)
        outcome.missing_rest = err.rest or outcome.missing_rest

    try:
        while queue or solo or inflight:
            if solo and not inflight:
                case = solo.popleft()
                f = backend.submit([case])
                inflight[f] = [case]
                alone.add(f)
            while queue and not solo and not alone and len(inflight) < backend.slots:
                n = batch_size(len(queue), backend.workers, per_case)
                batch = [queue.popleft() for _ in range(n)]
                f = backend.submit(batch)
                inflight[f] = batch
            try:
                finished = backend.wait(inflight, 0.2)
            except WorkerLost as err:
                lose(err)
                outcome.missing.extend(k for b in inflight.values() for k, _ in b)
                outcome.missing.extend(k for k, _ in [*solo, *queue])
                return
            for f in finished:
                batch = inflight.pop(f)
                try:
                    results = backend.result(f)
                except WorkerLost as err:
                    r = backend.recover(err, f, batch, inflight, f in alone)
                    alone.discard(f)
                    lose(err, r.reason)
                    if r.all_inflight:  # none of them will answer: r says what to run again
                        inflight.clear()
                        alone.clear()
                    queue.extendleft(reversed(r.again))
                    solo.extend(r.alone)
                    if r.failed:
                        _keep(r.failed, journal, outcome, save_histories)
                        done += len(r.failed)
                        failed += len(r.failed)
                        if progress:
                            progress(done, failed, len(todo))
                    outcome.missing.extend(k for k, _ in r.lost)
                    if r.stop:
                        outcome.missing.extend(k for b in inflight.values() for k, _ in b)
                        outcome.missing.extend(k for k, _ in [*solo, *queue])
                        inflight.clear()
                        solo.clear()
                        queue.clear()
                        return
                    if r.all_inflight:
                        break
                    continue
                alone.discard(f)
                _keep(results, journal, outcome, save_histories)
                if outcome.t_first is None:
                    outcome.t_first = time.perf_counter()
                    outcome.n_first = len(batch)
                done += len(results)
                failed += sum(r["status"] != "ok" for r in results)
                costs = [r["elapsed_s"] for r in results if "elapsed_s" in r]
                outcome.elapsed_s.extend(costs)
                outcome.wall_s.extend(r["wall_s"] for r in results if "wall_s" in r)
                if outcome.elapsed_s:
                    per_case = sum(outcome.elapsed_s[-200:]) / len(outcome.elapsed_s[-200:])
                if progress:
                    progress(done, failed, len(todo))
    except BaseException:  # Ctrl-C, SIGTERM, a bug: end the workers now, keep what is written
        killed = True
        backend.close(kill=True, pending=list(inflight))
        raise
    finally:
        if not killed:
            backend.close()


def damage_notes(sweep: Sweep, untrusted: list[tuple[str | None, str]], shown: int = 5) -> list[str]:
    """One line naming the stored cases that could not be trusted (they are computed again),
    by their numbers in cases.csv and why; damaged lines of cases no longer in the sweep are
    counted only."""
    numbers = {c.key: c.number for c in sweep.cases}
    named = sorted((numbers[k], why) for k, why in untrusted if k in numbers)
    other = sum(1 for k, _ in untrusted if k not in numbers)
    if not named and not other:
        return []
    parts = [f"case {n} ({why})" for n, why in named[:shown]]
    if len(named) > shown:
        parts.append(f"{len(named) - shown} more")
    if other:
        parts.append(f"{other} damaged line{'s' * (other != 1)} of no case of this sweep (set aside)")
    n = len(named)
    return [f"the store could not vouch for {n} finished case{'s' * (n != 1)}, computed again: " + "; ".join(parts)
            if n else f"the store had {'; '.join(parts)}"]


def batch_size(remaining: int, workers: int, per_case: float | None) -> int:
    """Guided batches: a third of each worker's share of what remains, so that batches shrink
    towards the end and no worker waits long for the last one; at most about BATCH_S of work
    (2 cases until a case's cost is known), so that progress shows and an interrupt loses little."""
    n = math.ceil(remaining / (3 * workers))
    cap = 2 if per_case is None else max(1, int(BATCH_S / max(per_case, 1e-6)))
    return max(1, min(n, cap, remaining))


def _keep(results: list[dict], journal: Journal, outcome: Outcome, save_histories: bool) -> None:
    """Write a batch's cases into the journal (and their histories beside it); internal errors
    are reported but not kept, so that the next run tries them again."""
    histories = [(r["key"], r.pop("history")) for r in results if "history" in r]
    if save_histories and histories:
        from rbhyst.analyses.sweep.histories import write_part

        name, tmp = journal.new_history_file()
        with journal.space(tmp):
            write_part(tmp, journal.history_path(name), histories)
        digest = journal.sum_of_history(name)
        for r in results:
            if r["status"] == "ok":
                r["history"], r["history_sha256"] = name, digest
    keep = [r for r in results if not (r.get("internal") or r.get("killed"))]
    if keep:
        journal.add(keep)
    for r in results:
        outcome.results[r["key"]] = r
    outcome.computed += len(results)


def _write(outcome: Outcome, journal: Journal, save_histories: bool, plotter, made) -> None:
    try:
        _write_files(outcome, journal, save_histories, plotter, made)
    except DiskFull as err:
        n = len(outcome.results)
        raise DiskFull(err.folder, err.free, "the sweep's tables" + " and plots" * (plotter is not None),
                       f"its {n} case{'s are' if n != 1 else ' is'} kept in {journal.folder}: the same command "
                       "writes them once there is space") from None


def _write_files(outcome: Outcome, journal: Journal, save_histories: bool, plotter, made) -> None:
    sweep = outcome.sweep
    made_from, (header, rows), units = made
    with staged_directory(outcome.out) as tmp:
        write_case_rows(tmp / CASES_CSV, header, rows)
        write_stats(tmp / STATS_CSV, sweep.cases, sweep.vary_keys, outcome.results,
                    known=peak_cells(header, rows, sweep.cases))
        if save_histories:
            from rbhyst.analyses.sweep.histories import assemble

            parts = {c.key: journal.history_path(outcome.results[c.key]["history"]) for c in sweep.cases
                     if c.key in outcome.results and outcome.results[c.key].get("history")}
            assemble(tmp / HISTORIES_FILE, sweep.cases, parts)
        if plotter is not None:
            plotter.write_plots(header, rows, sweep.vary_keys, sweep.scale_kind, tmp, units)
        if sweep.fragility is not None:
            from rbhyst.analyses.fragility import write_fragility

            write_fragility(sweep.fragility, header, rows, tmp, plotter)
        # (last: it lists the files written, itself included, for the next run's up-to-date check)
        files = sorted({p.relative_to(tmp).as_posix() for p in tmp.rglob("*") if p.is_file()} | {SWEEP_JSON})
        about = {**_about(outcome), OUTPUTS_SUM: made_from, OUTPUT_FILES: files}
        (tmp / SWEEP_JSON).write_text(json.dumps(about, indent=2) + "\n", encoding="utf-8")


def _vary_units(sweep) -> dict[str, str | None]:
    """The unit of each vary key, from the first case's deck (a signal's amplitude takes the
    units of its motion)."""
    from rbhyst.model.deck import key_unit

    data = sweep.base.data
    if sweep.cases:
        try:
            data = sweep.base.deck().with_values(sweep.cases[0].values).model_dump(mode="python")
        except InputError:
            pass
    return {k: key_unit(k, data) for k in sweep.vary_keys}


def _about(outcome: Outcome) -> dict:
    sweep = outcome.sweep
    return {
        "rbhyst_version": __version__,
        "sweep": sweep.path.name,
        "deck": sweep.spec.deck,
        "cases": len(sweep.cases),
        "ok": outcome.ok,
        "failed": outcome.failed,
        "computed": outcome.computed,
        "reused": outcome.reused,
        "where": outcome.where or None,
        "wall_s": outcome.t_end - outcome.t_start,
        "motions": sweep.motions,
        "scale": {"kind": sweep.scale_kind, "levels": sweep.levels},
        "vary": sweep.vary_keys,
        "statistics": f"stats.csv over the motions of each scale level and vary combination: mean, median "
                      f"and p84 = numpy.percentile(x, {PERCENTILE:g}) (linear interpolation between order "
                      f"statistics), max",
        **({"fragility": sweep.fragility.about()} if sweep.fragility is not None else {}),
        "case_key": "sha256 of the case's validated deck (without title, output.directory, output.plots), "
                    "each record file replaced by the sha256 of its bytes, and the rbhyst version",
    }
