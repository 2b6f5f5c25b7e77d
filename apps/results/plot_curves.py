r"""Learning curves of `apps.train` runs: fraction of slots filled against env steps and CPU time.

Run::

    python -m apps.results.plot_curves --runs out/rl_pair_d6/seed_* \\
        --label "MaskablePPO pair scorer" \\
        --runs out/rl_mlp_d6/seed_* --label "MaskablePPO flat MLP" --out docs/baselines_rl.png

Each ``--runs`` group (one or more run folders of one method) is read from the folders'
``monitor/*.monitor.csv`` (``filled`` and ``cpu_s`` of every training episode, logged by
`agents.learning.wrappers.EpisodeProgress`); each run's curve is the mean filled fraction of the
training episodes in each bin of env steps (left) and of CPU minutes (right), the group's line
the mean over its runs, each run also drawn thin. A ``--target`` draws a horizontal line.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from apps.cli import CommandParser, run_cli
from apps.results.monitor_log import monitor_episodes
from configs.files import atomic_path

BINS = 25
"""Bins of a curve."""
FILLED_COLUMN = "filled"
"""Monitor column of an episode's filled fraction."""
CPU_COLUMN = "cpu_s"
"""Monitor column of the training process's CPU seconds at an episode's end."""


def episode_table(run: Path, *values: Callable[[dict[str, str]], float]) -> np.ndarray:
    """(env steps at the end, CPU minutes at the end, each of ``values``) per training episode.

    Episodes of all the run's envs, ordered by their end (wall time), read from the run's
    ``monitor/`` logs; each of ``values`` maps an episode's monitor row to a number. Env steps
    are summed over the episodes. Shape (m, 2 + len(values)).
    """
    rows = [
        (
            float(ep["t"]),
            float(ep["l"]),
            float(ep[CPU_COLUMN]) / 60,
            *(float(v(ep)) for v in values),
        )
        for ep in monitor_episodes(run / "monitor")
    ]
    if not rows:
        return np.zeros((0, 2 + len(values)))
    arr = np.array(sorted(rows))
    return np.column_stack([np.cumsum(arr[:, 1]), arr[:, 2:]])


def episodes(run: Path) -> np.ndarray:
    """(env steps at the end, CPU minutes at the end, filled fraction) per training episode.

    Episodes of all the run's envs, ordered by their end (wall time); shape (m, 3).
    """
    return episode_table(run, lambda ep: float(ep[FILLED_COLUMN]))


def binned(x: np.ndarray, y: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Mean of ``y`` per bin of ``x`` (NaN where a bin is empty), shape (len(edges) - 1,)."""
    out = np.full(len(edges) - 1, np.nan)
    idx = np.digitize(x, edges) - 1
    for b in range(len(out)):
        sel = idx == b
        if sel.any():
            out[b] = y[sel].mean()
    return out


def plot(groups: Sequence[tuple[str, Sequence[Path]]], out: Path, target: float = 0.0) -> None:
    """Draw the curves of each (label, run folders) group into ``out`` (PNG)."""
    import matplotlib as mpl  # noqa: PLC0415

    mpl.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for i, (label, runs) in enumerate(groups):
        data = [e for e in (episodes(r) for r in runs) if len(e)]
        if not data:
            continue
        for col, ax in enumerate(axes):
            top = max(float(e[:, col].max()) for e in data)
            edges = np.linspace(0, top, BINS + 1)
            mids = (edges[1:] + edges[:-1]) / 2
            curves = np.array([binned(e[:, col], e[:, 2], edges) for e in data])
            for c in curves:
                ax.plot(mids, c, color=f"C{i}", alpha=0.3, lw=0.8)
            ax.plot(
                mids, np.nanmean(curves, 0), color=f"C{i}", lw=2, label=f"{label} (n={len(data)})"
            )
    for ax, name in zip(axes, ("env steps", "CPU minutes (training process)"), strict=True):
        ax.set_xlabel(name)
        ax.set_ylabel("slots filled (training episodes)")
        ax.set_ylim(0, 1.02)
        ax.grid(alpha=0.3)
        if target:
            ax.axhline(target, color="k", ls="--", lw=0.8)
    axes[0].legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    with atomic_path(out) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", nargs="+", type=Path, action="append", required=True)
    ap.add_argument("--label", action="append", default=[])
    ap.add_argument("--target", type=float, default=0.0, help="horizontal line (0: none)")
    ap.add_argument("--out", type=Path, default=Path("out/curves.png"))
    args = ap.parse_args(argv)
    labels = args.label + [str(r[0].parent) for r in args.runs[len(args.label) :]]
    groups = list(zip(labels, args.runs, strict=False))
    plot(groups, args.out, args.target)
    print(f"wrote {args.out}")
    return {"out": str(args.out), "groups": labels}


__all__ = ["episodes", "main", "plot"]

if __name__ == "__main__":
    run_cli(main)
