"""Benchmark of `MosaicAssembly-v0`: steps per second, memory per env, async vector scaling.

Run ``python -m benchmarks.env`` (``--quick`` for shorter runs); prints the figures and writes
``out/bench_env.json``. Every figure is measured in a fresh subprocess pinned to one CPU core
(``os.sched_setaffinity``) with one BLAS/OpenMP thread, on the bundled ``paper_mixed`` design
(16 tiles):

- ``steps_per_s`` (wall clock) and ``steps_per_cpu_s`` (per second of the process's CPU time,
  what a dedicated core would give on a shared machine) for each action mode, without images
  (``obs_mode="state"``) and with images (``obs_mode="rgb"``, two 96 x 96 cameras);
  pick_place modes in ``dynamic`` and ``kinematic`` execution, driven by a scripted policy
  with privileged correct poses (every step a full cycle); joint and cartesian modes by
  uniform random actions. Resets are timed separately.
- ``peak_rss_mb``: peak resident memory of the process holding one env (Python, MuJoCo,
  renderers included) after building it, resetting and stepping; ``env_rss_mb``: its increase
  over the same process before the env was made.
- ``async``: env steps per second of ``gym.make_vec(..., "async")`` with 1 and 2 workers
  (joint mode, images), and the speed-up.
- ``decision``: the decision level (``pick_place_discrete``, kinematic) with its two 72 x 96
  camera images, the scripted correct decision every step (episodes of 16 steps); again
  without multisampling (``cell.render.samples: 0``, stair-stepped edges).
- ``reset``: `reset` time [ms] of the 16-tile design and of its first 6 slots (mean, median
  and worst over seeds 0..``RESET_SEEDS`` - 1, CPU and wall), decision level with images (the
  reset renders its observation); ``task_resets``: the same CPU figures for every registered
  rung of the task ladder (`envs.tasks`) as bundled. CPU time is the figure to read on a
  shared machine (wall time includes waiting for the core).
- ``sections``: where a step's CPU time goes [ms per step], kinematic ``pick_place`` (state)
  and the decision level with images: physics (`Cell.step`), IK, the planners' lower bound,
  vacuum (seal check), evaluation, observation (the renders with images) and the rest
  (action decoding, rewards, info, Gymnasium wrappers). Measured by timing those calls of
  one env (the timers add a little to "rest").

Targets (issues 5, 13, 14): kinematic pick_place >= 1,000 steps/s (was 500); joint with images
>= 60 steps/s on one core; <= 600 MB per env; decision level with two 72 x 96 images >= 150
steps/s; reset of the 16-tile design <= 20 ms.
"""

from __future__ import annotations

import json
import math
import multiprocessing as mp
import os
import platform
import resource
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from apps.cli import CommandParser, run_cli
from configs.files import write_text

OUT = Path(__file__).resolve().parents[1] / "out" / "bench_env.json"
OUT_RESETS = OUT.with_name("bench_env_resets.json")
TARGET_KINEMATIC = 1000.0
TARGET_JOINT_RGB = 60.0
TARGET_RSS_MB = 600.0
TARGET_DECISION_RGB = 150.0
TARGET_RESET_MS = 20.0
RESET_SEEDS = 20
DECISION_IMAGE = (72, 96)
DEFAULT_SAMPLES = 4
"""``cell.render.samples`` of ``configs/cell.yaml`` (the decision row is also run with 0)."""
DESIGN = "paper_mixed"
CASES = (
    ("joint", "dynamic"),
    ("cartesian", "dynamic"),
    ("pick_place", "dynamic"),
    ("pick_place", "kinematic"),
    ("pick_place_discrete", "dynamic"),
    ("pick_place_discrete", "kinematic"),
)


def _scripted(env: Any, step: int) -> Any:
    """Privileged correct action for tile/slot ``step`` (pick_place modes)."""
    i = step % len(env.unwrapped.cell.slots)
    return env.unwrapped.expert_action(i, i)


@dataclass
class _Run:
    """What `_play` measured: step counts and times [s]; episode ends and reset times."""

    steps: int = 0
    wall: float = 0.0  # inside env.step
    cpu: float = 0.0  # inside env.step, this process
    placed: int = 0  # tiles placed over the finished episodes
    sim: float = 0.0  # simulated time of the finished episodes
    reset_s: list[float] = field(default_factory=list)  # wall time of each reset after one


def _play(
    env: Any,
    seconds: float,
    scripted: bool = True,
    budget: Literal["wall", "cpu"] = "wall",
    reset: Callable[[], Any] | None = None,
) -> _Run:
    """Step ``env`` (already reset) until ``seconds`` of step time (wall or CPU) are spent.

    Actions: the privileged correct one (`_scripted`) or random samples. At an episode's end
    ``reset`` (default ``env.reset``) runs outside the step timers.
    """
    run, k = _Run(), 0
    while (run.wall if budget == "wall" else run.cpu) < seconds:
        action = _scripted(env, k) if scripted else env.action_space.sample()
        t, c = time.perf_counter(), time.process_time()
        _, _, term, trunc, info = env.step(action)
        run.wall += time.perf_counter() - t
        run.cpu += time.process_time() - c
        run.steps += 1
        k += 1
        if term or trunc:
            run.placed += info["tiles_placed"]
            run.sim += info["sim_time"]
            t = time.perf_counter()
            (reset or env.reset)()
            run.reset_s.append(time.perf_counter() - t)
            k = 0
    return run


def _measure(mode: str, execution: str, obs_mode: str, seconds: float, queue: mp.Queue) -> None:
    """Child process: build one env, step it for ``seconds``, report speed and memory."""
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: PLC0415

    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    env = gym.make(
        envs.ENV_ID,
        design=DESIGN,
        action_mode=mode,
        execution=execution,
        obs_mode=obs_mode,
        image_size=96,
    )
    picks = mode.startswith("pick_place")
    env.action_space.seed(0)
    t_reset = time.perf_counter()
    env.reset(seed=0)
    first_reset_s = time.perf_counter() - t_reset
    run = _play(env, seconds, picks)
    steps, busy, cpu = run.steps, run.wall, run.cpu
    reset_s = [first_reset_s, *run.reset_s]
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    env.close()
    queue.put(
        {
            "action_mode": mode,
            "execution": execution if picks else "-",
            "obs_mode": obs_mode,
            "steps": steps,
            "steps_per_s": steps / busy,
            "steps_per_cpu_s": steps / cpu if cpu > 0 else math.nan,
            "ms_per_step": 1e3 * busy / steps,
            "reset_ms": 1e3 * sum(reset_s) / len(reset_s),
            "tiles_per_min_sim": 60.0 * run.placed / run.sim if run.sim > 0 else math.nan,
            "peak_rss_mb": rss1,
            "env_rss_mb": rss1 - rss0,
        }
    )


def _decision(seconds: float, samples: int, queue: mp.Queue) -> None:
    """Child process: decision level with two 72 x 96 images, scripted correct decisions.

    ``samples``: multisamples per pixel of the renders (``cell.render.samples``; 4 default).
    """
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: PLC0415

    env = gym.make(
        envs.ENV_ID,
        design=DESIGN,
        action_mode="pick_place_discrete",
        execution="kinematic",
        obs_mode="rgb",
        image_size=DECISION_IMAGE,
        cell={"render": {"samples": samples}},
    )
    env.reset(seed=0)
    run = _play(env, seconds)
    env.close()
    queue.put(
        {
            "steps_per_s": run.steps / run.wall,
            "steps_per_cpu_s": run.steps / run.cpu,
            "steps": run.steps,
        }
    )


def _resets(max_slots: int, queue: mp.Queue) -> None:
    """Child process: reset times [ms] over seeds, decision level with images."""
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: PLC0415

    env = gym.make(
        envs.ENV_ID,
        design=DESIGN,
        max_slots=max_slots,
        action_mode="pick_place_discrete",
        execution="kinematic",
        obs_mode="rgb",
        image_size=DECISION_IMAGE,
    )
    queue.put(_time_resets(env))


def _task_resets(queue: mp.Queue) -> None:
    """Child process: reset times [ms] of every registered rung of the task ladder."""
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    import gymnasium as gym  # noqa: PLC0415

    from envs.tasks import register_tasks  # noqa: PLC0415

    rows = []
    for task_id in register_tasks():
        row = _time_resets(gym.make(task_id))
        rows.append({"task": task_id, **row})
    queue.put(rows)


def _time_resets(env: Any) -> dict[str, Any]:
    """Reset ``env`` over seeds 0..``RESET_SEEDS`` - 1 (after a first reset); closes it."""
    env.reset(seed=RESET_SEEDS)  # first renders, probes
    wall, cpu = [], []
    for seed in range(RESET_SEEDS):
        t, c = time.perf_counter(), time.process_time()
        env.reset(seed=seed)
        wall.append(1e3 * (time.perf_counter() - t))
        cpu.append(1e3 * (time.process_time() - c))
    tiles = len(env.get_wrapper_attr("cell").tiles)
    env.close()
    return {
        "tiles": tiles,
        "reset_ms": sum(wall) / len(wall),
        "reset_cpu_ms": sum(cpu) / len(cpu),
        "reset_cpu_ms_median": sorted(cpu)[len(cpu) // 2],
        "reset_cpu_ms_max": max(cpu),
    }


SECTIONS = (
    ("physics", "cell", "step"),
    ("ik", "ik", "solve"),
    ("lower_bound", "planner", "lower_bound"),
    ("vacuum", "cell", "vacuum"),
    ("evaluate", "task", "evaluate"),
    ("observe", "observer", "observe"),
)
"""Timed calls of a step: (label, owner attribute of the env, method)."""


def _sections(decision: bool, seconds: float, queue: mp.Queue) -> None:
    """Child process: CPU time per step [ms] in each of `SECTIONS` and the rest."""
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: PLC0415

    kwargs: dict[str, Any] = (
        {"action_mode": "pick_place_discrete", "obs_mode": "rgb", "image_size": DECISION_IMAGE}
        if decision
        else {"action_mode": "pick_place", "obs_mode": "state"}
    )
    env = gym.make(envs.ENV_ID, design=DESIGN, execution="kinematic", **kwargs)
    u: Any = env.unwrapped
    owners = {
        "cell": u.cell,
        "ik": u.ik,
        "planner": u.executor.planner,
        "task": u.task,
        "observer": u.observer,
    }
    spent = dict.fromkeys([s[0] for s in SECTIONS], 0.0)

    def timed(label: str, fn: Any) -> Any:
        def call(*a: Any, **k: Any) -> Any:
            c = time.process_time()
            try:
                return fn(*a, **k)
            finally:
                spent[label] += time.process_time() - c

        return call

    for label, owner, name in SECTIONS:
        obj = owners[owner]
        setattr(obj, name, timed(label, getattr(obj, name)))

    def reset() -> None:
        after = dict(spent)
        env.reset()
        spent.update(after)  # a reset's calls are not a step's

    env.reset(seed=0)
    run = _play(env, seconds, budget="cpu", reset=reset)
    env.close()
    ms = {key: 1e3 * v / run.steps for key, v in spent.items()}
    ms["rest"] = 1e3 * run.cpu / run.steps - sum(ms.values())
    queue.put({"steps": run.steps, "ms_per_step": 1e3 * run.cpu / run.steps, "sections_ms": ms})


def _child(target: Any, *args: Any) -> Any:
    ctx = mp.get_context("spawn")
    q: mp.Queue = ctx.Queue()
    p = ctx.Process(target=target, args=(*args, q))
    p.start()
    out = q.get()
    p.join()
    return out


def _async(n: int, seconds: float, queue: mp.Queue) -> None:
    """Child process: env steps/s of an async vector env of ``n`` workers (joint, images)."""
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: PLC0415

    vec = gym.make_vec(
        envs.ENV_ID,
        num_envs=n,
        vectorization_mode="async",
        design=DESIGN,
        action_mode="joint",
        obs_mode="rgb",
        image_size=96,
        vector_kwargs={"context": "spawn"},
    )
    vec.reset(seed=0)
    vec.action_space.seed(0)
    for _ in range(5):
        vec.step(vec.action_space.sample())
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        vec.step(vec.action_space.sample())
        steps += n
    rate = steps / (time.perf_counter() - t0)
    vec.close()
    queue.put(rate)


def _reset_rows() -> tuple[dict[int, Any], list[dict[str, Any]]]:
    """Measure and print the reset rows (design and task ladder); also writes them alone."""
    resets = {k: _child(_resets, k) for k in (0, 6)}
    for r in resets.values():
        print(
            f"reset, {r['tiles']} tiles: {r['reset_ms']:.1f} ms [CPU {r['reset_cpu_ms']:.1f} ms, "
            f"median {r['reset_cpu_ms_median']:.1f} ms, worst {r['reset_cpu_ms_max']:.1f} ms]",
            flush=True,
        )
    task_resets = _child(_task_resets)
    for r in task_resets:
        print(
            f"reset, {r['task']} ({r['tiles']} tiles): CPU {r['reset_cpu_ms']:.1f} ms "
            f"[median {r['reset_cpu_ms_median']:.1f}, worst {r['reset_cpu_ms_max']:.1f}]",
            flush=True,
        )
    cpu = resets[0]["reset_cpu_ms"]
    print(
        f"reset_16_tiles_cpu_ms: {cpu:.1f} (target {TARGET_RESET_MS}) "
        f"{'MET' if cpu <= TARGET_RESET_MS else 'NOT MET'}"
    )
    OUT_RESETS.parent.mkdir(exist_ok=True)
    write_text(
        OUT_RESETS,
        json.dumps(
            {
                "design": DESIGN,
                "load_average": os.getloadavg(),
                "reset": {f"{r['tiles']}_tiles": r for r in resets.values()},
                "task_resets": task_resets,
            },
            indent=2,
        ),
    )
    return resets, task_resets


def main() -> None:
    """Run every measurement, print a table, write ``out/bench_env.json``."""
    parser = CommandParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=4.0, help="stepping time per case [s]")
    parser.add_argument("--quick", action="store_true", help="1 s per case")
    parser.add_argument(
        "--resets", action="store_true", help=f"the reset rows only (writes {OUT_RESETS.name})"
    )
    args = parser.parse_args()
    seconds = 1.0 if args.quick else args.seconds
    os.environ.setdefault("MUJOCO_GL", "egl")
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ[var] = "1"
    if args.resets:
        _reset_rows()
        return
    rows = []
    for mode, execution in CASES:
        for obs_mode in ("state", "rgb"):
            r = _child(_measure, mode, execution, obs_mode, seconds)
            rows.append(r)
            print(
                f"{mode:20s} {r['execution']:9s} {obs_mode:5s} {r['steps_per_s']:8.1f} steps/s "
                f"[{r['steps_per_cpu_s']:7.1f} per CPU-s] "
                f"({r['ms_per_step']:.2f} ms)  reset {r['reset_ms']:.0f} ms  "
                f"peak RSS {r['peak_rss_mb']:.0f} MB (env +{r['env_rss_mb']:.0f} MB)",
                flush=True,
            )
    decision = _child(_decision, seconds, DEFAULT_SAMPLES)
    aliased = _child(_decision, seconds, 0)
    for label, r in (("", decision), (", no multisampling", aliased)):
        print(
            f"decision level, two {DECISION_IMAGE[0]}x{DECISION_IMAGE[1]} images{label}: "
            f"{r['steps_per_s']:.1f} steps/s [{r['steps_per_cpu_s']:.1f} per CPU-s]",
            flush=True,
        )
    resets, task_resets = _reset_rows()
    sections = {
        "kinematic pick_place": _child(_sections, False, seconds),
        "decision level, images": _child(_sections, True, seconds),
    }
    labels = [*(sec[0] for sec in SECTIONS), "rest"]
    print(f"CPU ms per step: {'':22s}" + "".join(f"{lab:>12s}" for lab in labels) + "       total")
    for name, r in sections.items():
        row = "".join(f"{r['sections_ms'][lab]:12.3f}" for lab in labels)
        print(f"  {name:36s}{row}{r['ms_per_step']:12.3f}", flush=True)
    one = _child(_async, 1, seconds * 2)
    two = _child(_async, 2, seconds * 2)
    print(
        f"async joint+rgb: 1 worker {one:.1f}, 2 workers {two:.1f} env steps/s (x{two / one:.2f})"
    )

    def figure(key: str, mode: str, execution: str, obs: str) -> float:
        return next(
            r[key]
            for r in rows
            if r["action_mode"] == mode
            and r["obs_mode"] == obs
            and r["execution"] in (execution, "-")
        )

    kin = figure("steps_per_s", "pick_place", "kinematic", "state")
    joint_rgb = figure("steps_per_s", "joint", "-", "rgb")
    kin_cpu = figure("steps_per_cpu_s", "pick_place", "kinematic", "state")
    joint_rgb_cpu = figure("steps_per_cpu_s", "joint", "-", "rgb")
    peak = max(r["peak_rss_mb"] for r in rows)
    targets = {
        "kinematic_pick_place_steps_per_s": {
            "value": kin,
            "target": TARGET_KINEMATIC,
            "met": kin >= TARGET_KINEMATIC,
        },
        "joint_rgb_steps_per_s": {
            "value": joint_rgb,
            "target": TARGET_JOINT_RGB,
            "met": joint_rgb >= TARGET_JOINT_RGB,
        },
        "kinematic_pick_place_steps_per_cpu_s": {
            "value": kin_cpu,
            "target": TARGET_KINEMATIC,
            "met": kin_cpu >= TARGET_KINEMATIC,
        },
        "joint_rgb_steps_per_cpu_s": {
            "value": joint_rgb_cpu,
            "target": TARGET_JOINT_RGB,
            "met": joint_rgb_cpu >= TARGET_JOINT_RGB,
        },
        "peak_rss_mb": {"value": peak, "target": TARGET_RSS_MB, "met": peak <= TARGET_RSS_MB},
        "decision_rgb_steps_per_s": {
            "value": decision["steps_per_s"],
            "target": TARGET_DECISION_RGB,
            "met": decision["steps_per_s"] >= TARGET_DECISION_RGB,
        },
        "decision_rgb_steps_per_cpu_s": {
            "value": decision["steps_per_cpu_s"],
            "target": TARGET_DECISION_RGB,
            "met": decision["steps_per_cpu_s"] >= TARGET_DECISION_RGB,
        },
        "reset_16_tiles_ms": {
            "value": resets[0]["reset_ms"],
            "target": TARGET_RESET_MS,
            "met": resets[0]["reset_ms"] <= TARGET_RESET_MS,
        },
        "reset_16_tiles_cpu_ms": {
            "value": resets[0]["reset_cpu_ms"],
            "target": TARGET_RESET_MS,
            "met": resets[0]["reset_cpu_ms"] <= TARGET_RESET_MS,
        },
    }
    for k, v in targets.items():
        print(f"{k}: {v['value']:.1f} (target {v['target']}) {'MET' if v['met'] else 'NOT MET'}")
    result = {
        "machine": {
            "cpus": os.cpu_count(),
            "platform": platform.platform(),
            "python": platform.python_version(),
            "note": "shared 2-core machine (other engineers' jobs may run); one core per case",
            "load_average": os.getloadavg(),
            "gl": os.environ.get("MUJOCO_GL", ""),
        },
        "design": DESIGN,
        "seconds_per_case": seconds,
        "cases": rows,
        "async": {"workers_1": one, "workers_2": two, "speedup": two / one},
        "decision_rgb": decision,
        "decision_rgb_no_multisampling": aliased,
        "reset": {f"{r['tiles']}_tiles": r for r in resets.values()},
        "task_resets": task_resets,
        "sections": sections,
        "targets": targets,
    }
    OUT.parent.mkdir(exist_ok=True)
    write_text(OUT, json.dumps(result, indent=2))
    print(f"wrote {OUT}")


if __name__ == "__main__":
    run_cli(main)
