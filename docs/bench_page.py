"""The benchmarks page's tables, generated from committed benchmark JSON files.

``python -m benchmarks`` writes ``out/bench.json`` (`benchmarks.table`: date, machine, every
figure with its target); a copy of the latest run is committed as ``docs/bench.json`` because CI
cannot run every benchmark. The docs build writes ``docs/_generated/bench_table.md`` from it
(the run's date and machine line, then the table), which ``benchmarks.md`` includes.

Likewise ``python -m benchmarks.env --ratios`` writes ``out/bench_env_ratios.json`` (the three
ratios of where training spends its time, `benchmarks.env_ratios`); its committed copy
``docs/bench_env_ratios.json`` becomes ``docs/_generated/bench_ratios.md``.

The page opens on ``docs/_generated/bench_glance.md``: the figures of both files that do not
depend on the machine's speed (accuracies, simulated-time rates, ratios measured within one run;
`portable`), each with its run and that run's load; and on the plot ``docs/img/bench_overview.png``
(``python docs/gen_bench_plot.py``).
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
RATIOS_JSON = DOCS / "bench_env_ratios.json"
"""The committed copy of the latest ``out/bench_env_ratios.json``."""
RATIOS_MD = DOCS / "_generated" / "bench_ratios.md"
"""Generated include of the benchmarks page's ratio table."""
GLANCE_MD = DOCS / "_generated" / "bench_glance.md"
"""Generated include: the figures that hold across machines, first on the page."""
MACHINE_UNITS = ("s", "ms", "frames/s", "x real time")
"""Units of figures that scale with the machine's speed and load."""
MACHINE_WORDS = ("steps per", "rss", " ms", "wall", "workers", "per cycle", "per image")
"""Words naming such figures among the unitless ones (env steps per second, memory, times)."""
RATIO_FIGURES = {
    "reset": ("procedural reset", "fixed reset"),
    "reset_pool": ("procedural reset, design pool (env's process)", "fixed reset"),
    "step": ("kinematic pick_place step", "its physics"),
    "camera": ("decision step with both images", "without images"),
}
"""Each ratio's two sides, as the table names them."""
MACHINE_KEYS = ("mujoco", "torch", "stable_baselines3", "gymnasium", "numpy")
"""Library versions named on the machine line."""


def portable(f: Figure) -> bool:
    """Whether a figure holds across machines: not a time, rate or memory of this machine."""
    if f.unit in MACHINE_UNITS:
        return False
    return not any(w in f" {f.name}" for w in MACHINE_WORDS)


def load_text(machine: dict[str, Any]) -> str:
    """The run's load: load average (1, 5, 15 min) at its start and end, and the CPUs it used."""
    load = machine.get("load")
    if not load:  # a report written before the start was recorded
        end = machine.get("load_average")
        return f"load average {end[0]:.1f} at the end" if end else "load not recorded"

    def avg(x: dict[str, Any]) -> str:
        a = x.get("load_average")
        return "/".join(f"{v:.1f}" for v in a) if a else "?"

    used = load["start"].get("cpus_usable", machine.get("cpus"))
    return (
        f"load average (1/5/15 min) {avg(load['start'])} at the start and {avg(load['end'])} "
        f"at the end, {used} of {machine.get('cpus')} CPUs used"
    )


def machine_line(report: dict[str, Any]) -> str:
    """One sentence saying when, where and how the figures were measured."""
    m = report["machine"]
    load_txt = f", {load_text(m)}"
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


def ratios_markdown(report: dict[str, Any]) -> str:
    """The load line and a table of each ratio: both sides [CPU ms], ratio, target, met."""
    m = report["machine"]
    lines = [
        f"Run of {report.get('date', '?')} on {m['cpus']} CPUs ({m['platform']}, Python "
        f"{m['python']}), each ratio in "
        f"one process pinned to one core, its two sides interleaved; CPU time of the process "
        f"(the software renderer's threads included).",
        "",
        "| ratio | side | CPU ms | other side | CPU ms | ratio | target | met | load average |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in report["ratios"].items():
        ms = [(k, v) for k, v in r.items() if k.endswith("_ms")]
        top, bottom = RATIO_FIGURES.get(name, (ms[0][0], ms[1][0]))
        load = r["load_average"][1]
        met = "yes" if r["ratio"] <= r["target"] else "**no**"
        lines.append(
            f"| {name} | {top} | {ms[0][1]:.2f} | {bottom} | {ms[1][1]:.2f} | {r['ratio']:.2f} "
            f"| <= {r['target']:g} | {met} | {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} |"
        )
    return "\n".join(lines) + "\n"


def glance_markdown(report: dict[str, Any], ratios: dict[str, Any]) -> str:
    """The page's first table: every figure with a target that holds across machines.

    Rows of ``report`` (the benchmark's table) whose figure is `portable`, then the three
    ratios of ``ratios``; each row names its run (date, mode), whose load the lines above give.
    """
    run = f"{report['mode']} run {report['date'][:16].replace('T', ' ')} UTC"
    rrun = f"ratios run {ratios.get('date', '?')}"
    lines = [
        f"- **{run}** (`python -m benchmarks"
        + ("" if report["mode"] == "full" else f" --{report['mode']}")
        + f"`): {load_text(report['machine'])}.",
        f"- **{rrun}** (`python -m benchmarks.env --ratios`, each ratio in one process pinned "
        f"to one core, its two sides interleaved): load average (1/5/15 min) at each ratio's "
        f"start and end in the table.",
        "",
        "| group | figure | value | target | met | run |",
        "|---|---|---|---|---|---|",
    ]
    for f in (Figure(**x) for x in report["figures"]):
        if f.passed is None or not portable(f):
            continue
        unit = f" {f.unit}" if f.unit else ""
        met = "yes" if f.passed else "**no**"
        lines.append(f"| {f.group} | {f.name} | {f.value:.4g}{unit} | {f.target} | {met} | {run} |")
    for name, r in ratios["ratios"].items():
        top, bottom = RATIO_FIGURES.get(name, (name, "baseline"))
        start, end = r["load_average"]
        met = "yes" if r["ratio"] <= r["target"] else "**no**"
        lines.append(
            f"| env ratio | {top} / {bottom} (CPU time) | {r['ratio']:.2f} | <= {r['target']:g} "
            f"| {met} | {rrun}, load {start[0]:.1f} -> {end[0]:.1f} |"
        )
    return "\n".join(lines) + "\n"


def write_glance_table(
    src: Path = BENCH_JSON, ratios: Path = RATIOS_JSON, dst: Path = GLANCE_MD
) -> Path:
    """Write the page's first include from the committed run and ratios; returns its path."""
    text = glance_markdown(
        json.loads(src.read_text(encoding="utf-8")), json.loads(ratios.read_text(encoding="utf-8"))
    )
    dst.parent.mkdir(parents=True, exist_ok=True)
    if not dst.is_file() or dst.read_text(encoding="utf-8") != text:
        dst.write_text(text, encoding="utf-8")
    return dst


def write_ratio_table(src: Path = RATIOS_JSON, dst: Path = RATIOS_MD) -> Path:
    """Write the benchmarks page's ratio include from ``src``; returns its path."""
    text = ratios_markdown(json.loads(src.read_text(encoding="utf-8")))
    dst.parent.mkdir(parents=True, exist_ok=True)
    if not dst.is_file() or dst.read_text(encoding="utf-8") != text:
        dst.write_text(text, encoding="utf-8")
    return dst


def write_bench_table(src: Path = BENCH_JSON, dst: Path = TABLE_MD) -> Path:
    """Write the benchmarks page's include from ``src``; returns its path."""
    report = json.loads(src.read_text(encoding="utf-8"))
    text = bench_markdown(report)
    dst.parent.mkdir(parents=True, exist_ok=True)
    if not dst.is_file() or dst.read_text(encoding="utf-8") != text:
        dst.write_text(text, encoding="utf-8")
    return dst
