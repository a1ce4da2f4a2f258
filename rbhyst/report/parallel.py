"""Draw a list of figures on two cores where that is safe: half in a forked child, half here.

matplotlib spends its time in Python (ticks, text), so figures of one run drawn in turn keep
one core busy for a second or more. A forked child inherits the imported matplotlib and the
data, so it costs nothing to start. Forking is safe only in a process with no other threads
(a notebook's kernel has several) on Linux (macOS system frameworks do not survive a fork), and
worth it only with a second core: otherwise the figures are drawn here, in turn. Whatever the
child does not finish is drawn here too, so the files are the same either way.
"""

from __future__ import annotations

import gc
import os
import signal
import sys
import threading
from typing import Callable


def _fork_is_safe() -> bool:
    from rbhyst.cores import usable_cores

    return sys.platform.startswith("linux") and threading.active_count() == 1 and usable_cores() > 1


def draw_all(jobs: list[Callable[[], None]]) -> None:
    """Run every job (each draws and saves one figure); every other one in a child process."""
    if len(jobs) < 2 or not _fork_is_safe():
        for job in jobs:
            job()
        return
    mine, theirs = jobs[0::2], jobs[1::2]  # alternate: figures of a kind cost alike
    # the objects made so far out of the collector's reach while the child lives: a collection
    # in the child would otherwise write to every one of them (each page of the heap copied)
    # and go over all of them, as the parent's would (Python's documentation of gc.freeze)
    gc.freeze()
    try:
        pid = os.fork()
    except BaseException:
        gc.unfreeze()
        raise
    if pid == 0:  # the child: its half, then out without running the parent's cleanup
        status = 1
        try:
            signal.signal(signal.SIGINT, signal.SIG_DFL)  # Ctrl-C or the parent's kill: just end
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            for job in theirs:
                job()
            status = 0
        finally:
            os._exit(status)
    finished = False
    try:
        for job in mine:
            job()
        _, status = os.waitpid(pid, 0)
        finished = True
        if os.waitstatus_to_exitcode(status) != 0:
            for job in theirs:  # the child failed: draw its half here (and raise what it met)
                job()
    finally:
        if not finished:  # interrupted here: the child must be gone before the folder is removed
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
        gc.unfreeze()
