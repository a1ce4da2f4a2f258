"""The body's modes (rbhyst.solve.modes, summary.json modes, `rbhyst modes`): against scipy's
eigen-solution of a stiffness built here from the geometry, against closed forms, against the
free vibration the time stepping computes, and under gravity against the VRM tangent by hand."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.linalg
from scipy.optimize import brentq
from typer.testing import CliRunner

import rbhyst
from rbhyst.cli import app
from rbhyst.model.body import Body
from rbhyst.model.coordinates import rotation, translation
from rbhyst.model.hysteresis import parameter_set
from rbhyst.model.system import Element, Excitation, System
from rbhyst.solve.modes import AT_REST, INITIAL, initial_modes, modes_of
from conftest import DECKS, invoke, linear_set, write_deck

runner = CliRunner()

# a 1.2 m x 0.8 m plate of 300 kg on four linear springs, one inclined: every mode couples
WIDTH, HEIGHT, MASS = 1.2, 0.8, 300.0
SPRINGS = [  # (point in the deck's frame, angle deg, k N/m)
    ((0.0, 0.0), 90.0, 1.0e5),
    ((1.2, 0.0), 90.0, 2.0e5),
    ((0.0, 0.0), 0.0, 1.5e5),
    ((1.2, 0.8), 30.0, 0.8e5),
]


def plate_deck(**extra) -> dict:
    """The plate on its springs, one set per spring (linear: equal branches kb = k, f0 = 0)."""
    return {
        "body": {"vertices": [[0.0, 0.0], [WIDTH, 0.0], [WIDTH, HEIGHT], [0.0, HEIGHT]], "mass": MASS},
        "hysteresis": {f"s{i}": linear_set(k) for i, (_, _, k) in enumerate(SPRINGS, start=1)},
        "elements": [{"point": list(p), "angle_deg": a, "hysteresis": f"s{i}"}
                     for i, (p, a, _) in enumerate(SPRINGS, start=1)],
        "analysis": {"dt": 1e-3, "duration": 1.0},
        **extra,
    }


def plate_by_hand() -> tuple[np.ndarray, np.ndarray]:
    """M and K of the plate from its geometry alone: G at the rectangle's centre, J = m (w^2 + h^2)
    / 12, each spring's deformation along (cos a, sin a) at x - G: b = (cos a, sin a, x1 sin a -
    x2 cos a), K = sum k b b^T."""
    g = np.array([WIDTH / 2, HEIGHT / 2])
    m = np.diag([MASS, MASS, MASS * (WIDTH ** 2 + HEIGHT ** 2) / 12.0])
    k = np.zeros((3, 3))
    for p, angle, stiffness in SPRINGS:
        x = np.array(p) - g
        c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
        b = np.array([c, s, x[0] * s - x[1] * c])
        k += stiffness * np.outer(b, b)
    return m, k


def scipy_modes(m: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies (Hz) and shapes (rows), each scaled to a largest component of +1."""
    lam, vec = scipy.linalg.eigh(k, m)
    shapes = []
    for j in range(len(lam)):
        v = vec[:, j]
        shapes.append(v / v[np.argmax(np.abs(v))])
    return np.sqrt(lam) / (2 * math.pi), np.array(shapes)


# ------------------------------------------------------------------ against scipy and closed forms


def test_a_plate_on_springs_has_scipys_modes_of_the_stiffness_built_by_hand(tmp_path):
    modes = rbhyst.modes(write_deck(tmp_path, plate_deck()))
    f, shapes = scipy_modes(*plate_by_hand())
    assert modes["coordinates"] == ["u1", "u2", "theta3"]
    assert modes["stiffness"] == INITIAL and "at_rest" not in modes and "notes" not in modes
    assert np.allclose(modes["frequencies_hz"], f, rtol=1e-9, atol=0)
    assert np.allclose(modes["shapes"], shapes, rtol=0, atol=1e-9)
    for shape in modes["shapes"]:  # each coupled, and its largest component +1
        assert max(shape, key=abs) == 1.0 and sum(abs(x) > 1e-3 for x in shape) >= 2


def square_deck(kv: float, kh: float, a: float = 0.5, mass: float = 400.0) -> dict:
    """A square of side 2a on four vertical springs kv and four horizontal kh, one of each at
    every corner."""
    corners = [[-a, -a], [a, -a], [a, a], [-a, a]]
    return {
        "body": {"vertices": corners, "mass": mass},
        "hysteresis": {"v": linear_set(kv), "h": linear_set(kh)},
        "elements": [{"vertex": i, "angle_deg": angle, "hysteresis": name}
                     for i in range(1, 5) for angle, name in ((90.0, "v"), (0.0, "h"))],
        "analysis": {"dt": 1e-3, "duration": 1.0},
    }


def test_a_symmetric_square_has_its_closed_form_modes(tmp_path):
    """K = diag(4 kh, 4 kv, 4 (kv + kh) a^2), J = m (2a)^2 / 6: f = sqrt(4 kh / m), sqrt(4 kv / m)
    and sqrt(6 (kv + kh) / m) over 2 pi, each mode along one coordinate."""
    kv, kh, m = 3.0e5, 1.0e5, 400.0
    modes = rbhyst.modes(write_deck(tmp_path, square_deck(kv, kh, mass=m)))
    w = np.sqrt([4 * kh / m, 4 * kv / m, 6 * (kv + kh) / m])
    assert modes["frequencies_hz"] == pytest.approx(w / (2 * math.pi), rel=1e-12)
    assert modes["shapes"] == [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def test_repeated_frequencies_are_said(tmp_path):
    """kv = kh: the two translations share sqrt(4k / m); the note says their shapes are a choice."""
    modes = rbhyst.modes(write_deck(tmp_path, square_deck(2.0e5, 2.0e5)))
    assert modes["frequencies_hz"][0] == pytest.approx(modes["frequencies_hz"][1], rel=1e-12)
    assert modes["notes"] == ["modes 1 and 2: the same frequency; their shapes are one choice among the "
                              "combinations of the two"]


def test_dampers_and_rayleigh_damping_leave_the_modes_as_they_are(tmp_path):
    """Undamped modes; and Rayleigh's modes of (M, K0) are these."""
    plain = rbhyst.modes(write_deck(tmp_path, plate_deck(), name="plain"))
    damped = plate_deck(dampers=[{"point": [0.6, 0.0], "angle_deg": 90.0, "c": 2.0e3}],
                        damping={"rayleigh": {"ratio": 0.02, "modes": [1, 3]}})
    path = write_deck(tmp_path, damped, name="damped")
    assert rbhyst.modes(path) == plain
    from rbhyst.model.system import assemble

    d = rbhyst.load_deck(path)
    assert np.allclose(assemble(d, d.base).rayleigh.mode_frequencies_hz, plain["frequencies_hz"], rtol=1e-12)


def hand_system(coordinates, mass, rows, k) -> System:
    """A body on linear springs built by hand (rows b_e, stiffnesses k_e), any number of coordinates."""
    rows = np.asarray(rows, dtype=float)
    n = len(coordinates)
    square = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    body = Body("direct", float(mass[0]), np.zeros(2), 1.0, (), square, 1.0)
    branch = lambda ke: parameter_set({"kb": ke, "alpha": 100.0}, {"kb": ke, "alpha": 100.0})  # noqa: E731
    return System(
        title="by hand", body=body, mass=np.asarray(mass, dtype=float), bvec=rows, mult=np.ones(len(rows)),
        params=np.array([branch(ke) for ke in k]), k0=np.asarray(k, dtype=float),
        k_reversal=np.asarray(k, dtype=float),
        elements=tuple(Element((0.0, 0.0), 0.0, "spring", 1, e) for e in range(len(rows))),
        excitation=Excitation(directions={}, constant=(0.0,) * n), coordinates=tuple(coordinates),
    )


SPACE = (translation(1), translation(2), translation(3), rotation(1, "M1"), rotation(2, "M2"), rotation(3, "M3"))


def test_a_body_of_six_coordinates_has_scipys_modes():
    """The solve is dimension-generic: a body of three translations and three rotations on nine
    springs in general directions, against scipy."""
    rng = np.random.default_rng(7)
    rows = rng.normal(size=(9, 6))
    k = rng.uniform(1e4, 1e5, size=9)
    mass = np.array([120.0, 120.0, 120.0, 9.0, 12.0, 15.0])
    sys6 = hand_system(SPACE, mass, rows, k)
    modes = initial_modes(sys6)
    f, shapes = scipy_modes(np.diag(mass), (rows.T * k) @ rows)
    assert modes.coordinates == ("u1", "u2", "u3", "theta1", "theta2", "theta3")
    assert np.allclose(modes.frequencies_hz, f, rtol=1e-9, atol=0)
    assert np.allclose(modes.shapes, shapes, rtol=0, atol=1e-9)
    assert list(modes.frequencies_hz) == sorted(modes.frequencies_hz)


def test_a_free_motion_is_a_zero_frequency_mode_never_nan():
    """A body sliding along x1 and rocking, held by one spring: the motion that leaves the spring
    undeformed is a rigid-body mode, 0 Hz with a note; the other is sqrt(k b M^-1 b)."""
    h, k, m, j = 0.4, 5.0e4, 100.0, 8.0
    sys2 = hand_system((translation(1), rotation(3)), [m, j], [[1.0, -h]], [k])
    modes = initial_modes(sys2)
    assert modes.frequencies_hz[0] == 0.0 and not any(math.isnan(f) for f in modes.frequencies_hz)
    assert modes.frequencies_hz[1] == pytest.approx(math.sqrt(k * (1 / m + h * h / j)) / (2 * math.pi), rel=1e-12)
    assert modes.notes == ("mode 1: a rigid-body motion no element resists (0 Hz)",)
    # the free motion: u1 = h theta3 deforms nothing; theta3 is the larger component, +1
    assert modes.shapes[0] == pytest.approx((h, 1.0), rel=1e-12)


def test_a_negative_tangent_is_zero_hertz_with_a_note():
    modes = modes_of([2.0, 1.0], np.array([[-50.0, 0.0], [0.0, 400.0]]), ("u1", "u2"), AT_REST)
    assert modes.frequencies_hz[0] == 0.0 and "negative" in modes.notes[0]
    assert modes.frequencies_hz[1] == pytest.approx(20.0 / (2 * math.pi))


# ------------------------------------------------------------------ the time stepping rings at them


def zero_crossing_frequency(t: np.ndarray, x: np.ndarray) -> float:
    """Mean frequency from the first to the last zero crossing (times interpolated linearly)."""
    i = np.nonzero(np.sign(x[:-1]) * np.sign(x[1:]) < 0)[0]
    tc = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    return (len(tc) - 1) / (2.0 * (tc[-1] - tc[0]))


def fft_peak(t: np.ndarray, x: np.ndarray, near: float) -> float:
    """The frequency of the largest spectral peak within 10 % of ``near`` (Hann window, 16 x zero
    padding, parabolic interpolation of the log magnitude)."""
    dt = t[1] - t[0]
    size = 16 * len(x)
    spec = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(len(x)), size))
    f = np.fft.rfftfreq(size, dt)
    band = np.nonzero(np.abs(f - near) < 0.1 * near)[0]
    i = band[np.argmax(spec[band])]
    a, b, c = np.log(spec[i - 1:i + 2])
    return f[i] + 0.5 * (a - c) / (a - 2 * b + c) * (f[1] - f[0])


def test_the_plate_rings_at_its_modes_after_a_short_pulse(tmp_path):
    """Half-sine pulses of force off G set every mode ringing; after them, every coordinate's
    spectrum peaks at the three frequencies, and each modal coordinate phi_j^T M q (the shapes'
    M-orthogonality) is one sinusoid at its own: within 1 % and 0.1 %."""
    pulse = {"type": "half-sine", "amplitude": 2.0, "units": "kN", "duration": 0.01}
    deck = plate_deck(excitation={"force": {"point": [1.1, 0.7], "p1": pulse, "p2": dict(pulse, amplitude=-1.5)}})
    deck["analysis"] = {"dt": 1e-3, "duration": 12.0, "integrator": "chang", "estimate_error": False}
    path = write_deck(tmp_path, deck)
    modes = rbhyst.modes(path)
    res = rbhyst.run(path)
    after = res.time > 0.05
    t, q = res.time[after], res.d[after]
    freqs = modes["frequencies_hz"]
    for c in range(3):
        for f in freqs:
            assert fft_peak(t, q[:, c], f) == pytest.approx(f, rel=0.01), (c, f)
    m = np.diag(res.system.mass)
    for f, shape in zip(freqs, modes["shapes"]):
        eta = q @ (m @ np.array(shape))
        # (measured: within 2.3e-4, Chang's period elongation (omega dt)^2 / 12 at the third)
        assert zero_crossing_frequency(t, eta) == pytest.approx(f, rel=1e-3)
    # and the run's summary holds the same modes
    assert res.summary()["modes"] == modes


# ------------------------------------------------------------------ gravity


def hanging(alpha: float = 100.0) -> dict:
    """A 1 m square of 200 kg on two vertical VRM elements under its lower corners and two
    horizontal linear springs, under gravity: the weight loads the vertical ones along their
    loading curve, where the tangent is well above the limiting curves' slope k0 = kb."""
    branch = {"kb": 5.0e4, "f0": 300.0, "alpha": alpha}
    return {
        "body": {"vertices": [[-0.5, 0.0], [0.5, 0.0], [0.5, 1.0], [-0.5, 1.0]], "mass": 200.0,
                 "gravity": [0.0, -9.81]},
        "hysteresis": {"vert": {"loading": dict(branch), "unloading": dict(branch)}, "hor": linear_set(1.0e5)},
        "elements": [{"vertex": 1, "angle_deg": 90.0, "hysteresis": "vert"},
                     {"vertex": 2, "angle_deg": 90.0, "hysteresis": "vert"},
                     {"point": [0.0, 0.0], "angle_deg": 0.0, "hysteresis": "hor"},
                     {"point": [0.0, 1.0], "angle_deg": 0.0, "hysteresis": "hor"}],
        "analysis": {"dt": 1e-3, "duration": 0.2},
    }


def test_a_deck_with_gravity_has_the_modes_of_its_tangent_at_rest(tmp_path):
    """Each vertical element carries half the weight, pressed from its virgin state along
    f(u) = kb u - f0 + f0 exp(alpha u) (eq. 14, s = -1), its tangent there kb + alpha f0 exp(alpha
    u) (eq. 16); K = diag(2 kh, 2 kt, 2 (kt + kh) / 4) about G = (0, 0.5), J = m / 6 (the seed's
    small rotations: exact ones add the weight's geometric stiffness to the rocking)."""
    data = hanging()
    data["analysis"]["kinematics"] = "small"
    kb, f0, alpha, kh, m = 5.0e4, 300.0, 100.0, 1.0e5, 200.0
    u = brentq(lambda x: kb * x - f0 + f0 * math.exp(alpha * x) + m * 9.81 / 2, -1.0, 0.0)
    kt = kb + alpha * f0 * math.exp(alpha * u)
    assert kt > 1.1 * kb  # the test means something: the tangent is not k0
    j = m * (1.0 + 1.0) / 12.0

    def expected(kv):
        return sorted(np.sqrt([2 * kh / m, 2 * kv / m, (kv + kh) / 2 / j]) / (2 * math.pi))

    path = write_deck(tmp_path, data)
    modes = rbhyst.modes(path)
    assert modes["frequencies_hz"] == pytest.approx(expected(kb), rel=1e-12)
    rest = modes["at_rest"]
    assert rest["stiffness"] == AT_REST and rest["coordinates"] == ["u1", "u2", "theta3"]
    assert rest["frequencies_hz"] == pytest.approx(expected(kt), rel=1e-9)
    # the run's summary has the same, from the equilibrium it started from; a body at rest to
    # rounding (it turns by 1e-18 rad) draws no warning of its kinematics
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", rbhyst.AccuracyWarning)
        summary = rbhyst.run(path).summary()
    assert not any("small rotations" in w for w in summary["warnings"])
    assert summary["modes"]["at_rest"]["frequencies_hz"] == pytest.approx(rest["frequencies_hz"], rel=1e-12)
    assert summary["static"]["u2_m"] == pytest.approx(u, rel=1e-9)


def test_without_gravity_there_is_no_at_rest(tmp_path):
    data = hanging()
    del data["body"]["gravity"]
    assert "at_rest" not in rbhyst.modes(write_deck(tmp_path, data))


# ------------------------------------------------------------------ the command


def cli(*args):
    res = runner.invoke(app, [str(a) for a in args])
    return res.exit_code, res.stdout, res.stderr


def test_rbhyst_modes_prints_the_seed_decks_frequencies():
    code, out, err = cli("modes", DECKS / "seed_wri.toml")
    assert code == 0, err
    expected = rbhyst.modes(DECKS / "seed_wri.toml")
    lines = out.splitlines()
    assert lines[0].startswith("modes of the initial system")
    assert lines[1].split() == ["mode", "f", "[Hz]", "u1", "u2", "theta3"]
    for j, f in enumerate(expected["frequencies_hz"]):
        row = lines[2 + j].split()
        assert row[0] == str(j + 1) and float(row[1]) == pytest.approx(f, rel=1e-3)
        assert [float(x) for x in row[2:]] == pytest.approx(expected["shapes"][j], abs=5e-4)


def test_with_gravity_rbhyst_modes_says_which_table_to_use(tmp_path):
    code, out, err = cli("modes", write_deck(tmp_path, hanging()))
    assert code == 0, err
    lines = out.splitlines()
    rest = next(i for i, line in enumerate(lines) if line.startswith("modes at rest under gravity"))
    which = next(i for i, line in enumerate(lines) if line.startswith("which to use:"))
    assert lines[0].startswith("modes of the initial system") and which > rest + 4  # after the second table
    assert "measured frequencies" in " ".join(lines[which:]) and "K0" in " ".join(lines[which:])
    data = hanging()
    del data["body"]["gravity"]
    code, out, _ = cli("modes", write_deck(tmp_path, data, "plain"))
    assert code == 0 and "which to use" not in out


def test_rbhyst_modes_json_is_the_summarys_form(tmp_path):
    path = write_deck(tmp_path, hanging())
    code, out, err = cli("modes", path, "--json")
    assert code == 0, err
    assert json.loads(out) == json.loads(json.dumps(rbhyst.modes(path)))
    assert "at_rest" in json.loads(out)


def test_rbhyst_modes_needs_no_analysis_section_nor_excitation_files(tmp_path):
    data = plate_deck(excitation={"support": {"x1": {"file": "missing.csv", "units": "g"}}})
    del data["analysis"]
    code, out, err = cli("modes", write_deck(tmp_path, data))
    assert code == 0, err
    assert "theta3" in out


def test_rbhyst_modes_on_a_bad_deck_says_every_problem_and_exits_2(tmp_path):
    data = plate_deck()
    data["body"]["mass"] = -1.0
    data["elements"][0]["angle_deg"] = "level"
    code, out, err = cli("modes", write_deck(tmp_path, data))
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 2 and all(line.startswith("error: ") for line in lines)
    assert any("body.mass" in line for line in lines) and any("elements[1].angle_deg" in line for line in lines)
    code, _, err = cli("modes", tmp_path / "nothing.toml")
    assert code == 2 and err.startswith("error: ")


def test_the_run_prints_the_modes(tmp_path):
    data = plate_deck(excitation={"force": {"p1": {"type": "half-sine", "amplitude": 1.0, "units": "kN",
                                                   "duration": 0.02}}})
    code, _, err = cli("run", write_deck(tmp_path, data), "--out", tmp_path / "out", "--no-plots")
    assert code == 0, err
    assert "modes of the initial system (K0 = sum k0 b b^T, undamped):" in err
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["modes"]["frequencies_hz"] == pytest.approx(scipy_modes(*plate_by_hand())[0], rel=1e-9)
    for key in ("body", "elements", "analysis", "energy", "peaks", "extremes", "notes", "warnings"):
        assert key in summary  # the keys users script against stay


@pytest.mark.parametrize("deck", sorted(p.name for p in DECKS.glob("*.toml")))
@pytest.mark.parametrize("kinematics", [None, "small", "exact"])
def test_modes_of_every_sample_deck_with_either_kinematics(tmp_path, deck, kinematics):
    """`rbhyst modes` on every sample deck with a body exits 0, whatever its kinematics (exact
    ones in space once ended in a traceback from the excitation's point, which modes never read);
    a deck of loops alone (no body) is told so, exit 2."""
    import tomllib

    data = tomllib.loads((DECKS / deck).read_text())
    if kinematics is not None and "analysis" in data:
        data["analysis"]["kinematics"] = kinematics
    for section in data.get("excitation", {}).values():  # (the records beside the sample decks)
        for sig in section.values():
            if isinstance(sig, dict) and "file" in sig:
                sig["file"] = str(DECKS / sig["file"])
    code, err = invoke("modes", write_deck(tmp_path, data))
    if "body" not in data:
        assert code == 2 and err.startswith("error: body: required"), err
        return
    assert code == 0, err
