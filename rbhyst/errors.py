"""Errors a user can act on. The command line prints them as one line each, exit 2 or 3."""

from __future__ import annotations


class InputError(ValueError):
    """Something in the deck or a file it names is wrong: one message per problem."""

    def __init__(self, problems: list[str] | str):
        self.problems = [problems] if isinstance(problems, str) else list(problems)
        super().__init__("\n".join(self.problems))


class AnalysisError(RuntimeError):
    """The analysis cannot give an answer it can vouch for (numerical failure)."""
