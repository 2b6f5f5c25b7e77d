"""What a sweep reports when its runs are done: the summary table and the training curves.

`summarize` groups the runs of `apps.sweep` by (task as ran, entry) and writes
``summary.json``, ``summary.md`` (the IQM over runs with its 95 % stratified-bootstrap interval of
every protocol metric, the env return, and the compute used) and ``curves.png`` (training
success and return against env steps, mean over seeds with a 95 % bootstrap band, read from each
run's SB3 monitor files).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from agents.protocol import aggregate_runs, iqm_ci
from apps.results.monitor_log import monitor_episodes, succeeded
from configs.files import atomic_path, complete_lines, write_json, write_text

CURVE_BINS = 20
"""Points of a training curve."""
CURVE_BOOTSTRAP = 1000
"""Bootstrap resamples of a curve's band."""


def run_return(result: Mapping[str, Any]) -> float | None:
    """Mean env return of a run's held-out episodes (its ``episodes.jsonl``), or None.

    The return is the env's own reward (a shaped training reward is never in it); on a task
    with a staged reward it shows how far through the stages a policy gets when no tile is
    placed.
    """
    path = Path(result.get("folder", "")) / "episodes.jsonl"
    if not path.is_file():
        return None
    values = [json.loads(line)["episode_return"] for line in complete_lines(path)]
    return float(np.mean(values)) if values else None


def summarize(results: Sequence[dict[str, Any]], out: Path) -> dict[str, Any]:
    """Write ``summary.json``, ``summary.md`` and ``curves.png`` from run results."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in results:
        groups.setdefault((r.get("ran", r["task"]), r["entry"]), []).append(r)
    summary = []
    lines = [
        "| task | policy | runs | success | slots filled | misplaced/ep | dropped/ep | lost/ep | "
        "stranded/ep | left/ep | tiles/min (sim) | return/ep | training steps | "
        "train wall s (per run) | train CPU min (per run) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (task, entry), rs in groups.items():
        est = aggregate_runs([r["metrics"] for r in rs])
        returns = [run_return(r) for r in rs]
        ret = iqm_ci([x for x in returns if x is not None]) if None not in returns else None
        steps = [r.get("timesteps", 0) for r in rs]
        walls = [r.get("train_wall_s", 0.0) for r in rs]
        cpus = [r.get("train_cpu_s", 0.0) / 60 for r in rs]
        summary.append(
            {
                "task": rs[0]["task"],
                "ran": task,
                "entry": entry,
                "runs": len(rs),
                "estimates": {k: asdict(v) for k, v in est.items()},
                "episode_return": asdict(ret) if ret is not None else None,
                "timesteps": steps,
                "train_wall_s": walls,
                "train_cpu_min": cpus,
            }
        )
        lines.append(
            f"| {task} | {entry} | {len(rs)} | {est['success'].text('{:.2f}')} | "
            f"{est['filled'].text('{:.2f}')} | {est['misplaced'].text('{:.2f}')} | "
            f"{est['dropped'].text('{:.2f}')} | {est['lost'].text('{:.2f}')} | "
            f"{est['stranded'].text('{:.2f}')} | "
            f"{est['left'].text('{:.2f}')} | {est['tiles_per_min'].text('{:.1f}')} | "
            f"{ret.text('{:.2f}') if ret is not None else '-'} | "
            f"{int(np.mean(steps)) if any(steps) else '-'} | "
            f"{f'{np.mean(walls):.0f}' if any(walls) else '-'} | "
            f"{f'{np.mean(cpus):.2f}' if any(cpus) else '-'} |"
        )
    write_json(out / "summary.json", summary)
    write_text(out / "summary.md", "\n".join(lines) + "\n")
    plot_curves(results, out / "curves.png")
    return {"rows": summary}


def training_curve(monitor_dir: Path, edges: np.ndarray) -> np.ndarray | None:
    """Success rate and mean return of a run's training episodes per step bin, shape (2, bins).

    Bins without a finished episode repeat the previous value; None without episodes.
    """
    rows = [
        (float(ep["t"]), float(ep["l"]), float(ep["r"]), succeeded(ep))
        for ep in monitor_episodes(monitor_dir)
    ]
    if not rows:
        return None
    arr = np.array(sorted(rows))
    steps = np.cumsum(arr[:, 1])
    out = np.full((2, len(edges) - 1), np.nan)
    for b in range(len(edges) - 1):
        sel = (steps > edges[b]) & (steps <= edges[b + 1])
        if sel.any():
            out[0, b] = arr[sel, 3].mean()
            out[1, b] = arr[sel, 2].mean()
        elif b:
            out[:, b] = out[:, b - 1]
    return out


def plot_curves(results: Sequence[dict[str, Any]], path: Path) -> None:
    """Training success and return vs steps per learned entry, mean over seeds, 95 % band."""
    import matplotlib as mpl  # noqa: PLC0415

    mpl.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    learned: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in results:
        if r.get("timesteps") and (Path(r["folder"]) / "monitor").is_dir():
            learned.setdefault((r.get("ran", r["task"]), r["entry"]), []).append(r)
    if not learned:
        return
    series = []
    for (task, entry), rs in sorted(learned.items()):
        top = max(r["timesteps"] for r in rs)
        edges = np.linspace(0, top, CURVE_BINS + 1)
        curves = [training_curve(Path(r["folder"]) / "monitor", edges) for r in rs]
        stack = np.array([c for c in curves if c is not None])
        if len(stack):
            series.append((task, entry, (edges[1:] + edges[:-1]) / 2, stack))
    # An all-zero success panel shows nothing: then only the returns, and the title says so.
    no_success = all(np.nan_to_num(s[3][:, 0, :]).max() == 0 for s in series)
    panels = (1,) if no_success else (0, 1)
    fig, ax_list = plt.subplots(1, len(panels), figsize=(6 * len(panels), 4.2), squeeze=False)
    axes = dict(zip(panels, ax_list[0], strict=True))
    rng = np.random.default_rng(0)
    for i, (task, entry, x, stack) in enumerate(series):
        for k, ax in axes.items():
            y = stack[:, k, :]
            mean = np.nanmean(y, axis=0)
            boot = y[rng.integers(len(y), size=(CURVE_BOOTSTRAP, len(y)))]
            lo, hi = np.nanpercentile(np.nanmean(boot, axis=1), [2.5, 97.5], axis=0)
            color = f"C{i % 10}"
            ax.plot(x, mean, color=color, label=f"{task.removesuffix('-v0')}: {entry} (n={len(y)})")
            ax.fill_between(x, lo, hi, color=color, alpha=0.2)
    if no_success:
        axes[1].set_title("training episode return (mean over seeds, 95% CI); success 0 in all")
    else:
        axes[0].set_title("training success rate (mean over seeds, 95% CI)")
        axes[1].set_title("training episode return (mean over seeds, 95% CI)")
    for ax in axes.values():
        ax.set_xlabel("env steps")
        ax.grid(alpha=0.3)
    axes[panels[0]].legend(fontsize=7)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100)
    plt.close(fig)


__all__ = [
    "CURVE_BINS",
    "CURVE_BOOTSTRAP",
    "plot_curves",
    "run_return",
    "summarize",
    "training_curve",
]
