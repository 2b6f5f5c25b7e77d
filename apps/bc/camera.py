r"""Behaviour cloning of the camera policy (two images -> pick_place_discrete) from demonstrations.

Run::

    python -m apps.record_demos --task MosaicDecision6-v0 --expert --lossless --episodes 200 \\
        --dataset-id mosaic/decision6-expert-rgb96-v0 --env obs_mode=rgb 'image_size=[96,128]'
    python -m apps.bc.camera --dataset-id mosaic/decision6-expert-rgb96-v0 --demos 200 \\
        --seed 0 --out runs/camera_bc/d200/seed_0
    python -m apps.evaluate --task MosaicDecision6-v0 \\
        --policies runs/camera_bc/d200/seed_0/camera.pt

Held-out designs (``MosaicHeldOutDesigns-v0``): one dataset per training design, recorded on
the env that design's training entry makes (``--env`` keys of `BenchmarkTask.design_kwargs`),
trained on together; the curve plays the env ``--env`` makes (here the procedural designs)::

    python -m apps.bc.camera --task MosaicHeldOutDesigns-v0 --dataset-id \
        mosaic/heldout-procedural-expert-rgb96-v0 mosaic/heldout-square-grid-expert-rgb96-v0 \
        mosaic/heldout-paper-mixed-expert-rgb96-v0 --env 'image_size=[96,128]' \
        design_source=procedural 'exclude_designs=[hexagon,trencadis]' --out runs/held/seed_0

The policy (`agents.camera.crop_scorer`) reads only the ``input_camera`` and ``output_camera``
images and the env's public task description; the program builds the task's env with
``obs_mode: rgb`` at the dataset's image size, refuses a dataset whose spaces differ from that
env's, rebuilds each demonstrated episode's task description (`agents.camera.crop_bc.episode_specs`:
the recording env reset with the episode's seed), cuts the first ``--demos`` episodes of each
dataset into crops, trains (`CameraBCConfig`,
``configs/camera_bc.yaml``) and writes ``camera.pt``, ``camera_summary.json`` (CPU time,
gradient steps, samples) and ``camera_curve.json`` (loss, training accuracy and, with
``--curve-episodes``, slots filled on validation seeds during training).
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import torch

from agents.camera.crop_bc import (
    check_dataset_spaces,
    demo_arrays,
    episode_specs,
    join_demos,
    train_camera_bc,
)
from agents.camera.crop_scorer import (
    CAMERA_BC_CONFIG,
    CameraBCConfig,
    CameraPolicy,
    load_camera_bc_config,
    save_policy,
)
from agents.errors import AgentError
from agents.policies import parse_pairs
from agents.protocol import EpisodeMetrics
from apps.cli import CommandParser, run_cli
from apps.record_demos import DEFAULT_ROOT, load
from configs.files import write_json
from envs.cell.rendering import use_headless_rendering
from envs.tasks import get_task

CURVE_SEED = 3000
"""First validation seed of the training curve (outside the evaluation seeds 1000-1019)."""


def play(env: gym.Env, policy: CameraPolicy, seed: int, max_steps: int, horizon_s: float) -> float:
    """Slots filled correctly by one episode of ``policy`` from ``reset(seed=seed)``."""
    obs, info = env.reset(seed=seed)
    spec = env.get_wrapper_attr("task_spec")
    for _ in range(max_steps):
        action, _ = policy.predict(obs, spec)
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    return EpisodeMetrics.of(info, horizon_s).filled


def train(
    dataset_id: str | Sequence[str],
    out: Path,
    *,
    root: Path = DEFAULT_ROOT,
    task_id: str = "MosaicDecision6-v0",
    env_kwargs: dict[str, Any] | None = None,
    demos: int | Sequence[int] = 0,
    seed: int = 0,
    cfg: CameraBCConfig | None = None,
    curve_episodes: int = 0,
) -> dict[str, Any]:
    """Train one camera policy; writes ``out/camera.pt`` and its summary and curve.

    ``dataset_id``: one dataset or several (trained on together); ``demos``: the first
    episodes read of each (0: all), one count for all or one per dataset.
    """
    torch.set_num_threads(1)
    cpu0 = time.process_time()
    cfg = cfg or load_camera_bc_config()
    task = get_task(task_id)
    ids = [dataset_id] if isinstance(dataset_id, str) else list(dataset_id)
    counts = [demos] * len(ids) if isinstance(demos, int) else list(demos)
    if len(counts) != len(ids):
        raise AgentError(f"{len(counts)} demonstration counts for {len(ids)} datasets")
    kwargs = {**task.env_kwargs("train"), "obs_mode": "rgb", **(env_kwargs or {})}
    env = gym.make(f"envs:{task.id}", **kwargs)
    try:
        parts = []
        for name, count in zip(ids, counts, strict=True):
            dataset = load(name, root)
            check_dataset_spaces(dataset, env)
            parts.append(demo_arrays(dataset, episode_specs(dataset, count), cfg, count))
        data = join_demos(parts)
        env.reset(seed=CURVE_SEED)
        size = env.get_wrapper_attr("task_spec").image_size

        def on_point(step: int, net: Any) -> dict[str, float]:
            del step
            if not curve_episodes:
                return {}
            pol = CameraPolicy(net, cfg, size)
            seeds = range(CURVE_SEED, CURVE_SEED + curve_episodes)
            filled = [play(env, pol, s, task.max_episode_steps, task.horizon_s) for s in seeds]
            return {"val_filled": sum(filled) / len(filled)}

        net, curve = train_camera_bc(data, cfg, seed, on_point)
    finally:
        env.close()
    path = out / "camera.pt"
    meta = {
        "image_size": list(size),
        "task": task.id,
        "dataset_id": ",".join(ids),
        "demos": data.episodes,
    }
    save_policy(path, net, cfg, meta)
    summary = {
        "model_path": str(path),
        "dataset_id": ",".join(ids),
        "demos": data.episodes,
        "samples": len(data.tiles),
        "skipped_steps": data.skipped,
        "env_steps": 0,
        "gradient_steps": cfg.steps,
        "seed": seed,
        "cpu_minutes": (time.process_time() - cpu0) / 60,
        "final": curve[-1],
        "image_size": list(size),
        "parameters": sum(p.numel() for p in net.parameters()),
    }
    write_json(out / "camera_summary.json", summary)
    write_json(out / "camera_curve.json", {"curve": curve})
    return summary


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset-id", nargs="+", required=True, help="one or more datasets")
    ap.add_argument("--root", type=Path, default=DEFAULT_ROOT)
    ap.add_argument("--task", default="MosaicDecision6-v0")
    ap.add_argument("--env", nargs="*", default=[], metavar="KEY=VALUE", help="env overrides")
    ap.add_argument(
        "--demos", type=int, nargs="+", default=[0], help="first N episodes of each (0: all)"
    )
    ap.add_argument("--out", type=Path, default=Path("runs/camera_bc"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--config", default=CAMERA_BC_CONFIG, help="name in configs/ or a YAML path")
    ap.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE", help="config overrides")
    ap.add_argument("--curve-episodes", type=int, default=0, help="validation episodes per point")
    args = ap.parse_args(argv)
    use_headless_rendering()
    summary = train(
        args.dataset_id,
        args.out,
        root=args.root,
        task_id=args.task,
        env_kwargs=parse_pairs(args.env),
        demos=args.demos[0] if len(args.demos) == 1 else args.demos,
        seed=args.seed,
        cfg=load_camera_bc_config(args.config, **parse_pairs(args.set)),
        curve_episodes=args.curve_episodes,
    )
    print(json.dumps(summary, indent=2))
    return summary


__all__ = ["CURVE_SEED", "main", "play", "train"]

if __name__ == "__main__":
    run_cli(main)
