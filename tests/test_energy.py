"""Energy balance: input = kinetic + hysteretic (stored and dissipated), per step."""


import numpy as np
import pytest
from typer.testing import CliRunner

from rbhyst.cli import app
from rbhyst.model.deck import parse_deck
from rbhyst.model.system import assemble
from rbhyst.files.outdir import staged_directory
from rbhyst.solve.plan import Settings, simulate
from conftest import seed_deck, square_linear_deck, write_deck


def test_balance_error_falls_as_dt_squared_on_a_linear_scene(tmp_path):
    data = square_linear_deck()
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 2.0, "frequency_hz": 2.5,
                                             "units": "m/s2", "phase_deg": 90.0}}}
    system = assemble(parse_deck(data), tmp_path)
    errs = [simulate(system, Settings(dt=dt, duration=2.0)).energy_balance for dt in (2e-3, 1e-3, 5e-4)]
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    np.testing.assert_allclose(ratios, 4.0, rtol=0.15)


def test_hysteretic_scene_balances_and_dissipates(tmp_path):
    data = seed_deck(duration=4.0)
    data["excitation"]["support"]["x1"]["cycles"] = 4  # 2 s of shaking, then free vibration
    data["excitation"]["support"]["x2"]["cycles"] = 6
    system = assemble(parse_deck(data), tmp_path)
    res = simulate(system, Settings(dt=5e-4, duration=4.0))
    e_in, e_kin, e_hyst = res.energy.T
    assert res.energy_balance < 2e-4
    # after the shaking the input stops growing and the elements keep what they took
    assert e_in[-1] == pytest.approx(e_in[4001], rel=1e-12)  # (x1 ends at its peak: one step ramps it off)
    assert e_hyst[-1] > 0.9 * e_in[-1]
    # each element's work is its own integral of f du
    u, f = res.element_u, res.element_f
    trap = np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(u, axis=0))
    assert e_hyst[-1] == pytest.approx(trap, rel=2e-3)


def test_run_warns_when_the_balance_is_poor(tmp_path):
    """Sharp yield with the monitor turned off: the answer is wrong, and the balance says so."""
    data = seed_deck(duration=2.0)
    for name in ("wri_axial", "wri_shear"):
        for branch in ("loading", "unloading"):
            data["hysteresis"][name][branch]["alpha"] *= 100
    data["analysis"]["max_omega_dt"] = 1000.0
    res = CliRunner().invoke(app, ["run", str(write_deck(tmp_path, data)), "--out", str(tmp_path / "o"),
                                   "--no-plots", "--integrator", "chang"])
    assert res.exit_code == 0
    assert "warning: energy balance error" in res.stderr


def test_interrupted_writing_leaves_the_old_folder(tmp_path):
    target = tmp_path / "results"
    target.mkdir()
    (target / "keep.txt").write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with staged_directory(target) as tmp:
            (tmp / "time_history.csv").write_text("partial")
            raise KeyboardInterrupt
    assert [p.name for p in target.iterdir()] == ["keep.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results"]
    with staged_directory(target) as tmp:
        (tmp / "new.txt").write_text("new")
    assert sorted(p.name for p in target.iterdir()) == [".rbhyst.json", "keep.txt", "new.txt"]  # not rbhyst's: kept
    assert (target / "keep.txt").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results"]
