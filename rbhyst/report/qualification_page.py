"""report.html of a qualification (``rbhyst qualify``): the verdict and what it rests on.

The verdict first, with the condition each part of it met or missed; the figure; then every
criterion's demand, capacity and margin (per motion too); the required response spectrum and how
each motion's test response spectrum met it; each run's accuracy; each run's peaks; the deck as
run. Every number is qualification.json's or a run's summary.json's, as the files hold it
(rbhyst.report.html's conventions).
"""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

from rbhyst.report.html import (esc, figure, figure_names, items, load_json, num, page, peaks_section, table,
                                toml_text)
from rbhyst.report.signing import about, signature

SRC = "qualification.json"
STANDARDS = {"ac156": "ICC-ES AC156", "ieee693": "IEEE 693"}
#: a required response spectrum of at most this many points is shown point by point
RRS_POINTS_SHOWN = 16


def qualification_report(folder: Path, owned: set[str], written: datetime | None = None) -> str:
    """A qualification's page from qualification.json, its runs' summary.json and its figure
    (``written``: the moment to say it was written, default now)."""
    q = load_json(folder / SRC)
    runs = [(r["motion"], r["summary"], load_json(folder / r["summary"])) for r in q.get("runs", [])
            if r["summary"] in owned and (folder / r["summary"]).is_file()]
    files = sorted({r.get("source") or "" for r in q.get("rrs", {}).values()} - {""})
    standard = STANDARDS.get(q.get("standard")) or f"the required response spectra of {', '.join(files) or 'files'}"
    body = [_glance(q, standard), _verdict(q, standard)]
    warnings, notes = q.get("warnings", []), q.get("notes", [])
    body.append("<h2>Warnings</h2>" + (items(warnings, "warnings") if warnings else '<p class="ok">No warnings.</p>'))
    if notes:
        body.append("<h3>Notes</h3>" + items(notes, "notes"))
    # the figure next to the verdict: the spectra in their bands and every margin at one glance
    figures = figure_names(folder, owned, ("qualification.png",))
    body.append('<section class="page"><h2>Figures</h2>'
                + ("".join(figure(folder, n, _caption(n)) for n in figures) if figures else
                   '<p class="muted">The qualification wrote no figure (--no-plots or output.plots = false).</p>')
                + "</section>")
    body.append(_criteria(q))
    body.append(_spectra(q))
    body.append(_accuracy(q))
    for label, src, s in runs:
        label = "The deck's own motion" if label == "deck" else f"{label[:1].upper()}{label[1:]}"
        body.append(peaks_section(s, src, f"{label}: peaks and extremes ({src})"))
    body.append(_deck(q))
    title = next((s.get("title") for _, _, s in runs if s.get("title")), None) or "rbhyst qualify"
    fields = (q.get("deck_as_run") or {}).get("report")
    return page(title, f"Qualification to {standard}, rbhyst {q.get('rbhyst_version', '')}: results in "
                       f"{folder.name}/", body,
                about(q.get("provenance"), fields, written or datetime.now(UTC), SRC), signature(fields))


def _caption(name: str) -> str:
    if name == "qualification.png":
        return ("Each axis' required response spectrum, its band and the test response spectra; every criterion's "
                "demand over its capacity (qualification.png)")
    return name


def _made(motion: dict) -> bool:
    """A motion rbhyst made (its records in motions/), not the deck's own excitation.support."""
    return "files" in motion


def _least_margin(criteria: list[dict]) -> int | None:
    return min(range(len(criteria)), key=lambda i: criteria[i]["margin"]) if criteria else None


def _glance(q: dict, standard: str) -> str:
    criteria, acc = q.get("criteria", []), q.get("accuracy", {})
    passed = bool(q.get("pass"))
    cells = [f'<div><b>verdict</b><span class="{"ok" if passed else "bad"}">{"PASS" if passed else "FAIL"}'
             "</span></div>",
             f"<div><b>against</b>{esc(standard)}</div>",
             f"<div><b>motions</b>{len(q.get('motions', []))}</div>",
             f"<div><b>criteria within capacity</b>{sum(1 for c in criteria if c['pass'])} of {len(criteria)}</div>"]
    i = _least_margin(criteria)
    if i is not None:
        c = criteria[i]
        cells.append(f"<div><b>least margin ({esc(c['criterion'])} {esc(c['item'])})</b>"
                     f"{num(c['margin'], f'{SRC}:criteria.{i}.margin', 'g', 'span')}</div>")
    cells.append(f"<div><b>TRS within the band</b>{'yes' if q.get('trs', {}).get('pass') else 'no'}</div>")
    cells.append(f"<div><b>largest estimated error</b>"
                 f"{num(acc.get('estimated_error'), f'{SRC}:accuracy.estimated_error', 'pct', 'span')} "
                 f"(at most {num(acc.get('warn_error'), f'{SRC}:accuracy.warn_error', 'pct', 'span')})</div>")
    cells.append(f"<div><b>warnings</b>{len(q.get('warnings', []))}</div>")
    return f'<div class="glance">{"".join(cells)}</div>'


def _verdict(q: dict, standard: str) -> str:
    """The verdict and the four conditions it takes, each met or not."""
    criteria, trs, acc = q.get("criteria", []), q.get("trs", {}), q.get("accuracy", {})
    over = [c for c in criteria if not c["pass"]]
    made = any(_made(m) for m in q.get("motions", []))
    conditions = [
        (trs.get("pass"), "Every motion's test response spectrum lies within its band at every frequency of the "
                          "1/48-octave grid of the check range (the standard's 1/6-octave points among it) "
                          "and its peak acceleration is at least the least it may be"
                          + (", and its components are independent" if made else "") + "."),
        (acc.get("pass"), f"Every run vouches for its accuracy: {acc.get('rule', '')}."),
        (not q.get("warnings"), "No run warned."),
        (not over, f"Every criterion is within its capacity ({len(criteria) - len(over)} of {len(criteria)})."),
    ]
    passed = bool(q.get("pass"))
    missed = sum(1 for ok, _ in conditions if not ok)
    lines = "".join(f'<li><span class="{"ok" if ok else "bad"}">{"met" if ok else "not met"}</span>: {esc(text)}</li>'
                    for ok, text in conditions)
    head = (f'<p class="ok"><b>The deck qualifies to {esc(standard)}</b>: every condition below is met.</p>' if passed
            else f'<p class="bad"><b>The deck does not qualify to {esc(standard)}</b>: a pass needs every condition '
                 f'below, and {missed} {"is" if missed == 1 else "are"} not met.</p>')
    return f"<section><h2>Verdict</h2>{head}<ul>{lines}</ul></section>"


def _criteria(q: dict) -> str:
    criteria = q.get("criteria", [])
    n = max((len(c.get("per_motion", [])) for c in criteria), default=0)
    rows = []
    for i, c in enumerate(criteria):
        p = f"{SRC}:criteria.{i}"
        rows.append([c["criterion"], c["item"], num(c["demand"], f"{p}.demand"), num(c["capacity"], f"{p}.capacity"),
                     c["unit"], num(c["margin"], f"{p}.margin"),
                     '<td class="ok">within</td>' if c["pass"] else '<td class="bad">exceeded</td>',
                     *([_each(v, f"{p}.per_motion.{k}", ok) for k, (v, ok) in
                        enumerate(zip(c.get("per_motion", []), c.get("per_motion_pass", [True] * n)))]
                       if n > 1 else [])])
    motions = [f"motion {k + 1}" for k in range(n)] if n > 1 else []
    statistic = q.get("statistic", "")
    rule = statistic.get("rule", "") if isinstance(statistic, dict) else statistic
    over = [f"{c['item']}: {', '.join(c['over_capacity'])}" for c in criteria if c.get("over_capacity")]
    said = ("" if not over or n < 2 else
            f"<p class=\"bad\">Over capacity in a motion of their own: {esc('; '.join(over))} (marked below).</p>")
    return ('<section class="page"><h2>Criteria</h2>'
            f"<p>Demand: {esc(rule)}. Margin: {esc(q.get('margin', ''))}.</p>" + said
            + table(["criterion", "item", "demand", "capacity", "unit", "margin", "", *motions], rows,
                    {2, 3, 5, *range(7, 7 + len(motions))})
            + "</section>")


def _each(v, src: str, ok: bool) -> str:
    """A motion's own demand, marked where it is over the capacity."""
    cell = num(v, src)
    return cell if ok else cell.replace('class="num"', 'class="num bad"', 1)


def _spectra(q: dict) -> str:
    out = ['<section class="page"><h2>Required and test response spectra</h2>']
    for axis, r in q.get("rrs", {}).items():
        p = f"{SRC}:rrs.{axis}"
        rows = [["spectrum", r.get("name", "")], ["source", r.get("source", "")],
                ["axis", f"{axis} ({q.get('axes', {}).get(axis, '')})"],
                ["damping ratio", num(r.get("damping"), f"{p}.damping", "pct")],
                ["band, times the RRS", f"{r['band'][0]:g} to {r['band'][1]:g}"],
                ["check range [Hz]", f"{r['check_range_hz'][0]:g} to {r['check_range_hz'][1]:g}"],
                ["least peak acceleration [g]", num(r.get("peak_min_g"), f"{p}.peak_min_g", "g4")]]
        out.append(f"<h3>{esc(axis)}: {esc(r.get('name', ''))}</h3>" + table(["", ""], rows))
        freq, sa, key = r.get("frequency_hz", []), r.get("sa_g", []), ("frequency_hz", "sa_g")
        if r.get("formula"):  # a standard's formulas: them, and their breakpoints (the curve is tabulated)
            out.append(f"<p>{esc(r['formula'])}</p>")
            freq, sa, key = r.get("breakpoints_hz", []), r.get("breakpoints_sa_g", []), ("breakpoints_hz",
                                                                                         "breakpoints_sa_g")
        if 0 < len(freq) <= RRS_POINTS_SHOWN:
            out.append(table(["RRS point", "frequency [Hz]", "spectral acceleration [g]"],
                             [[str(k + 1), num(f, f"{p}.{key[0]}.{k}"), num(a, f"{p}.{key[1]}.{k}", "g4")]
                              for k, (f, a) in enumerate(zip(freq, sa))], {1, 2}))
        elif freq:
            out.append(f'<p class="muted">The RRS has {len(freq)} points, {freq[0]:g} to {freq[-1]:g} Hz.</p>')
    rows = []
    for m, motion in enumerate(q.get("motions", [])):
        for axis in q.get("rrs", {}):
            if _made(motion):
                p = f"{SRC}:motions.{m}.axes.{axis}"
                facts = motion["axes"][axis]
                t, tp = facts["trs"], f"{p}.trs"
                where = motion["files"][axis]
            else:  # the deck's own: its TRS, and its strong motion where it is a record
                tp = f"{SRC}:motions.{m}.trs.{axis}"
                p = f"{SRC}:motions.{m}.strong_motion.{axis}"
                facts, t = (motion.get("strong_motion") or {}).get(axis) or {}, motion["trs"][axis]
                where = motion.get("source", "the deck's excitation.support")
            rows.append([str(motion.get("number", m + 1)), axis, where,
                         num(t.get("min_ratio"), f"{tp}.min_ratio"), num(t.get("min_at_hz"), f"{tp}.min_at_hz"),
                         num(t.get("max_ratio"), f"{tp}.max_ratio"), num(t.get("max_at_hz"), f"{tp}.max_at_hz"),
                         num(t.get("peak_g"), f"{tp}.peak_g"), num(t.get("peak_min_g"), f"{tp}.peak_min_g", "g4"),
                         '<td class="ok">yes</td>' if t.get("pass") else '<td class="bad">no</td>',
                         num(facts.get("strong_motion_s"), f"{p}.strong_motion_s"),
                         num(facts.get("strong_motion_min_s"), f"{p}.strong_motion_min_s"),
                         num(facts.get("arias_5_75_s"), f"{p}.arias_5_75_s"),
                         num(facts.get("arias_5_95_s"), f"{p}.arias_5_95_s")])
    every = " (trs.csv holds the standard's points, trs_fine.csv the fine grid)" if any(_made(m) for m in q.get("motions", [])) else ""
    out.append("<h3>The motions' test response spectra (TRS)</h3>"
               "<p>The TRS over the RRS on the 1/48-octave grid of the check range (the standard's 1/6-octave "
               "points among it): its lowest and highest anywhere, and where; "
               f"each motion's peak acceleration against the least it may be{every}; its strong motion "
               f"({esc(q.get('trs', {}).get('strong_motion_definition', ''))}) against the least, and its "
               "Arias durations beside.</p>"
               + table(["motion", "axis", "record", "lowest TRS/RRS", "at [Hz]", "highest TRS/RRS", "at [Hz]",
                        "peak [g]", "least peak [g]", "within", "strong motion [s]", "least [s]",
                        "Arias 5-75 % [s]", "Arias 5-95 % [s]"], rows, set(range(3, 9)) | set(range(10, 14))))
    correlations = [(m, motion) for m, motion in enumerate(q.get("motions", [])) if "correlation_x1_x2" in motion]
    if correlations:
        cells = []
        for m, motion in correlations:
            cells.append([str(motion.get("number", m + 1)),
                          num(motion["correlation_x1_x2"], f"{SRC}:motions.{m}.correlation_x1_x2")])
            for pair, v in (motion.get("correlations") or {}).items():
                if pair != "x1_x2":
                    cells[-1].append(num(v, f"{SRC}:motions.{m}.correlations.{pair}"))
        pairs = ["x1, x2"] + [k.replace("_", ", ") for k in (correlations[0][1].get("correlations") or {})
                              if k != "x1_x2"]
        limit = q.get("trs", {}).get("max_correlation")
        out.append(f"<p>Correlation of each motion's components (independent below {limit:g} in absolute value):</p>"
                   if limit is not None else "<p>Correlation of each motion's components:</p>")
        out.append(table(["motion", *[f"correlation {p}" for p in pairs]], cells, set(range(1, 1 + len(pairs)))))
    return "".join(out) + "</section>"


def _accuracy(q: dict) -> str:
    acc = q.get("accuracy", {})
    rows = [[r.get("motion", ""), num(r.get("estimated_error"), f"{SRC}:accuracy.per_motion.{k}.estimated_error", "pct"),
             r.get("output") or "", r.get("status") or "",
             '<td class="ok">yes</td>' if r.get("pass") else '<td class="bad">no</td>']
            for k, r in enumerate(acc.get("per_motion", []))]
    return ("<section><h2>Accuracy</h2>"
            f"<p>Rule: {esc(acc.get('rule', ''))}. The largest estimated error of each run, over every output "
            "(max over time of |x - x_exact| / max |x_exact|), and the output it is in; each run's every output "
            "is in its summary.json (accuracy.estimated_error).</p>"
            + table(["run", "largest estimated error", "in", "status", "vouches"], rows, {1}) + "</section>")


def _deck(q: dict) -> str:
    deck = q.get("deck_as_run")
    if deck is None:
        return ('<section class="page"><h2>The deck</h2><p class="muted">qualification.json holds no deck '
                "(written by an older rbhyst).</p></section>")
    made = [m for m in q.get("motions", []) if _made(m)]
    said = (f"<p>{esc(q.get('deck') or 'The deck')} as given, with the command's overrides. Each run replaced its "
            "excitation.support by the motion's records (units g), in this folder: "
            + esc("; ".join(f"motion {m.get('number')}: " + ", ".join(f"{a} = {f}" for a, f in m["files"].items())
                            for m in made))
            + ".</p>") if made else f"<p>{esc(q.get('deck') or 'The deck')} as given, with the command's overrides.</p>"
    return f'<section class="page"><h2>The deck as run</h2>{said}<pre>{esc(toml_text(deck))}</pre></section>'
