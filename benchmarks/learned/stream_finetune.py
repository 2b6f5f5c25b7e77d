r"""RL fine-tuning of the stream clone with masks: MaskablePPO started from the clone, evaluated.

Run::

    python -m benchmarks.learned.stream_finetune --seed 0 --out runs/stream_ft \
        --figure docs/img/stream_finetune_curve.png
    python -m apps.evaluate --task MosaicStream-v2 --policies runs/stream_ft/seed_0/model.zip

Trains ``configs/train/maskable_ppo_stream_finetune.yaml`` (``apps.train``: the pair-scorer
MaskablePPO policy started from the clone named by its ``init_clone``, the critic warmed up with
the actor frozen, then small, KL-limited PPO updates; its ``task`` is the rung, ``--task``
overrides it) into ``<out>/seed_<s>`` (a finished run there is reused), draws the training
curve (success and return of the training episodes, sampled actions, against env steps and
CPU minutes; ``<out>/seed_<s>/curve.png`` and ``--figure``), then plays the clone and the
fine-tuned policy, greedy with the env's masks, on the rung's held-out seeds (1000-1019) and on
seeds 2000-2019 with `apps.evaluate`'s protocol, and prints their figures side by side. All
figures go to ``<out>/seed_<s>/finetune_summary.json``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from apps.cli import CommandParser, run_cli
from apps.results.monitor_log import succeeded
from apps.results.plot_curves import episode_table
from apps.train import (
    TrainConfig,
    clone_path,
    finished_run,
    load_train_config,
    train,
)
from configs.files import atomic_path, write_json

CONFIG = "maskable_ppo_stream_finetune"
"""The preset in ``configs/train/``."""
SECOND_SEEDS = "2000-2019"
"""Seeds never looked at while tuning, evaluated after the rung's own held-out seeds."""
WINDOW = 20
"""Training episodes in the curve's running mean."""


def training_curve(run: Path) -> np.ndarray:
    """(env steps, CPU minutes, success, return) at the end of each training episode.

    Episodes of all the run's envs in the order they ended; env steps are summed over them.
    Shape (m, 4).
    """
    return episode_table(run, succeeded, lambda ep: float(ep["r"]))


def running_mean(y: np.ndarray, window: int = WINDOW) -> np.ndarray:
    """Mean of the last ``window`` values at each index (fewer at the start)."""
    c = np.cumsum(np.concatenate([[0.0], y]))
    idx = np.arange(1, len(y) + 1)
    lo = np.maximum(idx - window, 0)
    return (c[idx] - c[lo]) / (idx - lo)


def plot_curve(
    curve: np.ndarray, warmup_steps: int, clone_success: float | None, paths: list[Path]
) -> None:
    """Success and return (running means) against env steps and CPU minutes, to ``paths``."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
    cpu_at_warmup = np.interp(warmup_steps, curve[:, 0], curve[:, 1]) if len(curve) else 0.0
    for ax, col, label, edge in (
        (axes[0], 0, "env steps", warmup_steps),
        (axes[1], 1, "CPU minutes of training", cpu_at_warmup),
    ):
        x = curve[:, col]
        ax.plot(x, running_mean(curve[:, 2]), color="C0", label="success (training, sampled)")
        ax.axvspan(0, edge, color="0.9", label="critic warm-up (actor frozen)")
        if clone_success is not None:
            ax.axhline(clone_success, color="C2", ls="--", label="clone, greedy, seeds 1000-1019")
        ax.set_xlabel(label)
        ax.set_ylim(-0.02, 1.02)
        twin = ax.twinx()
        twin.plot(x, running_mean(curve[:, 3]), color="C1", lw=0.8, label="return")
        twin.set_ylabel("episode return", color="C1")
    axes[0].set_ylabel(f"success (mean of last {WINDOW} episodes)")
    axes[0].legend(loc="lower left", fontsize=7)
    fig.suptitle("MaskablePPO fine-tuning of the stream clone", fontsize=10)
    fig.tight_layout()
    for path in paths:
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


def evaluate(task: str, policies: list[str], out: Path, seeds: str | None) -> dict[str, Any]:
    """`apps.evaluate` of ``policies`` on the task's protocol (``seeds`` instead of its own)."""
    from apps import evaluate as ev  # noqa: PLC0415

    argv = ["--task", task, "--policies", *policies, "--out", str(out), "--quiet"]
    if seeds:
        argv += ["--seeds", seeds]
    return ev.main(argv)


def rows_by_file(report: dict[str, Any], files: dict[str, str]) -> dict[str, dict[str, Any]]:
    """The evaluation rows keyed ``clone``/``finetuned`` (matched by the label of each file)."""
    from agents.policies import checkpoint_label  # noqa: PLC0415

    by_label = {row["policy"]: row for row in report["rows"]}
    return {name: by_label[checkpoint_label(Path(path))] for name, path in files.items()}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=CONFIG, help="preset name in configs/train/ or YAML")
    ap.add_argument("--task", default=None, help="override the preset's task (a ladder id)")
    ap.add_argument("--seed", type=int, default=0, help="training seed")
    ap.add_argument("--out", type=Path, required=True, help="folder; the run is <out>/seed_<s>")
    ap.add_argument("--timesteps", type=int, default=None, help="override total_timesteps")
    ap.add_argument("--max-cpu-s", type=float, default=None, help="override max_cpu_s [s]")
    ap.add_argument("--figure", type=Path, default=None, help="also save the curve here")
    ap.add_argument("--no-eval", dest="evaluate", action="store_false")
    args = ap.parse_args(argv)
    from envs.cell.rendering import use_headless_rendering  # noqa: PLC0415

    use_headless_rendering()
    cfg: TrainConfig = load_train_config(
        args.config,
        seed=args.seed,
        task=args.task,
        total_timesteps=args.timesteps,
        max_cpu_s=args.max_cpu_s,
        progress_bar=False,
    )
    run = args.out / f"seed_{args.seed}"
    result = finished_run(run) or train(cfg, run)
    summary: dict[str, Any] = {
        "task": cfg.task,
        "config": dataclasses.asdict(cfg),
        "training": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(result).items()},
        "cpu_min": result.cpu_s / 60,
    }
    files = {"clone": str(clone_path(cfg.init_clone)), "finetuned": str(result.model_path)}
    clone_1000: float | None = None
    if args.evaluate:
        for name, seeds in (("eval1000", None), ("eval2000", SECOND_SEEDS)):
            report = evaluate(cfg.task, list(files.values()), run / name, seeds)
            summary[name] = rows_by_file(report, files)
        clone_1000 = float(summary["eval1000"]["clone"]["success_rate"])
    curve = training_curve(run)
    paths = [run / "curve.png", *([args.figure] if args.figure else [])]
    if len(curve):
        plot_curve(curve, cfg.critic_warmup_steps, clone_1000, paths)
        warm = curve[:, 0] <= cfg.critic_warmup_steps
        summary["curve"] = {
            "episodes": len(curve),
            "warmup_success": float(curve[warm, 2].mean()) if warm.any() else None,
            "last_success": float(curve[-WINDOW:, 2].mean()),
            "last_return": float(curve[-WINDOW:, 3].mean()),
        }
    write_json(run / "finetune_summary.json", summary)
    print(
        f"{cfg.task}: {result.timesteps} env steps, {summary['cpu_min']:.1f} CPU-min, "
        f"{result.episodes} training episodes; curve {summary.get('curve')}"
    )
    for name in ("eval1000", "eval2000"):
        for who, row in summary.get(name, {}).items():
            print(
                f"  {name} {who:9s}: success {row['success_rate']:.2f}, filled "
                f"{row['filled']:.3f}, lost/ep {row['lost']:.2f}, misplaced/ep "
                f"{row['misplaced']:.2f}, tiles/min {row['tiles_per_min']:.1f}"
            )
    return summary


__all__ = ["CONFIG", "main", "plot_curve", "running_mean", "training_curve"]

if __name__ == "__main__":
    run_cli(main)
