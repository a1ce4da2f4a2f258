"""What the command line shows on the terminal beyond its results (top layer, beside cli.py).

- Mistakes on the command line (``--dt abc``, ``--pga -1``, a missing ``--units``) in rbhyst's
  own frame: one ``error:`` line per problem, every problem at once, exit 2, as for a deck;
  not the boxed usage text of the command-line library.
- A progress bar for work that takes more than a couple of seconds, shown only on a terminal
  and only once that much time has passed (a quick command prints nothing more).
"""

from __future__ import annotations

import copy
import sys
import time

from typer.core import TyperCommand, TyperGroup

try:  # typer carries its own copy of click from 0.17 on
    from typer._click import exceptions as _exc
except ImportError:  # pragma: no cover - an older typer on click itself
    from click import exceptions as _exc

EXIT_INPUT = 2


class ProblemsError(_exc.UsageError):
    """Every problem of a command line, one line each."""

    def __init__(self, lines: list[str], ctx=None):
        super().__init__("; ".join(lines), ctx)
        self.lines = lines


def _name(param) -> str:
    if param.param_type_name == "option" and param.opts:
        return max(param.opts, key=len)
    return (param.name or "argument").upper()


def _problem(err, args: list[str]) -> str:
    """One line for the library's complaint about one parameter: its name, the value given, what
    is wrong."""
    param = getattr(err, "param", None)
    if param is None:
        return err.format_message()
    if isinstance(err, _exc.MissingParameter):
        return f"{_name(param)}: required"
    msg = err.message[:1].lower() + err.message[1:]
    value = _value(args, param)
    return f"{_name(param)}: {value!r} is not valid: {msg}" if value is not None else f"{_name(param)}: {msg}"


def _value(args: list[str], param) -> str | None:
    """What the command line gave an option (its last occurrence), if it can be told."""
    value = None
    for i, tok in enumerate(args):
        if tok in param.opts and i + 1 < len(args):
            value = args[i + 1]
        for opt in param.opts:
            if opt.startswith("--") and tok.startswith(opt + "="):
                value = tok[len(opt) + 1:]
    return value if param.param_type_name == "option" else None


def _without(args: list[str], param) -> list[str] | None:
    """The command line without an option's tokens (and its value); None for an argument (its
    place cannot be told apart from the others')."""
    if param.param_type_name != "option":
        return None
    takes_value = not getattr(param, "is_flag", False) and (param.nargs or 1) > 0
    out, skip = [], False
    for tok in args:
        if skip:
            skip = False
            continue
        if tok in param.opts:
            skip = takes_value
            continue
        if any(tok.startswith(opt + "=") for opt in param.opts if opt.startswith("--")):
            continue
        out.append(tok)
    return out


#: where a command's context keeps its arguments as given (its name first)
ARGV = "rbhyst.argv"


class Command(TyperCommand):
    """A command whose usage mistakes are all reported at once: the library stops at the first,
    so the line is parsed again without each parameter found wrong, until none is."""

    def parse_args(self, ctx, args: list[str]) -> list[str]:
        ctx.meta[ARGV] = [ctx.info_name, *args]  # the command as given, for the report to say
        problems: list[str] = []
        cmd, remaining = self, list(args)
        for _ in range(len(self.params) + 1):
            try:
                out = TyperCommand.parse_args(cmd, ctx, list(remaining))  # (the parser consumes its list)
            except _exc.NoArgsIsHelpError:
                raise
            except _exc.UsageError as err:
                problems.append(_problem(err, remaining))
                param = getattr(err, "param", None)
                if param is None:
                    break
                shorter = _without(remaining, param) if not isinstance(err, _exc.MissingParameter) else remaining
                if shorter is None:
                    break
                cmd = copy.copy(cmd)
                cmd.params = [p for p in cmd.params if p is not param]
                remaining = shorter
                continue
            if not problems:
                return out
            break
        raise ProblemsError(problems, ctx)


class Group(TyperGroup):
    """The ``rbhyst`` group: a usage mistake is ``error:`` lines and exit 2; help stays help."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        try:
            code = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
            code = code if isinstance(code, int) else 0  # (a command's typer.Exit(n) comes back as n)
        except _exc.NoArgsIsHelpError as err:
            print(err.ctx.get_help(), file=sys.stderr)
            code = EXIT_INPUT
        except _exc.UsageError as err:
            lines = err.lines if isinstance(err, ProblemsError) else [_problem(err, [])]
            for line in lines:
                print("error: " + line.replace("\r", "\\r").replace("\n", "\\n"), file=sys.stderr)
            code = EXIT_INPUT
        except _exc.ClickException as err:  # pragma: no cover - no command raises one
            print(f"error: {err.format_message()}", file=sys.stderr)
            code = err.exit_code
        if standalone_mode:
            sys.exit(code)
        return code


class Progress:
    """A progress bar on stderr for work that outlasts ``after`` seconds, on a terminal only.

    ``update(done, total, label)`` as the work goes (total 0: a phase of unknown length);
    ``close()`` at the end. Nothing is drawn
    before ``after`` seconds (a quick command stays as it was), nor when stderr is not a terminal.
    """

    def __init__(self, after: float = 2.0, stream=None):
        self.after = after
        self.stream = stream if stream is not None else sys.stderr
        self.start = time.perf_counter()
        self._progress = None
        self._task = None
        self.shown = False
        self.said: list[str] = []

    def note(self, text: str) -> None:
        """Say a note now (before the work it is about), once."""
        self.said.append(text)
        print(f"note: {text}", file=self.stream)

    def update(self, done: float, total: float, label: str = "") -> None:
        if self._progress is None:
            if time.perf_counter() - self.start < self.after or not self.stream.isatty():
                return
            from rich.console import Console
            from rich.progress import BarColumn, Progress as Bar, TaskProgressColumn, TextColumn, TimeRemainingColumn

            self._progress = Bar(TextColumn("{task.description}"), BarColumn(), TaskProgressColumn(),
                                 TimeRemainingColumn(), console=Console(file=self.stream), transient=True)
            self._progress.start()
            self._task = self._progress.add_task(label, total=total or None)
            self.shown = True
        self._progress.update(self._task, completed=done, total=total or None, description=label)

    def close(self) -> None:
        if self._progress is not None:
            self._progress.stop()
            self._progress = None
