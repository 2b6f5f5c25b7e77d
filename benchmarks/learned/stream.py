r"""The moving belt's learned row: clone the scheduler's rule into a pair scorer with deadlines.

Run::

    python -m benchmarks.learned.stream --episodes 60 --seed 0 --out runs/stream/seed_0
    python -m apps.evaluate --task MosaicStream-v2 --policies runs/stream/seed_0/bc.pt

The teacher is `agents.experts.deadline.DeadlineExpert`: the scripted cell's scheduler rule
(earliest deadline first) on the env's ground truth. It plays ``episodes`` episodes of
``--task`` (default ``MosaicStream-v2``; dynamic execution) on training seeds
``seed * SEED_STRIDE + episode``, disjoint from the held-out seeds; its picks (not its waits,
whose index does not matter) are cloned into the pair scorer on ``stream`` rows
(`agents.pair.stream_rows`: the ``state`` rows and each tile's time left before the belt's end),
with ``configs/bc_pair.yaml``'s settings. The run
folder gets ``bc.pt``, ``bc_summary.json`` (samples, gradient steps, CPU seconds of recording and
of training, the teacher's own figures on its training episodes), ``demos.npz`` (the recording,
reused by a later run into the same folder) and, unless ``--no-eval``,
``eval1000/`` (``apps.evaluate`` on the task's held-out seeds).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import envs  # noqa: F401 - registers the ladder
from agents.experts.deadline import DeadlineExpert
from agents.learning.decision_bc import load_bc_config
from apps.cli import CommandParser, run_cli
from configs.files import write_json

TASK = "MosaicStream-v2"
"""The rung this clone is for."""
SEED_STRIDE = 100_000
"""Reset seeds of training seed s start at s * SEED_STRIDE (never 1000-1019 or 2000-2019)."""


def record(
    task: str, episodes: int, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any], dict[str, float]]:
    """Play the deadline expert; its picks as (tiles, slots, flat action, nvec), the belt, figures.

    Returns:
        Flat ``tiles`` (N, n*7) and ``slots`` (N, k*6) observations, flat action indices (N,),
        the action sizes, the adapter's belt timing (a dict) and the teacher's figures
        (success, slots filled, waits per episode).
    """
    env = gym.make(task)
    try:
        expert = DeadlineExpert(env)
        nvec = np.asarray(env.action_space.nvec, np.int64)  # type: ignore[attr-defined]
        tiles, slots, acts = [], [], []
        wins, filled, waits = 0, 0.0, 0
        for ep in range(episodes):
            obs, _ = env.reset(seed=seed * SEED_STRIDE + ep)
            expert.reset()
            done = False
            while not done:
                choice = expert.choose()
                action = expert.encode(choice)
                if choice is not None:
                    tiles.append(np.asarray(obs["tiles"], np.float32))
                    slots.append(np.asarray(obs["slots"], np.float32))
                    acts.append(int(np.ravel_multi_index(tuple(action), tuple(nvec))))
                else:
                    waits += 1
                obs, _, term, trunc, _ = env.step(action)
                done = bool(term or trunc)
            ev = env.unwrapped.evaluate()  # type: ignore[attr-defined]
            wins += int(ev.success)
            filled += float(np.mean(ev.slot_filled))
        figures = {
            "success": wins / episodes,
            "filled": filled / episodes,
            "waits_per_episode": waits / episodes,
        }
        return (
            np.stack(tiles),
            np.stack(slots),
            np.asarray(acts, np.int64),
            nvec,
            expert.timing.as_dict(),
            figures,
        )
    finally:
        env.close()


def recorded(
    task: str, episodes: int, seed: int, out: Path
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any], dict[str, float], float]:
    """`record`'s output and its CPU seconds, kept in ``out/demos.npz`` (reused when there)."""
    path = out / "demos.npz"
    if path.is_file():
        z = np.load(path)
        meta = json.loads(str(z["meta"]))
        if (meta["task"], meta["episodes"], meta["seed"]) == (task, episodes, seed):
            return (
                z["tiles"], z["slots"], z["flat"], z["nvec"],
                meta["timing"], meta["teacher"], meta["record_cpu_s"],
            )  # fmt: skip
    cpu0 = time.process_time()
    tiles, slots, flat, nvec, timing, teacher = record(task, episodes, seed)
    cpu = time.process_time() - cpu0
    meta = {"task": task, "episodes": episodes, "seed": seed, "timing": timing,
            "teacher": teacher, "record_cpu_s": cpu}  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        path, tiles=tiles, slots=slots, flat=flat, nvec=nvec, meta=np.array(json.dumps(meta))
    )
    return tiles, slots, flat, nvec, timing, teacher, cpu


def train(task: str, episodes: int, seed: int, out: Path) -> dict[str, Any]:
    """Record (or reuse the run's recording), clone, write ``bc.pt`` and ``bc_summary.json``."""
    import torch  # noqa: PLC0415

    from agents.pair.adapters import row_adapter  # noqa: PLC0415
    from agents.pair.state_bc import ARCH, fit_scorer  # noqa: PLC0415

    torch.set_num_threads(1)
    tiles, slots, flat, nvec, timing, teacher, record_cpu = recorded(task, episodes, seed, out)
    cpu1 = time.process_time()
    rows = row_adapter("stream", timing)(torch.as_tensor(tiles), torch.as_tensor(slots))
    y = torch.as_tensor(flat)
    cfg = load_bc_config("bc_pair")
    net, fit, path = fit_scorer(
        rows, y, nvec, cfg, adapter="stream", seed=seed, out=out, adapter_args=timing
    )
    with torch.no_grad():
        acc = float((net(rows).argmax(1) == y).float().mean())
    summary = {
        "model_path": str(path),
        "arch": ARCH,
        "adapter": "stream",
        "task": task,
        "episodes": episodes,
        "samples": len(y),
        "parameters": sum(p.numel() for p in net.parameters()),
        "gradient_steps": fit.gradient_steps,
        "train_accuracy": acc,
        "record_cpu_s": record_cpu,
        "train_cpu_s": time.process_time() - cpu1,
        "teacher": teacher,
        "timing": timing,
        "seed": seed,
    }
    write_json(out / "bc_summary.json", summary)
    return summary


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default=TASK)
    ap.add_argument("--episodes", type=int, default=60, help="teacher episodes recorded")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--no-eval", dest="evaluate", action="store_false")
    args = ap.parse_args(argv)
    if args.episodes < 1:
        ap.error(f"--episodes {args.episodes}: at least 1")
    summary = train(args.task, args.episodes, args.seed, args.out)
    print({k: v for k, v in summary.items() if k != "timing"})
    if args.evaluate:
        from apps import evaluate  # noqa: PLC0415

        evaluate.main(
            [
                "--task",
                args.task,
                "--policies",
                str(args.out / "bc.pt"),
                "--out",
                str(args.out / "eval1000"),
                "--quiet",
            ]
        )
    return summary


__all__ = ["SEED_STRIDE", "TASK", "main", "record", "recorded", "train"]

if __name__ == "__main__":
    run_cli(main)
