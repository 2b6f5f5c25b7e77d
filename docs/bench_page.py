"""The benchmarks page's table, generated from the committed ``docs/bench.json``.

``python -m benchmarks`` writes ``out/bench.json`` (`benchmarks.table`: date, machine, every
figure with its target); a copy of the latest run is committed as ``docs/bench.json`` because CI
cannot run every benchmark. The docs build writes ``docs/_generated/bench_table.md`` from it
(the run's date and machine line, then the table), which ``benchmarks.md`` includes.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from benchmarks.figures import Figure
from benchmarks.table import table

DOCS = Path(__file__).resolve().parent
BENCH_JSON = DOCS / "bench.json"
"""The committed copy of the latest ``out/bench.json``."""
TABLE_MD = DOCS / "_generated" / "bench_table.md"
"""Generated include of the benchmarks page."""
MACHINE_KEYS = ("mujoco", "torch", "stable_baselines3", "gymnasium", "numpy")
"""Library versions named on the machine line."""


def machine_line(report: dict[str, Any]) -> str:
    """One sentence saying when, where and how the figures were measured."""
    m = report["machine"]
    load = m.get("load_average")
    load_txt = f", load average {load[0]:.1f} at the end" if load else ""
    libs = ", ".join(f"{k} {m[k]}" for k in MACHINE_KEYS if m.get(k))
    s = report["summary"]
    return (
        f"Run of {report['date']} (mode `{report['mode']}`) on {m['processor']} with "
        f"{m['cpus']} CPUs, {m['platform']}, Python {m['python']}{load_txt}; {libs}. "
        f"{s['passed']} of {s['with_target']} targets met."
    )


def bench_markdown(report: dict[str, Any]) -> str:
    """The date and machine line, the failed targets if any, and the table of every figure."""
    figures = [Figure(**f) for f in report["figures"]]
    parts = [machine_line(report)]
    failed = report["summary"]["failed"]
    if failed:
        parts.append("Targets missed in this run: " + "; ".join(failed) + ".")
    runs = {name: src.get("run") for name, src in report.get("sources", {}).items()}
    broken = [f"{name} ({run['error'].strip()})" for name, run in runs.items() if run and run["rc"]]
    if broken:
        parts.append("Scripts that gave no figures in this run: " + "; ".join(broken) + ".")
    parts.append(table(figures))
    return "\n\n".join(parts) + "\n"


def write_bench_table(src: Path = BENCH_JSON, dst: Path = TABLE_MD) -> Path:
    """Write the benchmarks page's include from ``src``; returns its path."""
    report = json.loads(src.read_text(encoding="utf-8"))
    text = bench_markdown(report)
    dst.parent.mkdir(parents=True, exist_ok=True)
    if not dst.is_file() or dst.read_text(encoding="utf-8") != text:
        dst.write_text(text, encoding="utf-8")
    return dst
