"""Stand-ins for rbhyst.analyses.sweep.worker.run_batch that tests put in its place (monkeypatch on
rbhyst.analyses.sweep.backends): a case that kills its worker process, as a memory blowup does.
Nothing in rbhyst reads this module; a worker imports it to unpickle the batch's function."""

from __future__ import annotations

import os
import signal

from rbhyst.analyses.sweep.worker import run_batch

#: body.mass of the case that kills every worker it lands on
KILLER_MASS = 666.0


def run_batch_or_die(base, cases, histories=False):
    if any(values.get("body.mass") == KILLER_MASS for _, values in cases):
        os.kill(os.getpid(), signal.SIGKILL)
    return run_batch(base, cases, histories)
