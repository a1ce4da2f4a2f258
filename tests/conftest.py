"""Shared scenes and helpers: decks are written from dicts so every test shows its scene."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import tomli_w
import yaml

ROOT = Path(__file__).resolve().parents[1]
DECKS = ROOT / "decks"
RECORDS = ROOT.parent / "shared" / "records"

SEED_VERTICES = [
    [0.4714, -0.9429], [0.4714, 1.0571], [-0.1286, 1.0571], [-0.1286, 0.2571],
    [-0.7286, 0.2571], [-0.7286, -0.5429], [-0.1286, -0.5429], [-0.1286, -0.9429],
]
SEED_MASS = 815.7730
TABLE3_AXIAL = {
    "loading": {"kb": 500000.0, "f0": -500.0, "alpha": 1800.0, "beta1": 2500.0, "beta2": 230.0},
    "unloading": {"kb": 550000.0, "f0": 4215.0, "alpha": 1700.0, "beta1": 1400.0, "beta2": 200.0},
}
TABLE3_SHEAR = {
    "loading": {"kb": 220000.0, "f0": 1150.0, "alpha": 680.0, "beta1": 100.0, "beta2": 300.0},
    "unloading": {"kb": 240000.0, "f0": 1044.0, "alpha": 700.0, "beta1": -100.0, "beta2": -300.0},
}
TABLE1 = {
    "2a": {"loading": {"kb": 0.5, "f0": 2.0, "alpha": 10.0}, "unloading": {"kb": 0.0, "f0": 2.0, "alpha": 10.0}},
    "2b": {"loading": {"kb": 0.5, "f0": 2.0, "alpha": 10.0, "gamma1": 0.5, "gamma2": 4.0, "gamma3": 0.5},
           "unloading": {"kb": 0.5, "f0": 2.0, "alpha": 10.0, "gamma1": 0.5, "gamma2": 4.0, "gamma3": -0.5}},
    "2c": {"loading": {"kb": 0.5, "f0": 1.0, "alpha": 10.0, "gamma1": 2.0, "gamma2": 2.0},
           "unloading": {"kb": 0.5, "f0": 1.0, "alpha": 10.0, "gamma1": 2.0, "gamma2": 2.0}},
    "2d": {"loading": {"kb": 0.5, "f0": 1.0, "alpha": 10.0, "gamma1": 2.0, "gamma2": 40.0},
           "unloading": {"kb": 0.5, "f0": 1.0, "alpha": 10.0, "gamma1": 2.0, "gamma2": 40.0}},
}


def linear_set(k: float) -> dict:
    """Equal branches with f0 = 0: both limiting curves are k u, so f = k u exactly."""
    branch = {"kb": k, "f0": 0.0, "alpha": 1.0}
    return {"loading": dict(branch), "unloading": dict(branch)}


def seed_deck(**analysis) -> dict:
    """The seed's scene (Table 2 body, Table 3 sets at P1 and P2) with a sine support motion."""
    deck = {
        "title": "seed scene",
        "body": {"vertices": copy.deepcopy(SEED_VERTICES), "mass": SEED_MASS},
        "hysteresis": {"wri_axial": copy.deepcopy(TABLE3_AXIAL), "wri_shear": copy.deepcopy(TABLE3_SHEAR)},
        "elements": [
            {"vertex": 1, "angle_deg": 0.0, "hysteresis": "wri_axial", "count": 2},
            {"vertex": 1, "angle_deg": 90.0, "hysteresis": "wri_shear", "count": 2},
            {"vertex": 2, "angle_deg": 0.0, "hysteresis": "wri_axial", "count": 2},
            {"vertex": 2, "angle_deg": 90.0, "hysteresis": "wri_shear", "count": 2},
        ],
        "excitation": {"support": {
            "x1": {"type": "sine", "amplitude": 0.3, "frequency_hz": 2.0, "units": "g", "phase_deg": 90.0},
            "x2": {"type": "sine", "amplitude": 0.2, "frequency_hz": 3.0, "units": "g"},
        }},
        "analysis": {"dt": 0.001, "duration": 2.0, **analysis},
    }
    return deck


def square_linear_deck(k: float = 2.0e5, mass: float = 500.0, side: float = 1.0) -> dict:
    """A square body on four linear springs whose modes decouple: K = diag(2k, 2k, k side^2)."""
    c = side / 2
    return {
        "body": {"vertices": [[-c, -c], [c, -c], [c, c], [-c, c]], "mass": mass},
        "hysteresis": {"lin": linear_set(k)},
        "elements": [
            {"point": [0.0, c], "angle_deg": 0.0, "hysteresis": "lin"},
            {"point": [0.0, -c], "angle_deg": 0.0, "hysteresis": "lin"},
            {"point": [c, 0.0], "angle_deg": 90.0, "hysteresis": "lin"},
            {"point": [-c, 0.0], "angle_deg": 90.0, "hysteresis": "lin"},
        ],
        "analysis": {"dt": 0.001, "duration": 1.0},
    }


def write_deck(folder: Path, data: dict, name: str = "deck", fmt: str = "toml") -> Path:
    path = Path(folder) / f"{name}.{fmt}"
    if fmt == "toml":
        path.write_text(tomli_w.dumps(data))
    else:
        path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.fixture
def deck_dict():
    """A fresh copy of the seed scene for a test to change."""
    return copy.deepcopy(seed_deck())


#: pydantic's own words, which no message to a user may carry
PYDANTIC_WORDS = ("constrained-", "Input should be", "literal_error", "function-after", "function-before",
                  "tagged-union", "Field required")


def invoke(*args) -> tuple[int, str]:
    """An rbhyst command in this process: (exit status, what it wrote to stderr)."""
    from typer.testing import CliRunner

    from rbhyst.cli import app

    res = CliRunner().invoke(app, [str(a) for a in args])
    err = res.stderr
    if res.exit_code == 2:  # a mistake is said in rbhyst's words, never in pydantic's
        assert not any(w in err for w in PYDANTIC_WORDS), err
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        # an exception the command let through (a bug: it says what is wrong in one line):
        # its traceback, which the runner keeps to itself, for the test's message
        import traceback

        err += "".join(traceback.format_exception(res.exception))
    return res.exit_code, err


def snapshot(folder: Path) -> dict[str, tuple[bytes, int]]:
    """Every file below ``folder`` (hidden ones too): its bytes and mtime."""
    return {p.relative_to(folder).as_posix(): (p.read_bytes(), p.stat().st_mtime_ns)
            for p in sorted(folder.rglob("*")) if p.is_file()}


def records_or_skip() -> Path:
    if not (RECORDS / "I-ELC180.AT2").exists():
        pytest.skip("the El Centro records (../shared/records) are not on this machine")
    return RECORDS


# property tests draw the same examples on every CI run: a red CI is then a real regression,
# not a lucky draw (locally they explore afresh each time)
from hypothesis import settings as _hypothesis_settings  # noqa: E402

_hypothesis_settings.register_profile("ci", derandomize=True, print_blob=True)
if __import__("os").environ.get("CI"):
    _hypothesis_settings.load_profile("ci")


def pytest_collection_modifyitems(session, config, items):
    """A test module's slow independent work (``start_in_background()``, e.g. numba compiling
    every kernel) starts before the first test, once, where any of its tests is to run."""
    started = set()
    for item in items:
        module = getattr(item, "module", None)
        start = getattr(module, "start_in_background", None)
        if start is not None and module not in started:
            started.add(module)
            start()
