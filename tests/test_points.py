"""Points of interest: their columns follow from G's by the seed's kinematics (eqs. 7-8)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import rbhyst
from rbhyst.model.deck import parse_deck
from rbhyst.errors import InputError
from conftest import seed_deck, write_deck

CABINET_PARTS = [  # G is not at the deck's origin: points must be taken from it
    {"vertices": [[0.0, 0.0], [0.8, 0.0], [0.8, 2.0], [0.0, 2.0]], "mass": 300.0},
    {"vertices": [[0.1, 0.2], [0.7, 0.2], [0.7, 0.6], [0.1, 0.6]], "mass": 250.0},
]


def cabinet_deck(**analysis) -> dict:
    d = seed_deck(**analysis)
    d["body"] = {"parts": CABINET_PARTS}
    for el in d["elements"]:
        el["part"] = 1
    d["output"] = {"points": [{"name": "top", "point": [0.0, 2.0]}, {"name": "corner_2", "point": [0.8, 0.0]}]}
    return d


@pytest.mark.parametrize("integrator", ["chang", "adaptive"])
def test_point_columns_follow_from_the_mass_centre_by_eqs_7_8(integrator):
    res = rbhyst.run(parse_deck(cabinet_deck(duration=0.5, kinematics="small")), integrator=integrator, estimate=False)
    g = res.system.body.mass_centre
    assert g[1] == pytest.approx((300 * 1.0 + 250 * 0.4) / 550)  # far from the origin
    u1, u2, th = res.d.T
    at1, at2, alpha = res.total_acceleration.T
    for name, p in (("top", (0.0, 2.0)), ("corner_2", (0.8, 0.0))):
        x1, x2 = p[0] - g[0], p[1] - g[1]
        np.testing.assert_allclose(res.column(f"{name}_u1_m"), u1 - th * x2, rtol=1e-15, atol=0)
        np.testing.assert_allclose(res.column(f"{name}_u2_m"), u2 + th * x1, rtol=1e-15, atol=0)
        np.testing.assert_allclose(res.column(f"{name}_at1_m_s2"), at1 - alpha * x2, rtol=1e-15, atol=0)
        np.testing.assert_allclose(res.column(f"{name}_at2_m_s2"), at2 + alpha * x1, rtol=1e-15, atol=0)
    assert np.abs(res.d[:, 2]).max() > 1e-4  # the rotation is not negligible: the test can tell


def test_a_point_at_an_element_moves_as_the_element_deforms():
    """u_e = b . q (eqs. 5-8) is the point's displacement along the element: the kernel's
    element columns check the point columns independently."""
    d = cabinet_deck(duration=0.5, kinematics="small")
    d["output"]["points"] = [{"name": "p1", "point": [0.0, 0.0]}, {"name": "p2", "point": [0.8, 0.0]}]
    res = rbhyst.run(parse_deck(d), estimate=False)
    # elements in CSV order: e1-2 axial (0 deg) at vertex 1, e3-4 shear (90 deg) at vertex 1, then vertex 2
    for name, axial, shear in (("p1", 1, 3), ("p2", 5, 7)):
        np.testing.assert_allclose(res.column(f"{name}_u1_m"), res.column(f"e{axial}_u_m"), rtol=1e-12, atol=1e-18)
        np.testing.assert_allclose(res.column(f"{name}_u2_m"), res.column(f"e{shear}_u_m"), rtol=1e-12, atol=1e-18)


def test_points_sit_between_the_resultant_and_the_elements_and_join_every_reduction(tmp_path):
    d = cabinet_deck(duration=0.5)
    all_rows = rbhyst.run(parse_deck(d), estimate=False)
    names = list(all_rows.columns)
    i = names.index("R3_Nm")
    assert names[i + 1:i + 9] == ["top_u1_m", "top_u2_m", "top_at1_m_s2", "top_at2_m_s2",
                                  "corner_2_u1_m", "corner_2_u2_m", "corner_2_at1_m_s2", "corner_2_at2_m_s2"]
    assert names[i + 9] == "e1_u_m"
    d["output"]["every"] = 7
    path = write_deck(tmp_path, d)
    res = rbhyst.run(path, out=tmp_path / "out", plots=True, estimate=False)
    out = tmp_path / "out"
    assert (out / "time_history.csv").read_text().splitlines()[0].split(",") == names
    summary = json.loads((out / "summary.json").read_text())
    # peaks and extremes are over every step of dt, not only the rows every = 7 writes
    peak = np.abs(all_rows.column("top_at1_m_s2")).max()
    assert summary["peaks"]["top_at1_m_s2"] == res.extremes.peak("top_at1_m_s2") == peak
    assert np.abs(all_rows.column("top_at1_m_s2")[::7]).max() < peak
    assert summary["extremes"]["corner_2_u2_m"]["min"] == all_rows.column("corner_2_u2_m").min()
    assert (out / "response_top.png").stat().st_size > 0 and (out / "response_corner_2.png").stat().st_size > 0


@pytest.mark.parametrize("points, lines", [
    ([{"name": "top", "point": [0.0, 2.0]}, {"name": "top", "point": [0.8, 2.0]}],
     ["output.points[2].name: 'top' is already the name of output.points[1]"]),
    ([{"name": "Top", "point": [0.0, 2.0]}, {"name": "top", "point": [0.8, 2.0]}],
     ["output.points[2].name: 'top' is already the name of output.points[1] (names differ only in case, "
      "and they name files)"]),
    ([{"name": "top left", "point": [0.0, 2.0]}, {"name": "x1", "point": [0.8, 2.0]}, {"name": "b", "point": [1.0]},
      {"name": "c", "point": [0, 1], "x": 1}],
     ["output.points[1].name: 'top left': letters, digits and _ only (it names columns and files)",
      "output.points[2].name: 'x1' is taken by rbhyst's own outputs (G, ground, x1, x2, theta3: the mass "
      "centre's plots, the ground's spectra): choose another",
      "output.points[3].point: List should have at least 2 items after validation, not 1",
      "output.points[4].x: unknown key"]),
])
def test_point_mistakes_one_line_each(points, lines):
    d = seed_deck()
    d["output"] = {"points": points}
    with pytest.raises(InputError) as err:
        parse_deck(d)
    assert err.value.problems == lines


def test_a_name_like_a_column_prefix_is_fine():
    d = seed_deck(duration=0.05)
    d["output"] = {"points": [{"name": "e1", "point": [0.0, 0.0]}, {"name": "u1", "point": [0.1, 0.0]}]}
    res = rbhyst.run(parse_deck(d), estimate=False)
    assert len(set(res.columns)) == len(res.columns)
    assert "e1_u1_m" in res.columns and "e1_u_m" in res.columns and "u1_u1_m" in res.columns
