"""The Python API: load_deck, run, Result, Deck.with_values; the command line is a layer on it."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

import rbhyst
from rbhyst.cli import app
from rbhyst.errors import InputError
from conftest import DECKS, seed_deck, write_deck


@pytest.fixture
def deck_path(tmp_path):
    return write_deck(tmp_path, seed_deck(duration=1.0))


def test_run_takes_a_deck_or_its_path_and_gives_what_the_command_writes(deck_path, tmp_path):
    deck = rbhyst.load_deck(deck_path)
    res = rbhyst.run(deck)
    again = rbhyst.run(deck_path)
    np.testing.assert_array_equal(res.table, again.table)
    out = tmp_path / "cli"
    assert CliRunner().invoke(app, ["run", str(deck_path), "--out", str(out), "--no-plots"]).exit_code == 0
    header = (out / "time_history.csv").read_text().splitlines()[0].split(",")
    frame = res.to_pandas()
    assert list(frame.columns) == header
    np.testing.assert_allclose(frame.to_numpy(), np.loadtxt(out / "time_history.csv", delimiter=",", skiprows=1),
                               rtol=1e-9, atol=1e-300)
    written = json.loads((out / "summary.json").read_text())
    mine = res.summary()
    assert set(mine) == set(written)
    for key in ("peaks", "extremes", "body", "elements", "energy", "notes", "warnings"):
        assert mine[key] == pytest.approx(written[key], rel=1e-12) if key in ("peaks", "energy") else \
            mine[key] == written[key], key


def test_write_gives_exactly_the_summary_and_the_table(deck_path, tmp_path):
    res = rbhyst.run(deck_path)
    res.write(tmp_path / "w", plots=False)
    assert json.loads((tmp_path / "w" / "summary.json").read_text()) == json.loads(json.dumps(res.summary()))
    table = np.loadtxt(tmp_path / "w" / "time_history.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(table, res.table, rtol=5e-10, atol=0)


def test_a_streamed_run_keeps_only_its_reductions(deck_path, tmp_path):
    res = rbhyst.run(deck_path, out=tmp_path / "s", plots=False)
    assert res.table is None and res.csv_path == tmp_path / "s" / "time_history.csv"
    assert res.extremes.peak("u1_m") == rbhyst.run(deck_path).extremes.peak("u1_m")
    with pytest.raises(ValueError, match="streamed"):
        res.to_pandas()


def test_overrides_like_the_command_line(deck_path):
    res = rbhyst.run(deck_path, integrator="newmark", dt=5e-4)
    assert res.summary()["analysis"]["integrator"] == "newmark" and res.settings.dt == 5e-4
    with pytest.raises(InputError, match="--integrator: unknown 'euler'"):
        rbhyst.run(deck_path, integrator="euler")


def test_with_values_changes_a_deck_by_dotted_keys(deck_path):
    deck = rbhyst.load_deck(deck_path)
    soft = deck.with_values({"hysteresis.wri_shear.loading.kb": 1.1e5, "hysteresis.wri_shear.unloading.kb": 1.2e5,
                             "body.mass": 700.0, "elements[2].count": 3})
    assert soft.hysteresis["wri_shear"].loading.kb == 1.1e5 and soft.body.mass == 700.0
    assert soft.elements[1].count == 3 and deck.elements[1].count == 2  # a copy: the deck is unchanged
    assert soft.base == deck.base
    assert rbhyst.run(soft).extremes.peak("u2_m") != rbhyst.run(deck).extremes.peak("u2_m")


@pytest.mark.parametrize("values, message", [
    ({"hysteresis.wri_shaer.loading.kb": 1.0}, "hysteresis.wri_shaer.loading.kb: no hysteresis.wri_shaer in the deck"),
    ({"body.mass": -5.0}, "body.mass: must be greater than 0"),
    ({"body.colour": "red"}, "body.colour: unknown key"),
    ({"elements[9].count": 2}, "elements[9].count: no elements[9] in the deck"),
    ({"analysis..dt": 1.0}, "analysis..dt: cannot read the key"),
])
def test_with_values_names_a_wrong_key_or_value(deck_path, values, message):
    with pytest.raises(InputError) as err:
        rbhyst.load_deck(deck_path).with_values(values)
    assert err.value.problems == [message]


def test_load_deck_errors_are_input_errors(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[body]\nmass = 'heavy'\n")
    with pytest.raises(rbhyst.InputError):
        rbhyst.load_deck(bad)


def test_pandas_and_matplotlib_are_imported_only_when_used(tmp_path):
    code = ("import sys, rbhyst; r = rbhyst.run(sys.argv[1]); "
            "assert 'pandas' not in sys.modules and 'matplotlib' not in sys.modules; "
            "r.to_pandas(); assert 'pandas' in sys.modules")
    # (from a folder outside the source tree, as every subprocess here: the installed package)
    subprocess.run([sys.executable, "-c", code, str(DECKS / "machine_on_mounts.toml")], check=True, cwd=tmp_path)


def test_writing_plots_leaves_the_callers_matplotlib_as_it_was(tmp_path):
    """A notebook that draws its own figures keeps its settings and its figure list."""
    code = ("import sys, matplotlib; matplotlib.use('Agg'); import matplotlib.pyplot as plt, rbhyst; "
            "before = dict(matplotlib.rcParams); fig = plt.figure(); "
            "rbhyst.run(sys.argv[1]).write(sys.argv[2], plots=True); "
            "assert dict(matplotlib.rcParams) == before; assert plt.get_fignums() == [fig.number]")
    subprocess.run([sys.executable, "-c", code, str(DECKS / "machine_on_mounts.toml"), str(tmp_path / "out")],
                   check=True, cwd=tmp_path)
    assert (tmp_path / "out" / "model.png").exists()


def test_a_run_into_a_folder_loads_only_what_its_scene_needs(tmp_path):
    """Without spectra or plots, writing a run's files imports no spectra kernels, no scipy, no
    matplotlib (each costs a command tens of milliseconds and more memory); numba's JIT, where
    the kernels were not built at install, brings scipy with it."""
    import subprocess
    import sys

    code = ("import sys, rbhyst; rbhyst.run(sys.argv[1], out=sys.argv[2], plots=False); "
            "jit = 'numba' in sys.modules; "
            "print(sorted(m for m in ('rbhyst.solve.spectra', 'scipy', 'matplotlib', 'pandas') "
            "if m in sys.modules and not (jit and m == 'scipy')))")
    done = subprocess.run([sys.executable, "-c", code, str(DECKS / "machine_on_mounts.toml"), str(tmp_path / "o")],
                          capture_output=True, text=True, check=True, cwd=tmp_path)
    assert done.stdout.split("\n")[-2] == "[]", done.stdout + done.stderr
