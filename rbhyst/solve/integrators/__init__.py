"""Integrators: one module per method, one registry name -> :class:`Method`.

A fixed-step method names its step in the compiled loop (``kernel_id``) and
builds that step's n x n coefficient matrices for a step h (``coefficients``), n the
body's number of coordinates: every constant matrix a step needs, inverted here once per
substep level, so that the compiled step only multiplies.
A method with a solver of its own (the reference) gives ``solve`` instead.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable

import numpy as np

from rbhyst.model.integrators import INTEGRATORS

N_COEF = 7  # coefficient matrices per substep level


@dataclass(frozen=True)
class Method:
    name: str
    summary: str
    order: int
    explicit: bool
    kernel_id: int | None = None
    #: the step depends on K0 (Chang, Chen-Ricles, KR-alpha): omega_0 h must stay resolved
    structure_dependent: bool = False
    #: (mass (n,), K0 (n, n), C (n, n), h) -> (N_COEF, n, n); h an array of steps -> one set each
    coefficients: Callable[[np.ndarray, np.ndarray, np.ndarray, float | np.ndarray], np.ndarray] | None = None
    #: (system, settings, keep=, csv=) -> Result, for methods outside the fixed-step loop
    solve: Callable | None = None


#: name -> module: a module is imported only when its method is used (the reference
#: pulls in more than a plain run needs)
_MODULES = {
    "chang": "chang",
    "central-difference": "central_difference",
    "newmark": "newmark",
    "kr-alpha": "kr_alpha",
    "reference": "reference",
    "adaptive": "adaptive",
}


def names() -> list[str]:
    return list(INTEGRATORS)


assert tuple(_MODULES) == INTEGRATORS  # one list of names: the deck's


def get(name: str) -> Method:
    if name not in _MODULES:
        raise KeyError(f"unknown integrator {name!r}; choose one of {', '.join(_MODULES)}")
    return importlib.import_module(f".{_MODULES[name]}", __name__).METHOD
