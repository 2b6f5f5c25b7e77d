r"""The camera policy's rows: train per (demonstrations, seed), evaluate, aggregate, plot.

Run::

    python -m apps.record_demos --task MosaicDecision6-v0 --expert --lossless --episodes 200 \\
        --dataset-id mosaic/decision6-expert-rgb96-v0 --env obs_mode=rgb 'image_size=[96,128]'
    python -m benchmarks.learned.camera_bc --demos 200 --seeds 0 1 2 --out runs/camera_bc
    python -m benchmarks.learned.camera_bc --demos 50 10 --seeds 0 1 2 --out runs/camera_bc \\
        --set steps=500

Held-out designs (``--suite held_out``): every run trains on the three training-design
datasets of ``MosaicHeldOutDesigns-v0`` together (``--demos N``: the first N episodes of each,
0: all; the curve on procedural designs), then plays the rung's evaluation designs (hexagon,
trencadis) on seeds 1000-1019 and 2000-2019::

    python -m benchmarks.learned.camera_bc --suite held_out --demos 0 --seeds 0 1 2 --out runs/held

Each run trains `apps.bc.camera` on the first ``N`` episodes of the dataset (its curve with
``--curve-episodes`` validation episodes per point, seeds from `apps.bc.camera.CURVE_SEED`),
then plays the evaluation protocol of ``MosaicDecision6-v0`` (seeds 1000-1019), of
``MosaicHeldOutDesigns-v0`` (its evaluation designs) and seeds 2000-2019 of
``MosaicDecision6-v0``. A run already trained (its ``camera_summary.json`` exists) is not
trained again, one already evaluated (``camera_eval.json``) not evaluated again. Writes
``results.json`` (per run, and IQM with 95 % intervals over seeds per demonstration count) and
``curves.png``.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from agents.camera.crop_scorer import CAMERA_BC_CONFIG, CameraBCConfig, load_camera_bc_config
from agents.policies import make_policies, parse_pairs
from agents.protocol import iqm_ci
from apps.bc.camera import train
from apps.cli import CommandParser, run_cli
from apps.evaluate import Protocol, evaluate_policy_set, task_protocol
from apps.record_demos import DEFAULT_ROOT
from configs.files import write_json
from envs.cell.rendering import use_headless_rendering

DATASET = "mosaic/decision6-expert-rgb96-v0"
"""Default dataset (200 expert episodes, 96 x 128 images)."""
IMAGE_SIZE = [96, 128]
"""Training image size [px]."""
EXTRA_SEEDS = tuple(range(2000, 2020))
"""Held-out seeds other than the protocol's, on ``MosaicDecision6-v0``."""
EVALUATIONS = {
    "decision6": "MosaicDecision6-v0",
    "held_out_designs": "MosaicHeldOutDesigns-v0",
    "decision6_seeds2000": "MosaicDecision6-v0",
}
"""Evaluation name -> task whose protocol is played."""
HELD_OUT_DATASETS = (
    "mosaic/heldout-procedural-expert-rgb96-v0",
    "mosaic/heldout-square-grid-expert-rgb96-v0",
    "mosaic/heldout-paper-mixed-expert-rgb96-v0",
)
"""The training designs of ``MosaicHeldOutDesigns-v0`` (procedural, square_grid, paper_mixed)."""
HELD_OUT_ENV: dict[str, Any] = {
    "image_size": IMAGE_SIZE,
    "design_source": "procedural",
    "exclude_designs": ["hexagon", "trencadis"],
}
"""Env of the held-out runs' training curve: its procedural training entry."""


@dataclass(frozen=True)
class Suite:
    """What a benchmark's runs train on and are evaluated on.

    Attributes:
        task: Task id the policy trains on.
        datasets: Datasets read together (empty: ``--dataset-id``).
        env_kwargs: Env overrides of training (and of the training curve).
        evaluations: Evaluation name -> task whose protocol is played (names ending in
            ``seeds2000`` play seeds 2000-2019).
    """

    task: str
    datasets: tuple[str, ...] = ()
    env_kwargs: dict[str, Any] = field(default_factory=lambda: {"image_size": IMAGE_SIZE})
    evaluations: dict[str, str] = field(default_factory=lambda: dict(EVALUATIONS))


SUITES = {
    "decision6": Suite("MosaicDecision6-v0"),
    "held_out": Suite(
        "MosaicHeldOutDesigns-v0",
        HELD_OUT_DATASETS,
        HELD_OUT_ENV,
        {
            "held_out_designs": "MosaicHeldOutDesigns-v0",
            "held_out_designs_seeds2000": "MosaicHeldOutDesigns-v0",
        },
    ),
}
"""Benchmark suites by name (``--suite``)."""


def evaluate_run(
    model: Path, evaluations: dict[str, str] | None = None
) -> dict[str, dict[str, float]]:
    """Slots filled and success of one trained policy on every evaluation."""
    out: dict[str, dict[str, float]] = {}
    for name, task in (evaluations or EVALUATIONS).items():
        base, proto = task_protocol(task)
        if name.endswith("seeds2000"):
            proto = Protocol(EXTRA_SEEDS, proto.designs, proto.max_steps, proto.horizon_s)
        rows, _ = evaluate_policy_set(make_policies([str(model)], base), proto)
        out[name] = {"filled": rows[0].filled, "success": rows[0].success_rate}
    return out


def run_all(
    demos: Sequence[int],
    seeds: Sequence[int],
    out: Path,
    *,
    dataset_id: str = DATASET,
    root: Path = DEFAULT_ROOT,
    curve_episodes: int = 5,
    cfg: CameraBCConfig | None = None,
    suite: Suite = SUITES["decision6"],
) -> dict[str, Any]:
    """Train and evaluate every (demonstrations, seed) run, then aggregate over seeds."""
    runs: list[dict[str, Any]] = []
    datasets: str | tuple[str, ...] = suite.datasets or dataset_id
    for n in demos:
        for seed in seeds:
            folder = out / f"d{n}" / f"seed_{seed}"
            summary_path = folder / "camera_summary.json"
            if summary_path.is_file():
                summary = json.loads(summary_path.read_text(encoding="utf-8"))
            else:
                summary = train(
                    datasets,
                    folder,
                    root=root,
                    task_id=suite.task,
                    env_kwargs=suite.env_kwargs,
                    demos=n,
                    seed=seed,
                    cfg=cfg,
                    curve_episodes=curve_episodes,
                )
            eval_path = folder / "camera_eval.json"
            if eval_path.is_file():
                evals = json.loads(eval_path.read_text(encoding="utf-8"))
            else:
                evals = evaluate_run(Path(summary["model_path"]), suite.evaluations)
                write_json(eval_path, evals)
            runs.append({"demos": n, "seed": seed, "summary": summary, "eval": evals})
            write_json(out / "results.json", {"runs": runs})
    table = aggregate(runs, suite.evaluations)
    write_json(out / "results.json", {"runs": runs, "table": table})
    plot_curves(out, demos, seeds, out / "curves.png", suite.task)
    return {"runs": runs, "table": table}


def aggregate(
    runs: Sequence[dict[str, Any]], evaluations: dict[str, str] | None = None
) -> list[dict[str, Any]]:
    """IQM and 95 % interval over seeds of each evaluation, per demonstration count."""
    table = []
    for n in sorted({r["demos"] for r in runs}, reverse=True):
        mine = [r for r in runs if r["demos"] == n]
        row: dict[str, Any] = {"demos": n, "runs": len(mine)}
        for name in evaluations or EVALUATIONS:
            for metric in ("filled", "success"):
                est = iqm_ci([r["eval"][name][metric] for r in mine])
                row[f"{name}_{metric}"] = est.text()
        cpu = [r["summary"]["cpu_minutes"] for r in mine]
        row["cpu_minutes_max"] = max(cpu)
        row["gradient_steps"] = mine[0]["summary"]["gradient_steps"]
        row["samples"] = mine[0]["summary"]["samples"]
        row["episodes"] = mine[0]["summary"]["demos"]
        table.append(row)
    return table


def plot_curves(
    out: Path,
    demos: Sequence[int],
    seeds: Sequence[int],
    path: Path,
    task: str = "MosaicDecision6-v0",
) -> None:
    """Validation slots filled and training loss against gradient steps, one line per run."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, (ax_val, ax_loss) = plt.subplots(1, 2, figsize=(10, 4))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, n in enumerate(demos):
        for seed in seeds:
            f = out / f"d{n}" / f"seed_{seed}" / "camera_curve.json"
            if not f.is_file():
                continue
            curve = json.loads(f.read_text(encoding="utf-8"))["curve"]
            steps = [p["step"] for p in curve]
            count = json.loads((f.parent / "camera_summary.json").read_text(encoding="utf-8"))
            label = f"{count['demos']} demos" if seed == seeds[0] else None
            colour = colours[i % len(colours)]
            if "val_filled" in curve[0]:
                ax_val.plot(steps, [p["val_filled"] for p in curve], color=colour, label=label)
            ax_loss.plot(steps, [p["loss"] for p in curve], color=colour, label=label)
    ax_val.set(xlabel="gradient steps", ylabel="slots filled (validation seeds)", ylim=(0, 1.02))
    ax_loss.set(xlabel="gradient steps", ylabel="training loss", yscale="log")
    ax_val.legend()
    ax_val.set_title(f"{task}, camera policy")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", choices=sorted(SUITES), default="decision6")
    ap.add_argument("--demos", type=int, nargs="+", default=[200, 50, 10])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--out", type=Path, default=Path("runs/camera_bc"))
    ap.add_argument("--dataset-id", default=DATASET)
    ap.add_argument("--root", type=Path, default=DEFAULT_ROOT)
    ap.add_argument("--curve-episodes", type=int, default=5)
    ap.add_argument("--config", default=CAMERA_BC_CONFIG, help="name in configs/ or a YAML path")
    ap.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE", help="config overrides")
    args = ap.parse_args(argv)
    use_headless_rendering()
    result = run_all(
        args.demos,
        args.seeds,
        args.out,
        dataset_id=args.dataset_id,
        root=args.root,
        curve_episodes=args.curve_episodes,
        cfg=load_camera_bc_config(args.config, **parse_pairs(args.set)),
        suite=SUITES[args.suite],
    )
    print(json.dumps(result["table"], indent=2))
    return result


__all__ = [
    "HELD_OUT_DATASETS",
    "SUITES",
    "Suite",
    "aggregate",
    "evaluate_run",
    "main",
    "plot_curves",
    "run_all",
]

if __name__ == "__main__":
    run_cli(main)
