"""The multiple shear spring (MSS) of an isolator whose two shear lines are one behaviour in the
shear plane (``coupling = "mss"``): ``n`` uniaxial VRM springs at the angles pi i / n from shear
line 1 towards shear line 2, each deformed by the projection of the shear displacement on its
line, their forces acting along their lines (Wada and Hirose; OpenSees' multipleShearSpring).

Each spring's set is the deck's shear set with its terms scaled so that a uniaxial motion along
either shear line reproduces the set (what the set was measured as):

- ``kb`` by 2 / n and ``f0`` by 1 / S, S = sum |cos(pi i / n)|: the linear term is then exact at
  any deformation (sum cos^2 = n / 2) and the constant one wherever every spring is saturated;
- ``alpha`` by 2 S / n: the stiffness at a reversal, kb + alpha (f0+ + f0-), is then the set's;
  with the two above this is the set as the force and deformation scaled, a F(u / b) with
  a = 1 / S, b = n / (2 S), exact for the VRM (the logistic term scales the same way);
- the exponential term beta1 (exp(beta2 u) - 1), which no such scaling keeps, by matching the
  MSS's monotonic force of that term to the set's at ``reference`` and at half of it (two
  equations for beta1 and beta2 of the springs): OpenSees' ``-lim`` (Feq at a deformation the
  element reaches) applied to the one term it matters for.

What remains is the transition between the branches (the springs turn at different times), and where the set's loading and unloading branches are
not mirror images, a small force across the line of motion:
along a shear line the loop of the seed's Table 3 shear set is within 7 % of its peak force for
amplitudes up to ``reference`` with 8 springs (tests/test_mss.py).
"""

from __future__ import annotations

import math

import numpy as np

from rbhyst.model.hysteresis import ALPHA, BETA1, BETA2, F0, GAMMA1, GAMMA2, GAMMA3, KB

#: the springs of an MSS isolator unless the deck says: eight, every 22.5 deg (OpenSees suggests
#: 8 or more; the resultant's magnitude on a circular orbit then varies by about 2 %)
DEFAULT_SPRINGS = 8


def angles(n: int) -> np.ndarray:
    """The springs' angles from shear line 1, pi i / n (rad), i = 0 .. n - 1."""
    return math.pi * np.arange(n) / n


def spring_cosines(n: int) -> tuple[np.ndarray, np.ndarray]:
    """(cos, sin) of the springs' angles, exact at 0 and pi / 2 (their lines along the shear lines)."""
    th = angles(n)
    c, s = np.cos(th), np.sin(th)
    c[np.isclose(th, 0.5 * math.pi)] = 0.0
    return c, s


def spring_set(p: np.ndarray, n: int, reference: float | None) -> np.ndarray:
    """The (2, 8) set of each of the n springs of an MSS whose uniaxial response is the set p's
    (module docstring); ``reference`` (m) where the exponential term is matched (needed only
    where p has one)."""
    c, _ = spring_cosines(n)
    ac = np.abs(c)
    total = float(ac.sum())
    a, b = 1.0 / total, n / (2.0 * total)
    q = np.array(p, dtype=float, copy=True)
    q[:, KB] *= a / b
    q[:, F0] *= a
    q[:, ALPHA] /= b
    q[:, GAMMA1] *= a
    q[:, GAMMA2] /= b
    q[:, GAMMA3] *= b
    for row in (0, 1):
        b1, b2 = p[row, BETA1], p[row, BETA2]
        if b1 == 0.0 or b2 == 0.0:
            continue
        if reference is None:
            raise ValueError("an MSS of a set with an exponential term needs its reference deformation")
        q[row, BETA1], q[row, BETA2] = _exponential(b1, b2, ac, reference)
    return q


def _exponential(b1: float, b2: float, ac: np.ndarray, x: float) -> tuple[float, float]:
    """beta1, beta2 of the springs whose sum_i beta1 (exp(beta2 x |c_i|) - 1) |c_i| is the set's
    beta1 (exp(|beta2| x) - 1) at x and x / 2 (the term grows on the side where beta2 u > 0: a
    spring whose line is against the motion bears it on the other branch, of the opposite sign)."""
    # (imported here: a run without an MSS of such a set loads no scipy)
    from scipy.optimize import brentq

    k0 = abs(b2)

    def of(k, y):
        return float(np.sum(np.expm1(k * y * ac) * ac))

    want = math.expm1(k0 * x) / math.expm1(0.5 * k0 * x)
    k = brentq(lambda k: of(k, x) / of(k, 0.5 * x) - want, 0.25 * k0, 8.0 * k0, xtol=1e-12 * k0)
    return b1 * math.expm1(k0 * x) / of(k, x), math.copysign(k, b2)


def spring_label(index: int) -> str:
    """The role of spring ``index`` (1-based) of an MSS isolator, as its element's label says."""
    return f"mss{index}"
