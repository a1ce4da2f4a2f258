"""Hysteresis loops of one VRM element under an imposed displacement, and parameter identification.

Everything here is in SI (m, N, J) and works on the ``(2, 8)`` parameter arrays of
:mod:`rbhyst.model.hysteresis`:

* :func:`protocol` turns the deck's ``[loops]`` table into a displacement history;
* :func:`loop_result` drives one set through a history from the virgin state and
  measures it: hysteretic work (closed form per step, seed ref. [8]), the cycles
  between successive displacement peaks with the energy each closed one dissipates,
  and NRMSE / R^2 against measured forces;
* :func:`fit_set` identifies the 16 parameters of a set (or a subset) from measured
  data with ``scipy.optimize.least_squares``, several starts, in scaled variables.

Only the writers at the end touch files; matplotlib lives in :mod:`rbhyst.report.loops`.
"""

from __future__ import annotations

import json
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import njit

from rbhyst._version import __version__
from rbhyst.errors import AnalysisError, InputError
from rbhyst.model.hysteresis import ALPHA, BETA2, GAMMA2, GAMMA3, PARAMS, limiting_curve
from rbhyst.model.vrm import loop
from rbhyst.model.testdata import significant_reversals

BRANCHES = ("loading", "unloading")
#: the 16 parameter names, in the order of ``p.ravel()``
NAMES = tuple(f"{b}.{k}" for b in BRANCHES for k in PARAMS)

#: a cycle counts as closed when the displacement and force at its two peaks agree to
#: this fraction of the cycle's ranges; its work is then the energy it dissipated
CLOSURE_TOL = 0.02


# --------------------------------------------------------------------------- protocol


def protocol(loops=None) -> tuple[np.ndarray, np.ndarray]:
    """Times and displacements of the ``[loops]`` protocol (default: the seed's Fig. 2).

    ``cycles`` sine cycles ``A sin(2 pi f t)`` at each amplitude in turn, from and
    back to u = 0, ``points_per_cycle`` samples per cycle.
    """
    if loops is None:
        from rbhyst.model.deck import Loops

        loops = Loops()
    amps = loops.amplitude if isinstance(loops.amplitude, list) else [loops.amplitude]
    n = loops.points_per_cycle
    phase = 2.0 * np.pi * np.arange(n) / n  # one cycle, without its last point
    u = np.concatenate([a * np.sin(np.tile(phase, loops.cycles)) for a in amps] + [np.zeros(1)])
    u[::n] = 0.0
    t = np.arange(u.size) / (n * loops.frequency_hz)
    return t, u


# --------------------------------------------------------------------------- one loop


@dataclass(frozen=True)
class Cycle:
    """The stretch between two successive displacement peaks (samples ``start``..``end``)."""

    start: int
    end: int
    u_min: float
    u_max: float
    work: float  # integral of f du over the stretch [J]
    closure: float  # f(end) - f(start) [N]
    closed: bool  # peaks agree (CLOSURE_TOL): work = energy dissipated

    def as_dict(self) -> dict:
        return {
            "samples": [self.start, self.end],
            "u_min_m": self.u_min,
            "u_max_m": self.u_max,
            "work_J": self.work,
            "closure_N": self.closure,
            "dissipated_J": self.work if self.closed else None,
        }


@dataclass(frozen=True)
class LoopResult:
    """One set driven through a displacement history from the virgin state."""

    name: str
    p: np.ndarray  # (2, 8)
    u: np.ndarray  # [m]
    f: np.ndarray  # [N]
    work: np.ndarray  # cumulative hysteretic work [J]
    cycles: list[Cycle]
    f_data: np.ndarray | None = None

    @property
    def dissipated(self) -> list[float]:
        """Energy dissipated by each closed cycle [J]."""
        return [c.work for c in self.cycles if c.closed]

    @property
    def nrmse(self) -> float | None:
        return None if self.f_data is None else nrmse(self.f, self.f_data)

    @property
    def r2(self) -> float | None:
        return None if self.f_data is None else r_squared(self.f, self.f_data)

    def summary(self) -> dict:
        out = {
            "parameters": parameters_dict(self.p),
            "samples": int(self.u.size),
            "u_range_m": [float(self.u.min()), float(self.u.max())],
            "f_range_N": [float(self.f.min()), float(self.f.max())],
            "hysteretic_work_J": float(self.work[-1]),
            "dissipated_per_cycle_J": self.dissipated,
            "cycles": [c.as_dict() for c in self.cycles],
        }
        if self.f_data is not None:
            out["nrmse"] = self.nrmse
            out["r2"] = self.r2
        return out


def nrmse(f_model, f_data) -> float:
    """RMS of the force error over the range of the measured force."""
    f_model, f_data = np.asarray(f_model), np.asarray(f_data)
    span = float(np.ptp(f_data))
    rms = float(np.sqrt(np.mean((f_model - f_data) ** 2)))
    return rms / span if span > 0 else math.inf


def r_squared(f_model, f_data) -> float:
    f_model, f_data = np.asarray(f_model), np.asarray(f_data)
    ss_tot = float(np.sum((f_data - f_data.mean()) ** 2))
    ss_res = float(np.sum((f_model - f_data) ** 2))
    return 1.0 - ss_res / ss_tot if ss_tot > 0 else -math.inf


def cycles_of(u: np.ndarray, f: np.ndarray, work: np.ndarray) -> list[Cycle]:
    """The stretches between successive significant displacement maxima."""
    rev = significant_reversals(u)
    if rev.size == 0:
        return []
    nxt = np.append(u[rev[1:]], u[-1])
    peaks = [int(i) for i, un in zip(rev, nxt) if u[i] > un]
    out = []
    for a, b in zip(peaks[:-1], peaks[1:]):
        seg_u, seg_f = u[a:b + 1], f[a:b + 1]
        du, df = float(np.ptp(seg_u)), float(np.ptp(seg_f))
        closure = float(f[b] - f[a])
        closed = abs(u[b] - u[a]) <= CLOSURE_TOL * du and abs(closure) <= CLOSURE_TOL * df
        out.append(Cycle(a, b, float(seg_u.min()), float(seg_u.max()), float(work[b] - work[a]),
                         closure, bool(closed)))
    return out


def loop_result(name: str, p: np.ndarray, u: np.ndarray, f_data: np.ndarray | None = None) -> LoopResult:
    """Drive set ``p`` through ``u`` from the virgin state; AnalysisError on overflow."""
    try:
        f, _, w = loop(p, u)
    except OverflowError as exc:
        raise AnalysisError(f"hysteresis.{name}: {exc}") from None
    return LoopResult(name, np.array(p, dtype=float), np.asarray(u, dtype=float), f, w,
                      cycles_of(u, f, w), f_data)


def check_orientation(u: np.ndarray, f: np.ndarray, where: str = "data") -> None:
    """InputError when the measured loops give out energy (net work of the force < 0).

    A hysteretic element dissipates: with u across and f up its loops run clockwise
    (loading along the top). Loops run the other way mean a sign convention is
    reversed (force or displacement, not both). The net work is taken between the
    first and the last displacement maximum.
    """
    rev = significant_reversals(u)
    peaks = [i for i in rev if i + 1 < u.size and u[i] >= u[i + 1]]
    a, b = (peaks[0], peaks[-1]) if len(peaks) >= 2 else (0, u.size - 1)
    w = float(np.sum(0.5 * (f[a + 1:b + 1] + f[a:b]) * np.diff(u[a:b + 1])))
    scale = float(np.ptp(u) * np.ptp(f))
    if w < -1e-3 * scale:
        raise InputError(f"{where}: the loops run counter-clockwise (net work {w:.4g} J: the element would give "
                         "out energy); is the sign of the force or of the displacement reversed?")


def parameters_dict(p: np.ndarray) -> dict:
    return {b: {k: float(p[r, c]) for c, k in enumerate(PARAMS)} for r, b in enumerate(BRANCHES)}


# --------------------------------------------------------------------------- identification


@njit(cache=True)
def _dc_dtheta(p, row, s, u, out):
    """Derivatives of the limiting curve c_s(u) with respect to the 8 parameters of ``row``.

    Valid also where a term's amplitude or rate is zero (the function is smooth there),
    which is where the force kernel skips the term.
    """
    kb, f0, alpha, b1, b2, g1, g2, g3 = p[row]
    e = math.exp(b2 * u)
    x = u - g3
    t = math.tanh(0.5 * g2 * x)
    sech2 = 1.0 - t * t
    out[0] = u
    out[1] = s
    out[2] = 0.0
    out[3] = e - 1.0
    out[4] = b1 * u * e
    out[5] = 2.0 * t
    out[6] = g1 * sech2 * x
    out[7] = -g1 * g2 * sech2


@njit(cache=True)
def drive_sensitivity(p, u, f_out, jac_out):
    """Force (as :func:`rbhyst.model.vrm.drive`) and its derivatives with respect to the
    16 parameters ``p.ravel()`` along an imposed history from the virgin state.

    Along a branch started at (u_P, f_P), f = c_s(u) - g_P exp(-alpha |u - u_P|) with
    g_P = c_s(u_P) - f_P, so df = dc_s(u) - exp(..) (dg_P - g_P |u - u_P| dalpha) with
    dg_P = dc_s(u_P) - df_P. Returns the index of the first sample whose exp()
    overflows, or -1.
    """
    n = u.shape[0]
    df = np.zeros(16)  # df/dtheta at the current sample
    dgp = np.zeros(16)  # d(gap)/dtheta at the start of the branch
    dc = np.zeros(8)
    f = 0.0
    s = 0.0
    gp = 0.0
    up = 0.0
    uprev = 0.0
    for i in range(n):
        ui = u[i]
        du = ui - uprev
        if du != 0.0:
            sn = 1.0 if du > 0.0 else -1.0
            row = 0 if sn > 0 else 1
            if sn != s:  # a new branch at (uprev, f)
                if p[row, 4] * uprev > 700.0:
                    return i
                _dc_dtheta(p, row, sn, uprev, dc)
                gp = _c(p, row, sn, uprev) - f
                for k in range(16):
                    dgp[k] = -df[k]
                for k in range(8):
                    dgp[row * 8 + k] += dc[k]
                up = uprev
                s = sn
            if p[row, 4] * ui > 700.0:
                return i
            dist = abs(ui - up)
            alpha = p[row, 2]
            decay = math.exp(-alpha * dist)
            f = _c(p, row, s, ui) - gp * decay
            _dc_dtheta(p, row, s, ui, dc)
            for k in range(16):
                df[k] = -decay * dgp[k]
            df[row * 8 + 2] += decay * gp * dist
            for k in range(8):
                df[row * 8 + k] += dc[k]
            uprev = ui
        f_out[i] = f
        for k in range(16):
            jac_out[i, k] = df[k]
    return -1


@njit(cache=True, inline="always")
def _c(p, row, s, u):
    kb, f0, alpha, b1, b2, g1, g2, g3 = p[row]
    return kb * u + s * f0 + b1 * (math.exp(b2 * u) - 1.0) + 2.0 * g1 * math.tanh(0.5 * g2 * (u - g3))


def parse_names(tokens, what: str = "--free") -> list[int]:
    """Parameter names -> indices into NAMES.

    ``loading.kb`` / ``unloading.alpha`` as in the deck, ``kb+`` / ``kb-`` as in the seed,
    or ``kb`` for both branches; several may be given comma-separated.
    """
    out = []
    for token in tokens:
        for name in (x.strip() for x in token.split(",")):
            if not name:
                continue
            if name in NAMES:
                idx = [NAMES.index(name)]
            elif name[-1:] in "+-" and name[:-1] in PARAMS:
                idx = [NAMES.index(f"{'loading' if name[-1] == '+' else 'unloading'}.{name[:-1]}")]
            elif name in PARAMS:
                idx = [NAMES.index(f"loading.{name}"), NAMES.index(f"unloading.{name}")]
            else:
                raise InputError(f"{what}: unknown parameter {name!r}; use e.g. loading.kb, kb+, kb- "
                                 f"or kb (both branches); parameters: {', '.join(PARAMS)}")
            out += [i for i in idx if i not in out]
    return out


def scales(u_scale: float, f_scale: float) -> np.ndarray:
    """Per-parameter scale (16,) that makes every parameter O(1) for data of these sizes."""
    U, F = u_scale, f_scale
    row = np.array([F / U, F, 1.0 / U, F, 1.0 / U, F, 1.0 / U, U])
    return np.concatenate([row, row])


#: bounds on the scaled parameters (value * scale is the parameter): alpha > 0 and
#: |beta2| max|u| <= 40 keep exp() finite; gamma2 >= 0 removes the (gamma1, gamma2)
#: -> (-gamma1, -gamma2) symmetry; gamma3 stays within 10 data ranges of the origin
_LOWER = np.array([-np.inf, -np.inf, 1e-3, -np.inf, -40.0, -np.inf, 0.0, -10.0])
_UPPER = np.array([np.inf, np.inf, 1e4, np.inf, 40.0, np.inf, 1e3, 10.0])


@dataclass
class Fit:
    """The outcome of :func:`fit_set`: the best start and what every start did."""

    p: np.ndarray  # (2, 8) fitted set (physical units)
    free: list[int]
    nrmse: float
    r2: float
    nfev: int
    njev: int
    status: int
    message: str
    std: np.ndarray  # (16,) standard error (nan for fixed, inf where the data do not determine it)
    at_bound: np.ndarray  # (16,) bool
    starts: list[dict] = field(default_factory=list)
    wall_s: float = 0.0

    def parameters(self) -> list[dict]:
        rows = []
        for i, name in enumerate(NAMES):
            v = float(self.p.flat[i])
            free = i in self.free
            sd = float(self.std[i]) if free and math.isfinite(self.std[i]) else None
            rows.append({
                "name": name,
                "value": v,
                "free": free,
                "std": sd,
                "determined": bool(free and sd is not None and sd <= 0.1 * abs(v) and not self.at_bound[i]),
                "at_bound": bool(free and self.at_bound[i]),
            })
        return rows


def _ordered_grid(u: np.ndarray) -> np.ndarray:
    return np.union1d(np.linspace(u.min(), u.max(), 65), [0.0])


def curves_ordered(p: np.ndarray, u_grid: np.ndarray) -> bool:
    """c+(u) >= c-(u) at every grid point (u = 0 included: the deck requires it there)."""
    with np.errstate(over="ignore", invalid="ignore"):
        gap = limiting_curve(p, 1, u_grid) - limiting_curve(p, -1, u_grid)
    return bool(np.all(np.isfinite(gap)) and np.all(gap >= 0.0))


def fit_set(p0: np.ndarray, u: np.ndarray, f: np.ndarray, free: list[int] | None = None,
            starts: int = 6, seed: int = 0, max_nfev: int | None = None) -> Fit:
    """Least-squares identification of the free parameters of ``p0`` from ``(u, f)``.

    The model is driven through the measured displacement history from the virgin
    state and its force compared sample by sample. Variables are scaled by the data
    (``max|u|``, half the force range) so that N and m condition well; alpha > 0 and
    exp() overflow are box bounds, the order c+ > c- of the limiting curves over the
    data range is a penalty and is checked on the result. Start 1 is ``p0``; the others
    perturb it at random (``seed``). Raises AnalysisError when no start gives a set with
    ordered limiting curves.

    Long because the stages share the data, the bounds and the best start: split, they would
    pass them all around.
    """
    from scipy.optimize import least_squares

    t0 = time.perf_counter()
    u = np.ascontiguousarray(u, dtype=float)
    f = np.asarray(f, dtype=float)
    free = list(range(16)) if free is None else sorted(free)
    if not free:
        raise InputError("--free: no parameter left to fit")
    p0 = np.array(p0, dtype=float)
    for r in range(2):  # (gamma1, gamma2) and (-gamma1, -gamma2) are the same curve
        if p0[r, GAMMA2] < 0:
            p0[r, [5, 6]] *= -1.0

    U = float(np.max(np.abs(u)))
    F = 0.5 * float(np.ptp(f))
    if not (U > 0 and F > 0):
        raise InputError("data: the displacement and the force must both vary")
    check_orientation(u, f)
    scale = scales(U, F)
    x_all = p0.ravel() / scale
    lo, hi = np.tile(_LOWER, 2), np.tile(_UPPER, 2)
    lo, hi = np.minimum(lo, x_all), np.maximum(hi, x_all)  # an init outside a bound widens it
    lo_f, hi_f = lo[free], hi[free]
    # least_squares wants a start strictly inside finite bounds
    x0 = _inside(x_all[free], lo_f, hi_f)

    grid = _ordered_grid(u)
    n = u.size
    inv = 1.0 / (F * math.sqrt(n))
    big = np.full(n + grid.size, 1e3)

    def assemble(x):
        xa = x_all.copy()
        xa[free] = x
        return (xa * scale).reshape(2, 8)

    fbuf = np.empty(n)
    jbuf = np.empty((n, 16))
    dcg = np.empty((2, 8))
    tmp = np.empty(8)
    cache = {}

    def evaluate(x):
        key = x.tobytes()
        if key in cache:
            return cache[key]
        p = assemble(x)
        bad = drive_sensitivity(p, u, fbuf, jbuf)
        with np.errstate(over="ignore", invalid="ignore"):
            gap = (limiting_curve(p, 1, grid) - limiting_curve(p, -1, grid)) / F
        pen = 10.0 * np.maximum(0.0, 1e-6 - np.nan_to_num(gap, nan=-1.0))
        r = np.concatenate([(fbuf - f) * inv, pen])
        if bad >= 0 or not np.all(np.isfinite(r)):
            out = (big, np.zeros((big.size, len(free))))
        else:
            jac = np.empty((r.size, len(free)))
            jac[:n] = jbuf[:, free] * (scale[free] * inv)
            jac[n:] = 0.0
            for j in np.flatnonzero(pen > 0):  # penalty rows: -10 d(gap)/dtheta / F where active
                _dc_dtheta(p, 0, 1.0, grid[j], tmp)
                dcg[0] = tmp
                _dc_dtheta(p, 1, -1.0, grid[j], tmp)
                dcg[1] = -tmp
                jac[n + j] = -10.0 * dcg.ravel()[free] * (scale[free] / F)
            out = (r, jac)
        cache.clear()
        cache[key] = out
        return out

    def residuals(x):
        return evaluate(x)[0]

    def jacobian(x):
        return evaluate(x)[1]

    rng = np.random.default_rng(seed)
    cols = np.array(free) % 8
    candidates = [x0]
    for _ in range(max(0, starts - 1)):
        candidates.append(_perturb(x0, cols, lo_f, hi_f, rng))

    best = None
    log = []
    for k, xs in enumerate(candidates, start=1):
        try:
            res = least_squares(residuals, xs, jac=jacobian, bounds=(lo_f, hi_f), method="trf", x_scale=1.0,
                                tr_solver="lsmr", max_nfev=max_nfev or 25 * len(free))
        except (ValueError, np.linalg.LinAlgError) as exc:
            log.append({"start": k, "nrmse": None, "status": -1, "message": str(exc)})
            continue
        p = assemble(res.x)
        ok = curves_ordered(p, grid) and res.status >= 0
        fm = _force(p, u)
        e = nrmse(fm, f) if fm is not None else math.inf
        log.append({"start": k, "nrmse": e, "status": int(res.status), "nfev": int(res.nfev),
                    "njev": int(res.njev or 0), "ordered": ok, "message": res.message})
        if ok and math.isfinite(e) and (best is None or e < best[0]):
            best = (e, res, p)

    if best is None:
        finite = [s for s in log if s.get("nrmse") is not None and math.isfinite(s["nrmse"])]
        detail = (f"best NRMSE {min(s['nrmse'] for s in finite):.3g} with crossing limiting curves"
                  if finite else log[-1]["message"] if log else "no start")
        raise AnalysisError(f"calibration failed: none of {len(candidates)} starts gave a set with "
                            f"ordered limiting curves c+ > c- ({detail}); try another --init, "
                            "more --starts or other --free parameters")

    e, res, p = best
    # polish the best start with tight tolerances (the defaults stop early on clean data)
    try:
        polished = least_squares(residuals, res.x, jac=jacobian, bounds=(lo_f, hi_f), method="trf",
                                 x_scale=1.0, tr_solver="lsmr", max_nfev=10 * len(free),
                                 ftol=1e-12, xtol=1e-12, gtol=1e-14)
    except (ValueError, np.linalg.LinAlgError):
        polished = None
    if polished is not None and polished.cost <= res.cost:
        pp = assemble(polished.x)
        fm = _force(pp, u)
        if curves_ordered(pp, grid) and fm is not None:
            res = _merge_counts(polished, res)
            e, p = nrmse(fm, f), pp
    std = np.full(16, np.nan)
    std[free] = _standard_errors(res.jac[:n] * math.sqrt(n), res.fun[:n] * math.sqrt(n), len(free)) * scale[free]
    at_bound = np.zeros(16, dtype=bool)
    at_bound[free] = res.active_mask != 0
    fm = _force(p, u)
    return Fit(p=p, free=free, nrmse=e, r2=r_squared(fm, f), nfev=int(res.nfev), njev=int(res.njev or 0),
               status=int(res.status), message=res.message, std=std, at_bound=at_bound, starts=log,
               wall_s=time.perf_counter() - t0)


def _merge_counts(polished, start):
    """The polished result, counting the evaluations of the start it came from as well; a
    polish cut short by its evaluation limit keeps the start's own termination status."""
    polished.nfev = int(polished.nfev) + int(start.nfev)
    polished.njev = int(polished.njev or 0) + int(start.njev or 0)
    if polished.status == 0:
        polished.status, polished.message = start.status, start.message
    return polished


def _force(p, u):
    try:
        return loop(p, u)[0]
    except OverflowError:
        return None


def _perturb(x0, cols, lo, hi, rng) -> np.ndarray:
    """A random start near x0 (scaled variables): relative for rates, absolute otherwise."""
    x = x0.copy()
    for j, c in enumerate(cols):
        if c == ALPHA:
            x[j] = x0[j] * math.exp(rng.normal(0.0, 0.7))
        elif c == GAMMA2:
            x[j] = x0[j] * math.exp(rng.normal(0.0, 0.5)) if x0[j] > 0 else rng.uniform(1.0, 10.0)
        elif c == BETA2:
            x[j] = x0[j] + rng.normal(0.0, max(abs(x0[j]) * 0.3, 1.0))
        elif c == GAMMA3:
            x[j] = x0[j] + rng.normal(0.0, 0.3)
        else:  # kb, f0, beta1, gamma1: in units of the force range (per max|u| for kb)
            x[j] = x0[j] + rng.normal(0.0, max(abs(x0[j]) * 0.3, 0.1))
    return _inside(x, lo, hi, 1e-6)


def _inside(x, lo, hi, rel=1e-9):
    """Clip x strictly inside the (possibly infinite) bounds."""
    with np.errstate(invalid="ignore"):
        a = np.where(np.isfinite(lo), lo + rel * (1 + np.abs(lo)), lo)
        b = np.where(np.isfinite(hi), hi - rel * (1 + np.abs(hi)), hi)
    return np.clip(x, a, b)


def _standard_errors(jac: np.ndarray, r: np.ndarray, k: int) -> np.ndarray:
    """sqrt(diag(s^2 (J^T J)^-1)) in scaled variables; inf along directions J does not see."""
    n = r.size
    s2 = float(r @ r) / max(n - k, 1)
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    tiny = sv <= 1e-10 * sv[0] if sv.size and sv[0] > 0 else np.ones_like(sv, dtype=bool)
    with np.errstate(divide="ignore"):
        inv_s2 = np.where(tiny, 0.0, 1.0 / np.where(tiny, 1.0, sv) ** 2)
    var = (vt.T ** 2) @ inv_s2 * s2
    unseen = np.any((np.abs(vt[tiny]) > 1e-3), axis=0) if np.any(tiny) else np.zeros(vt.shape[1], bool)
    return np.where(unseen, np.inf, np.sqrt(var))


def round_set(p: np.ndarray, digits: int = 7) -> np.ndarray:
    """Round every parameter to ``digits`` significant digits (what the deck fragment holds)."""
    out = np.array(p, dtype=float)
    for idx, v in np.ndenumerate(out):
        out[idx] = float(f"{v:.{digits}g}")
    return out


# --------------------------------------------------------------------------- writers


def safe_names(names) -> dict[str, str]:
    """Set names as distinct file-name parts (other characters become ``_``)."""
    out: dict[str, str] = {}
    for name in names:
        base = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("_.") or "set"
        part, k = base, 2
        while part in out.values():
            part, k = f"{base}_{k}", k + 1
        out[name] = part
    return out


def write_loop_csv(res: LoopResult, path: Path) -> None:
    """Columns u [m], f [N] (and f_data [N] when measured data were given)."""
    cols, names = [res.u, res.f], ["u", "f"]
    if res.f_data is not None:
        cols.append(res.f_data)
        names.append("f_data")
    np.savetxt(path, np.column_stack(cols), delimiter=",", header=",".join(names), comments="", fmt="%.10g")


def effective_rows(sets: dict[str, np.ndarray], amplitudes) -> list[dict]:
    """effective.csv's rows (rbhyst.model.effective): every set at every amplitude; AnalysisError
    where a set's exponentials overflow on a cycle."""
    from rbhyst.model.effective import effective

    rows = []
    for name, p in sets.items():
        for a in amplitudes:
            try:
                rows.append(effective(p, a).row(name))
            except OverflowError as exc:
                raise AnalysisError(f"hysteresis.{name}: the cycle of amplitude {a:g} m: {exc}") from None
    return rows


def write_effective_csv(rows: list[dict], path: Path) -> None:
    """effective.csv: set, amplitude_m, k_eff_N_m, beta_eff, energy_J (12 significant digits)."""
    from rbhyst.model.effective import COLUMNS

    lines = [",".join(COLUMNS)]
    for r in rows:
        lines.append(",".join([r["set"]] + [f"{r[c]:.12g}" for c in COLUMNS[1:]]))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def write_json(obj: dict, path: Path) -> None:
    path.write_text(json.dumps(_plain(obj), indent=2) + "\n", encoding="utf-8")


def _plain(x):
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def deck_fragment(name: str, p: np.ndarray, comment: str = "") -> str:
    """TOML text of ``[hysteresis.<name>]`` that a deck takes as it is."""
    import tomli_w

    body = tomli_w.dumps({"hysteresis": {name: parameters_dict(p)}})
    head = "".join(f"# {line}\n" for line in comment.splitlines())
    return head + body


def header(kind: str) -> dict:
    return {"rbhyst": __version__, "command": kind, "units": {"u": "m", "f": "N", "work": "J"}}
