"""The cores this process may run on: what a sweep starts as many workers as, and what decides
whether a run's error estimate (rbhyst.solve.estimate) and its figures (rbhyst.report.parallel)
take a second one."""

from __future__ import annotations

import os


def usable_cores() -> int:
    """The cores this process may run on (its affinity where the system says, else all)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)
