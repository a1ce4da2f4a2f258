"""What makes report.html a page to sign: who and what it is for (the deck's [report]), when and
by which rbhyst and command the results were made, the sha256 of every file they were made from,
and a signature block at the end. Plain HTML, no matplotlib."""

from __future__ import annotations

import html
from datetime import UTC, datetime

from rbhyst._version import __version__

#: the deck's [report] fields in the order the page gives them, with their labels
FIELDS = (("project", "Project"), ("equipment", "Equipment"), ("engineer", "Engineer"), ("reviewer", "Reviewer"))

CSS = """
table.signed td:first-child { color: var(--muted); }
td.hash, code { font-family: ui-monospace, "DejaVu Sans Mono", Menlo, Consolas, monospace; font-size: 11.5px; }
td.hash { word-break: break-all; white-space: normal; }
p.fieldnotes { white-space: pre-wrap; border-left: 4px solid var(--rule); padding: 3px 8px; }
section.signature { break-inside: avoid; page-break-inside: avoid; margin-top: 28px; }
table.signature { width: 100%; }
table.signature td { height: 16mm; vertical-align: bottom; border-bottom: 1px solid var(--ink); width: 25%; }
table.signature th { background: none; width: 12%; vertical-align: bottom; }
@media print { td.hash, code { font-size: 7.5pt; } }
"""


def esc(x) -> str:
    return html.escape(str(x), quote=True)


def when(stamp: datetime) -> str:
    """A moment as the page says it: 2026-03-04 15:06:07 UTC."""
    return stamp.astimezone(UTC).strftime("%Y-%m-%d %H:%M:%S UTC")


def _stamp(text: str | None) -> str:
    """provenance.started_utc (ISO 8601, Z) as :func:`when` says it; anything else as it is."""
    try:
        return when(datetime.fromisoformat(str(text)))
    except ValueError:
        return str(text)


def _rows(rows: list[tuple[str, str]]) -> str:
    """A table of labels and cells already rendered (<td>...) or plain text (escaped here)."""
    cells = "".join(f"<tr><td>{esc(k)}</td>{v if v.startswith('<td') else f'<td>{esc(v)}</td>'}</tr>"
                    for k, v in rows)
    return f'<div class="wide"><table class="signed"><tbody>{cells}</tbody></table></div>'


def about(facts: dict | None, fields: dict | None, written: datetime, source: str) -> str:
    """The section under the title: the [report] fields given, when the results were made and
    the report written, by which rbhyst and command, and every file read with its sha256
    (``facts``: the results' provenance, None for results of an older rbhyst; ``source``: the
    file that holds it, named where it lacks one)."""
    fields = fields or {}
    rows = [(label, fields[key]) for key, label in FIELDS if fields.get(key)]
    out = ['<section class="about"><h2>About these results</h2>']
    if facts:
        rows.append(("results computed", _stamp(facts.get("started_utc"))))
    rows.append(("report written", when(written)))
    made_by = (facts or {}).get("rbhyst_version")
    rows.append(("rbhyst", f"{made_by} (results), {__version__} (report)" if made_by and made_by != __version__
                 else str(made_by or __version__)))
    if facts:
        command = facts.get("command")
        rows.append(("command", f"<td><code>{esc(command)}</code></td>" if command else
                     "through the Python API (rbhyst.run), not the command line"))
    out.append(_rows(rows))
    if fields.get("notes"):
        out.append(f'<p class="fieldnotes">{esc(fields["notes"])}</p>')
    if not facts:
        out.append(f'<p class="bad">{esc(source)} says nothing of the files it was made from (written by an older '
                   "rbhyst): they cannot be checked against it.</p>")
        return "".join(out) + "</section>"
    files = facts.get("inputs") or []
    body = "".join(f"<tr><td>{esc(f['key'])}</td><td>{esc(f['file'])}</td>"
                   f'<td class="num">{esc(f["bytes"])}</td><td class="hash">{esc(f["sha256"])}</td></tr>'
                   for f in files)
    out.append("<h3>Files read</h3><p>Each file the results were computed from, with its sha256 as "
               "<code>sha256sum</code> prints it: a file whose checksum differs is not the one these results "
               "come from.</p>"
               '<div class="wide"><table class="inputs"><thead><tr><th>named by</th><th>file</th>'
               '<th class="num">bytes</th><th>sha256</th></tr></thead>'
               f"<tbody>{body}</tbody></table></div>" if files else
               '<p class="muted">No file was read: the deck was built in code and names no file.</p>')
    return "".join(out) + "</section>"


def signature(fields: dict | None) -> str:
    """The block to sign at the end: prepared by the engineer, reviewed by the reviewer (their
    names where the deck's [report] gives them), each with a signature and a date to fill in."""
    fields = fields or {}
    rows = "".join(f"<tr><th>{role}</th><td>{esc(fields.get(key) or '')}</td><th>signature</th><td></td>"
                   "<th>date</th><td></td></tr>"
                   for role, key in (("Prepared by", "engineer"), ("Reviewed by", "reviewer")))
    return ('<section class="signature"><h2>Signatures</h2>'
            f'<table class="signature"><tbody>{rows}</tbody></table></section>')


def page_css(title: str) -> str:
    """Print's page numbers ("page 3 of 12") and the title in each page's foot (CSS margin boxes)."""
    quoted = title.replace("\\", "\\\\").replace('"', '\\"').replace("\n", " ")
    return ('@page { @bottom-left { content: "' + quoted + '"; font: 8pt system-ui, sans-serif; color: #5b6670; }'
            ' @bottom-right { content: "page " counter(page) " of " counter(pages); font: 8pt system-ui, sans-serif;'
            " color: #5b6670; } }")
