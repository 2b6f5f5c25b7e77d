"""The command-line error contract shared by every program of the project.

Every command (``python -m apps.<name>``, ``python -m benchmarks[.<name>]``) builds its parser
with `CommandParser` and ends with ``run_cli(main)``:

- a usage error (unknown option, missing or malformed argument) prints ``error: <message>`` on
  one line to stderr and exits with status 2 (`EXIT_USAGE`);
- an error of the project's own types (`PROJECT_ERRORS`: the base exception of each package,
  which names what was wrong and what is allowed) prints ``error: <message>`` on one line and
  exits with status 1 (`EXIT_ERROR`);
- ``--debug`` (accepted by every `CommandParser`) or the environment variable
  ``MOSAIC_DEBUG=1`` lets either kind raise with its traceback instead;
- any other exception is a bug and keeps its traceback.

Why here: the contract needs the base exception of every library package (``qshape``,
``planners``, ``envs``, ``agents``, ``configs``), so it sits above all of them, in the programs
layer. ``apps`` holds the programs and never imports ``benchmarks``; the benchmark programs are
programs of the same layer and import this module sideways. It imports no package of the
project: it names each base exception and finds it among the modules already imported.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn, TypeVar

T = TypeVar("T")

EXIT_ERROR = 1
"""Exit status of a command refused by one of the project's errors."""
EXIT_USAGE = 2
"""Exit status of a command line that could not be parsed (argparse's own status)."""
DEBUG_FLAG = "--debug"
"""Command-line flag that shows the traceback of a project error."""
DEBUG_ENV = "MOSAIC_DEBUG"
"""Environment variable that, set to ``1``, shows the traceback of a project error."""
EXIT_INTERRUPTED = 130
"""Exit status after Ctrl-C (128 + SIGINT, the shell's convention)."""
PROJECT_ERRORS = (
    ("configs", "ConfigError"),
    ("qshape.errors", "QShapeError"),
    ("planners.errors", "PlannerError"),
    ("envs.errors", "EnvError"),
    ("agents.errors", "AgentError"),
)
"""(module, class) of the base exception of each package: caught and printed as one line.

Looked up among the modules already imported when an error arrives (`project_errors`): an
error of a package can only be raised once that package is imported, and a command that never
touches the simulator does not pay for importing it here.
"""


def project_errors() -> tuple[type[BaseException], ...]:
    """The base exceptions of `PROJECT_ERRORS` whose packages are imported (plus `UsageError`)."""
    found: list[type[BaseException]] = [UsageError]
    for module, name in PROJECT_ERRORS:
        if module in sys.modules:
            found.append(getattr(sys.modules[module], name))
    return tuple(found)


class UsageError(Exception):
    """A command line that could not be parsed; the message is argparse's."""


class CommandParser(argparse.ArgumentParser):
    """`argparse.ArgumentParser` that raises `UsageError` instead of exiting, with ``--debug``.

    ``--help`` still prints and exits with status 0.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.add_argument(
            DEBUG_FLAG,
            action="store_true",
            help=f"show the traceback of an error (or set {DEBUG_ENV}=1)",
        )

    def error(self, message: str) -> NoReturn:
        """Raise `UsageError` with argparse's message (instead of printing usage and exiting)."""
        raise UsageError(message)


def debug_requested(argv: Sequence[str] | None = None) -> bool:
    """Whether ``--debug`` is on the command line or ``MOSAIC_DEBUG=1`` is set."""
    args = sys.argv[1:] if argv is None else argv
    return DEBUG_FLAG in args or os.environ.get(DEBUG_ENV, "") == "1"


def one_line(exc: BaseException) -> str:
    """The exception's message on one line (``error: <message>``)."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    return f"error: {text}"


def run_cli(main: Callable[[], Any], argv: Sequence[str] | None = None) -> NoReturn:
    """Run a command's ``main()`` under the error contract (module docstring) and exit.

    Args:
        main: The command; it reads ``sys.argv`` (its parser is a `CommandParser`).
        argv: The arguments ``--debug`` is looked for in; None: ``sys.argv[1:]``.
    """
    debug = debug_requested(argv)
    try:
        main()
    except UsageError as exc:
        if debug:
            raise
        print(one_line(exc), file=sys.stderr)
        sys.exit(EXIT_USAGE)
    except KeyboardInterrupt:
        if debug:
            raise
        print("error: interrupted", file=sys.stderr)
        sys.exit(EXIT_INTERRUPTED)
    except Exception as exc:
        if debug or not isinstance(exc, project_errors()):
            raise
        print(one_line(exc), file=sys.stderr)
        sys.exit(EXIT_ERROR)
    sys.exit(0)


def write_result(path: str | Path, result: T, note: str = "") -> T:
    """Write a command's result as indented JSON (whole or not at all), say where, return it.

    Args:
        path: The JSON file (its folder is made).
        result: A JSON-serialisable value.
        note: Appended to the printed ``wrote <path>`` line (e.g. the run's time).
    """
    from configs.files import write_json  # noqa: PLC0415 - this module imports no package

    write_json(path, result)
    print(f"wrote {path}{note}")
    return result


__all__ = [
    "DEBUG_ENV",
    "DEBUG_FLAG",
    "EXIT_ERROR",
    "EXIT_INTERRUPTED",
    "EXIT_USAGE",
    "PROJECT_ERRORS",
    "CommandParser",
    "UsageError",
    "debug_requested",
    "one_line",
    "project_errors",
    "run_cli",
    "write_result",
]
