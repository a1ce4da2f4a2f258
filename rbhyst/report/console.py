"""What `rbhyst run` prints about its elements: one aligned row per [[elements]] entry and per
direction of an [[isolators]] entry (identical elements in parallel, `count`, share one; a column
names the isolator and direction where the deck has isolators), from summary.json's numbers; and the body's modes (what
`rbhyst modes` prints too). Plain text, no matplotlib."""

from __future__ import annotations

#: every entry up to this many; beyond, the most loaded SHOWN and a line for the rest
ALL_UP_TO = 12
SHOWN = 8


def element_table(summary: dict, all_up_to: int = ALL_UP_TO, shown: int = SHOWN) -> list[str]:
    """The lines of the elements' table for ``summary`` (Result.summary(), summary.json): peak
    |force|, the peak deformation (signed; with a stroke, that on the side it used most) and
    how much of the stroke it used."""
    entries = summary.get("elements") or []
    if not entries:
        return []
    rest = set(summary.get("at_rest", ()))  # (rounding: shown as 0)
    peaks = {c: 0.0 if c in rest else v for c, v in summary["peaks"].items()}
    extremes = {c: {**v, "max": 0.0, "min": 0.0} if c in rest else v for c, v in summary["extremes"].items()}
    rows, k = [], 1
    for el in entries:
        n = el["count"]
        u = extremes[f"e{k}_u_m"]
        stroke = el.get("stroke")
        rows.append({
            "label": f"e{k}" if n == 1 else f"e{k}-e{k + n - 1} (each)",
            "isolator": f"{el['isolator']} {el['role']}" if "isolator" in el else "-",
            "set": el["hysteresis"],
            "angle": el.get("angle_deg"),
            "direction": el.get("direction"),
            "f": peaks[f"e{k}_f_N"],
            "u": 0.0 if f"e{k}_u_m" in rest else stroke["peak_deformation_m"] if stroke else (
                u["max"] if abs(u["max"]) >= abs(u["min"]) else u["min"]),
            "limits": stroke["limits_m"] if stroke else None,
            "used": stroke["utilization"] if stroke else None,
        })
        k += n
    heading = "elements (peaks over the run):"
    if len(rows) > all_up_to:
        rows = sorted(rows, key=lambda r: (-1.0 if r["used"] is None else r["used"], r["f"]), reverse=True)
        more = len(rows) - shown
        rows = rows[:shown]
        how = "stroke used, then peak force" if any(r["used"] is not None for r in rows) else "peak force"
        heading = f"elements: the {shown} most loaded of {shown + more} ({how}):"
    else:
        more = 0
    kn = max(r["f"] for r in rows) >= 1e3
    strokes = any(r["limits"] is not None for r in rows)
    space = any(r["direction"] is not None for r in rows)
    isolators = any(r["isolator"] != "-" for r in rows)  # a column of which isolator, when there are any
    header = ["element", *(["isolator"] if isolators else []), "set", "direction" if space else "angle [deg]",
              f"peak |f| [{'kN' if kn else 'N'}]", "peak u [mm]"]
    if strokes:
        header += ["stroke [mm]", "used"]
    table = [header]
    for r in rows:
        line = ("(" + ", ".join(f"{d + 0.0:.3g}" for d in r["direction"]) + ")") if space else f"{r['angle']:g}"
        cells = [r["label"], *([r["isolator"]] if isolators else []), r["set"], line,
                 f"{r['f'] * (1e-3 if kn else 1.0):.4g}",
                 f"{r['u'] * 1e3:+.4g}" if r["u"] else "0"]
        if strokes:
            if r["limits"] is None:
                cells += ["-", "-"]
            else:
                lo, hi = r["limits"]
                cells += [f"{lo * 1e3:g}, +{hi * 1e3:g}", _percent(r["used"])]
        table.append(cells)
    left = {0, 1, 2} if isolators else {0, 1}  # names to the left, numbers to the right
    if strokes and any(r["used"] is not None and r["used"] > 1.0 for r in rows):
        # "152% over": the percentages aligned on their right, the word after them
        used = len(header) - 1
        width = max(len(row[used].removesuffix(" over")) for row in table[1:])
        for row in table[1:]:
            number = row[used].removesuffix(" over")
            row[used] = number.rjust(width) + row[used][len(number):]
        table[0][used] = table[0][used].rjust(width)
        left.add(used)
    widths = [max(len(row[i]) for row in table) for i in range(len(header))]
    lines = [heading]
    for row in table:
        lines.append("  " + "  ".join(c.ljust(w) if i in left else c.rjust(w)
                                      for i, (c, w) in enumerate(zip(row, widths))).rstrip())
    if more:
        lines.append(f"  ... and {more} more (every element in summary.json)")
    return lines


def stop_lines(summary: dict) -> list[str]:
    """What the stops met (summary.json's elements' ``stop``, rbhyst.model.stop): one line for the
    entries that struck theirs (impacts, peak contact force and penetration, energy lost), one for
    those that never did; nothing where no element has a stop."""
    struck, clear, k = [], [], 1
    for el in summary.get("elements") or []:
        stop = el.get("stop")
        name = f"e{k}" if el["count"] == 1 else f"e{k}-e{k + el['count'] - 1} (each)"
        k += el["count"]
        if stop is None or "impacts" not in stop:
            continue
        if stop["impacts"] or stop["peak_force_N"] > 0.0:
            struck.append(f"{name}: {stop['impacts']} impact{'s' * (stop['impacts'] != 1)}, peak "
                          f"{stop['peak_force_N']:.4g} N at {stop['peak_penetration_m'] * 1e3:.3g} mm, "
                          f"{stop['impact_J']:.3g} J lost")
        else:
            clear.append(name)
    lines = [f"stops struck: {'; '.join(struck)}"] if struck else []
    if clear:
        lines.append(f"stops never reached: {', '.join(clear)}")
    return lines


def _percent(used: float) -> str:
    text = f"{100 * used:.0f}%" if used >= 0.1 else f"{100 * used:#.2g}%"
    return text + " over" if used > 1.0 else text


#: what each stiffness's table is headed with
MODE_HEADINGS = {"initial": "modes of the initial system (K0 = sum k0 b b^T, undamped):",
                 "tangent at rest under gravity": "modes at rest under gravity (the elements' tangents there, undamped):"}


def mode_table(modes: dict) -> list[str]:
    """The lines of the modes' tables for summary.json's ``modes`` (rbhyst.solve.modes): one row
    per mode, its frequency and its shape (largest component +1), then its notes; the same for
    ``at_rest`` where there is one."""
    lines = []
    for part in (modes, modes.get("at_rest")):
        if not part:
            continue
        header = ["mode", "f [Hz]", *part["coordinates"]]
        table = [header]
        for j, (f, shape) in enumerate(zip(part["frequencies_hz"], part["shapes"]), start=1):
            table.append([str(j), f"{f:#.4g}", *("0" if x == 0.0 else f"{round(x, 3) + 0.0:+.3f}" for x in shape)])
        widths = [max(len(row[i]) for row in table) for i in range(len(header))]
        lines.append(MODE_HEADINGS.get(part["stiffness"], f"modes ({part['stiffness']}):"))
        for row in table:
            lines.append("  " + "  ".join(c.rjust(w) for c, w in zip(row, widths)).rstrip())
        lines.extend(f"  {note}" for note in part.get("notes", ()))
    if modes.get("at_rest"):
        lines.extend(WHICH_MODES)
    return lines


#: after the two tables of a body under gravity: what each is for
WHICH_MODES = ("which to use: the modes at rest are those of the body as installed, its elements loaded by its weight",
               "  (their loading tangents): compare them with the equipment's measured frequencies on its mounts;",
               "  the initial ones (K0, independent of the load) are those Rayleigh damping and the integrators take.")


def rang_lines(rang: dict | None) -> list[str]:
    """One line for summary.json's ``rang`` (rbhyst.solve.ringing): the coordinates that rang after
    the excitation, their frequency and those of their first and last cycle at their amplitudes."""
    coords = (rang or {}).get("coordinates") or {}
    parts = []
    for name, c in coords.items():
        if c.get("frequency_hz") is None:
            continue
        unit = "rad" if name.startswith("theta") else "m"
        parts.append(f"{name} {c['frequency_hz']:.4g} Hz (first cycle {c['first_cycle_hz']:.4g} Hz at "
                     f"{c['amplitude_first']:.3g} {unit}, last {c['last_cycle_hz']:.4g} Hz at "
                     f"{c['amplitude_last']:.3g} {unit})")
    return [f"rang after the excitation: {'; '.join(parts)}"] if parts else []
