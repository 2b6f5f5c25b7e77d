"""Where training spends its time, as ratios measured in one process (`benchmarks.env`).

Four ratios of CPU time [s of the process, every thread: the software renderer's included],
each between two things timed in the same process, interleaved (an episode of one, then of
the other), so that a shared machine's load slows both alike and the ratio holds across
machines and loads:

- ``reset``: a reset of ``MosaicHeldOutDesigns-v1``'s procedural training entry (a new design
  drawn and its cell built) over a reset of the same rung on its fixed design (6 slots both,
  the rung's state observation). Target <= `TARGET_RESET`.
- ``reset_pool``: the same with the design pool (``design_pool: design_pool``,
  `envs.pool`), seeds in order: this process's CPU time (the worker process draws
  and builds), with the wall time, the wall ratio and the worker's CPU time per design beside
  it. Target <= `TARGET_RESET`.
- ``step``: a kinematic ``pick_place`` step (state observation, `DESIGN`, the privileged
  correct action) over its physics (`Cell.step`, the calls timed inside the same steps).
  Target <= `TARGET_STEP`.
- ``camera``: a decision step (``pick_place_discrete``, kinematic, the scripted correct
  decision) with both 72 x 96 camera images over the same step without images
  (``obs_mode="state"``). Target <= `TARGET_CAMERA`. Beside it, ``floor_ratio``: the same
  step with both images at `FLOOR_IMAGE` (3 x 4 px) over the step without, the least any
  picture size costs with this renderer (its per-picture cost apart from pixels: the scene,
  the draw calls, the vertices, the read-back).

Each row also gives the absolute figures [ms] and the machine's load average (1, 5, 15 min)
before and after it (`os.getloadavg`).
"""

from __future__ import annotations

import functools
import multiprocessing as mp
import os
import time
import warnings
from collections.abc import Callable
from typing import Any

from benchmarks.env_measure import DECISION_IMAGE, DESIGN

TARGET_RESET = 3.0
"""A procedural-design reset within this many fixed-design resets of the same size."""
TARGET_STEP = 2.0
"""A kinematic pick_place step within this many times its physics."""
TARGET_CAMERA = 2.0
"""A decision step with both images within this many times the step without."""
RUNG = "MosaicHeldOutDesigns-v1"
"""The rung whose procedural and fixed resets are compared (6 slots)."""
PROCEDURAL: dict[str, Any] = {
    "design_source": "procedural",
    "exclude_designs": ["hexagon", "trencadis"],
}
"""Its procedural training entry (`envs.tasks.BenchmarkTask.design_kwargs`)."""
FLOOR_IMAGE = (3, 4)
"""The smallest image of the cameras' 4:3 shape [px] (height, width): the ``camera`` ratio's
floor, what the pictures cost with next to no pixels."""
POOL = "design_pool"
"""The design pool configuration of the ``reset_pool`` ratio (``configs/design_pool.yaml``)."""


def _pin() -> None:
    """One core and one BLAS thread for this process (the figures are per core)."""
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    warnings.simplefilter("ignore")


def _cpu(fn: Callable[[], Any]) -> float:
    """CPU seconds of ``fn()``."""
    c = time.process_time()
    fn()
    return time.process_time() - c


def _episode(env: Any, steps: int) -> tuple[float, int]:
    """CPU seconds of up to ``steps`` correct steps (tile i into slot i) and the step count."""
    u, spent, n = env.unwrapped, 0.0, 0
    k = len(u.cell.slots)
    for i in range(steps):
        action = u.expert_action(i % k, i % k)
        c = time.process_time()
        _, _, term, trunc, _ = env.step(action)
        spent += time.process_time() - c
        n += 1
        if term or trunc:
            break
    return spent, n


def measure_reset_ratio(seconds: float, queue: mp.Queue) -> None:
    """Child process: procedural over fixed reset CPU time, interleaved seed by seed."""
    _pin()
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: F401, PLC0415

    load0 = os.getloadavg()
    proc: Any = gym.make(RUNG, **PROCEDURAL)
    fixed: Any = gym.make(RUNG)
    proc.reset(seed=10_000)
    fixed.reset(seed=10_000)
    a = b = 0.0
    seed = 0
    while a + b < seconds or seed < 3:
        a += _cpu(functools.partial(proc.reset, seed=seed))
        b += _cpu(functools.partial(fixed.reset, seed=seed))
        seed += 1
    proc.close()
    fixed.close()
    queue.put(
        {
            "what": f"{RUNG} reset: procedural design / fixed design (6 slots)",
            "procedural_ms": 1e3 * a / seed,
            "fixed_ms": 1e3 * b / seed,
            "ratio": a / b,
            "target": TARGET_RESET,
            "resets": seed,
            "load_average": [load0, os.getloadavg()],
        }
    )


def measure_reset_pool_ratio(seconds: float, queue: mp.Queue) -> None:
    """Child process: procedural reset with the design pool over a fixed reset, interleaved.

    The pool (``design_pool``, `envs.pool`) draws the designs and builds their cells in
    its worker process: this process's CPU time is the figure of the ratio; the wall time
    (which includes waiting for the worker when resets come faster than it prepares them) and
    the worker's CPU time per design are given beside it.
    """
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: F401, PLC0415

    load0 = os.getloadavg()
    proc: Any = gym.make(RUNG, design_pool=POOL, **PROCEDURAL)
    _pin()  # this process on one core, the pool's worker (started unpinned) on any
    fixed: Any = gym.make(RUNG)
    proc.reset(seed=10_000)
    fixed.reset(seed=10_000)
    pool = proc.unwrapped.pool
    a = b = wa = wb = 0.0
    seed = 0
    proc.reset(seed=seed)  # the pool plans from the seeds after this one
    fixed.reset(seed=seed)
    hits0, misses0 = pool.hits, pool.misses
    while a + b < seconds or seed < 3:
        seed += 1
        w = time.perf_counter()
        a += _cpu(functools.partial(proc.reset, seed=seed))
        wa += time.perf_counter() - w
        w = time.perf_counter()
        b += _cpu(functools.partial(fixed.reset, seed=seed))
        wb += time.perf_counter() - w
    worker = pool.worker_cpu_s / max(1, pool.hits + pool.dropped)
    hits, misses = pool.hits - hits0, pool.misses - misses0
    proc.close()
    fixed.close()
    queue.put(
        {
            "what": (
                f"{RUNG} reset: procedural design with the design pool / fixed design "
                "(6 slots; this process's CPU)"
            ),
            "procedural_ms": 1e3 * a / seed,
            "fixed_ms": 1e3 * b / seed,
            "procedural_wall_ms": 1e3 * wa / seed,
            "fixed_wall_ms": 1e3 * wb / seed,
            "worker_cpu_ms_per_design": 1e3 * worker,
            "wall_ratio": wa / wb,
            "pool_hits": hits,
            "pool_misses": misses,
            "ratio": a / b,
            "target": TARGET_RESET,
            "resets": seed,
            "load_average": [load0, os.getloadavg()],
        }
    )


def measure_step_ratio(seconds: float, queue: mp.Queue) -> None:
    """Child process: kinematic pick_place step CPU time over its physics (`Cell.step`)."""
    _pin()
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: PLC0415

    load0 = os.getloadavg()
    env: Any = gym.make(
        envs.ENV_ID,
        design=DESIGN,
        action_mode="pick_place",
        execution="kinematic",
        obs_mode="state",
    )
    cell_step = type(env.unwrapped.cell).step
    physics = [0.0]

    def timed(cell: Any, *a: Any, **k: Any) -> Any:
        c = time.process_time()
        try:
            return cell_step(cell, *a, **k)
        finally:
            physics[0] += time.process_time() - c

    total, steps, seed = 0.0, 0, 0
    while total < seconds:
        env.reset(seed=seed)
        u = env.unwrapped
        u.cell.step = timed.__get__(u.cell)  # this episode's cell, timed
        spent, n = _episode(env, len(u.cell.slots))
        total, steps, seed = total + spent, steps + n, seed + 1
    env.close()
    queue.put(
        {
            "what": "kinematic pick_place step / its physics (Cell.step)",
            "step_ms": 1e3 * total / steps,
            "physics_ms": 1e3 * physics[0] / steps,
            "ratio": total / physics[0],
            "target": TARGET_STEP,
            "steps": steps,
            "load_average": [load0, os.getloadavg()],
        }
    )


def measure_camera_ratio(seconds: float, queue: mp.Queue) -> None:
    """Child process: decision step CPU time with both images over without, interleaved."""
    _pin()
    import gymnasium as gym  # noqa: PLC0415

    import envs  # noqa: PLC0415

    load0 = os.getloadavg()
    kw: dict[str, Any] = {
        "design": DESIGN,
        "action_mode": "pick_place_discrete",
        "execution": "kinematic",
        "image_size": DECISION_IMAGE,
    }
    rgb: Any = gym.make(envs.ENV_ID, obs_mode="rgb", **kw)
    state: Any = gym.make(envs.ENV_ID, obs_mode="state", **kw)
    floor: Any = gym.make(envs.ENV_ID, obs_mode="rgb", **{**kw, "image_size": FLOOR_IMAGE})
    a = b = f = 0.0
    na = nb = nf = seed = 0
    while a + b < seconds:
        for env in (rgb, state, floor):
            env.reset(seed=seed)
        spent, n = _episode(rgb, len(rgb.unwrapped.cell.slots))
        a, na = a + spent, na + n
        spent, n = _episode(state, len(state.unwrapped.cell.slots))
        b, nb = b + spent, nb + n
        spent, n = _episode(floor, len(floor.unwrapped.cell.slots))
        f, nf = f + spent, nf + n
        seed += 1
    for env in (rgb, state, floor):
        env.close()
    queue.put(
        {
            "what": (
                f"decision step with two {DECISION_IMAGE[0]}x{DECISION_IMAGE[1]} images / "
                "without images"
            ),
            "with_images_ms": 1e3 * a / na,
            "without_images_ms": 1e3 * b / nb,
            "floor_images_ms": 1e3 * f / nf,
            "floor_ratio": (f / nf) / (b / nb),
            "ratio": (a / na) / (b / nb),
            "target": TARGET_CAMERA,
            "steps": na + nb,
            "load_average": [load0, os.getloadavg()],
        }
    )


RATIOS = {
    "reset": measure_reset_ratio,
    "reset_pool": measure_reset_pool_ratio,
    "step": measure_step_ratio,
    "camera": measure_camera_ratio,
}
"""Each ratio's measurement (a child process's target: ``seconds``, result queue)."""


__all__ = [
    "RATIOS",
    "FLOOR_IMAGE",
    "TARGET_CAMERA",
    "TARGET_RESET",
    "TARGET_STEP",
    "measure_camera_ratio",
    "measure_reset_pool_ratio",
    "measure_reset_ratio",
    "measure_step_ratio",
]
