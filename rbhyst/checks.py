"""What a finished run says about itself: notes (information) and warnings (a result to doubt)."""

from __future__ import annotations

from .results import ENERGY_WARN, Result

#: rotations above this (rad) leave the small-rotation kinematics of seed eqs. 7-8: a point at
#: x from G moves by x theta to first order, and the neglected second-order terms (1 - cos
#: theta) x ~ x theta^2 / 2 are theta / 2 of it: 2.5 % at 0.05 rad, beyond the 1 % accuracy
#: rbhyst states for the integration itself
ROTATION_WARN = 0.05


def diagnose(result: Result) -> tuple[list[str], list[str]]:
    """Notes and warnings of a run, in the words the command line prints."""
    notes = list(result.system.notes)
    warnings: list[str] = []
    s, st = result.settings, result.stats
    ex = result.system.excitation
    t_end = st.steps * s.dt
    if not ex.signals:
        warnings.append("the deck has no excitation: the body stays at rest and every response is zero")
    elif not ex.acts_before(t_end):
        warnings.append(f"no excitation acts within the analysis (0 to {t_end:g} s): every response is zero")
    if st.record_substeps > 1:
        notes.append(f"the excitation is sampled finer than dt = {s.dt:g} s: {st.record_substeps} substeps per "
                     "step follow it (output stays on dt)")
    if st.substeps:
        notes.append(f"{st.substeps} substeps (up to 2^{st.max_substep_level} per step) resolved stiff instants; "
                     "see summary.json")
    if result.energy_balance > ENERGY_WARN:
        warnings.append(f"energy balance error {result.energy_balance:.2%} exceeds {ENERGY_WARN:.0%}: reduce dt")
    e = result.extremes
    theta = e.peak("theta3_rad")
    if theta > ROTATION_WARN:
        i = e.names.index("theta3_rad")
        t = e.t_max[i] if abs(e.max[i]) >= abs(e.min[i]) else e.t_min[i]
        warnings.append(f"the rotation reaches {theta:.3g} rad at t = {t:.4g} s, beyond the small rotations of the "
                        f"seed's kinematics (eqs. 7-8, about {theta / 2:.1%} error in point motions; rbhyst warns "
                        f"above {ROTATION_WARN:g} rad)")
    warnings += stroke_warnings(result)
    return notes, warnings


def stroke_warnings(result: Result) -> list[str]:
    """An element beyond its stroke: which, how far, when."""
    from .results import stroke_use

    out, k = [], 1
    for el in result.system.elements:
        if el.stroke is not None:
            use = stroke_use(result.extremes, f"e{k}_u_m", el.stroke)
            if use["utilization"] > 1.0:
                span = f"e{k}" if el.count == 1 else f"e{k}-e{k + el.count - 1}"
                out.append(f"element {span} ({el.hysteresis!r}) goes beyond its stroke: {use['peak_deformation_m']:.4g} m "
                           f"at t = {use['time_of_peak_s']:.4g} s against a limit of "
                           f"{el.stroke[1] if use['peak_deformation_m'] > 0 else el.stroke[0]:g} m "
                           f"({use['utilization']:.0%} of it)")
        k += el.count
    return out
