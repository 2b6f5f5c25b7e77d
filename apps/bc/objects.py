r"""Learned matching on the ``objects`` observation: record expert demos, clone a pair scorer.

Run::

    python -m apps.bc.objects --task MosaicHeldOutDesigns-v0 --episodes 150 --seed 0 \\
        --out runs/objects_bc/seed_0
    python -m apps.evaluate --task MosaicHeldOutDesigns-v0 \\
        --policies runs/objects_bc/seed_0/bc.pt@obs_mode=objects

Episodes are played by the privileged expert (`MosaicAssemblyEnv.expert_action`, every tile to
its slot, encoded in the discrete action's current index maps) on the task's training designs in
turn (``train_designs``; ``procedural`` draws a new design at every reset, never one of the eval
designs' classes), with ``obs_mode="objects"``; reset seeds are ``seed * SEED_STRIDE + episode``,
disjoint from the evaluation seeds. The steps are cloned into the pair scorer on outlines and
colours (`agents.pair.objects_bc`, ``configs/bc_objects.yaml``); ``--arch mlp --config bc``
clones them into the flat MLP of `agents.learning.decision_bc` instead (the ablation: one network
over the concatenated rows). ``--env KEY=VALUE`` adds env
overrides to the recorded episodes (``objects_noise_mm=0.5``). The summary gives env steps,
gradient steps and CPU seconds of recording and of training (process time).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from agents.learning.decision_bc import load_bc_config
from agents.pair.objects_bc import ObjectDemos, train_objects_bc, train_objects_mlp
from agents.policies import parse_pairs
from apps.cli import CommandParser, run_cli
from configs.files import write_json
from envs import ENV_ID

"""Gymnasium id of the environment."""
TASK = "MosaicHeldOutDesigns-v0"
"""Default task (its training designs are recorded)."""
CONFIG = "bc_objects"
"""Default cloning configuration (``configs/bc_objects.yaml``)."""
SEED_STRIDE = 100_000
"""Reset seeds of training seed s start at s * SEED_STRIDE (never 1000-1019 or 2000-2019)."""


def record_expert(
    task_id: str, episodes: int, seed: int, overrides: dict[str, Any]
) -> tuple[ObjectDemos, int]:
    """Expert steps on the task's training designs in turn; returns them and the env steps."""
    from envs.tasks import get_task  # noqa: PLC0415

    task = get_task(task_id)
    designs = len(task.designs("train"))
    envs = [
        gym.make(ENV_ID, **{**task.env_kwargs("train", i), "obs_mode": "objects", **overrides})
        for i in range(designs)
    ]
    robot, tiles, slots, acts, steps = [], [], [], [], 0
    for ep in range(episodes):
        env = envs[ep % designs]
        obs, _ = env.reset(seed=seed * SEED_STRIDE + ep)
        u: Any = env.unwrapped
        for i in range(len(u.task_spec.slots)):
            action = u.expert_action(i, i)
            robot.append(obs["robot"].copy())
            tiles.append(obs["tiles"].copy())
            slots.append(obs["slots"].copy())
            acts.append(action)
            obs, _, term, trunc, _ = env.step(action)
            steps += 1
            if term or trunc:
                break
    nvec = np.asarray(envs[0].action_space.nvec, np.int64)  # type: ignore[attr-defined]
    for env in envs:
        env.close()
    flat = np.asarray(np.ravel_multi_index(np.asarray(acts, np.int64).T, nvec), np.int64)
    demos = ObjectDemos(np.stack(tiles), np.stack(slots), flat, nvec, episodes, np.stack(robot))
    return demos, steps


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default=TASK, help="a ladder id; its training designs are recorded")
    ap.add_argument("--episodes", type=int, default=150, help="expert episodes to record")
    ap.add_argument("--seed", type=int, default=0, help="training seed (weights, reset seeds)")
    ap.add_argument("--out", type=Path, default=Path("runs/objects_bc"))
    ap.add_argument("--config", default=CONFIG, help="name in configs/ or a YAML path")
    ap.add_argument("--arch", choices=("pair", "mlp"), default=None, help="override the config's")
    ap.add_argument("--env", nargs="*", default=[], metavar="KEY=VALUE", help="env overrides")
    args = ap.parse_args(argv)
    import torch  # noqa: PLC0415 - heavy import

    torch.set_num_threads(1)
    cpu0 = time.process_time()
    demos, env_steps = record_expert(args.task, args.episodes, args.seed, parse_pairs(args.env))
    record_cpu = time.process_time() - cpu0
    cfg = load_bc_config(args.config, **({"arch": args.arch} if args.arch else {}))
    train = train_objects_bc if cfg.arch == "pair" else train_objects_mlp
    summary = train(demos, args.out, args.seed, cfg)
    summary.update({"task": args.task, "env_steps": env_steps, "record_cpu_s": record_cpu})
    write_json(args.out / "bc_summary.json", summary)
    print(json.dumps({k: v for k, v in summary.items() if k != "curve"}, indent=2))
    return summary


__all__ = ["SEED_STRIDE", "main", "record_expert"]

if __name__ == "__main__":
    run_cli(main)
