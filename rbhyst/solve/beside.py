"""Work on a thread of its own beside the caller's (the compiled kernels let go of Python's lock).

The error estimate uses a second core where the process has one: the companion's check while
the companion steps, half of the elements' re-drive (rbhyst.solve.estimate, .companion).
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


class Pieces:
    """Work in pieces that whoever is free takes, one at a time: the caller, and a Beside
    thread once its own work is done (the companion's re-drive, a few elements a piece, taken
    by the companion's thread and by its check's). Opened once with the work, or closed with
    none; ``work`` waits for either."""

    def __init__(self):
        self._cond = threading.Condition()
        self._todo = None  # None: neither opened nor closed yet
        self._fn = None
        self._busy = 0
        self._err = None

    def open(self, fn, pieces) -> None:
        """fn(*piece) to be called once for every piece."""
        with self._cond:
            self._fn, self._todo = fn, list(pieces)
            self._cond.notify_all()

    def close(self) -> None:
        """No (more) pieces: whoever waits goes on."""
        with self._cond:
            self._todo = []
            self._cond.notify_all()

    def work(self) -> None:
        """Take pieces until none is left, waiting for them to be opened or closed."""
        while True:
            with self._cond:
                while self._todo is None:
                    self._cond.wait()
                if not self._todo:
                    return
                piece = self._todo.pop(0)
                self._busy += 1
            try:
                self._fn(*piece)
            except BaseException as exc:  # (raised in finish, in the caller's thread)
                self._err = exc
                self.close()
            finally:
                with self._cond:
                    self._busy -= 1
                    self._cond.notify_all()

    def finish(self) -> None:
        """work, then wait for the pieces the others took; raises what a piece raised."""
        self.work()
        with self._cond:
            while self._busy:
                self._cond.wait()
        if self._err is not None:
            raise self._err
