"""Benchmark of the ``objects`` observation against ``state`` on ``MosaicDecision6-v0``.

Run ``python -m benchmarks.learned.objects_obs``. Two figures per obs mode, measured in one process
with the modes alternated block by block, each first in every other block (a shared
machine's load falls on both alike):

- ``step``: steps/s and ms/step of the whole env (kinematic ``pick_place_discrete``), driven by
  the privileged expert (every step a full cycle that fills a slot; the reset after each
  6-step episode is not timed);
- ``observe``: the observation alone [ms] (`Observer.observe` plus the rows' permutation into
  the action indices), repeated on one state: the per-step cost ``objects`` adds.

Prints both and the differences (target: ``objects`` costs <= 0.1 ms per step more than
``state``), CPU time of the process (``time.process_time``); writes
``out/bench_objects_obs.json``.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np

import envs  # noqa: F401 - registers the ids
from apps.cli import CommandParser, run_cli
from benchmarks.learned.expert_step import timed_expert_step
from configs.files import write_text
from envs.mosaic_env import MosaicAssemblyEnv

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out"
TASK = "MosaicDecision6-v0"
MODES = ("state", "objects")
TARGET_MS = 0.1
"""Largest extra cost of ``objects`` per step [ms] (issue 26)."""


def _expert_steps(env: gym.Env, steps: int, seed: int) -> float:
    """CPU seconds of ``steps`` expert steps (resets excluded)."""
    spent, done, episode = 0.0, 0, seed
    while done < steps:
        env.reset(seed=episode)
        episode += 1
        for _ in range(6):
            step = timed_expert_step(env)
            if step is None:
                break
            spent += step[0]
            done += 1
            if step[1] or done >= steps:
                break
    return spent


def _observe_cost(env: gym.Env, repeats: int) -> float:
    """CPU seconds of ``repeats`` observations of one state (rows permuted as the env does)."""
    u = cast(MosaicAssemblyEnv, env.unwrapped)
    env.reset(seed=0)
    evaluation = u.task.evaluate()
    rng = np.random.default_rng(0)
    t0 = time.process_time()
    for _ in range(repeats):
        u.index.update()
        obs = u.observer.observe(rng, evaluation)
        u.index.permute_state(obs["tiles"], obs["slots"])
    return time.process_time() - t0


def measure(blocks: int, steps: int, repeats: int) -> dict[str, Any]:
    """Median over ``blocks`` alternated blocks of each figure, per mode."""
    made = {m: gym.make(TASK, obs_mode=m) for m in MODES}
    step_ms: dict[str, list[float]] = {m: [] for m in MODES}
    obs_ms: dict[str, list[float]] = {m: [] for m in MODES}
    for b in range(blocks):
        for m in MODES if b % 2 == 0 else MODES[::-1]:  # each mode first in every other block
            step_ms[m].append(1e3 * _expert_steps(made[m], steps, seed=100 * b) / steps)
            obs_ms[m].append(1e3 * _observe_cost(made[m], repeats) / repeats)
    for e in made.values():
        e.close()
    out: dict[str, Any] = {"task": TASK, "blocks": blocks, "steps": steps, "repeats": repeats}
    for m in MODES:
        ms = float(np.median(step_ms[m]))
        out[m] = {
            "step_ms": ms,
            "steps_per_s": 1e3 / ms,
            "observe_ms": float(np.median(obs_ms[m])),
        }
    out["extra_step_ms"] = out["objects"]["step_ms"] - out["state"]["step_ms"]
    out["extra_observe_ms"] = out["objects"]["observe_ms"] - out["state"]["observe_ms"]
    out["target_ms"] = TARGET_MS
    return out


def main(argv: list[str] | None = None) -> None:
    """Print the figures and write ``out/bench_objects_obs.json``."""
    p = CommandParser(description=__doc__.splitlines()[0])
    p.add_argument("--blocks", type=int, default=5, help="alternated blocks per mode")
    p.add_argument("--steps", type=int, default=120, help="expert steps timed per block")
    p.add_argument("--repeats", type=int, default=2000, help="observations timed per block")
    args = p.parse_args(argv)
    r = measure(args.blocks, args.steps, args.repeats)
    print(f"{TASK}, CPU time, median of {args.blocks} alternated blocks")
    print("mode      steps/s   ms/step   observe ms")
    for m in MODES:
        print(
            f"{m:8s}  {r[m]['steps_per_s']:7.1f}   {r[m]['step_ms']:7.3f}   "
            f"{r[m]['observe_ms']:.4f}"
        )
    print(
        f"objects - state: {r['extra_step_ms']:+.3f} ms/step (whole step), "
        f"{r['extra_observe_ms']:+.4f} ms (observation alone); target <= {TARGET_MS} ms"
    )
    OUT.mkdir(exist_ok=True)
    write_text(OUT / "bench_objects_obs.json", json.dumps(r, indent=1))
    print(f"wrote {OUT / 'bench_objects_obs.json'}")


if __name__ == "__main__":
    run_cli(main)
