r"""The distractor rung's learned row: a pair scorer on ``objects`` rows leaves the distractors.

Run::

    python -m benchmarks.learned.distractors --out runs/distractors      # the row and its curve
    python -m benchmarks.learned.distractors --out runs/distractors \
        --figure docs/img/distractors_curve.png

On ``MosaicDistractors-v1`` a third of the tiles on the belt are distractors: a tile of the
design's shape in a wrong colour, one scaled by 0.7 or 1.35, or one with a corner broken off.
The ``state`` observation cannot tell them apart: a distractor's class index is the class of the
shape it imitates, so a clone on ``state`` rows places them (0.72 of the slots filled, success 0.10,
in the run this page's docs quote). The ``objects`` rows carry each tile's outline, colour and area,
and the pair scorer on them (`agents.pair.objects_rows`: turned-outline distances, colour and area
differences per pair) is cloned from the privileged expert, who never picks a distractor
(`apps.bc.objects`, ``configs/bc_objects.yaml``).

For each demonstration count of ``--curve`` and each training seed, the run records and clones
(`apps.bc.objects`) and plays the clone on the task's held-out seeds 1000-1019 (and, for the row's
count ``--episodes``, on 2000-2019, never looked at) with ``apps.evaluate``. Printed: per count the
IQM over seeds of slots filled and success with the 95 % interval, distractors placed per
episode, and CPU-minutes per run (recording and training). ``--figure`` draws success against
demonstrations. Runs already in ``--out`` are reused.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from agents.protocol import iqm_ci
from apps.cli import CommandParser, run_cli
from configs.files import write_json

TASK = "MosaicDistractors-v1"
"""The rung."""
EVALS = {"eval1000": "1000-1019", "eval2000": "2000-2019"}
"""Evaluation folders and their held-out seeds."""


def run_folder(out: Path, episodes: int, seed: int) -> Path:
    """Folder of one run: ``out/ep<episodes>_seed_<seed>``."""
    return out / f"ep{episodes}_seed_{seed}"


def play(folder: Path, evaluation: str) -> dict[str, float]:
    """Evaluate the run's clone on one seed range (reused when done); its mean figures."""
    from apps import evaluate  # noqa: PLC0415 - heavy import

    if not (folder / evaluation / "eval.json").is_file():
        evaluate.main(
            [
                "--task",
                TASK,
                "--seeds",
                EVALS[evaluation],
                "--policies",
                str(folder / "bc.pt"),
                "--out",
                str(folder / evaluation),
                "--quiet",
            ]
        )
    episodes = [
        json.loads(line)
        for line in (folder / evaluation / "episodes.jsonl").read_text().splitlines()
        if line.strip()
    ]
    n = len(episodes)
    return {
        "filled": sum(e["correct"] / e["slots"] for e in episodes) / n,
        "success": sum(bool(e["success"]) for e in episodes) / n,
        "misplaced_per_episode": sum(e["misplaced"] for e in episodes) / n,
        # A placed distractor costs a step and fills nothing: steps beyond the slots filled.
        "extra_steps_per_episode": sum(e["steps"] - e["correct"] for e in episodes) / n,
    }


def train(folder: Path, episodes: int, seed: int) -> dict[str, Any]:
    """Record and clone (reused when done); the run's summary."""
    from apps.bc import objects  # noqa: PLC0415 - heavy import

    if not (folder / "bc.pt").is_file():
        objects.main(
            ["--task", TASK, "--episodes", str(episodes), "--seed", str(seed), "--out", str(folder)]
        )
    summary: dict[str, Any] = json.loads((folder / "bc_summary.json").read_text())
    return summary


def aggregate(runs: list[dict[str, Any]], evaluation: str) -> dict[str, Any]:
    """IQM [95 % CI] over the runs of one count."""
    out: dict[str, Any] = {}
    for key in ("filled", "success"):
        out[key] = iqm_ci([r[evaluation][key] for r in runs]).text()
        out[f"{key}_per_seed"] = [round(r[evaluation][key], 3) for r in runs]
    for key in ("misplaced_per_episode", "extra_steps_per_episode"):
        out[key] = round(sum(r[evaluation][key] for r in runs) / len(runs), 3)
    return out


def figure(table: dict[str, Any], path: Path) -> None:
    """Success and slots filled on seeds 1000-1019 against demonstration episodes."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, ax = plt.subplots(figsize=(5.2, 3.4))
    counts = sorted(int(c) for c in table)
    for key, colour in (("success", "C0"), ("filled", "C1")):
        means = []
        for c in counts:
            ys = table[str(c)]["eval1000"][f"{key}_per_seed"]
            ax.scatter([c] * len(ys), ys, color=colour, s=12, alpha=0.6)
            means.append(sum(ys) / len(ys))
        ax.plot(counts, means, color=colour, label=f"{key} (mean over seeds)")
    ax.axhline(0.9, color="grey", ls="--", lw=1, label="target: success 0.90")
    ax.set(
        xscale="log",
        xlabel="expert episodes recorded",
        ylabel="fraction",
        ylim=(0, 1.03),
        title=f"{TASK}, objects rows, seeds 1000-1019",
    )
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--episodes", type=int, default=150, help="the row's demonstration episodes")
    ap.add_argument("--seeds", type=int, default=5, help="training seeds of the row")
    ap.add_argument(
        "--curve", type=int, nargs="*", default=[1, 3, 10, 30], help="other counts (3 seeds each)"
    )
    ap.add_argument("--figure", type=Path, default=None, help="PNG of the curve")
    args = ap.parse_args(argv)
    if args.episodes < 1 or any(c < 1 for c in args.curve) or args.seeds < 1:
        ap.error("episode counts and --seeds must be at least 1")
    import torch  # noqa: PLC0415

    torch.set_num_threads(1)
    plan = [(args.episodes, s) for s in range(args.seeds)]
    plan += [(c, s) for c in args.curve if c != args.episodes for s in range(3)]
    by_count: dict[int, list[dict[str, Any]]] = {}
    for episodes, seed in plan:
        folder = run_folder(args.out, episodes, seed)
        summary = train(folder, episodes, seed)
        run = {
            "cpu_min": (summary["record_cpu_s"] + summary["train_cpu_s"]) / 60,
            "eval1000": play(folder, "eval1000"),
        }
        if episodes == args.episodes:
            run["eval2000"] = play(folder, "eval2000")
        by_count.setdefault(episodes, []).append(run)
    table: dict[str, Any] = {}
    for c in sorted(by_count):
        runs = by_count[c]
        row: dict[str, Any] = {
            "seeds": len(runs),
            "cpu_min_per_run": round(max(r["cpu_min"] for r in runs), 3),
        }
        for ev in EVALS:
            if all(ev in r for r in runs):
                row[ev] = aggregate(runs, ev)
        table[str(c)] = row
    print(json.dumps(table, indent=2))
    write_json(args.out / "distractors.json", table)
    if args.figure is not None:
        figure(table, args.figure)
    return table


__all__ = ["TASK", "aggregate", "main", "play", "run_folder", "train"]

if __name__ == "__main__":
    run_cli(main)
