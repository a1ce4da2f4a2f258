"""Fragility curves from a sweep's cases, by maximum likelihood on the stripes (Baker 2015,
"Efficient analytical fragility function fitting using dynamic structural analysis",
Earthquake Spectra 31(1)).

A limit state names a quantity of each case (a cases.csv column, or + - * / max min abs of
columns and numbers) and a limit; a case reaches it when quantity >= limit. The cases of a
vary combination are grouped into stripes by their intensity measure x (the scale level, the
PGA or Sa of the case's motion), and P(reach | x) = Phi(ln(x / theta) / beta) is fitted by
maximising the binomial likelihood sum_j ln C(n_j, z_j) + z_j ln p_j + (n_j - z_j) ln(1 - p_j).
Confidence intervals and the band come from a seeded bootstrap that resamples the cases
within each stripe. Where the stripes cannot identify a curve (no case reaches the limit,
every case does, one intensity level, stripes that separate), the curve is refused with why.

Expressions are parsed by Python's ``ast`` into a tree of the allowed nodes only and that tree
is walked here: nothing of the user's text is ever executed.
"""

from __future__ import annotations

import ast
import difflib
import functools
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rbhyst.files.csvfile import to_csv

#: the files fragility adds to a sweep's folder (and its plot, with plots)
CSV_FILE, STRIPES_FILE, PLOT_FILE = "fragility.csv", "fragility_stripes.csv", "fragility.png"
#: where fewer bootstrap resamples than this share identify a curve, no interval is given
MIN_IDENTIFIED = 0.5
#: points of the band drawn in fragility.png
BAND_POINTS = 200

# ---------------------------------------------------------------- quantities


_OPS = {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.divide}
_FUNCS = {"max": (2, functools.partial(functools.reduce, np.fmax)),
          "min": (2, functools.partial(functools.reduce, np.fmin)),
          "abs": (1, np.abs)}
_ALLOWED = ("column names (peak_..., stroke_e...) and numbers joined by + - * / and "
            "max(a, b, ...), min(a, b, ...), abs(a)")


@dataclass(frozen=True)
class Quantity:
    """A parsed quantity: the tree of allowed nodes and the column names it reads."""

    text: str
    tree: ast.expr
    names: tuple[str, ...]


def parse_quantity(text: str) -> Quantity:
    """Parse ``text``; a ValueError says what is not allowed."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as err:
        raise ValueError(f"{text!r} is not an expression ({err.msg}); a quantity is {_ALLOWED}") from None
    except (RecursionError, MemoryError, ValueError):
        raise ValueError(f"{text[:40]!r}...: too deeply nested") from None
    names: list[str] = []
    _check(tree.body, names)
    return Quantity(text, tree.body, tuple(dict.fromkeys(names)))


def _check(node: ast.AST, names: list[str]) -> None:
    if isinstance(node, ast.Name):
        if node.id in _FUNCS:
            raise ValueError(f"{node.id} is a function: {node.id}(...)")
        names.append(node.id)
    elif isinstance(node, ast.Constant) and type(node.value) in (int, float) and math.isfinite(node.value):
        pass
    elif isinstance(node, ast.BinOp) and type(node.op) in _OPS:
        _check(node.left, names)
        _check(node.right, names)
    elif isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        _check(node.operand, names)
    elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _FUNCS
          and not node.keywords and not any(isinstance(a, ast.Starred) for a in node.args)):
        least, _ = _FUNCS[node.func.id]
        count = len(node.args)
        if node.func.id == "abs" and count != 1 or count < least:
            want = "one argument" if node.func.id == "abs" else "two arguments or more"
            raise ValueError(f"{node.func.id}() takes {want}, not {count}")
        for a in node.args:
            _check(a, names)
    else:
        shown = ast.unparse(node)
        shown = shown if len(shown) <= 40 else shown[:37] + "..."
        raise ValueError(f"{shown!r} is not allowed: a quantity is {_ALLOWED}")


def evaluate(q: Quantity, columns: dict[str, np.ndarray], n: int) -> np.ndarray:
    """The quantity for ``n`` cases from their columns (NaN where a case has no value)."""

    def ev(node):
        if isinstance(node, ast.Name):
            return columns[node.id]
        if isinstance(node, ast.Constant):
            return float(node.value)
        if isinstance(node, ast.BinOp):
            return _OPS[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.UnaryOp):
            v = ev(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        _, f = _FUNCS[node.func.id]
        args = [ev(a) for a in node.args]
        # a missing value stays missing: fmax/fmin would drop it, so NaN is put back
        missing = functools.reduce(np.logical_or, [np.isnan(np.asarray(a, float)) for a in args])
        return np.where(missing, np.nan, f(args) if node.func.id != "abs" else f(args[0]))

    with np.errstate(all="ignore"):
        out = np.asarray(ev(q.tree), dtype=float)
    out = np.broadcast_to(out, (n,)).copy()
    out[~np.isfinite(out)] = np.nan  # a division by zero: no value
    return out


# ---------------------------------------------------------------- the fit


class NotIdentified(Exception):
    """The stripes cannot identify a median and a dispersion; the message says why."""


def identification_problem(x: np.ndarray, n: np.ndarray, z: np.ndarray, what: str = "intensity") -> str | None:
    """Why stripes (intensity x, cases n, cases reaching the limit z; n > 0) cannot identify a
    lognormal curve, or None. Where the cases that do not reach the limit all lie at or below
    those that do, the likelihood grows without bound as beta -> 0: no finite fit exists."""
    big, total = int(z.sum()), int(n.sum())
    if total == 0:
        return "no case gave a value"
    span = f"{what} {x.min():.4g}" + (f" to {x.max():.4g}" if len(x) > 1 else "")
    if big == 0:
        return f"no case reaches the limit (0 of {total}, {span}): the median lies above every intensity run"
    if big == total:
        return f"every case reaches the limit ({total} of {total}, {span}): the median lies below every intensity run"
    if len(x) == 1:
        return (f"one intensity level ({what} {x[0]:.4g}, {big} of {total} reach the limit): a median and a "
                "dispersion need two levels or more")
    below, above = x[z < n].max(), x[z > 0].min()
    if below < above:
        return (f"the stripes separate: no case reaches the limit up to {what} {below:.4g} and every case does "
                f"from {above:.4g}: any steep curve between fits them (beta -> 0); levels between would identify it")
    if below == above:
        j = int(np.flatnonzero(x == below)[0])
        return (f"the stripes separate at {what} {below:.4g}: no case reaches the limit below it and every case "
                f"above it, {int(z[j])} of {int(n[j])} there: beta -> 0; levels around it would identify it")
    return None


def _nll(p, t, n, z):
    """Negative log-likelihood of probit stripes, s = a + b ln x, and its gradient and Hessian
    (the binomial coefficients are constant and left out)."""
    from scipy.stats import norm

    a, b = p
    s = a + b * t
    lcp, lcm = norm.logcdf(s), norm.logcdf(-s)
    lpdf = norm.logpdf(s)
    lam_p, lam_m = np.exp(lpdf - lcp), np.exp(lpdf - lcm)  # phi/Phi(s), phi/Phi(-s)
    f = -np.sum(z * lcp + (n - z) * lcm)
    d1 = z * lam_p - (n - z) * lam_m  # dl/ds
    d2 = -z * lam_p * (s + lam_p) - (n - z) * lam_m * (lam_m - s)  # d2l/ds2
    g = -np.array([d1.sum(), (d1 * t).sum()])
    h = -np.array([[d2.sum(), (d2 * t).sum()], [(d2 * t).sum(), (d2 * t * t).sum()]])
    return f, g, h


def _start(t, n, z) -> np.ndarray:
    """A probit line through the stripes' fractions (nudged off 0 and 1): where the fit starts."""
    from scipy.stats import norm

    s = norm.ppf((z + 0.5) / (n + 1.0))
    b, a = np.polyfit(t, s, 1, w=np.sqrt(n))
    return np.array([a, b]) if b > 0 else np.array([-np.average(t, weights=n) / 0.4, 1 / 0.4])


def fit_lognormal(x, n, z, start=None, what: str = "intensity") -> tuple[float, float]:
    """(theta, beta) maximising the stripes' binomial likelihood; NotIdentified where no finite
    maximum exists. In (a, b) = (-ln theta / beta, 1 / beta) the log-likelihood is concave (a
    probit regression), so the trust-region Newton iteration finds the one maximum."""
    from scipy.optimize import minimize

    x, n, z = (np.asarray(v, dtype=float) for v in (x, n, z))
    keep = n > 0
    x, n, z = x[keep], n[keep], z[keep]
    why = identification_problem(x, n, z, what)
    if why:
        raise NotIdentified(why)
    t = np.log(x)
    p0 = _start(t, n, z) if start is None else np.asarray(start, float)
    res = minimize(lambda p: _nll(p, t, n, z)[0], p0, jac=lambda p: _nll(p, t, n, z)[1],
                   hess=lambda p: _nll(p, t, n, z)[2], method="trust-exact", options={"gtol": 1e-11})
    a, b = res.x
    g = _nll(res.x, t, n, z)[1]
    if not np.all(np.isfinite(res.x)) or np.max(np.abs(g)) > 1e-6 * max(1.0, n.sum()):
        raise NotIdentified(f"the likelihood's maximisation did not converge ({res.message})")
    if b <= 0:
        raise NotIdentified("the share of cases reaching the limit does not grow with the intensity "
                            "(the best probit line falls): no fragility curve fits")
    return float(math.exp(-a / b)), float(1.0 / b)


def probability(x, theta: float, beta: float) -> np.ndarray:
    """P(reach | x) = Phi(ln(x / theta) / beta)."""
    from scipy.stats import norm

    return norm.cdf(np.log(np.asarray(x, dtype=float) / theta) / beta)


def log_likelihood(x, n, z, theta: float, beta: float) -> float:
    """sum_j ln C(n_j, z_j) + z_j ln p_j + (n_j - z_j) ln(1 - p_j)."""
    from scipy.stats import binom

    return float(np.sum(binom.logpmf(np.asarray(z), np.asarray(n), probability(x, theta, beta))))


def bootstrap(x, outcomes: list[np.ndarray], fitted: tuple[float, float], replicates: int,
              rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """theta and beta of ``replicates`` resamples, each stripe's cases drawn with replacement
    from its own. A resample whose stripes separate the cases that reach the limit from those
    that do not (some of each) has its likelihood's supremum at a step, beta -> 0 with theta
    anywhere in the gap: it counts as beta = 0 at the gap's geometric middle, so that the
    intervals are percentiles of every such resample, not of the others alone; NaN where a
    resample has no case or every case reaching the limit (no curve at all)."""
    x = np.asarray(x, dtype=float)
    n = np.array([len(o) for o in outcomes], dtype=float)
    z = np.empty((replicates, len(outcomes)))
    for j, o in enumerate(outcomes):
        z[:, j] = o[rng.integers(0, len(o), size=(replicates, len(o)))].sum(axis=1) if len(o) else 0.0
    theta, beta = fit_many(x, n, z, fitted)
    total = z.sum(axis=1)
    step = separated(x, n, z) & (total > 0) & (total < n.sum())
    below = np.where(z < n, x, -np.inf).max(axis=1)
    above = np.where(z > 0, x, np.inf).min(axis=1)
    theta[step] = np.sqrt(below[step] * above[step])
    beta[step] = 0.0
    return theta, beta


def probabilities(x: np.ndarray, theta: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """P(reach | x) for each (theta, beta) (rows) at each x (columns); beta = 0: the step at theta."""
    from scipy.stats import norm

    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.log(x[None, :] / theta[:, None]) / beta[:, None]
    step = np.where(x[None, :] >= theta[:, None], 1.0, 0.0)
    return np.where(beta[:, None] > 0.0, norm.cdf(z), step)


def separated(x: np.ndarray, n: np.ndarray, z: np.ndarray) -> np.ndarray:
    """(replicates,) True where the stripes z (replicates, stripes) identify no curve: no case
    or every case reaching the limit, or the ones that do not all at or below the ones that do
    (identification_problem's conditions, for many at once)."""
    below = np.where(z < n, x, -np.inf).max(axis=1)
    above = np.where(z > 0, x, np.inf).min(axis=1)
    return below <= above


def fit_many(x: np.ndarray, n: np.ndarray, z: np.ndarray, fitted: tuple[float, float],
             iterations: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """fit_lognormal for many sets of stripes at once (rows of z), started from ``fitted``:
    Newton's method on the concave probit log-likelihood, each step halved until the likelihood
    does not fall. The same maximum as fit_lognormal (the test checks it), a thousand times
    faster than a thousand calls; NaN where a row identifies no curve or does not converge."""
    from scipy.stats import norm

    t = np.log(x)[None, :]
    m = len(z)
    p = np.tile([-math.log(fitted[0]) / fitted[1], 1.0 / fitted[1]], (m, 1))
    live = ~separated(x, n, z)
    done = np.zeros(m, dtype=bool)

    def parts(p, rows):
        s = p[rows, :1] + p[rows, 1:] * t
        lcp, lcm, lpdf = norm.logcdf(s), norm.logcdf(-s), norm.logpdf(s)
        zz = z[rows]
        f = -np.sum(zz * lcp + (n - zz) * lcm, axis=1)
        lam_p, lam_m = np.exp(lpdf - lcp), np.exp(lpdf - lcm)
        d1 = zz * lam_p - (n - zz) * lam_m
        d2 = -zz * lam_p * (s + lam_p) - (n - zz) * lam_m * (lam_m - s)
        g = -np.stack([d1.sum(1), (d1 * t).sum(1)], axis=1)
        h = -np.stack([np.stack([d2.sum(1), (d2 * t).sum(1)], 1), np.stack([(d2 * t).sum(1), (d2 * t * t).sum(1)], 1)],
                      1)
        return f, g, h

    for _ in range(iterations):
        rows = np.flatnonzero(live & ~done)
        if not len(rows):
            break
        f, g, h = parts(p, rows)
        conv = np.max(np.abs(g), axis=1) <= 1e-9 * np.maximum(1.0, n.sum())
        done[rows[conv]] = True
        rows, f, g, h = rows[~conv], f[~conv], g[~conv], h[~conv]
        if not len(rows):
            break
        with np.errstate(all="ignore"):
            step = -np.linalg.solve(h, g[:, :, None])[:, :, 0]
        bad = ~np.all(np.isfinite(step), axis=1)
        step[bad] = -g[bad]
        lam = np.ones(len(rows))
        for _ in range(40):  # halve the step where the likelihood would fall
            trial = p.copy()
            trial[rows] = p[rows] + lam[:, None] * step
            f_new = parts(trial, rows)[0]
            worse = ~(f_new <= f)
            if not worse.any():
                break
            lam[worse] /= 2.0
        p[rows] = p[rows] + lam[:, None] * step
    ok = done & live & (p[:, 1] > 0)
    theta = np.where(ok, np.exp(-p[:, 0] / np.where(ok, p[:, 1], 1.0)), np.nan)
    beta = np.where(ok, 1.0 / np.where(ok, p[:, 1], 1.0), np.nan)
    return theta, beta


# ---------------------------------------------------------------- a sweep's curves


@dataclass
class Intensity:
    """The intensity measure: its key, its label (with unit), and its value for each case number."""

    key: str  # scale, pga_g or sa_g
    label: str
    short: str  # in messages: "scale", "PGA", "Sa"
    values: dict[int, float]


@dataclass
class FragilityPlan:
    """What a sweep's fragility needs once its cases are done: set up before anything runs."""

    limit_states: list  # spec.LimitState
    quantities: list[Quantity]
    options: object  # spec.FragilityOptions
    intensity: Intensity
    vary_keys: list[str]

    def about(self) -> dict:
        o = self.options
        return {
            "intensity": self.intensity.label,
            "limit_states": [{"name": ls.name, "quantity": ls.quantity, "limit": ls.limit} for ls in self.limit_states],
            "reaches": "a case reaches a limit state when quantity >= limit",
            "method": "P(reach | x) = Phi(ln(x / median) / beta) by maximum likelihood on the binomial likelihood of "
                      "the stripes (cases of equal intensity x), Baker (2015); failed cases and cases without a "
                      "value are left out",
            "confidence": o.confidence,
            "bootstrap": o.bootstrap,
            "seed": o.seed,
            "intervals": f"percentiles {50 * (1 - o.confidence):g} and {50 * (1 + o.confidence):g} of {o.bootstrap} "
                         "bootstrap resamples of the cases within each stripe (numpy.random.default_rng([seed, k]) "
                         "for the k-th curve); a resample whose stripes separate the cases counts as the step it "
                         "is (beta 0, theta at the gap's geometric middle), one with no case or every case reaching "
                         "the limit is left out and counted; the band is pointwise",
            "files": {CSV_FILE: "one row per limit state and vary combination", STRIPES_FILE:
                      "one row per limit state, vary combination and intensity level"},
        }


@dataclass
class Curve:
    """One limit state over one vary combination: its stripes and, where identified, its fit."""

    limit_state: object
    group: tuple[str, ...]
    x: np.ndarray  # stripes' intensities, ascending
    n: np.ndarray  # cases with a value
    z: np.ndarray  # of which reach the limit
    failed: np.ndarray
    missing: np.ndarray  # ok cases without a value of the quantity
    status: str = "not identified"
    message: str = ""
    median: float | None = None
    beta: float | None = None
    median_ci: tuple[float, float] | None = None
    beta_ci: tuple[float, float] | None = None
    identified: int = 0  # bootstrap resamples that identified a curve (steps among them)
    steps: int = 0  # ... of them a step (the cases separated: beta 0)
    grid: np.ndarray | None = None
    band: tuple[np.ndarray, np.ndarray] | None = None  # pointwise P bounds on grid
    p_bounds: tuple[np.ndarray, np.ndarray] | None = None  # at x
    notes: list[str] = field(default_factory=list)
    outcomes: list = field(default_factory=list, repr=False)  # per stripe: 1.0 where a case reaches the limit

    @property
    def fitted(self) -> bool:
        return self.status == "fitted"


def curves(plan: FragilityPlan, header: list[str], rows: list[list]) -> list[Curve]:
    """Every limit state over every vary combination (in cases.csv's order), fitted or refused."""
    col = {h: i for i, h in enumerate(header)}
    m = len(rows)
    status = np.array([r[col["status"]] for r in rows])
    numbers = [int(r[col["case"]]) for r in rows]
    im = np.array([plan.intensity.values.get(k, np.nan) for k in numbers], dtype=float)
    groups = [tuple(r[col[k]] for k in plan.vary_keys) for r in rows]
    needed = {name for q in plan.quantities for name in q.names}
    columns = {name: np.array([_float(r[col[name]]) if name in col else np.nan for r in rows]) for name in needed}
    out = []
    k = 0
    for ls, q in zip(plan.limit_states, plan.quantities):
        value = evaluate(q, columns, m)
        for g in dict.fromkeys(groups):
            mine = np.array([gg == g for gg in groups]) & np.isfinite(im)
            c = _stripes(ls, g, im[mine], value[mine], status[mine])
            _fit(c, plan, np.random.default_rng([plan.options.seed, k]))
            out.append(c)
            k += 1
    return out


def _float(text: str) -> float:
    return float(text) if text != "" else np.nan


def _stripes(ls, group, im, value, status) -> Curve:
    x = np.unique(im)
    ok = status == "ok"
    has = ok & np.isfinite(value)
    reach = has & (value >= ls.limit)
    c = Curve(ls, group, x, *(np.array([np.sum(mask & (im == v)) for v in x], dtype=int)
                              for mask in (has, reach, status == "failed", ok & ~np.isfinite(value))))
    c.outcomes = [reach[has & (im == v)].astype(float) for v in x]
    return c


def _fit(c: Curve, plan: FragilityPlan, rng: np.random.Generator) -> None:
    o = plan.options
    what = plan.intensity.short
    keep = c.n > 0
    if c.failed.sum():
        c.notes.append(f"{int(c.failed.sum())} failed case{'s' * (c.failed.sum() != 1)} left out")
    if c.missing.sum():
        c.notes.append(f"{int(c.missing.sum())} case{'s' * (c.missing.sum() != 1)} without a value of "
                       f"{c.limit_state.quantity} left out")
    try:
        c.median, c.beta = fit_lognormal(c.x[keep], c.n[keep], c.z[keep], what=what)
    except NotIdentified as err:
        c.message = "; ".join([str(err), *c.notes])
        return
    c.status = "fitted"
    if c.median > c.x[keep].max() or c.median < c.x[keep].min():
        c.notes.insert(0, f"the median lies outside the intensities run ({c.x[keep].min():.4g} to "
                          f"{c.x[keep].max():.4g}): an extrapolation")
    hi_x = max(c.x.max(), c.median) * 1.25
    c.grid = np.linspace(hi_x / BAND_POINTS, hi_x, BAND_POINTS)
    if o.bootstrap:
        outcomes = [o_ for o_, k in zip(c.outcomes, keep) if k]
        theta, beta = bootstrap(c.x[keep], outcomes, (c.median, c.beta), o.bootstrap, rng)
        good = np.isfinite(theta)
        c.identified = int(good.sum())
        c.steps = int(np.sum(beta[good] == 0.0))
        if c.steps:
            c.notes.append(f"{c.steps} of {o.bootstrap} bootstrap resamples separate the cases that reach the limit "
                           "from those that do not (a step: beta 0, theta at the gap's geometric middle) and count "
                           "so in the intervals")
        if c.identified < o.bootstrap:
            c.notes.append(f"{o.bootstrap - c.identified} of {o.bootstrap} bootstrap resamples have no case or every "
                           "case reaching the limit and are left out of the intervals")
        if c.identified >= MIN_IDENTIFIED * o.bootstrap:
            q = (50 * (1 - o.confidence), 50 * (1 + o.confidence))
            c.median_ci = tuple(float(v) for v in np.percentile(theta[good], q))
            c.beta_ci = tuple(float(v) for v in np.percentile(beta[good], q))

            def bounds(x):
                lo, hi = np.percentile(probabilities(x, theta[good], beta[good]), q, axis=0)
                return lo, hi

            c.band = bounds(c.grid)
            c.p_bounds = bounds(c.x)
        else:
            c.notes.append("too few to give intervals")
    c.message = "; ".join(c.notes)


# ---------------------------------------------------------------- files


def csv_text(plan: FragilityPlan, found: list[Curve]) -> str:
    """fragility.csv: one row per limit state and vary combination."""
    header = ["limit_state", "quantity", "limit", *plan.vary_keys, "intensity", "cases", "reached", "failed",
              "missing", "stripes", "status", "median", "beta", "median_lo", "median_hi", "beta_lo", "beta_hi",
              "confidence", "bootstrap", "identified", "message"]
    rows = []
    for c in found:
        ci_m, ci_b = c.median_ci or (None, None), c.beta_ci or (None, None)
        rows.append([c.limit_state.name, c.limit_state.quantity, _num(c.limit_state.limit), *c.group,
                     plan.intensity.label, int(c.n.sum()), int(c.z.sum()), int(c.failed.sum()), int(c.missing.sum()),
                     int(np.sum(c.n > 0)), c.status, _num(c.median), _num(c.beta), _num(ci_m[0]), _num(ci_m[1]),
                     _num(ci_b[0]), _num(ci_b[1]), _num(plan.options.confidence) if c.median_ci else "",
                     plan.options.bootstrap if c.fitted else "", c.identified if c.fitted else "", c.message])
    return to_csv(header, rows)


def stripes_text(plan: FragilityPlan, found: list[Curve]) -> str:
    """fragility_stripes.csv: one row per limit state, vary combination and intensity level."""
    header = ["limit_state", *plan.vary_keys, "im", "cases", "reached", "failed", "missing", "fraction",
              "p_fit", "p_lo", "p_hi"]
    rows = []
    for c in found:
        p = probability(c.x, c.median, c.beta) if c.fitted else None
        for j, x in enumerate(c.x):
            rows.append([c.limit_state.name, *c.group, _num(float(x)), int(c.n[j]), int(c.z[j]), int(c.failed[j]),
                         int(c.missing[j]), _num(float(c.z[j] / c.n[j])) if c.n[j] else "",
                         _num(None if p is None else float(p[j])),
                         _num(None if c.p_bounds is None else float(c.p_bounds[0][j])),
                         _num(None if c.p_bounds is None else float(c.p_bounds[1][j]))])
    return to_csv(header, rows)


def write_fragility(plan: FragilityPlan, header: list[str], rows: list[list], folder: Path,
                    plotter=None) -> list[Curve]:
    """fragility.csv, fragility_stripes.csv and, with a ``plotter`` (rbhyst.report.sweep, whose
    ``plot_fragility`` draws it), fragility.png into ``folder``."""
    found = curves(plan, header, rows)
    folder = Path(folder)
    (folder / CSV_FILE).write_text(csv_text(plan, found), encoding="utf-8")
    (folder / STRIPES_FILE).write_text(stripes_text(plan, found), encoding="utf-8")
    if plotter is not None:
        plotter.plot_fragility(found, plan.intensity.label, plan.vary_keys, folder / PLOT_FILE,
                               plan.options.confidence)
    return found


def files(plots: bool) -> list[str]:
    return [CSV_FILE, STRIPES_FILE, *([PLOT_FILE] if plots else [])]


def _num(v) -> str:
    if v is None:
        return ""
    return repr(float(v))


# ---------------------------------------------------------------- set up with the sweep


def plan_fragility(sweep) -> FragilityPlan | None:
    """The sweep's limit states checked against the columns its cases will have, and each case's
    intensity measure; None without limit states. InputError (one line per problem, naming the
    sweep file's key) before anything runs."""
    from rbhyst.errors import InputError
    from rbhyst.analyses.sweep.spec import FragilityOptions

    spec = sweep.spec
    if not spec.limit_states:
        return None
    options = spec.fragility or FragilityOptions()
    problems = []
    first: dict[str, int] = {}
    for i, ls in enumerate(spec.limit_states, start=1):
        k = first.setdefault(ls.name, i)
        if k != i:
            problems.append(f"limit_states[{i}].name: {ls.name!r} is the name of limit_states[{k}] too")
    systems = _systems(sweep, per_motion=options.intensity != "scale")
    known: dict[str, None] = {}
    for _, system, points in systems.values():
        known.update(dict.fromkeys(_columns(system, points)))
    quantities = []
    for i, ls in enumerate(spec.limit_states, start=1):
        try:
            q = parse_quantity(ls.quantity)
        except ValueError as err:
            problems.append(f"limit_states[{i}].quantity: {err}")
            continue
        quantities.append(q)
        for name in q.names:
            if name not in known:
                close = difflib.get_close_matches(name, list(known), n=1)
                hint = f" (did you mean {close[0]}?)" if close else ""
                problems.append(f"limit_states[{i}].quantity: {name} is not a column of this sweep's cases{hint}; "
                                "the columns are peak_<time_history.csv column> (peak_u1_m, peak_at1_m_s2, peak_e1_f_N, "
                                "...) and stroke_e<k> for each element with a stroke"
                                + (f" ({', '.join(k for k in known if k.startswith('stroke_'))})"
                                   if any(k.startswith("stroke_") for k in known) else " (none here)"))
    if problems:
        raise InputError(problems)
    intensity = _intensity(sweep, options, systems)
    return FragilityPlan(list(spec.limit_states), quantities, options, intensity, list(sweep.vary_keys))


def _systems(sweep, per_motion: bool) -> dict[int, tuple]:
    """The assembled deck of the first case of each vary combination (and of each motion, where
    the intensity is the motion's): {case number: (case, System, points)}; a case whose deck
    cannot be assembled (a record that cannot be read) is left out, as it fails when it runs."""
    from rbhyst.errors import InputError
    from rbhyst.model.system import assemble
    from rbhyst.model.settings import settings_from_deck

    chosen: dict[int, object] = {}
    seen_m, seen_v = set(), set()
    for c in sweep.cases:
        v = tuple(sorted((k, repr(x)) for k, x in c.vary.items()))
        if c.problem is None and ((per_motion and c.motion not in seen_m) or v not in seen_v):
            chosen[c.number] = c
            seen_m.add(c.motion)
            seen_v.add(v)
    base = sweep.base.deck()
    out = {}
    for number, c in chosen.items():
        try:
            deck = base.with_values(c.values)
            out[number] = (c, assemble(deck, deck.base), settings_from_deck(deck).points)
        except InputError:
            continue
    return out


def _columns(system, points) -> list[str]:
    from rbhyst.solve.history import Layout

    names = [f"peak_{n}" for n in Layout(system, points).names if n != "time_s"]
    k = 1
    for el in system.elements:
        if el.stroke is not None:
            names.append(f"stroke_e{k}")
        k += el.count
    return names


def _intensity(sweep, options, systems) -> Intensity:
    """Each case's intensity measure: the scale level as written, the PGA of its motion as scaled
    (the larger component's, as [scale] pga_g takes it), or Sa of that motion at period_s."""
    from rbhyst.model.deck import ACCEL_UNITS
    from rbhyst.errors import InputError

    g = ACCEL_UNITS["g"]
    kind = options.intensity
    cases = [c for c in sweep.cases if c.problem is None]
    if kind == "scale" or (kind == "pga_g" and sweep.scale_kind == "pga_g"):
        label = "scale factor" if sweep.scale_kind == "factors" else "PGA [g]"
        return Intensity(kind, label, "scale" if sweep.scale_kind == "factors" else "PGA",
                         {c.number: float(c.scale) for c in cases})
    per_motion: dict[str, tuple[float, float]] = {}  # motion: (its intensity in g, the factor it was taken at)
    for c, system, _ in systems.values():
        if c.motion in per_motion:
            continue
        ex = system.excitation
        if not ex.has_support:
            raise InputError(f"fragility.intensity: motion {c.motion} has no support acceleration to take "
                             f"{'a PGA' if kind == 'pga_g' else 'an Sa'} of; use intensity = \"scale\"")
        if kind == "pga_g":
            from rbhyst.analyses.sweep.motions import peak_acceleration

            support = c.values.get("excitation.support") or (c.values.get("excitation") or {}).get("support")
            if support is None:
                from rbhyst.analyses.sweep.motions import deck_support

                support = deck_support(sweep.base.deck())
            value = peak_acceleration(support) / g
        else:
            value = _sa(system, options.period_s, options.damping) / g
        per_motion[c.motion] = (value, c.factor if c.factor is not None else 1.0)
    values = {}
    for c in cases:
        if c.motion in per_motion and c.factor is not None:
            v, f0 = per_motion[c.motion]
            values[c.number] = v * abs(c.factor / f0)  # both linear in the factor
    if kind == "pga_g":
        return Intensity(kind, "PGA [g]", "PGA", values)
    return Intensity(kind, f"Sa({options.period_s:g} s; {100 * options.damping:g} %) [g]", "Sa", values)


def _sa(system, period: float, damping: float) -> float:
    """Sa (m/s2) of the support motion at one period: the larger component's, over the whole
    motion followed by rest for one period (the oscillator peaks within half of one after it)."""
    from rbhyst.solve.ground import ground_spectra

    ex = system.excitation
    end = ex.duration
    if end is None:  # an endless sine: its first 20 periods of either
        end = 20.0 * max(period, max(getattr(s, "step", 0.0) * 40.0 for s in ex.signals.values()))
    spectra = ground_spectra(ex, end + period, [damping], [period])
    return float(spectra.spectrum.sa[0, 0, :].max())
