"""From an isolator catalogue to a VRM set: the effective (secant) stiffness and equivalent damping a
maker gives at a few deflections (rbhyst.model.effective), and optionally static load-deflection
points, matched by a symmetric set.

A catalogue CSV has a header and one row per deflection, SI columns by name (any order, ``#``
comments):

* ``amplitude_m``: the deflection amplitude of the cycle (or of the static point);
* ``k_eff_N_m`` and ``beta_eff``: the cycle's effective stiffness and equivalent damping ratio;
* ``force_N`` (optional): the static force at that deflection on first loading from rest (a point
  of a monotonic load-deflection curve). A row may give the cycle, the static force, or both; a
  whole load-deflection curve is so many rows of ``amplitude_m, force_N``.

At least two cycle rows. The set fitted is symmetric, f(-u) = -f(u) (a catalogue gives one value
per deflection, not one per direction): the unloading branch mirrors the loading one (kb, f0,
alpha, gamma1, gamma2 equal; beta1, beta2, gamma3 of opposite sign). The free parameters (default
kb, f0, alpha) minimise the relative misfits of k_eff, beta_eff and force_N by
``scipy.optimize.least_squares`` from the --init set and random starts about it.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rbhyst.errors import AnalysisError, InputError
from rbhyst.model.effective import MAX_SETTLING, effective, settling_cycles
from rbhyst.model.hysteresis import PARAMS
from rbhyst.model.vrm import loop

COLUMNS = ("amplitude_m", "k_eff_N_m", "beta_eff", "force_N")
#: the free parameters by default: the three every set has
DEFAULT_FREE = ("kb", "f0", "alpha")
#: a catalogue is matched when every row's k_eff, beta_eff and force_N are within this (relative)
MATCHED = 0.02
#: the unloading branch of a symmetric set: each loading parameter times this sign
MIRROR = np.array([1.0, 1.0, 1.0, -1.0, -1.0, 1.0, 1.0, -1.0])
#: parameters kept positive (fitted by their logarithm)
POSITIVE = ("f0", "alpha", "gamma2")


@dataclass(frozen=True)
class Row:
    line: int  # in the file (1-based)
    amplitude: float
    k_eff: float | None
    beta_eff: float | None
    force: float | None


@dataclass(frozen=True)
class Catalogue:
    name: str
    rows: tuple[Row, ...]

    @property
    def cycles(self) -> list[Row]:
        return [r for r in self.rows if r.k_eff is not None]

    @property
    def static(self) -> list[Row]:
        return [r for r in self.rows if r.force is not None]


def read_catalogue(path: Path) -> Catalogue:
    """The catalogue at ``path``, or InputError with one line per problem (file and line)."""
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot be read ({exc.__class__.__name__}: {exc})") from None
    lines = [(i, ln) for i, ln in enumerate(text.splitlines(), start=1) if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise InputError(f"{path}: empty; a header amplitude_m, k_eff_N_m, beta_eff (and optionally force_N) and rows")
    head_line, head = lines[0]
    names = [h.strip() for h in next(csv.reader([head]))]
    problems = [f"{path}:{head_line}: column {n!r}: not one of {', '.join(COLUMNS)}" for n in names if n not in COLUMNS]
    if "amplitude_m" not in names:
        problems.append(f"{path}:{head_line}: no amplitude_m column")
    if not problems and ("k_eff_N_m" in names) != ("beta_eff" in names):  # (a misspelt one is said above)
        problems.append(f"{path}:{head_line}: k_eff_N_m and beta_eff go together (a cycle has both)")
    if problems:
        raise InputError(problems)
    rows = []
    for number, ln in lines[1:]:
        row, said = _row(path, number, names, next(csv.reader([ln])))
        problems += said
        if row is not None:
            rows.append(row)
    cat = Catalogue(Path(path).name, tuple(rows))
    if not problems and len(cat.cycles) < 2:
        problems.append(f"{path}: {len(cat.cycles)} row(s) with k_eff_N_m and beta_eff; at least 2 are needed")
    if problems:
        raise InputError(problems)
    return cat


def _row(path, number: int, names: list[str], cells: list[str]) -> tuple[Row | None, list[str]]:
    where = f"{path}:{number}"
    if len(cells) != len(names):
        return None, [f"{where}: {len(cells)} values for {len(names)} columns"]
    values, problems = {}, []
    for name, cell in zip(names, cells):
        cell = cell.strip()
        if not cell:
            values[name] = None
            continue
        try:
            x = float(cell)
        except ValueError:
            problems.append(f"{where}: {name}: {cell!r} is not a number")
            continue
        if not math.isfinite(x) or (x <= 0 and name != "force_N") or (name == "beta_eff" and x >= 1):
            limits = "a number > 0" if name != "beta_eff" else "a damping ratio, 0 < beta_eff < 1"
            problems.append(f"{where}: {name}: {cell}: {limits}" if name != "force_N" or not math.isfinite(x)
                            else f"{where}: {name}: {cell}: a finite force")
            continue
        values[name] = x
    if problems:
        return None, problems
    if values.get("amplitude_m") is None:
        return None, [f"{where}: amplitude_m: missing"]
    if (values.get("k_eff_N_m") is None) != (values.get("beta_eff") is None):
        return None, [f"{where}: k_eff_N_m and beta_eff go together (a cycle has both)"]
    if values.get("k_eff_N_m") is None and values.get("force_N") is None:
        return None, [f"{where}: neither a cycle (k_eff_N_m, beta_eff) nor a static force_N"]
    return Row(number, values["amplitude_m"], values.get("k_eff_N_m"), values.get("beta_eff"),
               values.get("force_N")), []


# --------------------------------------------------------------------------- the fit


def symmetric(loading: np.ndarray) -> np.ndarray:
    """The (2, 8) set whose loop is odd, f(-u) = -f(u), from the 8 loading parameters."""
    return np.vstack([loading, loading * MIRROR]) + 0.0  # (no -0.0 in a deck)


def static_force(p: np.ndarray, d: float) -> float:
    """The force at deflection d on first loading from rest (the virgin branch, eq. 14)."""
    return float(loop(p, np.array([0.0, d]))[0][-1])


def model_rows(p: np.ndarray, cat: Catalogue) -> list[dict]:
    """What set ``p`` gives for every catalogue row (k_eff, beta_eff on its steady cycle, force_N)."""
    out = []
    for r in cat.rows:
        row = {"line": r.line, "amplitude_m": r.amplitude}
        if r.k_eff is not None:
            e = effective(p, r.amplitude)
            row.update(k_eff_N_m=e.k_eff, beta_eff=e.beta_eff, energy_J=e.energy)
        if r.force is not None:
            row["force_N"] = static_force(p, r.amplitude)
        out.append(row)
    return out


def misfits(p: np.ndarray, cat: Catalogue) -> np.ndarray:
    """Relative misfits (model - catalogue) / catalogue of every value the catalogue gives."""
    out = []
    for r, m in zip(cat.rows, model_rows(p, cat)):
        if r.k_eff is not None:
            out += [(m["k_eff_N_m"] - r.k_eff) / r.k_eff, (m["beta_eff"] - r.beta_eff) / r.beta_eff]
        if r.force is not None:
            out.append((m["force_N"] - r.force) / abs(r.force) if r.force != 0 else m["force_N"])
    return np.array(out)


@dataclass
class CatalogueFit:
    p: np.ndarray  # (2, 8)
    free: list[str]
    worst: float  # largest |relative misfit|
    rows: list[dict]  # catalogue and model per row, with the misfits
    nfev: int
    starts: list[dict] = field(default_factory=list)

    @property
    def matched(self) -> bool:
        return self.worst <= MATCHED


def _scales(cat: Catalogue) -> dict[str, float]:
    """The size of each parameter for this catalogue: stiffness K (the median k_eff), deflection
    A (the largest amplitude), force K A."""
    k = float(np.median([r.k_eff for r in cat.cycles]))
    a = max(r.amplitude for r in cat.rows)
    return {"kb": k, "f0": k * a, "alpha": 1.0 / a, "beta1": k * a, "beta2": 1.0 / a, "gamma1": k * a,
            "gamma2": 1.0 / a, "gamma3": a}


def fit_catalogue(p0: np.ndarray, cat: Catalogue, free=DEFAULT_FREE, starts: int = 6, seed: int = 0) -> CatalogueFit:
    """The symmetric set nearest the catalogue (least squares of the relative misfits) from the
    loading branch of ``p0`` and ``starts - 1`` random starts about it; AnalysisError where no
    start gives a set that can run every row's cycle."""
    from scipy.optimize import least_squares

    free = [n for n in PARAMS if n in free]
    cols = [PARAMS.index(n) for n in free]
    size = _scales(cat)
    base = np.array(p0[0], dtype=float)
    for n in POSITIVE:  # a start needs them > 0 to take their logarithm
        i = PARAMS.index(n)
        if n in free and not base[i] > 0:
            base[i] = size[n]

    def to_x(loading):
        return np.array([math.log(loading[c] / size[n]) if n in POSITIVE else loading[c] / size[n]
                         for n, c in zip(free, cols)])

    def to_p(x):
        loading = base.copy()
        for v, n, c in zip(x, free, cols):
            loading[c] = math.exp(min(v, 50.0)) * size[n] if n in POSITIVE else v * size[n]
        return symmetric(loading)

    n_res = 2 * len(cat.cycles) + len(cat.static)

    smallest = min(r.amplitude for r in cat.cycles)

    def residuals(x):
        p = to_p(x)
        if settling_cycles(p, smallest) >= MAX_SETTLING:  # alpha A ~ 0: no loop a catalogue measured
            return np.full(n_res, 1e3)
        try:
            r = misfits(p, cat)
        except (OverflowError, ValueError):
            return np.full(n_res, 1e3)
        return np.where(np.isfinite(r), r, 1e3)

    rng = np.random.default_rng(seed)
    x0 = to_x(base)
    candidates = [x0] + [x0 + rng.normal(0.0, 0.7, x0.size) for _ in range(max(0, starts - 1))]
    best, log, nfev = None, [], 0
    for k, xs in enumerate(candidates, start=1):
        res = least_squares(residuals, xs, method="lm" if x0.size <= n_res else "trf", xtol=1e-12, ftol=1e-12,
                            max_nfev=200 * (x0.size + 1))
        nfev += int(res.nfev)
        worst = float(np.max(np.abs(res.fun)))
        log.append({"start": k, "worst_misfit": worst, "status": int(res.status)})
        if worst < 1e3 and (best is None or worst < best[0]):
            best = (worst, res.x)
    if best is None:
        raise AnalysisError(f"calibration failed: none of {len(candidates)} starts gave a set that runs every cycle "
                            "of the catalogue; try another --init")
    p = to_p(best[1])
    return CatalogueFit(p, free, best[0], compare(p, cat), nfev, log)


def compare(p: np.ndarray, cat: Catalogue) -> list[dict]:
    """Per row: the catalogue's values, the set's, and their relative misfits."""
    out = []
    for r, m in zip(cat.rows, model_rows(p, cat)):
        row = {"line": r.line, "amplitude_m": r.amplitude}
        for key, given in (("k_eff_N_m", r.k_eff), ("beta_eff", r.beta_eff), ("force_N", r.force)):
            if given is not None:
                row[key] = {"catalogue": given, "set": m[key], "misfit": (m[key] - given) / abs(given)}
        if "energy_J" in m:
            row["energy_J"] = m["energy_J"]
        out.append(row)
    return out


def parse_free(tokens) -> list[str]:
    """--free for a catalogue: names of the 8 parameters (the set stays symmetric)."""
    out = []
    for token in tokens:
        for name in (t.strip() for t in token.split(",")):
            if not name:
                continue
            if name not in PARAMS:
                raise InputError(f"--free: {name!r}: with --catalogue the set is symmetric; give parameters "
                                 f"without a branch: {', '.join(PARAMS)}")
            out += [name] if name not in out else []
    return out
