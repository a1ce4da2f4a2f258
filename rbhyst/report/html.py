"""report.html's pages of a run's and a sweep's results, and the pieces every page is made of
(rbhyst.report.qualification_page makes a qualification's; rbhyst.report.report_file writes
the file).

Every number is read from the folder's own files (summary.json, sweep.json, the CSVs) and shown
as it is there: each carries its source and its exact value in ``data-src`` and ``data-value``,
so that what the page says can be checked against the files. Images are the folder's PNGs,
embedded as base64 data URIs; the page loads nothing from anywhere. No matplotlib here.
"""

from __future__ import annotations

import base64
import csv
import html
import json
from datetime import UTC, datetime
from pathlib import Path

from rbhyst._version import __version__
from rbhyst.errors import InputError
from rbhyst.model.deck import ACCEL_UNITS
from rbhyst.report.signing import CSS as SIGNING_CSS, about, page_css, signature

G = ACCEL_UNITS["g"]  # m/s2 (a g column beside m/s2 only; every value in m/s2 is summary.json's)

#: a run's figures in the order the report shows them (others the folder lists follow)
RUN_FIGURES = ("support_motion.png", "response_x1.png", "response_x2.png", "response_x3.png", "response_theta1.png",
               "response_theta2.png", "response_theta3.png", "element_loops.png", "energy.png", "spectra.png",
               "srs.png", "pvss.png")
SWEEP_FIGURES = ("ida.png", "vary.png", "motions.png")
#: the peaks a sweep's statistics table shows (all are in stats.csv)
SWEEP_PEAKS = ("peak_u1_m", "peak_u2_m", "peak_theta3_rad", "peak_at1_m_s2", "peak_at2_m_s2")
MAX_CASE_ROWS = 300

CSS = """
:root { --ink: #1d2329; --muted: #5b6670; --rule: #d5dbe0; --warn: #9a3412; --warnbg: #fff4ed;
        --note: #eef3f8; --ok: #166534; }
* { box-sizing: border-box; }
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif;
       color: var(--ink); max-width: 1120px; margin: 24px auto; padding: 0 24px; background: #fff; }
h1 { font-size: 24px; margin: 0 0 4px; }
h2 { font-size: 19px; margin: 30px 0 10px; padding-bottom: 4px; border-bottom: 2px solid var(--ink); }
h3 { font-size: 15px; margin: 20px 0 8px; }
p.sub { color: var(--muted); margin: 0 0 16px; }
table { border-collapse: collapse; margin: 6px 0 14px; font-size: 12.5px; }
div.wide { overflow-x: auto; }
th, td { border-bottom: 1px solid var(--rule); padding: 3px 9px; text-align: left; vertical-align: top; }
th { background: #f3f5f7; font-weight: 600; }
td:first-child { white-space: nowrap; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
.glance { display: grid; grid-template-columns: repeat(auto-fill, minmax(200px, 1fr)); gap: 8px; margin: 10px 0; }
.glance div { background: var(--note); border-radius: 6px; padding: 8px 10px; }
.glance b { display: block; font-size: 11.5px; color: var(--muted); font-weight: 600; }
ul.warnings li { color: var(--warn); background: var(--warnbg); margin: 3px 0; padding: 4px 8px;
                 border-left: 4px solid var(--warn); list-style: none; }
ul.warnings, ul.notes { padding-left: 0; }
ul.notes li { list-style: none; margin: 3px 0; padding: 3px 8px; border-left: 4px solid var(--rule);
              color: var(--muted); }
.ok { color: var(--ok); }
figure { margin: 12px 0 20px; text-align: center; }
figure img { max-width: 100%; height: auto; border: 1px solid var(--rule); }
figcaption { color: var(--muted); font-size: 12px; margin-top: 4px; }
pre { background: #f6f8fa; border: 1px solid var(--rule); padding: 10px 12px; font-size: 12px;
      overflow-x: auto; white-space: pre-wrap; word-break: break-word; }
.muted { color: var(--muted); }
.bad { color: var(--warn); font-weight: 600; }
footer { margin-top: 40px; color: var(--muted); font-size: 12px; border-top: 1px solid var(--rule); padding-top: 8px; }
@page { size: A4; margin: 14mm 12mm; }
@media print {
  body { max-width: none; margin: 0; padding: 0; font-size: 10.5pt; }
  h2 { break-after: avoid; page-break-after: avoid; }
  h3 { break-after: avoid; page-break-after: avoid; }
  section.page { break-before: page; page-break-before: always; }
  figure { break-inside: avoid; page-break-inside: avoid; }
  figure img { max-height: 235mm; width: auto; max-width: 100%; border: none; }
  figure.model img { max-height: 120mm; }  /* the model's tables share its page */
  table { break-inside: auto; font-size: 8.5pt; }
  div.wide { overflow: visible; }
  tr, .glance div, ul.warnings li { break-inside: avoid; page-break-inside: avoid; }
  thead { display: table-header-group; }
  pre { font-size: 8.5pt; }
  .glance { grid-template-columns: repeat(3, 1fr); }
}
"""


# ---------------------------------------------------------------- small pieces


def esc(x) -> str:
    return html.escape(str(x), quote=True)


def fmt(v: float, kind: str = "g") -> str:
    """How a number reads: 5 significant digits (g), 4 (g4: a required response spectrum, whose
    standards' constants carry no more), a percentage (pct), or 0 for a column the run leaves at
    rest, to rounding (rest)."""
    if kind == "pct":
        return f"{100 * v:.3g} %"
    if kind == "g4":  # a value that carries four digits at most (a standard's spectrum: 1.25 g, not 1.2499 g)
        return f"{v:.4g}"
    if kind == "rest":  # at rest to rounding (summary.json at_rest): no response to show
        return "0"
    if kind == "restpct":  # ... and its error, rounding too
        return "0 %"
    return f"{v:.5g}"


def num(v, src: str, kind: str = "g", tag: str = "td") -> str:
    """A number as shown, with its source (file:path) and exact value for checking."""
    if v is None or v == "":
        return f'<{tag} class="num muted">-</{tag}>'
    v = float(v)
    return (f'<{tag} class="num" data-src="{esc(src)}" data-value="{v!r}" data-kind="{kind}">'
            f"{esc(fmt(v, kind))}</{tag}>")


def table(header: list[str], rows: list[list[str]], numeric: set[int] = frozenset()) -> str:
    """rows: cells already rendered (<td>...</td>) or plain text (escaped here)."""
    head = "".join(f'<th class="num">{esc(h)}</th>' if i in numeric else f"<th>{esc(h)}</th>"
                   for i, h in enumerate(header)) if any(header) else ""
    body = []
    for r in rows:
        cells = "".join(c if isinstance(c, str) and c.startswith("<td") else f"<td>{esc(c)}</td>" for c in r)
        body.append(f"<tr>{cells}</tr>")
    thead = f"<thead><tr>{head}</tr></thead>" if head else ""  # (a table of keys and values has no header)
    return f'<div class="wide"><table>{thead}<tbody>{"".join(body)}</tbody></table></div>'


def figure(folder: Path, name: str, caption: str = "") -> str:
    data = base64.b64encode((folder / name).read_bytes()).decode("ascii")
    cap = esc(caption or name)
    cls = f' class="{name[:-4]}"' if name == "model.png" else ""
    return (f'<figure{cls}><img alt="{esc(name)}" data-file="{esc(name)}" src="data:image/png;base64,{data}">'
            f"<figcaption>{cap}</figcaption></figure>")


def items(lines: list[str], cls: str) -> str:
    return f'<ul class="{cls}">' + "".join(f"<li>{esc(x)}</li>" for x in lines) + "</ul>"


def page(title: str, subtitle: str, body: list[str], top: str = "", end: str = "") -> str:
    """The whole page: ``top`` under the title (what it is about), ``body``, then ``end`` (the
    signatures) before the footer; in print, each page numbered in its foot."""
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{esc(title)}</title><style>{CSS}{SIGNING_CSS}{page_css(title)}</style></head><body>"
            f"<header><h1>{esc(title)}</h1><p class=\"sub\">{esc(subtitle)}</p></header>"
            + top + "\n".join(body) + end
            + f"<footer>Written by rbhyst {esc(__version__)} from the files of this folder, as listed in "
              ".rbhyst.json: every number names the file it is read from, every figure is one of its PNGs.</footer>"
              "</body></html>\n")


def read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    return (rows[0], rows[1:]) if rows else ([], [])


def _unit(column: str) -> tuple[str, str]:
    """('u1', 'm') from 'u1_m'; ('at1', 'm/s2') from 'at1_m_s2'."""
    for suffix, unit in (("_m_s2", "m/s2"), ("_rad_s2", "rad/s2"), ("_m_s", "m/s"), ("_rad_s", "rad/s"),
                         ("_rad", "rad"), ("_Nm", "N m"), ("_N", "N"), ("_J", "J"), ("_m", "m")):
        if column.endswith(suffix):
            return column[: -len(suffix)], unit
    return column, ""


def toml_text(data: dict) -> str:
    """The deck as TOML, laid out as a deck is written: arrays on one line, a table of plain
    values three levels down inline (a VRM branch, a record), None left out (TOML has none)."""
    lines: list[str] = []
    _toml_table(data, (), lines)
    return "\n".join(lines).strip() + "\n"


def _toml_key(k: str) -> str:
    import re

    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(x)}" for k, x in v.items() if x is not None) + " }"
    raise TypeError(type(v))


def _plain(v) -> bool:
    return not isinstance(v, dict) and not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v))


def _inline(v, depth: int) -> bool:
    return (isinstance(v, dict) and depth >= 3 and all(_plain(x) for x in v.values())
            and len(_toml_value(v)) <= 110)


def _toml_table(data: dict, path: tuple, lines: list[str]) -> None:
    here = [k for k, v in data.items() if v is not None and (_plain(v) or _inline(v, len(path) + 1))]
    for k in here:
        lines.append(f"{_toml_key(k)} = {_toml_value(data[k])}")
    for k, v in data.items():
        if v is None or k in here:
            continue
        sub = (*path, _toml_key(k))
        if isinstance(v, dict):
            if any(_plain(x) or _inline(x, len(sub) + 1) for x in v.values() if x is not None) or not v:
                lines += ["", f"[{'.'.join(sub)}]"]
            _toml_table(v, sub, lines)
        else:  # a list of tables
            for item in v:
                lines += ["", f"[[{'.'.join(sub)}]]"]
                _toml_table(item, sub, lines)


# ---------------------------------------------------------------- reading the folder


def load_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: cannot be read as JSON ({exc.__class__.__name__})") from None


def figure_names(folder: Path, owned: set[str], order: tuple[str, ...]) -> list[str]:
    have = sorted(n for n in owned if n.endswith(".png") and "/" not in n and (folder / n).is_file())
    first = [n for n in order if n in have]
    return first + [n for n in have if n not in first]


# ---------------------------------------------------------------- a run


def run_report(folder: Path, owned: set[str], written: datetime | None = None) -> str:
    """A run's page from its summary.json and PNGs (``written``: the moment to say it was
    written, default now)."""
    s = load_json(folder / "summary.json")
    src = "summary.json"
    peaks, ext = s.get("peaks", {}), s.get("extremes", {})
    an, en, acc = s.get("analysis", {}), s.get("energy", {}), s.get("accuracy")
    warnings, notes = s.get("warnings", []), s.get("notes", [])
    body = []

    # at a glance
    cells = []

    def glance(label, value, path, kind="g", unit=""):
        cells.append(f"<div><b>{esc(label)}</b>{num(value, f'{src}:{path}', kind, 'span')} {esc(unit)}</div>")

    cells.append(f"<div><b>integrator</b>{esc(an.get('integrator', ''))}</div>")
    glance("dt", an.get("dt_s"), "analysis.dt_s", unit="s")
    glance("duration", an.get("duration_s"), "analysis.duration_s", unit="s")
    rest = set(s.get("at_rest", ()))
    for c in ("u1_m", "u2_m", "u3_m", "theta1_rad", "theta2_rad", "theta3_rad", "at1_m_s2", "at2_m_s2", "at3_m_s2"):
        if c in peaks:
            name, unit = _unit(c)
            glance(f"peak |{name}|", peaks[c], f"peaks.{c}", "rest" if c in rest else "g", unit)
    if acc and acc.get("estimated_error"):
        worst = max(acc["estimated_error"], key=acc["estimated_error"].get)
        glance(f"largest estimated error ({worst})", acc["estimated_error"][worst],
               f"accuracy.estimated_error.{worst}", "pct")
    glance("energy balance error", en.get("balance_error"), "energy.balance_error", "pct")
    cells.append(f"<div><b>warnings</b>{len(warnings)}</div>")
    body.append(f'<div class="glance">{"".join(cells)}</div>')

    body.append("<h2>Warnings</h2>" + (items(warnings, "warnings") if warnings else
                                      '<p class="ok">No warnings.</p>'))
    if notes:
        body.append("<h3>Notes</h3>" + items(notes, "notes"))
    body.append(_accuracy(acc, en, {_unit(c)[0] for c in s.get("at_rest", ())}))
    body.append(_model(folder, owned, s))
    body.append(peaks_section(s))
    figures = [n for n in figure_names(folder, owned, RUN_FIGURES) if n != "model.png"]
    body.append('<section class="page"><h2>Figures</h2>'
                + ("".join(figure(folder, n) for n in figures) if figures else
                   '<p class="muted">The run wrote no figures (--no-plots or output.plots = false).</p>')
                + "</section>")
    body.append(_analysis(s))
    deck = s.get("deck")
    body.append('<section class="page"><h2>The deck as run</h2>'
                + (f"<pre>{esc(toml_text(deck))}</pre>" if deck is not None else
                   '<p class="muted">summary.json holds no deck (written by an older rbhyst).</p>')
                + "</section>")
    title = s.get("title") or "rbhyst run"
    fields = (deck or {}).get("report")
    return page(title, f"Time-history analysis, rbhyst {s.get('rbhyst_version', '')}: results in {folder.name}/",
                body, about(s.get("provenance"), fields, written or datetime.now(UTC), "summary.json"),
                signature(fields))


def _accuracy(acc: dict | None, en: dict, rest: set[str] = frozenset()) -> str:
    """The accuracy statement; ``rest``: the outputs at rest (their error, rounding too, reads 0 %)."""
    src = "summary.json"
    out = ["<h2>Accuracy</h2>"]
    if not acc:
        out.append('<p class="bad">The error of this run was not estimated (analysis.estimate_error = false): '
                   "nothing vouches for its accuracy.</p>")
    else:
        est = acc.get("estimated_error") or {}
        if est:
            worst = max(est, key=est.get)
            out.append(f"<p>Status <b>{esc(acc.get('status'))}</b>: the largest estimated error is "
                       f"{num(est[worst], f'{src}:accuracy.estimated_error.{worst}', 'pct', 'span')} in "
                       f"<b>{esc(worst)}</b> (max over time of |x - x_exact| / max |x_exact|), "
                       f"{esc(acc.get('method', ''))}.</p>")
        else:
            out.append(f"<p>Status <b>{esc(acc.get('status'))}</b>. {esc(acc.get('method', ''))}</p>")
        if acc.get("tolerance") is not None:
            out.append(f"<p>Tolerance asked for: {num(acc['tolerance'], f'{src}:accuracy.tolerance', 'g', 'span')}"
                       "</p>")
        # three outputs a row: a scene's 30-odd outputs fit on the page
        cells = [[k, num(v, f"{src}:accuracy.estimated_error.{k}", "restpct" if k in rest else "pct")]
                 for k, v in est.items()]
        per = 3
        rows = [sum(cells[r::-(-len(cells) // per)][:per], []) for r in range(-(-len(cells) // per))]
        rows = [r + ["", '<td class="num"></td>'] * ((2 * per - len(r)) // 2) for r in rows]
        if rows:
            out.append(table(["output", "estimated error"] * per, rows, {1, 3, 5}))
            out.append('<p class="muted">Each: max over time of |x - x_exact| / max |x_exact|, named as its '
                       "time_history.csv column without the unit (sa_: the spectra).</p>")
    out.append("<p>Energy balance error max |E_error| / max |E_input|: "
               f"{num(en.get('balance_error'), f'{src}:energy.balance_error', 'pct', 'span')}.</p>")
    return "<section>" + "".join(out) + "</section>"


def _model(folder: Path, owned: set[str], s: dict) -> str:
    src = "summary.json"
    out = ['<section class="page"><h2>Model</h2>']
    if "model.png" in owned and (folder / "model.png").is_file():
        out.append(figure(folder, "model.png", "The body, its elements and dampers (model.png)"))
    b = s.get("body", {})
    rows = [["form", b.get("form", "")], ["mass [kg]", num(b.get("mass_kg"), f"{src}:body.mass_kg")]]
    space = isinstance(b.get("inertia_kgm2"), list)  # a body in space: the tensor about G
    if space:
        rows += [[f"J{i + 1}{j + 1} about G [kg m2]", num(b["inertia_kgm2"][i][j], f"{src}:body.inertia_kgm2.{i}.{j}")]
                 for i in range(3) for j in range(i, 3)]
    else:
        rows.append(["J about G [kg m2]", num(b.get("inertia_kgm2"), f"{src}:body.inertia_kgm2")])
    if "area_m2" in b:
        rows.append(["area [m2]", num(b["area_m2"], f"{src}:body.area_m2")])
    if "volume_m3" in b:
        rows.append(["volume [m3]", num(b["volume_m3"], f"{src}:body.volume_m3")])
    for i, c in enumerate(b.get("mass_centre_m", [])):
        rows.append([f"mass centre G, x{i + 1} [m] (deck frame)", num(c, f"{src}:body.mass_centre_m.{i}")])
    out.append(table(["body", ""], rows))
    rows, k = [], 1
    for i, e in enumerate(s.get("elements", [])):
        p = f"{src}:elements.{i}"
        label = (f"e{k}" if e["count"] == 1 else f"e{k}-e{k + e['count'] - 1}") + _isolator(e)
        st = e.get("stroke")
        rows.append([label, e["hysteresis"], str(e["count"]), *_place(e, p),
                     num(e["k0_N_m"], f"{p}.k0_N_m"), num(e["k_reversal_N_m"], f"{p}.k_reversal_N_m"),
                     num(st["limits_m"][0], f"{p}.stroke.limits_m.0") if st else num(None, ""),
                     num(st["limits_m"][1], f"{p}.stroke.limits_m.1") if st else num(None, "")])
        k += e["count"]
    where = _place_heads(space)
    out.append("<h3>Elements</h3>" + table(["elements", "set", "count", *where, "k0 [N/m]", "k at reversal [N/m]",
                                            "stroke lower [m]", "stroke upper [m]"], rows,
                                           set(range(3, 7 + len(where)))))
    if s.get("dampers"):
        rows, k = [], 1
        for i, d in enumerate(s["dampers"]):
            p = f"{src}:dampers.{i}"
            label = f"d{k}" if d["count"] == 1 else f"d{k}-d{k + d['count'] - 1}"
            rows.append([label, str(d["count"]), *_place(d, p), num(d["c_N_s_m"], f"{p}.c_N_s_m")])
            k += d["count"]
        out.append("<h3>Dampers</h3>" + table(["dampers", "count", *where, "c [N s/m]"], rows,
                                               set(range(2, 3 + len(where)))))
    r = s.get("rayleigh")
    if r:
        rows = [[f"mode {i + 1}", num(f, f"{src}:rayleigh.mode_frequencies_hz.{i}"),
                 num(z, f"{src}:rayleigh.mode_ratios.{i}", "pct")]
                for i, (f, z) in enumerate(zip(r["mode_frequencies_hz"], r["mode_ratios"]))]
        out.append("<h3>Rayleigh damping, C = a0 M + a1 K0</h3>"
                   f"<p>a0 = {num(r['a0_1_s'], f'{src}:rayleigh.a0_1_s', 'g', 'span')} 1/s, "
                   f"a1 = {num(r['a1_s'], f'{src}:rayleigh.a1_s', 'g', 'span')} s. Stiffness-proportional damping "
                   "on the initial stiffness overstates the damping once the supports soften (see the README).</p>"
                   + table(["mode of (M, K0)", "frequency [Hz]", "damping ratio"], rows, {1, 2}))
    st = s.get("static")
    if st:
        out.append("<h3>Static preload under gravity</h3>" + table(["", ""], [
            [f"{_unit(c)[0]} [{_unit(c)[1]}]", num(st[c], f"{src}:static.{c}")]
            for c in ("u1_m", "u2_m", "u3_m", "theta1_rad", "theta2_rad", "theta3_rad") if c in st]))
    out.append("</section>")
    return "".join(out)


def _isolator(entry: dict) -> str:
    """" (isolator 2 shear1)" after an element's label when it is a direction of an isolator."""
    return f" (isolator {entry['isolator']} {entry['role']})" if "isolator" in entry else ""


def _place(entry: dict, path: str) -> list[str]:
    """An element's or damper's point from G and its line: x1, x2, angle in the plane; x1, x2,
    x3 and the direction's d1, d2, d3 in space."""
    cells = [num(x, f"{path}.x_m.{i}") for i, x in enumerate(entry["x_m"])]
    if "direction" in entry:
        return cells + [num(d, f"{path}.direction.{i}") for i, d in enumerate(entry["direction"])]
    return cells + [num(entry["angle_deg"], f"{path}.angle_deg")]


def _place_heads(space: bool) -> list[str]:
    """The headings of :func:`_place`'s cells."""
    if space:
        return ["x1 [m] from G", "x2 [m] from G", "x3 [m] from G", "d1", "d2", "d3"]
    return ["x1 [m] from G", "x2 [m] from G", "angle [deg]"]


def _extreme_rows(s: dict, columns: list[str], g_column: bool, src: str = "summary.json") -> list[list[str]]:
    rows = []
    rest = set(s.get("at_rest", ()))
    for c in columns:
        e = s["extremes"][c]
        name, unit = _unit(c)
        kind = "rest" if c in rest else "g"
        row = [f"{name} [{unit}]" if unit else name, num(s["peaks"][c], f"{src}:peaks.{c}", kind)]
        if g_column:
            row.append(f'<td class="num">{esc(fmt(s["peaks"][c] / G, kind))}</td>' if unit == "m/s2" else
                       '<td class="num muted">-</td>')
        if c in rest:  # (a time of a peak of rounding means nothing)
            row += [num(e["max"], f"{src}:extremes.{c}.max", kind), num(None, ""),
                    num(e["min"], f"{src}:extremes.{c}.min", kind), num(None, "")]
        else:
            row += [num(e["max"], f"{src}:extremes.{c}.max"), num(e["time_of_max_s"], f"{src}:extremes.{c}.time_of_max_s"),
                    num(e["min"], f"{src}:extremes.{c}.min"), num(e["time_of_min_s"], f"{src}:extremes.{c}.time_of_min_s")]
        rows.append(row)
    return rows


def _peak(s: dict, column: str, src: str) -> str:
    """A peak's cell: 0 where the run leaves the column at rest (summary.json at_rest)."""
    return num(s["peaks"].get(column), f"{src}:peaks.{column}", "rest" if column in s.get("at_rest", ()) else "g")


#: said under a table where a 0 stands for rounding
AT_REST_NOTE = ('<p class="muted">0: at rest, to rounding (its peak below 1e-9 of the largest of its kind, as '
                "summary.json's at_rest lists it; the files keep the value).</p>")


def peaks_section(s: dict, src: str = "summary.json", title: str = "Peaks and extremes") -> str:
    """The peaks and extremes of a run's summary.json (``src``: its path in the folder)."""
    peaks = s.get("peaks", {})
    rest = set(s.get("at_rest", ()))
    head = ["", "peak |x|", "peak [g]", "max", "at t [s]", "min", "at t [s]"]
    out = [f'<section class="page"><h2>{esc(title)}</h2>',
           "<p>Over every step of dt (whatever output.every keeps). Accelerations are total (what an "
           "accelerometer reads); the g column is the m/s2 value divided by 9.80665.</p>"]
    body = [c for c in ("u1_m", "u2_m", "u3_m", "theta1_rad", "theta2_rad", "theta3_rad", "at1_m_s2", "at2_m_s2",
                        "at3_m_s2", "alphat1_rad_s2", "alphat2_rad_s2", "alphat3_rad_s2", "R1_N", "R2_N", "R3_N",
                        "R3_Nm", "R4_Nm", "R5_Nm", "R6_Nm", "ag1_m_s2", "ag2_m_s2", "ag3_m_s2") if c in peaks]
    out.append("<h3>The body at G, the mounts' resultant, the support</h3>"
               + table(head, _extreme_rows(s, body, True, src), set(range(1, 7))))
    # elements: one row per element of the CSV, with its entry's stroke utilization
    rows, k = [], 1
    for i, e in enumerate(s.get("elements", [])):
        for _ in range(e["count"]):
            f, u = f"e{k}_f_N", f"e{k}_u_m"
            st = e.get("stroke")
            ku = "rest" if u in rest else "g"
            rows.append([f"e{k}{_isolator(e)}", e["hysteresis"], _peak(s, f, src), _peak(s, u, src),
                         num(s["extremes"][u]["max"], f"{src}:extremes.{u}.max", ku),
                         num(s["extremes"][u]["min"], f"{src}:extremes.{u}.min", ku),
                         num(st["utilization"], f"{src}:elements.{i}.stroke.utilization", "pct" if ku == "g" else ku)
                         if st else num(None, ""),
                         num(st["time_of_peak_s"], f"{src}:elements.{i}.stroke.time_of_peak_s") if st and ku == "g"
                         else num(None, "")])
            k += 1
    out.append("<h3>Elements</h3>" + table(["element", "set", "peak |force| [N]", "peak |deformation| [m]",
                                            "max deformation [m]", "min deformation [m]", "stroke used",
                                            "at t [s]"], rows, set(range(2, 8))))
    names = [p["name"] for p in (s.get("deck") or {}).get("output", {}).get("points") or []]
    # a summary without its deck (an older one, a qualification's run): the points from the columns
    if not names:
        names = sorted({c[: -len("_at1_m_s2")] for c in peaks if c.endswith("_at1_m_s2") and c != "at1_m_s2"})
    if names:
        # every direction the points move in: x1, x2 in the plane, and x3 in space
        axes = [k for k in "123" if any(f"{n}_at{k}_m_s2" in peaks for n in names)]
        rows = []
        for n in names:
            row = [n]
            for c in (f"{n}_at{k}_m_s2" for k in axes):
                row += [_peak(s, c, src), f'<td class="num">{esc(fmt(peaks[c] / G, "rest" if c in rest else "g"))}'
                        "</td>" if c in peaks else num(None, "")]
            row += [_peak(s, f"{n}_u{k}_m", src) for k in axes]
            rows.append(row)
        head = ["point", *[h for k in axes for h in (f"peak |at{k}| [m/s2]", "[g]")],
                *[f"peak |u{k}| [m]" for k in axes]]
        out.append("<h3>Points of interest: peak total accelerations</h3>"
                   + table(head, rows, set(range(1, len(head)))))
    dampers = [c for c in peaks if c.startswith("d") and c.endswith("_f_N")]
    if dampers:
        rows = [[c[: -len("_f_N")], num(peaks[c], f"{src}:peaks.{c}"),
                 num(peaks.get(c.replace("_f_N", "_v_m_s")), f"{src}:peaks.{c.replace('_f_N', '_v_m_s')}")]
                for c in dampers]
        out.append("<h3>Dampers</h3>" + table(["damper", "peak |force| [N]", "peak |rate| [m/s]"], rows, {1, 2}))
    if rest:
        out.append(AT_REST_NOTE)
    en = s.get("energy", {})
    rows = [[label, num(en.get(key), f"{src}:energy.{key}")] for label, key in
            (("input [J]", "input_J"), ("hysteretic [J]", "hysteretic_J"), ("viscous [J]", "viscous_J")) if key in en]
    out.append("<h3>Energy at the end</h3>" + table(["", ""], rows, {1}))
    out += _spectra_section(s.get("spectra"), src)
    out.append("</section>")
    return "".join(out)


def _spectra_section(sp: dict | None, src: str) -> list[str]:
    """The largest response (or shock response) spectrum of every location and direction."""
    out: list[str] = []
    if sp and sp.get("kind") == "srs":
        rows = [[p["location"], p["direction"], num(p["q"], f"{src}:spectra.peaks.{i}.q"),
                 num(p["maximax_m_s2"], f"{src}:spectra.peaks.{i}.maximax_m_s2"),
                 f'<td class="num">{esc(fmt(p["maximax_m_s2"] / G))}</td>',
                 num(p["frequency_hz"], f"{src}:spectra.peaks.{i}.frequency_hz"),
                 num(p["pv_m_s"], f"{src}:spectra.peaks.{i}.pv_m_s")] for i, p in enumerate(sp["peaks"])]
        out.append("<h3>Shock response spectra: largest maximax</h3>"
                   + table(["location", "direction", "Q", "maximax [m/s2]", "[g]", "at [Hz]", "largest PV [m/s]"],
                           rows, {2, 3, 4, 5, 6})
                   + '<p class="muted">Every frequency, with the positive, negative, primary and residual '
                     'spectra, is in srs.csv.</p>')
    elif sp:
        rows = [[p["location"], p["direction"], num(p["damping"], f"{src}:spectra.peaks.{i}.damping", "pct"),
                 num(p["sa_m_s2"], f"{src}:spectra.peaks.{i}.sa_m_s2"),
                 f'<td class="num">{esc(fmt(p["sa_m_s2"] / G))}</td>',
                 num(p["period_s"], f"{src}:spectra.peaks.{i}.period_s")] for i, p in enumerate(sp["peaks"])]
        out.append("<h3>Response spectra: largest sa</h3>"
                   + table(["location", "direction", "damping", "sa [m/s2]", "[g]", "at period [s]"], rows,
                           {2, 3, 4, 5}) + '<p class="muted">Every period is in spectra.csv.</p>')
    return out


def _analysis(s: dict) -> str:
    src = "summary.json"
    an = s.get("analysis", {})
    rows = [[k, num(v, f"{src}:analysis.{k}") if isinstance(v, (int, float)) and not isinstance(v, bool) else str(v)]
            for k, v in an.items() if not isinstance(v, dict)]
    return "<section><h2>Analysis</h2>" + table(["analysis", ""], rows) + "</section>"


# ---------------------------------------------------------------- a sweep


def sweep_report(folder: Path, owned: set[str]) -> str:
    about = load_json(folder / "sweep.json")
    src = "sweep.json"
    c_head, c_rows = read_csv(folder / "cases.csv")
    ci = {h: i for i, h in enumerate(c_head)}
    # a vary key with one value holds the deck at it (a sweep cut short): said once, not in every row
    held = {k: c_rows[0][ci[k]] for k in about.get("vary", []) if c_rows and len({r[ci[k]] for r in c_rows}) == 1}
    vary = [k for k in about.get("vary", []) if k not in held]
    body = []
    cells = [f"<div><b>{esc(label)}</b>{num(about.get(key), f'{src}:{key}', 'g', 'span')}</div>"
             for label, key in (("cases", "cases"), ("ok", "ok"), ("failed", "failed"), ("computed", "computed"),
                                ("already in the folder", "reused"))]
    scale = about.get("scale", {})
    cells.append(f"<div><b>motions</b>{len(about.get('motions', []))}</div>")
    cells.append(f"<div><b>scale levels ({esc(scale.get('kind', ''))})</b>{len(scale.get('levels', []))}</div>")
    body.append(f'<div class="glance">{"".join(cells)}</div>')
    body.append("<h2>What ran</h2>" + table(["", ""], [
        ["base deck", about.get("deck", "")], ["motions", ", ".join(about.get("motions", []))],
        ["scale", f"{scale.get('kind', '')}: " + ", ".join(f"{v:g}" for v in scale.get("levels", []))],
        ["varied", ", ".join(vary) or "nothing"],
        *([["held at", ", ".join(f"{k} = {v}" for k, v in held.items())]] if held else []),
        ["statistics", about.get("statistics", "")]]))
    failed = [r for r in c_rows if r[ci["status"]] != "ok"]
    warned = [r for r in c_rows if r[ci["status"]] == "ok" and r[ci["message"]]]
    body.append("<h2>Failures and warnings</h2>")
    if not failed and not warned:
        body.append('<p class="ok">Every case ran, without a warning.</p>')
    if failed:
        body.append("<h3>Failed cases</h3>" + table(["case", "motion", "scale", *vary, "status", "message"],
                                                    [[r[ci["case"]], r[ci["motion"]], r[ci["scale"]],
                                                      *[r[ci[k]] for k in vary], r[ci["status"]], r[ci["message"]]]
                                                     for r in failed]))
    if warned:
        body.append("<h3>Cases with warnings</h3>" + table(["case", "motion", "scale", *vary, "warnings"],
                                                           [[r[ci["case"]], r[ci["motion"]], r[ci["scale"]],
                                                             *[r[ci[k]] for k in vary], r[ci["message"]]]
                                                            for r in warned]))
    body.append(_sweep_accuracy(c_head, c_rows))
    body.append(_statistics(folder, vary))
    if "fragility.csv" in owned and (folder / "fragility.csv").is_file():
        body.append(_fragility(folder, owned, about.get("fragility") or {}, vary))
    figures = [n for n in figure_names(folder, owned, SWEEP_FIGURES) if n != "fragility.png"]
    body.append('<section class="page"><h2>Figures</h2>'
                + ("".join(figure(folder, n) for n in figures) if figures else
                   '<p class="muted">The sweep wrote no figures (--no-plots).</p>') + "</section>")
    body.append(_cases(c_head, c_rows, vary))
    return page(f"Sweep {about.get('sweep', '')}",
                f"{about.get('deck', '')} over {len(about.get('motions', []))} motions, rbhyst "
                f"{about.get('rbhyst_version', '')}: results in {folder.name}/", body)


def _sweep_accuracy(head: list[str], rows: list[list[str]]) -> str:
    """The largest estimated error over every case and output (cases.csv's accuracy_ columns)."""
    prefix = "accuracy_estimated_error_"
    cols = [(k, h) for k, h in enumerate(head) if h.startswith(prefix)]
    status = head.index("status")
    ok = [(n, r) for n, r in enumerate(rows) if r[status] == "ok"]
    found = [(float(r[k]), n, r, h) for n, r in ok for k, h in cols if r[k] != ""]
    bare = sum(1 for _, r in ok if all(r[k] == "" for k, _ in cols))
    out = ["<h2>Accuracy</h2>"]
    if found:
        v, n, r, h = max(found, key=lambda x: x[0])
        out.append(f"<p>The largest estimated error over every case and output is "
                   f"{num(v, f'cases.csv:{n}:{h}', 'pct', 'span')} (case {esc(r[0])}, {esc(h[len(prefix):])}); "
                   "each case's are in cases.csv (accuracy_estimated_error_*).</p>")
    if bare:
        out.append(f'<p class="bad">{bare} of {len(ok)} cases were run without an error estimate '
                   "(analysis.estimate_error = false): nothing vouches for their accuracy.</p>")
    return "<section>" + "".join(out) + "</section>" if len(out) > 1 else ""


def _statistics(folder: Path, vary: list[str]) -> str:
    head, rows = read_csv(folder / "stats.csv")
    i = {h: k for k, h in enumerate(head)}
    groups: dict[tuple, dict[str, tuple[int, list[str]]]] = {}
    for n, r in enumerate(rows):
        if r[i["peak"]] in SWEEP_PEAKS:
            groups.setdefault((r[i["scale"]], *[r[i[k]] for k in vary]), {})[r[i["peak"]]] = (n, r)
    out = ['<section class="page"><h2>Statistics over the motions</h2>'
           "<p>For each scale level and vary combination, over its motions: the median and the 84th percentile "
           f"of the peaks of G's motion (stats.csv holds mean, median, p84 and max of all "
           f"{len({r[i['peak']] for r in rows})} peaks; runs: those that gave a peak).</p>"]
    for title, wanted in (("Displacements", SWEEP_PEAKS[:3]), ("Total accelerations", SWEEP_PEAKS[3:])):
        peaks = [p for p in wanted if any(p in g for g in groups.values())]
        if not peaks:
            continue
        out_rows = []
        for ident, by_peak in groups.items():
            n0, r0 = by_peak.get(peaks[0], next(iter(by_peak.values())))
            row = [*ident, r0[i["count"]], r0[i["failed"]]]
            for p in peaks:
                n, r = by_peak.get(p, (None, None))
                row += [num(r[i[c]], f"stats.csv:{n}:{c}") if r else num(None, "") for c in ("median", "p84")]
            out_rows.append(row)
        header = ["scale", *vary, "runs", "failed"]
        for p in peaks:
            name, unit = _unit(p[len("peak_"):])
            header += [f"|{name}| median [{unit}]", "p84"]
        first = len(vary) + 3
        out.append(f"<h3>{title}</h3>" + table(header, out_rows, set(range(first - 2, first + 2 * len(peaks)))))
    return "".join(out) + "</section>"


def _fragility(folder: Path, owned: set[str], about: dict, vary: list[str]) -> str:
    head, rows = read_csv(folder / "fragility.csv")
    i = {h: k for k, h in enumerate(head)}
    out = ['<section class="page"><h2>Fragility</h2>',
           f"<p>{esc(about.get('method', ''))}. Intensity: <b>{esc(about.get('intensity', ''))}</b>; "
           f"{esc(about.get('reaches', ''))}; intervals: {esc(about.get('intervals', ''))}.</p>"]
    conf = about.get("confidence")
    band = f"{100 * conf:g} % interval" if conf else "interval"

    def with_ci(r, n, key):
        src = f"fragility.csv:{n}"
        if not r[i[key]]:
            return '<td class="num muted">-</td>'
        ci = (f' <span class="muted">[{num(r[i[key + "_lo"]], f"{src}:{key}_lo", "g", "span")}, '
              f'{num(r[i[key + "_hi"]], f"{src}:{key}_hi", "g", "span")}]</span>') if r[i[key + "_lo"]] else ""
        return f'<td class="num">{num(r[i[key]], f"{src}:{key}", "g", "span")}{ci}</td>'

    body = []
    width = 7 + len(vary)
    for n, r in enumerate(rows):
        cells = [r[i["limit_state"]], r[i["quantity"]], num(r[i["limit"]], f"fragility.csv:{n}:limit"),
                 *[r[i[k]] for k in vary], f"{r[i['reached']]} of {r[i['cases']]}", r[i["status"]],
                 with_ci(r, n, "median"), with_ci(r, n, "beta")]
        body.append("<tr>" + "".join(c if c.startswith("<td") else f"<td>{esc(c)}</td>" for c in cells) + "</tr>")
        if r[i["message"]]:
            cls = "muted" if r[i["status"]] == "fitted" else "bad"
            body.append(f'<tr><td></td><td colspan="{width}" class="{cls}">{esc(r[i["message"]])}</td></tr>')
    head = ["limit state", "quantity", "limit", *vary, "reached", "status", f"median [{band}]",
            f"beta [{band}]"]
    out.append('<div class="wide"><table><thead><tr>' + "".join(f"<th>{esc(h)}</th>" for h in head)
               + "</tr></thead><tbody>" + "".join(body) + "</tbody></table></div>")
    out.append('<p class="muted">Per intensity level: fragility_stripes.csv.</p>')
    if "fragility.png" in owned and (folder / "fragility.png").is_file():
        out.append(figure(folder, "fragility.png", "Fragility curves, their bands and the share of cases reaching "
                                                  "each limit state at each intensity (fragility.png)"))
    out.append("</section>")
    return "".join(out)


def _cases(head: list[str], rows: list[list[str]], vary: list[str]) -> str:
    i = {h: k for k, h in enumerate(head)}
    peaks = [c for c in SWEEP_PEAKS if c in i]
    shown = rows[:MAX_CASE_ROWS]
    out_rows = [[r[i["case"]], r[i["motion"]], r[i["scale"]], *[r[i[k]] for k in vary], r[i["status"]],
                 *[num(r[i[c]], f"cases.csv:{n}:{c}") for c in peaks]] for n, r in enumerate(shown)]
    more = (f" The first {MAX_CASE_ROWS} of {len(rows)}: every case is in cases.csv." if len(rows) > MAX_CASE_ROWS
            else " Every peak of every case is in cases.csv.")
    return ('<section class="page"><h2>Cases</h2>'
            f"<p>{esc(more.strip())}</p>"
            + table(["case", "motion", "scale", *vary, "status", *peaks], out_rows,
                    set(range(len(vary) + 4, len(vary) + 4 + len(peaks))))
            + "</section>")
