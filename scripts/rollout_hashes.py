"""Seeded rollouts of every registered rung, hashed: the proof that a reshaping changed nothing.

Each id is reset with a fixed seed and stepped with actions drawn from its own seeded action
space; every observation, reward, termination flag and the final evaluation go into one SHA-256
per id. Run before and after a change and compare the printed lines (or ``--out`` files)::

    python scripts/rollout_hashes.py --out before.txt
    python scripts/rollout_hashes.py --out after.txt && diff before.txt after.txt
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import envs  # noqa: E402, F401  registers the ladder
from envs.tasks import bundled_tasks, get_task  # noqa: E402


def _feed(h: hashlib._Hash, value: object) -> None:
    if isinstance(value, dict):
        for key in sorted(value):
            h.update(str(key).encode())
            _feed(h, value[key])
    elif isinstance(value, (list, tuple)):
        for item in value:
            _feed(h, item)
    elif isinstance(value, np.ndarray):
        h.update(str(value.dtype).encode())
        h.update(np.ascontiguousarray(value).tobytes())
    else:
        h.update(json.dumps(value, default=str, sort_keys=True).encode())


def _action(env: gym.Env, info: dict) -> np.ndarray:
    """A seeded sample of the action space, within the action mask where the rung has one."""
    space = env.action_space
    mask = info.get("action_mask")
    if mask is None or not isinstance(space, gym.spaces.MultiDiscrete):
        return space.sample()
    parts = np.split(np.asarray(mask, bool), np.cumsum(space.nvec)[:-1])
    return space.sample(mask=tuple(p.astype(np.int8) for p in parts))


VARIANTS: tuple[tuple[str, dict], ...] = (
    ("MosaicHeldOutDesigns-v1", {"split": "eval"}),  # the held-out designs (get_task)
    ("MosaicDecision6-v1", {"obs_mode": "rgb"}),
    ("MosaicDecision6-v1", {"obs_mode": "objects"}),
    ("MosaicDecision6-v1", {"obs_mode": "objects", "objects_source": "perception"}),
    ("MosaicAssembly-v0", {"action_mode": "pick_place", "execution": "kinematic"}),
    ("MosaicDecision6-v1", {"action_mode": "pick_place_discrete", "obs_mode": "rgb+state"}),
    ("MosaicAssembly-v0", {"action_mode": "pick_place", "execution": "dynamic"}),
)
"""Keyword overrides hashed besides each bundled preset (other modes, the held-out split)."""


def rollout_hash(task_id: str, seed: int, steps: int, **kwargs: object) -> str:
    """SHA-256 of a seeded random-action rollout of ``task_id`` made with ``kwargs``."""
    if "split" in kwargs:
        split = str(kwargs.pop("split"))
        kwargs = {**kwargs, **get_task(task_id).design_kwargs(split)}
    env = gym.make(task_id, **kwargs)
    h = hashlib.sha256()
    obs, info = env.reset(seed=seed)
    env.action_space.seed(seed)
    _feed(h, obs)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(_action(env, info))
        _feed(h, obs)
        _feed(h, [float(reward), bool(terminated), bool(truncated)])
        if terminated or truncated:
            break
    _feed(h, info.get("evaluation", {}))
    env.close()
    return h.hexdigest()[:16]


def main(argv: list[str] | None = None) -> int:
    """Print one ``id seed hash`` line per registered rung."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1000, 1001])
    parser.add_argument("--steps", type=int, default=12)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    lines = []
    for task_id in bundled_tasks(True):
        for seed in args.seeds:
            line = f"{task_id} {seed} {rollout_hash(task_id, seed, args.steps)}"
            print(line, flush=True)
            lines.append(line)
    for task_id, kwargs in VARIANTS:
        for seed in args.seeds:
            label = task_id + json.dumps(kwargs, sort_keys=True).replace(" ", "")
            line = f"{label} {seed} {rollout_hash(task_id, seed, args.steps, **kwargs)}"
            print(line, flush=True)
            lines.append(line)
    if args.out:
        args.out.write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
