"""Generate the task cards' animations: one short GIF per pictured id, the env rendering itself.

Each animation is one held-out episode (seed `ANIMATION_SEED`, the first evaluation design) of
the id with its acting policy (`ACTORS`): the best learned checkpoint where one ships, else the
scripted cell from its cameras, or the scripted low-level controller of the one-tile rungs.
Frames are the env's overview camera beside its output camera (the mesh), rendered by the cell
every `FRAME_PERIOD_S` of simulated time (inside a ``pick_place`` cycle too, through the env's
frame listener) until the arm is back home after the episode (``move_home``), then thinned to
at most `MAX_FRAMES` evenly spaced frames; the last one, held longest, shows the finished work.
A later version (``-v1``) starts like its ``-v0``, so only the ``-v0`` ids get animations.

This is a separate command, not part of the docs build (it renders and runs policies: about a
CPU-minute per id); its outputs are committed in ``docs/tasks/img/`` (under 1 MB each)::

    MUJOCO_GL=egl python docs/gen_animations.py                       # every pictured id
    MUJOCO_GL=egl python docs/gen_animations.py MosaicDecision6-v0    # some ids
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
from envs.cell.rendering import use_headless_rendering  # noqa: E402

use_headless_rendering()
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import gymnasium as gym  # noqa: E402 - after MUJOCO_GL is set
import numpy as np  # noqa: E402

import envs  # noqa: E402, F401 - registers the ids
from agents.policies import make_policy  # noqa: E402
from envs.tasks import bundled_tasks  # noqa: E402

IMG_DIR = DOCS / "tasks" / "img"
"""Folder of the committed animations (``<id>.gif``)."""
ANIMATION_SEED = 1000
"""Reset seed of the animated episode (the first held-out seed of every rung)."""
FRAME_SIZE = (120, 160)
"""Height and width of each of the two views of a frame [px]."""
FRAME_PERIOD_S = 0.25
"""Simulated time between rendered frames [s] (before thinning)."""
MAX_FRAMES = 24
"""Frames kept per animation (evenly spaced over the episode, the last one always kept)."""
GIF_FRAME_S = 0.2
"""Display time of one GIF frame [s]; the last frame is held `HOLD_LAST` times as long."""
HOLD_LAST = 6
MAX_BYTES = 1_000_000
"""Size limit of a committed animation [bytes]."""
VIEWS = ("overview", "output_camera")
"""Cell cameras side by side in a frame."""
CHECKPOINTS = ROOT / "checkpoints"


@dataclass(frozen=True)
class Actor:
    """Who acts in an id's animation.

    Attributes:
        policy: An `agents.policies.make_policy` name (``scripted``, a checkpoint path), or
            ``controller`` (the scripted low-level controller, `agents.experts.joint`).
        label: What the caption says acts.
        env_kwargs: Extra env overrides of the animated episode.
    """

    policy: str
    label: str
    env_kwargs: dict[str, Any]


_DYNAMIC = {"execution": "dynamic"}  # decision steps move the arm (kinematic ones teleport)
ACTORS: dict[str, Actor] = {
    "MosaicAssembly-v0": Actor("scripted", "the scripted cell from its cameras", {}),
    "MosaicOneTile-v0": Actor("controller", "the scripted cartesian controller", {}),
    "MosaicOneTileJoint-v0": Actor("controller", "the scripted joint controller", {}),
    "MosaicDecision6-v0": Actor(
        "checkpoints/MosaicDecision6-v0/PairBC_state/seed_0/bc.pt",
        "the shipped pair-scorer clone (seed 0)",
        _DYNAMIC,
    ),
    "MosaicDecision16-v0": Actor(
        "checkpoints/MosaicDecision16-v0/PairBC_state/seed_0/bc.pt",
        "the shipped pair-scorer clone (seed 0)",
        _DYNAMIC,
    ),
    "MosaicStream-v0": Actor("scripted", "the scripted cell from its cameras", {}),
    "MosaicStream-v2": Actor("scripted", "the scripted cell from its cameras", {}),
    "MosaicDistractors-v0": Actor("scripted", "the scripted cell from its cameras", _DYNAMIC),
    "MosaicHeldOutDesigns-v0": Actor(
        "checkpoints/MosaicHeldOutDesigns-v0/PairBC_objects/seed_0/bc.pt",
        "the shipped pair-scorer clone on objects rows (seed 0)",
        _DYNAMIC,
    ),
}
"""The acting policy of each animated id."""


def base_kwargs(env_id: str) -> dict[str, Any]:
    """The env keys of the animated episode before the actor's: the first held-out design."""
    tasks = bundled_tasks(all_versions=True)
    if env_id in tasks:
        return tasks[env_id].env_kwargs("eval", 0)
    return {}


def animation_design(env_id: str) -> str:
    """The design the animation shows (the rung's first held-out design)."""
    return str(base_kwargs(env_id).get("design", "paper_mixed"))


def _bind(env_id: str, actor: Actor) -> tuple[gym.Env[Any, Any], Callable[[Any, bool], Any]]:
    base = {**base_kwargs(env_id), **actor.env_kwargs}
    if actor.policy == "controller":
        from agents.experts.joint import lowlevel_controller  # noqa: PLC0415

        env = gym.make(env_id, **base)
        ctrl = lowlevel_controller(env)
        return env, lambda obs, start: ctrl.predict(obs)[0]
    policy = make_policy(str(ROOT / actor.policy) if "/" in actor.policy else actor.policy, base)
    env = gym.make(env_id, **policy.env_kwargs)
    if policy.wrap is not None:
        env = policy.wrap(env)
    return env, policy.factory(env)


def record(env_id: str, actor: Actor) -> tuple[list[np.ndarray], dict[str, Any]]:
    """Frames (uint8 (h, 2w, 3)) of one episode and its last ``info["evaluation"]``."""
    env, predict = _bind(env_id, actor)
    cell = env.get_wrapper_attr("cell")
    h, w = FRAME_SIZE
    frames: list[np.ndarray] = []

    def capture() -> None:
        frames.append(np.concatenate([cell.render(v, h, w) for v in VIEWS], axis=1))

    try:
        env.get_wrapper_attr("add_frame_listener")(capture, 1.0 / FRAME_PERIOD_S)
        obs, info = env.reset(seed=ANIMATION_SEED)
        capture()
        start, done = True, False
        while not done:
            obs, _, terminated, truncated, info = env.step(predict(obs, start))
            start, done = False, terminated or truncated
        env.get_wrapper_attr("move_home")()  # the arm out of the output camera's view
        capture()
    finally:
        env.close()
    return frames, dict(info.get("evaluation", {}))


def thin(frames: list[np.ndarray], n: int = MAX_FRAMES) -> list[np.ndarray]:
    """At most ``n`` evenly spaced frames, the first and the last kept."""
    if len(frames) <= n:
        return frames
    picks = np.linspace(0, len(frames) - 1, n).round().astype(int)
    return [frames[i] for i in picks]


def write_gif(frames: list[np.ndarray], path: Path) -> int:
    """Write a looping GIF (Pillow, adaptive palette); returns its size [bytes]."""
    from PIL import Image  # noqa: PLC0415

    images = [Image.fromarray(f).quantize(colors=128, dither=Image.Dither.NONE) for f in frames]
    durations = [round(GIF_FRAME_S * 1000)] * len(images)
    durations[-1] *= HOLD_LAST
    images[0].save(
        path, save_all=True, append_images=images[1:], duration=durations, loop=0, optimize=True
    )
    return path.stat().st_size


def main(argv: list[str] | None = None) -> int:
    """Command line (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("ids", nargs="*", help=f"ids to animate (default: {', '.join(ACTORS)})")
    args = ap.parse_args(argv)
    unknown = [i for i in args.ids if i not in ACTORS]
    if unknown:
        print(f"no animation for {unknown}; animated ids: {list(ACTORS)}", file=sys.stderr)
        return 2
    IMG_DIR.mkdir(parents=True, exist_ok=True)
    for env_id in args.ids or list(ACTORS):
        t0 = time.process_time()
        frames, evaluation = record(env_id, ACTORS[env_id])
        path = IMG_DIR / f"{env_id}.gif"
        size = write_gif(thin(frames), path)
        print(
            f"{env_id}: {len(frames)} frames -> {path.relative_to(ROOT)} ({size / 1e3:.0f} kB, "
            f"{time.process_time() - t0:.0f} CPU s); filled {evaluation.get('correct')} of "
            f"{evaluation.get('slots')}"
        )
        if size > MAX_BYTES:
            print(f"{path.name} is over {MAX_BYTES} bytes", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
