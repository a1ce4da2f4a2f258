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


class RbhystWarning(UserWarning):
    """What a finished analysis says of itself that a user must read (``Result.warnings``):
    ``rbhyst.run`` issues each through Python's ``warnings``, so that a notebook shows it and
    ``warnings.simplefilter("error", rbhyst.AccuracyWarning)`` makes it fatal. The command line
    prints the same lines as ``warning: ...`` instead."""


class AccuracyWarning(RbhystWarning):
    """The answer may be further from the truth than analysis.warn_error: its estimated error,
    a history no step determines, the energy balance, the small rotations' error."""


class ModelWarning(RbhystWarning):
    """The scene is likely not what was meant, or leaves what its model describes: no excitation
    within the run, an element beyond its stroke, a magnitude that betrays a unit mistake."""


class Warned(str):
    """A warning's text with its category (AccuracyWarning or ModelWarning): a str everywhere
    else (summary.json, the console)."""

    category: type = ModelWarning

    def __new__(cls, text: str, category: type = ModelWarning):
        out = super().__new__(cls, text)
        out.category = category
        return out


def accuracy_warnings(texts) -> list[Warned]:
    """Texts as AccuracyWarning's."""
    return [Warned(t, AccuracyWarning) for t in texts]


def issue(texts, stacklevel: int = 3) -> None:
    """Each text through Python's ``warnings``, in its category (ModelWarning for a plain str)."""
    import warnings

    for text in texts:
        warnings.warn(str(text), getattr(text, "category", ModelWarning), stacklevel=stacklevel)
