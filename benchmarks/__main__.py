"""``python -m benchmarks``: every benchmark, one table (see ``benchmarks.table``)."""

from apps.cli import run_cli
from benchmarks.table import main

if __name__ == "__main__":
    run_cli(main)
