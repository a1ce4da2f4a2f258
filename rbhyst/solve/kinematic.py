"""The error a run carries from its kinematics: the seed's small rotations against exact ones.

The seed's kinematics (eqs. 7-8) drop the terms of second order in theta3: a point at r from G
is off by about |r| theta^2 / 2, and an element's force f, acting at its turned point, has a
moment about G that differs by f (b3 (cos theta - 1) - c sin theta). The second is not small
beside the rotation's own share where the forces are large against the motion: a shear force
at a point level with G, or the weight W carried by the mounts (P-Delta, W h theta for G at h
above them: it softens rocking at any amplitude). So the run first measures, along its own
compared rows, how large those neglected terms are against each column they enter (element
deformations, the moment resultant, the points' motion): where the largest share exceeds
CHECK_FRACTION x warn_error, the same scene is run again with exact kinematics
(rbhyst.model.kinematics), same method and step, and the difference of every column the error
estimate compares is the error the run carries from its model. A run with exact kinematics
carries none.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rbhyst.errors import AnalysisError

#: the kinematic difference is computed where the neglected terms reach this fraction of warn_error
CHECK_FRACTION = 0.1


def kinematics_summary(result, settings, exact=None) -> dict:
    """summary.json's ``kinematics``: the model, the largest rotation, and the difference from
    exact kinematics per column where the rotation makes it matter (see the module docstring).
    ``exact``: the same run with exact kinematics where it was made already (the answer that
    analysis.kinematics = "auto" chose: rbhyst.solve.choose)."""
    system = result.system
    out, start = rotation_extent(result)
    if "max_rotation_rad" not in out:
        return out
    if system.kinematics == "exact":
        out["difference"] = None
        out["method"] = "exact rotations: no kinematic error"
        return out
    if result.compared is None:
        out["difference"] = None
        out["method"] = "not computed: the run kept no rows to compare"
        return out
    indicator, where = neglected_share(result, start)
    out["neglected"] = {"column": where, "share": indicator}
    if exact is None and indicator <= CHECK_FRACTION * settings.warn_error:
        out["difference"] = None
        out["method"] = (f"not computed: the terms the small rotations neglect reach {indicator:.3g} of {where} "
                         f"along the run, below {CHECK_FRACTION:g} x warn_error")
        return out
    if exact is None:
        try:
            exact = exact_run(result, settings)
        except AnalysisError as err:
            out["difference"] = None
            out["method"] = f"not computed: the run with exact kinematics failed: {err}"
            return out
        if exact is None:
            out["difference"] = None
            out["method"] = "not computed: exact kinematics are built for the plane and the body in space only"
            return out
    diff = difference(result, exact)
    if diff is None:
        out["difference"] = None
        out["method"] = "not computed: the run with exact kinematics compares other rows"
        return out
    out["difference"] = diff
    worst = max(diff, key=diff.get)
    out["worst"] = {"column": worst, "difference": diff[worst]}
    out["method"] = (f"the same run with exact kinematics ({settings.integrator}, dt = {settings.dt:g} s), "
                     "max_t |small - exact| / max_t |exact| per column")
    return out


def chosen_exact(small, settings, exact) -> dict:
    """summary.json's ``kinematics`` of an answer that analysis.kinematics = "auto" took in exact
    rotations: the small-rotation run's screen, and its difference from the answer ``exact``."""
    out = kinematics_summary(small, settings, exact=exact)
    neglected = out.get("neglected", {})
    out.update(model="exact", method=(
        f"chosen by analysis.kinematics = \"auto\": the terms the small rotations neglect reach "
        f"{neglected.get('share', 0.0):.3g} of {neglected.get('column', '')}, above a tenth of warn_error; "
        "difference: the small-rotation run at the same step against this one, max_t |small - exact| / "
        "max_t |exact| per column"))
    return out


def rotation_extent(result) -> tuple[dict, object]:
    """({"model", "max_rotation_rad"}, the rotation at rest) of a run; no max_rotation_rad for a
    body that does not turn (the start then None)."""
    system = result.system
    rot = next((j for j, c in enumerate(system.coordinates) if c.rotation), None)
    out: dict = {"model": system.kinematics}
    if rot is None:
        return out, None
    key = system.coordinates[rot].column("d")
    start = float(system.static.q[rot]) if system.static is not None else 0.0
    e = result.extremes
    i = e.names.index(key)
    theta = max(abs(start + e.max[i]), abs(start + e.min[i]))
    out["max_rotation_rad"] = theta
    spins = [j for j, c in enumerate(system.coordinates) if c.rotation]
    if len(spins) > 1:  # a body in space: the largest angle turned, its components measured from rest
        start_q = system.to_deck(system.static.q) if system.static is not None else np.zeros(system.n)
        start = start_q[spins]
        theta = 0.0
        for j in spins:
            i = e.names.index(system.coordinates[j].column("d"))
            theta = max(theta, abs(start_q[j] + e.max[i]), abs(start_q[j] + e.min[i]))
        out["max_rotation_rad"] = theta
    return out, start


def neglected_share(result, start=None) -> tuple[float, str]:
    """(share, column): the largest share of a column the small rotations' neglected terms reach
    along a small-rotation run's compared rows (model_residual, or model_residual_space in space);
    (0, "") for a body that does not turn."""
    if start is None:
        _, start = rotation_extent(result)
        if start is None:
            return 0.0, ""
    spins = [c for c in result.system.coordinates if c.rotation]
    return (model_residual_space if len(spins) > 1 else model_residual)(result, start)


def needs_exact(result, settings) -> tuple[bool, float, str]:
    """(whether analysis.kinematics = "auto" takes exact kinematics, the neglected share, its
    column): exact where the terms the small rotations neglect exceed CHECK_FRACTION x warn_error
    in any compared column, judged along the small-rotation run ``result``."""
    if result.system.kinematics == "exact" or result.compared is None:
        return False, 0.0, ""
    share, where = neglected_share(result)
    return share > CHECK_FRACTION * settings.warn_error, share, where


def exact_run(result, settings, answer: bool = False, keep: bool = False, csv=None, progress=None):
    """The run of ``result`` again with exact kinematics (same method, step and compared rows),
    its error not estimated; None where exact kinematics are not built for the body. ``answer``:
    the run is the answer (its spectra too, its rows kept or streamed as ``keep`` and ``csv``
    say), not only the measure of the small rotations' error."""
    from rbhyst.model.kinematics import exact_twin
    from rbhyst.solve.plan import prepare

    twin = exact_twin(result.system)
    if twin is None:
        return None
    s = dataclasses.replace(settings, estimate=False, **({} if answer else {"spectra": None}))
    return prepare(twin, s).run(keep=keep, csv=csv, compare_every=result.compare_every, progress=progress)


def difference(result, exact) -> dict | None:
    """max_t |small - exact| / max_t |exact| per compared column (the error estimate's measure,
    each against its family's scale), or None where the two runs compare other rows."""
    from rbhyst.solve.estimate import column_errors
    from rbhyst.solve.history import estimate_columns

    if exact.compared is None or result.compared is None or exact.compared.shape != result.compared.shape:
        return None
    columns = estimate_columns(result.layout)
    keys = [k for k, _, _ in columns]
    diff = column_errors(result.compared[:, 1:], exact.compared[:, 1:], keys, [f for _, _, f in columns],
                         result.system)
    return dict(zip(keys, map(float, diff)))


def model_residual(result, start: float) -> tuple[float, str]:
    """The largest share of a column that the small rotations' neglected terms reach along the
    run's compared rows: (share, column key). Element deformations (b3 (sin theta - theta) +
    c (cos theta - 1) against the element's peak force over k0: the rows hold forces), the
    moment resultant (sum f (b3 (cos theta - 1) - c sin theta) against R3's peak) and each
    point's motion (|x| theta^2 / 2 against its peak). An indicator of where to look, not a
    bound: the response may amplify a residual."""
    from rbhyst.model.system import axial_offset
    from rbhyst.solve.history import estimate_columns, largest_abs
    from rbhyst.solve.kernels.compiled import kernel

    system, layout = result.system, result.layout
    columns = {k: i for i, (k, _, _) in enumerate(estimate_columns(layout))}
    rows = result.compared[:, 1:]
    rot = next(j for j, c in enumerate(system.coordinates) if c.rotation)
    theta = start + rows[:, columns[system.coordinates[rot].key("d")]]
    b3 = np.ascontiguousarray(system.expand(system.bvec[None, :, rot])[0], dtype=float)
    c = np.array([axial_offset(el.x[0], el.x[1], np.radians(el.angle_deg))
                  for el in system.elements for _ in range(el.count)], dtype=float)
    k0 = system.expand(system.k0[None, :])[0]
    forces = rows[:, [columns[f"e{k}_f"] for k in range(1, len(b3) + 1)]]
    best, where = 0.0, ""
    # the forces' resultant: where the elements' first-order deformations cancel in it (a body
    # rocking on mounts either side of G), the second-order ones they neglect do not. Each
    # element's neglected force (b3 s + c m) k_rev along its direction, summed: s A + m B at
    # every row, A and B the elements' sums (k_rev: the stiffest tangent, the reversal's, as a
    # mount cycling about a point is that stiff)
    angles = np.radians([el.angle_deg for el in system.elements for _ in range(el.count)])
    directions = np.column_stack([np.cos(angles), np.sin(angles)])
    k_rev = system.expand(system.k_reversal[None, :])[0]
    along_a, along_b = (b3 * k_rev) @ directions, (c * k_rev) @ directions
    # each element's deformation error against its deformation (its force over k0: the rows
    # compare forces, not deformations), the moment resultant's and the forces' resultant's
    # along each axis, in one compiled pass over the rows
    du, dr_axes = np.empty(len(b3)), np.empty(2)
    dr = kernel("neglected_terms")(theta, b3, c, np.ascontiguousarray(forces), du, along_a, along_b, dr_axes)
    scale = largest_abs(forces) / np.maximum(k0, 1e-300)
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(scale > 0, du / scale, 0.0)
    if share.size and share.max() > best:
        best, where = float(share.max()), f"e{int(share.argmax()) + 1}_u"
    key = system.coordinates[rot].key("R")
    top = float(largest_abs(rows[:, [columns[key]]])[0])
    if top > 0 and dr / top > best:
        best, where = float(dr / top), key
    share_r, key_r = resultant_share(dr_axes, rows, columns, system)
    if share_r > best:
        best, where = share_r, key_r
    turn = float(np.max(np.abs(theta))) if len(theta) else 0.0
    for name, x in layout.points:
        keys = [k for k in columns if k.startswith(f"{name}_") and k[len(name) + 1:].startswith("u")]
        top = max(np.max(np.abs(rows[:, columns[k]])) for k in keys) if keys else 0.0
        miss = float(np.hypot(*x[:2])) * turn ** 2 / 2
        if top > 0 and miss / top > best:
            best, where = miss / top, keys[0]
    return best, where


def model_residual_space(result, start: np.ndarray) -> tuple[float, str]:
    """model_residual of a body in space: the terms of second order and above in the small
    rotation vector theta (rbhyst.model.rotations: R(theta) - I - [theta]x), in each element's
    deformation d . ((R - I) x - theta x x), in the resultant's moment sum f (R x - x) x d, and
    |x| |theta|^2 / 2 in each point's motion, against their peaks as in the plane."""
    from rbhyst.model.rotations import matrices
    from rbhyst.solve.history import estimate_columns

    system, layout = result.system, result.layout
    columns = {k: i for i, (k, _, _) in enumerate(estimate_columns(layout))}
    rows = result.compared[:, 1:]
    spins = [c for c in system.coordinates if c.rotation]
    theta = start[None, :] + np.column_stack([rows[:, columns[c.key("d")]] for c in spins])
    higher = matrices(theta) - np.eye(3)[None]  # R - I, the small rotations' [theta]x removed below
    higher[:, 0, 1] += theta[:, 2]
    higher[:, 0, 2] -= theta[:, 1]
    higher[:, 1, 0] -= theta[:, 2]
    higher[:, 1, 2] += theta[:, 0]
    higher[:, 2, 0] += theta[:, 1]
    higher[:, 2, 1] -= theta[:, 0]
    xs = np.array([el.x for el in system.elements for _ in range(el.count)], dtype=float)
    ds = np.array([el.direction for el in system.elements for _ in range(el.count)], dtype=float)
    k0 = system.expand(system.k0[None, :])[0]
    forces = np.column_stack([rows[:, columns[f"e{k}_f"]] for k in range(1, len(xs) + 1)])
    best, where = 0.0, ""
    du = np.einsum("ei,kij,ej->ke", ds, higher, xs)
    scale = np.max(np.abs(forces), axis=0) / np.maximum(k0, 1e-300)
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(scale > 0, np.max(np.abs(du), axis=0) / scale, 0.0)
    if share.size and share.max() > best:
        best, where = float(share.max()), f"e{int(share.argmax()) + 1}_u"
    # the forces' resultant, as in the plane: the second-order deformations at the reversal's
    # stiffness, summed
    k_rev = system.expand(system.k_reversal[None, :])[0]
    df = du * k_rev[None, :]
    share_r, key_r = resultant_share(np.abs(df @ ds).max(axis=0) if df.size else np.zeros(3), rows, columns,
                                     system)
    if share_r > best:
        best, where = share_r, key_r
    # the moment about G of the forces at their turned points, beyond the small rotations' share
    arms = np.einsum("kij,ej->kei", matrices(theta) - np.eye(3)[None], xs) - np.cross(theta[:, None, :], xs[None])
    dm = np.einsum("ke,kei->ki", forces, np.cross(arms, ds[None]))
    keys = [c.key("R") for c in spins]
    top = max(float(np.max(np.abs(rows[:, columns[k]]))) for k in keys)
    if top > 0 and np.max(np.abs(dm)) / top > best:
        best, where = float(np.max(np.abs(dm)) / top), keys[int(np.argmax(np.max(np.abs(dm), axis=0)))]
    turn = float(np.max(np.linalg.norm(theta, axis=1)))
    for name, x in layout.points:
        keys = [k for k in columns if k.startswith(f"{name}_") and k[len(name) + 1:].startswith("u")]
        top = max(np.max(np.abs(rows[:, columns[k]])) for k in keys) if keys else 0.0
        miss = float(np.linalg.norm(x)) * turn ** 2 / 2
        if top > 0 and miss / top > best:
            best, where = miss / top, keys[0]
    return best, where


def resultant_share(dr: np.ndarray, rows: np.ndarray, columns: dict, system) -> tuple[float, str]:
    """(share, key): the largest of the translational resultant's columns (R1, R2, and R3 in
    space) that the neglected forces reach, ``dr`` the largest along each deck axis (the
    elements' neglected deformations times their stiffest tangent, along their directions,
    summed), against the column's error scale (estimate.error_scales: its peak, or its
    family's where it is small)."""
    from rbhyst.solve.estimate import error_scales

    moving = [c for c in system.coordinates if not c.rotation]
    keys = [c.key("R") for c in moving][:len(dr)]
    if not keys or len(rows) == 0:
        return 0.0, ""
    dr = np.asarray(dr[:len(keys)], dtype=float)
    peaks = np.array([float(np.max(np.abs(rows[:, columns[k]]))) for k in keys])
    scales = error_scales(peaks, keys, ["R"] * len(keys), system)
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(scales > 0, dr / scales, 0.0)
    j = int(np.argmax(share))
    return float(share[j]), keys[j]


#: a rotation below this (rad) is rounding (a nanometre at a metre): small and exact kinematics
#: cannot differ by anything but rounding, whatever share of a column at rest it is
ROUNDING_ROTATION = 1e-9


def kinematics_warning(kinematics: dict | None, warn_error: float, result=None) -> list[str]:
    """One warning where the small rotations cost more than warn_error (or may, where it was
    not computed), with the numbers and what to do; the columns that matter first, in their
    family's terms (estimate.family_terms of ``result``'s peaks)."""
    from rbhyst.solve.estimate import family_terms, ranked

    if not kinematics or kinematics.get("model") != "small" or "max_rotation_rad" not in kinematics:
        return []
    theta = kinematics["max_rotation_rad"]
    if theta < ROUNDING_ROTATION:  # a body at rest to rounding: the terms of order theta^2 are nothing
        return []
    diff = kinematics.get("difference")
    if diff:
        over = ranked(diff, warn_error, *family_terms(diff, result))
        if not over:
            return []
        (name, worst), more = over[0], over[1:]
        also = f" (also {', '.join(f'{k} {v:.2%}' for k, v in more[:4])}{' ...' if len(more) > 4 else ''})" if more else ""
        return [f"the seed's small rotations (eqs. 7-8) differ from exact kinematics by {worst:.2%} in "
                f"{name}{also}, above analysis.warn_error = {warn_error:g}; the body turns by up to "
                f"{theta:.3g} rad: set analysis.kinematics = \"exact\" (or leave it out: \"auto\" takes exact "
                "kinematics where they matter)"]
    neglected = kinematics.get("neglected") or {}
    if neglected.get("share", 0.0) > warn_error:
        return [f"the terms the seed's small rotations (eqs. 7-8) neglect reach {neglected['share']:.2%} of "
                f"{neglected['column']} (the body turns by up to {theta:.3g} rad), above analysis.warn_error = "
                f"{warn_error:g}; the difference from exact kinematics was {kinematics['method']}"]
    return []
