"""The env benchmark's measurements, each run in a child process (`benchmarks.env`)."""

from __future__ import annotations

import math
import multiprocessing as mp
import os
import resource
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

RESET_SEEDS = 20


DECISION_IMAGE = (72, 96)


DESIGN = "paper_mixed"


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


def measure_case(mode: str, execution: str, obs_mode: str, seconds: float, queue: mp.Queue) -> None:
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


def measure_decision(seconds: float, samples: int, queue: mp.Queue) -> None:
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


def measure_resets(max_slots: int, queue: mp.Queue) -> None:
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


def measure_task_resets(queue: mp.Queue) -> None:
    """Child process: reset times [ms] of every registered rung of the task ladder."""
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    import gymnasium as gym  # noqa: PLC0415

    from envs.tasks import PROCEDURAL, get_task, register_tasks  # noqa: PLC0415

    rows = []
    for task_id in register_tasks():
        row = _time_resets(gym.make(task_id))
        rows.append({"task": task_id, **row})
        task = get_task(task_id)
        if PROCEDURAL in task.train_designs:  # its training entry drawing a design per reset
            kwargs = task.design_kwargs("train", task.train_designs.index(PROCEDURAL))
            row = _time_resets(gym.make(task_id, **kwargs))
            rows.append({"task": f"{task_id} ({PROCEDURAL})", **row})
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


def measure_sections(decision: bool, seconds: float, queue: mp.Queue) -> None:
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


def measure_async(n: int, seconds: float, queue: mp.Queue) -> None:
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


__all__ = [
    "DECISION_IMAGE",
    "DESIGN",
    "RESET_SEEDS",
    "SECTIONS",
    "measure_async",
    "measure_case",
    "measure_decision",
    "measure_resets",
    "measure_sections",
    "measure_task_resets",
]
