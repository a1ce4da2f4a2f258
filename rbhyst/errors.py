"""Errors a user can act on. The command line prints them as one line each, exit 2 or 3."""

from __future__ import annotations


class InputError(ValueError):
    """Something in the deck or a file it names is wrong: one message per problem."""

    def __init__(self, problems: list[str] | str):
        self.problems = [problems] if isinstance(problems, str) else list(problems)
        super().__init__("\n".join(self.problems))


class AnalysisError(RuntimeError):
    """The analysis cannot give an answer it can vouch for (numerical failure)."""


class DiskFull(InputError):
    """The disk (or a quota) filled while rbhyst wrote into ``folder``: one line naming the
    folder and the space it needed (``free``: what was free when the writing began, which was
    not enough), and what was kept."""

    def __init__(self, folder, free: int | None, what: str = "the outputs",
                 kept: str = "nothing in the folder was changed"):
        self.folder, self.free = folder, free
        need = f": they need more than the {byte_size(free)} that was free" if free is not None else ""
        super().__init__(f"{folder}: no space left on its disk for {what}{need}; {kept}: free some space "
                         "or choose another output folder")


def is_disk_full(exc: BaseException) -> bool:
    """An OSError that says the disk, or the user's quota, is full."""
    import errno

    return isinstance(exc, OSError) and (exc.errno in (errno.ENOSPC, errno.EDQUOT)
                                         or "No space left on device" in str(exc))  # (pyarrow sets no errno)


def byte_size(n: float) -> str:
    """A number of bytes as people read it: 812 bytes, 3.1 MB, 24.3 GB (SI units, as df -H)."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{int(n)} bytes"
