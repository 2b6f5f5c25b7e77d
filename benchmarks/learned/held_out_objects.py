r"""Figures of the ``MosaicHeldOutDesigns-v0`` ``objects`` rows from run folders, and their curves.

Run (after ``apps.bc.objects`` and ``apps.evaluate``, docs/held_out_baselines.md)::

    python -m benchmarks.learned.held_out_objects --runs runs/objects_bc --curve runs/objects_curve
    \
        --out docs/held_out_objects_curves.png

``--runs`` holds ``seed_<s>/`` folders, each with ``bc_summary.json`` and ``eval1000/`` and
``eval2000/`` (``apps.evaluate`` outputs on seeds 1000-1019 and 2000-2019). Per seed, the run's
figure is the mean over its evaluated episodes; over seeds the IQM with a 95 % stratified
bootstrap interval (`agents.protocol.iqm_ci`). ``--curve`` holds ``ep<E>_seed_<s>/`` folders
(E demonstration episodes) with ``eval1000/``: slots filled against demonstration episodes.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

from agents.protocol import iqm_ci
from apps.cli import CommandParser, run_cli

EVALS = ("eval1000", "eval2000")
"""Evaluation folders of a seed's run (held-out seeds 1000-1019 and 2000-2019)."""
CURVE_DIR = re.compile(r"ep(\d+)_seed_(\d+)$")
"""Name of a curve run folder: demonstration episodes and training seed."""


def seed_dirs(runs: Path) -> list[Path]:
    """The ``seed_<s>`` run folders under ``runs``, sorted."""
    return sorted(p for p in runs.glob("seed_*") if p.is_dir())


def run_figures(folder: Path, evaluation: str) -> dict[str, float]:
    """Mean filled fraction and success of one run's evaluation (episode-weighted over designs)."""
    rows = json.loads((folder / evaluation / "eval.json").read_text())["rows"]
    n = sum(r["episodes"] for r in rows)
    return {
        "filled": sum(r["filled"] * r["episodes"] for r in rows) / n,
        "success": sum(r["success_rate"] * r["episodes"] for r in rows) / n,
    }


def summarize(runs: Path) -> dict[str, Any]:
    """IQM [95 % CI] over seeds per evaluation, and the compute per run."""
    seeds = seed_dirs(runs)
    out: dict[str, Any] = {"seeds": len(seeds)}
    for ev in EVALS:
        figs = [run_figures(s, ev) for s in seeds]
        out[ev] = {m: iqm_ci([f[m] for f in figs]).text() for m in ("filled", "success")}
        out[ev]["per_seed_filled"] = [round(f["filled"], 3) for f in figs]
    sums = [json.loads((s / "bc_summary.json").read_text()) for s in seeds]
    out["env_steps"] = sums[0]["env_steps"]
    out["gradient_steps"] = sums[0]["gradient_steps"]
    out["cpu_min_per_run"] = max((s["record_cpu_s"] + s["train_cpu_s"]) / 60 for s in sums)
    return out


def plot(runs: Path, curve: Path, path: Path) -> None:
    """Training loss per seed against gradient steps, and held-out filled against demos."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
    for s in seed_dirs(runs):
        c = json.loads((s / "bc_summary.json").read_text())["curve"]
        ax1.plot([p["gradient_steps"] for p in c], [p["loss"] for p in c], label=s.name)
    ax1.set(xlabel="gradient steps", ylabel="cross-entropy (train)", title="cloning loss")
    ax1.legend(fontsize=7)
    points: dict[int, list[float]] = {}
    for d in (p for p in curve.glob("ep*_seed_*") if p.is_dir()):
        m = CURVE_DIR.search(d.name)
        if m and (d / "eval1000" / "eval.json").is_file():
            points.setdefault(int(m[1]), []).append(run_figures(d, "eval1000")["filled"])
    for s in seed_dirs(runs):
        episodes = json.loads((s / "bc_summary.json").read_text())["episodes"]
        points.setdefault(episodes, []).append(run_figures(s, "eval1000")["filled"])
    xs = sorted(points)
    for x in xs:
        ax2.scatter([x] * len(points[x]), points[x], color="C0", s=12)
    ax2.plot(xs, [sum(points[x]) / len(points[x]) for x in xs], color="C0")
    ax2.axhline(0.8, color="grey", ls="--", lw=1, label="target 0.80")
    ax2.set(
        xscale="log",
        xlabel="expert episodes (training designs)",
        ylabel="slots filled",
        title="hexagon + trencadis, seeds 1000-1019",
        ylim=(0, 1.02),
    )
    ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=Path, required=True)
    ap.add_argument("--curve", type=Path, default=None)
    ap.add_argument("--out", type=Path, default=None, help="PNG of the curves")
    args = ap.parse_args(argv)
    summary = summarize(args.runs)
    print(json.dumps(summary, indent=2))
    if args.out is not None:
        plot(args.runs, args.curve or args.runs, args.out)
    return summary


__all__ = ["main", "plot", "run_figures", "seed_dirs", "summarize"]

if __name__ == "__main__":
    run_cli(main)
