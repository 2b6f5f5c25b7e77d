"""``python -m apps.bc {decision,camera,objects} ...``: the behaviour-cloning commands as one.

- ``decision``: a clone of the decision-level expert from Minari demonstrations
  (`apps.bc.decision`, flat MLP or pair scorer on ``state``).
- ``camera``: the camera crop scorer from image demonstrations (`apps.bc.camera`).
- ``objects``: the pair scorer on ``objects`` rows, demonstrations recorded on the fly
  (`apps.bc.objects`).

Each subcommand takes its module's own options (``python -m apps.bc camera --help``).
"""

from __future__ import annotations

import importlib
import sys

from apps.cli import UsageError, run_cli

SUBCOMMANDS = ("decision", "camera", "objects")
"""The behaviour-cloning commands, each a module of `apps.bc`."""


def main(argv: list[str] | None = None) -> object:
    """Run the subcommand named by the first argument with the rest."""
    args = list(sys.argv[1:] if argv is None else argv)
    if args[:1] in (["-h"], ["--help"]):
        print(__doc__)
        return None
    if not args or args[0] not in SUBCOMMANDS:
        given = repr(args[0]) if args else "none"
        raise UsageError(f"subcommand {given}; allowed: {', '.join(SUBCOMMANDS)}")
    module = importlib.import_module(f"apps.bc.{args[0]}")
    return module.main(args[1:])


if __name__ == "__main__":
    run_cli(main)
