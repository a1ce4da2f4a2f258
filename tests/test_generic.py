"""The solve core takes the number of coordinates from the System, for any n a body may have.

Bodies of one and two coordinates (tests/generic_scenes.py) run through the kernels' own code
uncompiled: no deck makes such a body, so no kernel is built for it at install, and numba
compiling the loops for n = 1 and 2 took some four minutes of the suite for what the same
source, compiled, already shows at n = 3 and 6 (the built kernels, tests/test_aot.py). What is
compiled per n, the kernels' small linear algebra, is compiled here for every n up to 6."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent


def test_bodies_of_one_and_two_coordinates_match_their_closed_forms_uncompiled():
    """Every scene of generic_scenes.py, in a process of its own with NUMBA_DISABLE_JIT=1 (numba
    reads it once, at import). It runs from the tests' folder, so that the installed package
    is imported, as by the suite itself."""
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "generic_scenes.py"],
                         cwd=HERE, env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stdout[-6000:] + out.stderr[-2000:]
    last = out.stdout.strip().splitlines()[-1]
    assert " passed" in last and "skipped" not in last and "deselected" not in last, last


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6])
def test_the_kernels_linear_algebra_for_any_n(n):
    """K = sum k b b^T, the solve of a step's matrix and the monitor's largest eigenvalue
    against numpy, for every n a body may have."""
    from rbhyst.solve.kernels.elements import bbt_sums, solve_in_place, sym_max_eig

    rng = np.random.default_rng(n)
    ne = 7
    bvec = rng.normal(size=(ne, n))
    mult = rng.integers(1, 3, ne).astype(float)
    k = np.abs(rng.normal(size=(ne, 2))) * 1e4
    minv = tuple(1.0 / rng.uniform(1.0, 50.0, n))
    out, scale = np.zeros((n, n)), np.zeros(n)
    bbt_sums(bvec, mult, k, 1, minv, False, out, scale)
    expected = (bvec.T * (mult * k[:, 1])) @ bvec
    np.testing.assert_allclose(out, expected, rtol=1e-12, atol=1e-9 * np.abs(expected).max())
    matrix = expected + np.diag(4e6 / np.array(minv))
    rhs = rng.normal(size=n)
    b = rhs.copy()
    solve_in_place(matrix.copy(), b, n)
    np.testing.assert_allclose(b, np.linalg.solve(matrix, rhs), rtol=1e-10)
    bbt_sums(bvec, mult, k, 0, minv, True, out, scale)
    q = np.sqrt(np.array(minv))
    normalized = (bvec.T * (mult * k[:, 0])) @ bvec * np.outer(q, q)
    np.testing.assert_allclose(out, normalized, rtol=1e-12, atol=1e-12 * np.abs(normalized).max())
    top = sym_max_eig(out.copy(), n)
    assert abs(top - np.linalg.eigvalsh(normalized)[-1]) < 1e-10 * abs(top)
