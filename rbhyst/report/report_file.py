"""report.html in a results folder: which page the folder's files make (a run's, a sweep's,
a qualification's), written beside them and listed in the folder's manifest."""

from __future__ import annotations

from pathlib import Path

from rbhyst.errors import InputError

REPORT_FILE = "report.html"


def write_report(folder: str | Path) -> Path:
    """Write report.html into a results folder of ``rbhyst run``, ``rbhyst sweep``, ``rbhyst
    qualify`` or ``rbhyst shock`` and list it in the folder's manifest beside the files already there (which stay)."""
    from rbhyst.files.outdir import read_manifest, staged_directory

    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: {'is not a folder' if folder.exists() else 'no such folder'}")
    owned = read_manifest(folder).files
    if {"summary.json", "time_history.csv"} <= owned and (folder / "summary.json").is_file():
        from rbhyst.report.html import run_report

        text = run_report(folder, owned)
    elif {"sweep.json", "cases.csv"} <= owned and (folder / "sweep.json").is_file():
        from rbhyst.report.html import sweep_report

        text = sweep_report(folder, owned)
    elif "shock.json" in owned and (folder / "shock.json").is_file():  # rbhyst shock, or qualify under shock
        from rbhyst.report.shock_page import shock_report

        text = shock_report(folder, owned)
    elif "qualification.json" in owned and (folder / "qualification.json").is_file():
        from rbhyst.report.qualification_page import qualification_report

        text = qualification_report(folder, owned)
    else:
        raise InputError(f"{folder}: holds no results of rbhyst run, rbhyst sweep, rbhyst qualify or rbhyst shock "
                         "(summary.json, sweep.json, qualification.json or shock.json written by rbhyst, listed in "
                         ".rbhyst.json): give the folder one of them wrote")
    with staged_directory(folder, add=True) as tmp:
        (tmp / REPORT_FILE).write_text(text, encoding="utf-8")
    return folder / REPORT_FILE


def check_report_target(folder: str | Path) -> None:
    """Before a command with --report: a report.html there is rbhyst's or absent (the command
    stops before it runs, as it would for its own files)."""
    from rbhyst.files.outdir import MANIFEST, read_manifest

    folder = Path(folder)
    path = folder / REPORT_FILE
    if folder.is_dir() and (path.exists() or path.is_symlink()) and REPORT_FILE not in read_manifest(folder).files:
        raise InputError(f"{folder}: {REPORT_FILE} exists and rbhyst did not write it (not listed in {MANIFEST}); "
                         "rbhyst will not overwrite it: move it away or choose another output folder")
