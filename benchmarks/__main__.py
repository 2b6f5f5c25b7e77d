"""``python -m benchmarks``: every benchmark, one table (see ``benchmarks.table``)."""

from benchmarks.table import main

if __name__ == "__main__":
    main()
