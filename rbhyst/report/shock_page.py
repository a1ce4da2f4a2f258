"""report.html of a shock verdict (``rbhyst shock``, or ``rbhyst qualify`` under shock): the
verdict and what it rests on.

The verdict first, with the conditions it took; the figures (the pulse, the drive's SRS and
PVSS, or each axis's SRS against its specification's band); every criterion's demand, capacity
and margin with each run's; the drive of each axis; each shock's own peaks against the first's;
each run's accuracy and peaks; the deck as run. Every number is shock.json's or a run's
summary.json's, as the files hold it (rbhyst.report.html's conventions).
"""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

from rbhyst.report.html import esc, figure, figure_names, items, load_json, num, page, peaks_section, table, toml_text
from rbhyst.report.signing import about, signature

SRC = "shock.json"
CAPTIONS = {"pulse.png": "The classical pulse and its tolerance band (pulse.png)",
            "srs.png": "The drive's shock response spectrum (srs.png)",
            "pvss.png": "The drive's pseudo-velocity shock spectrum on tripartite axes (pvss.png)",
            "srs_check.png": "Each axis's drive: its SRS against the specification's tolerance band (srs_check.png)"}


def shock_report(folder: Path, owned: set[str], written: datetime | None = None) -> str:
    """A shock verdict's page from shock.json, its runs' summary.json and its figures."""
    d = load_json(folder / SRC)
    runs = [(r["run"], r["summary"], load_json(folder / r["summary"])) for r in d.get("runs", [])
            if r["summary"] in owned and (folder / r["summary"]).is_file()]
    drives = _drives(d)
    body = [_glance(d, drives), _verdict(d, drives)]
    warnings, notes = d.get("warnings", []), d.get("notes", [])
    body.append("<h2>Warnings</h2>" + (items(warnings, "warnings") if warnings else '<p class="ok">No warnings.</p>'))
    if notes:
        body.append("<h3>Notes</h3>" + items(notes, "notes"))
    figures = figure_names(folder, owned, tuple(CAPTIONS))
    body.append('<section class="page"><h2>Figures</h2>'
                + ("".join(figure(folder, n, CAPTIONS.get(n, n)) for n in figures) if figures else
                   '<p class="muted">The command wrote no figure (--no-plots or output.plots = false).</p>')
                + "</section>")
    body += [_criteria(d), _drive_section(d, drives), _shocks(d), _accuracy(d)]
    for label, src, s in runs:
        body.append(peaks_section(s, src, f"Run {label}: peaks and extremes ({src})"))
    deck = d.get("deck_as_run")
    if deck is not None:
        body.append(f'<section class="page"><h2>The deck as run</h2><p>{esc(d.get("deck") or "The deck")} as given, '
                    "with the command's overrides; each run replaced its excitation by its axis's drive.</p>"
                    f"<pre>{esc(toml_text(deck))}</pre></section>")
    title = next((s.get("title") for _, _, s in runs if s.get("title")), None) or "rbhyst shock"
    fields = (deck or {}).get("report")
    return page(title, f"Shock verdict, rbhyst {d.get('rbhyst_version', '')}: results in {folder.name}/", body,
                about(d.get("provenance"), fields, written or datetime.now(UTC), SRC), signature(fields))


def _drives(d: dict) -> dict[str, tuple[str, dict]]:
    """Each drive's facts and their path in shock.json: one for every axis, or one an axis."""
    drive = d.get("drive", {})
    if "per_axis" in drive:
        return {axis: (f"drive.per_axis.{axis}", facts) for axis, facts in drive["per_axis"].items()}
    return {"every axis": ("drive", drive)}


def _shocks_per_direction(d: dict) -> int:
    drive = d.get("drive", {})
    return drive.get("shocks_per_direction", 0)


def _glance(d: dict, drives: dict) -> str:
    criteria, acc = d.get("criteria", []), d.get("accuracy", {})
    passed = bool(d.get("pass"))
    sources = "; ".join(facts.get("source", "") for _, facts in drives.values())
    cells = [f'<div><b>verdict</b><span class="{"ok" if passed else "bad"}">{"PASS" if passed else "FAIL"}'
             "</span></div>",
             f"<div><b>shock</b>{esc(sources)}</div>",
             f"<div><b>runs</b>{len(d.get('runs', []))}, of {_shocks_per_direction(d)} shocks each</div>",
             f"<div><b>criteria within capacity</b>{sum(1 for c in criteria if c['pass'])} of {len(criteria)}</div>"]
    w = d.get("worst")
    if w:
        cells.append(f"<div><b>least margin ({esc(w['criterion'])}, run {esc(w['run'])})</b>"
                     f"{num(w['margin'], f'{SRC}:worst.margin', 'g', 'span')}</div>")
    cells.append(f"<div><b>largest estimated error</b>"
                 f"{num(acc.get('estimated_error'), f'{SRC}:accuracy.estimated_error', 'pct', 'span')} "
                 f"(at most {num(acc.get('warn_error'), f'{SRC}:accuracy.warn_error', 'pct', 'span')})</div>")
    cells.append(f"<div><b>warnings</b>{len(d.get('warnings', []))}</div>")
    return f'<div class="glance">{"".join(cells)}</div>'


def _verdict(d: dict, drives: dict) -> str:
    criteria, acc = d.get("criteria", []), d.get("accuracy", {})
    over = [c for c in criteria if not c["pass"]]
    n = _shocks_per_direction(d)
    conditions = [
        (acc.get("pass"), f"Every run vouches for its accuracy: {acc.get('rule', '')}."),
        (not d.get("warnings"), "No run warned."),
        (not over, f"Every criterion is within its capacity ({len(criteria) - len(over)} of {len(criteria)})."),
    ]
    lines = "".join(f'<li><span class="{"ok" if ok else "bad"}">{"met" if ok else "not met"}</span>: {esc(text)}</li>'
                    for ok, text in conditions)
    within = d.get("drive", {}).get("within")
    said = ("" if within is None else
            f'<p class="{"ok" if within else "bad"}">Every axis\'s drive has its SRS within the specification\'s band '
            f'at every 1/12-octave frequency: {"yes" if within else "no"} (srs_check.csv).</p>')
    head = (f'<p class="ok"><b>The deck passes</b> {n} shock{"s" * (n != 1)} in each direction of '
            f'{", ".join(d.get("shocked_axes", []))}: every condition below is met.</p>' if d.get("pass") else
            f'<p class="bad"><b>The deck does not pass</b>: {sum(1 for ok, _ in conditions if not ok)} of the '
            "conditions below not met.</p>")
    return f"<section><h2>Verdict</h2>{head}<ul>{lines}</ul>{said}</section>"


def _criteria(d: dict) -> str:
    criteria = d.get("criteria", [])
    runs = [r["run"] for r in d.get("runs", [])]
    rows = []
    for i, c in enumerate(criteria):
        p = f"{SRC}:criteria.{i}"
        rows.append([c["criterion"], c["item"], num(c["demand"], f"{p}.demand"), num(c["capacity"], f"{p}.capacity"),
                     c["unit"], num(c["margin"], f"{p}.margin"),
                     '<td class="ok">within</td>' if c["pass"] else '<td class="bad">exceeded</td>',
                     c.get("worst_run", ""),
                     *[num(c.get("per_run", {}).get(r), f"{p}.per_run.{r}") for r in runs]])
    return ('<section class="page"><h2>Criteria</h2>'
            f"<p>Demand: the largest over the runs, read from each run's summary.json. Margin: "
            f"{esc(d.get('margin', ''))}.</p>"
            + table(["criterion", "item", "demand", "capacity", "unit", "margin", "", "worst run", *runs], rows,
                    {2, 3, 5, *range(8, 8 + len(runs))})
            + "</section>")


def _drive_section(d: dict, drives: dict) -> str:
    rows = []
    for axis, (p, f) in drives.items():
        t, s = f.get("table", {}), f.get("srs", {})
        rows.append([axis, f.get("source", ""), f.get("file", ""), num(f.get("dt_s"), f"{SRC}:{p}.dt_s"),
                     num(f.get("shock_s"), f"{SRC}:{p}.shock_s"), num(f.get("peak_g"), f"{SRC}:{p}.peak_g"),
                     num(t.get("peak_velocity_m_s"), f"{SRC}:{p}.table.peak_velocity_m_s"),
                     num(t.get("end_velocity_m_s"), f"{SRC}:{p}.table.end_velocity_m_s"),
                     num(t.get("peak_displacement_m"), f"{SRC}:{p}.table.peak_displacement_m"),
                     num(t.get("end_displacement_m"), f"{SRC}:{p}.table.end_displacement_m"),
                     num(s.get("maximax_g"), f"{SRC}:{p}.srs.maximax_g"), num(s.get("at_hz"), f"{SRC}:{p}.srs.at_hz")])
    gap = d.get("free_vibration", {}).get("between_shocks_s")
    return ('<section class="page"><h2>The drive</h2>'
            f"<p>Each shock is followed by {esc(f'{gap:.3g}') if gap is not None else 'a'} s of rest "
            f"({esc(d.get('free_vibration', {}).get('rule', ''))}). The table's velocity and displacement are those "
            "of one shock, linear between its samples, from rest.</p>"
            + table(["axis", "shock", "file", "dt [s]", "length [s]", "peak [g]", "peak velocity [m/s]",
                     "end velocity [m/s]", "peak displacement [m]", "end displacement [m]", "SRS maximax [g]",
                     "at [Hz]"], rows, set(range(3, 12)))
            + "</section>")


def _shocks(d: dict) -> str:
    rows = []
    for k, r in enumerate(d.get("runs", [])):
        for j, s in enumerate(r.get("shocks", [])):
            rows.append([r["run"], str(j + 1), num(s.get("from_s"), f"{SRC}:runs.{k}.shocks.{j}.from_s"),
                         num(s.get("largest_change_from_the_first"),
                             f"{SRC}:runs.{k}.shocks.{j}.largest_change_from_the_first", "pct")])
    return ('<section><h2>Each shock against the first</h2>'
            f"<p>{esc(d.get('shocks_rule', ''))}.</p>"
            + table(["run", "shock", "from [s]", "largest change from the first"], rows, {2, 3}) + "</section>")


def _accuracy(d: dict) -> str:
    acc = d.get("accuracy", {})
    rows = [[r.get("run", ""), num(r.get("estimated_error"), f"{SRC}:accuracy.per_run.{k}.estimated_error", "pct"),
             r.get("output") or "", r.get("status") or "",
             '<td class="ok">yes</td>' if r.get("pass") else '<td class="bad">no</td>']
            for k, r in enumerate(acc.get("per_run", []))]
    return ("<section><h2>Accuracy</h2>"
            f"<p>Rule: {esc(acc.get('rule', ''))}.</p>"
            + table(["run", "largest estimated error", "in", "status", "vouches"], rows, {1}) + "</section>")
