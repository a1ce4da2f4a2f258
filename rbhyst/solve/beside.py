"""Work on a thread of its own beside the caller's (the compiled kernels let go of Python's lock).

The error estimate uses a second core where the process has one: the companion's check steps
while the companion steps (rbhyst.solve.estimate).
"""

from __future__ import annotations

import threading


class Beside:
    """fn(*args) on a thread of its own, started now; result() waits for it and raises what it
    raised. Never left running: whoever starts one calls result()."""

    def __init__(self, fn, *args, name: str = "rbhyst beside"):
        self._out, self._err = None, None
        self._thread = threading.Thread(target=self._run, args=(fn, args), name=name, daemon=True)
        self._thread.start()

    def _run(self, fn, args) -> None:
        try:
            self._out = fn(*args)
        except BaseException as exc:  # (raised again in the caller's thread)
            self._err = exc

    def result(self):
        self._thread.join()
        if self._err is not None:
            raise self._err
        return self._out
