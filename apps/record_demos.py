r"""Record scripted-agent episodes of `MosaicAssembly-v0` as a Minari dataset, and replay them.

Run::

    python -m apps.record_demos --episodes 20 --seed 0 [--root out/minari] \\
        [--dataset-id mosaic/scripted-kinematic-v0] [--env KEY=VALUE ...] [--replay]

    python -m apps.record_demos --task MosaicDecision6-v0 --expert --lossless --episodes 50 \
        --dataset-id mosaic/decision6-expert-v0    # discrete actions, 72 x 96 images, raw PNG-free

Episodes are collected with Minari's `DataCollector` wrapper (``pick_place`` actions, the
scripted agent's inputs: camera images, plus the privileged state so the dataset also serves
state-based imitation) and written under ``--root`` (``MINARI_DATASETS_PATH`` is set to it for
the call; nothing is downloaded). Each episode stores its reset seed, so `replay` rebuilds the
env from the dataset's spec, resets with the seed, steps the recorded actions and compares
rewards, end flags and the state observations.

``--task``: record on a rung of the task ladder at its training image size (72 x 96 by
default, what `apps.train` learns from) with ``rgb+state`` observations. ``--expert``: the
privileged expert (`MosaicAssemblyEnv.expert_action`, every tile to its slot) instead of the
scripted agent: the only demonstrator of ``pick_place_discrete`` (the scripted agent acts in
``pick_place``). ``--lossless``: store images as raw arrays (Minari JPEG-encodes them by
default, which changes pixels).

``--lowlevel``: the scripted low-level controller of the rung's action mode on a low-level
rung (``--task MosaicOneTile-v0``, the default then) with the rung's own observations
(``state``) and episode limit: the demonstrations low-level learners start from. A
``cartesian`` rung is played by `agents.experts.cartesian.LowLevelExpert`, a ``joint`` rung
(``--task MosaicOneTileJoint-v0``) by `agents.experts.joint.LowLevelJointExpert`::

    python -m apps.record_demos --lowlevel --episodes 20 --seed 0 \
        --dataset-id mosaic/one-tile-lowlevel-v0 --replay
    python -m apps.record_demos --lowlevel --task MosaicOneTileJoint-v0 --episodes 50 \
        --seed 0 --dataset-id mosaic/one-tile-joint-lowlevel-v0 --replay

``--expert-config NAME``: the controller's settings (``lowlevel_expert_smooth``: continuous
descents, what the behaviour clones learn from; on a ``joint`` rung a
`agents.experts.joint.LowLevelJointExpertConfig`, default ``lowlevel_joint_expert``).
``--action-noise SIGMA``: DART-style
recording (`agents.learning.dart.NoisyExecution`): the executed moves (tool or joint moves, not the
vacuum) get Gaussian noise of
SIGMA action units (plus ``--noise-relative`` times the action's size), the dataset keeps the
controller's clean action (such a dataset does not replay exactly; ``--replay`` then reports
mismatches)::

    python -m apps.record_demos --lowlevel --episodes 200 --seed 0 --action-noise 0.02 \
        --noise-relative 0.5 --expert-config lowlevel_expert_smooth \
        --dataset-id mosaic/one-tile-lowlevel-dart-v2
"""

from __future__ import annotations

import json
import os
import re
import shutil
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import yaml

from agents.errors import AgentError
from agents.learning.demos import DEFAULT_ROOT, DemoDatasetError, datasets_root, load_dataset
from apps.cli import CommandParser, run_cli
from configs.files import clear_partials, partial_path, replace_dir, write_json
from envs import ENV_ID
from envs.cell.rendering import use_headless_rendering

"""Gymnasium id of the environment."""
DEFAULT_ID = "mosaic/scripted-kinematic-v0"
"""Default dataset id."""
DEFAULT_ENV: dict[str, Any] = {
    "design": "paper_mixed",
    "max_slots": 6,
    "action_mode": "pick_place",
    "obs_mode": "rgb+state",
    "image_size": [492, 656],
    "execution": "kinematic",
}
"""Env overrides of the recorded episodes (the scripted agent needs ``pick_place`` + images)."""
STATE_KEYS = ("robot", "tiles", "slots")
"""Observation keys compared exactly on replay (images are JPEG-encoded in the dataset)."""
REPLAY_ATOL = 1e-5
"""Tolerance of the replayed state observations and rewards."""
STEPS_PER_SLOT = 2
"""Episode step limit per slot."""
LOWLEVEL_TASK = "MosaicOneTile-v0"
"""Rung of ``--lowlevel`` recordings without ``--task``."""
NOISY_MOVES = {"joint": range(6), "": range(4)}
"""Action entries DART noise perturbs, by action mode (the joint or tool moves, not the vacuum)."""
_LOWLEVEL_ACTIONS = {"cartesian": "cartesian tool moves", "joint": "joint target moves"}
"""What a low-level dataset's actions are, by action mode (its description)."""
STAGING_NAME = "recording"
"""Stem of the staging folder a dataset is recorded in (``<root>/.recording.partial-<pid>``)."""


DATASET_ID = re.compile(r"(?:[\w.-]+/)*[\w.]+(?:-[\w.]+)*-v\d+")
"""A Minari dataset id: ``[namespace/]name-vN`` (Minari reads the version from it)."""


class DemoError(AgentError, RuntimeError):
    """A dataset that cannot be written or replayed."""


@dataclass(frozen=True)
class RecordResult:
    """A recorded dataset.

    Attributes:
        dataset_id: Minari id.
        path: Dataset folder.
        episodes: Episodes recorded.
        steps: Steps recorded.
        seeds: Reset seed of each episode.
        success_rate: Fraction of successful episodes.
        size_mb: Size on disk [MB].
    """

    dataset_id: str
    path: Path
    episodes: int
    steps: int
    seeds: tuple[int, ...]
    success_rate: float
    size_mb: float


@dataclass(frozen=True)
class ReplayResult:
    """Replay of a dataset's actions from its seeds.

    Attributes:
        episodes: Episodes replayed.
        steps: Steps replayed.
        matching_episodes: Episodes whose rewards, end flags and state observations matched.
        max_state_error: Largest absolute difference of the state observations.
        max_reward_error: Largest absolute difference of the rewards.
        replayed_success: Successful episodes on replay.
    """

    episodes: int
    steps: int
    matching_episodes: int
    max_state_error: float
    max_reward_error: float
    replayed_success: int


class ExpertAgent:
    """The privileged expert as a policy: moves the tiles of the design into their slots in turn.

    Args:
        env: A ``pick_place`` or ``pick_place_discrete`` env (any wrapper).
    """

    def __init__(self, env: gym.Env) -> None:
        self.env = env.unwrapped
        self.slots = len(env.get_wrapper_attr("task_spec").slots)
        self.step = 0

    def predict(self, obs: Any, episode_start: np.ndarray) -> tuple[np.ndarray, None]:
        """The next expert action (the observation is not needed: the expert is privileged)."""
        del obs
        self.step = 0 if bool(np.asarray(episode_start).ravel()[0]) else self.step + 1
        i = self.step % self.slots
        return self.env.expert_action(i, i), None  # type: ignore[attr-defined]


def record(
    episodes: int,
    *,
    seed: int = 0,
    root: Path = DEFAULT_ROOT,
    dataset_id: str = DEFAULT_ID,
    env_kwargs: dict[str, Any] | None = None,
    calibrate: bool = True,
    overwrite: bool = False,
    expert: bool = False,
    lossless: bool = False,
    task: str = "",
    lowlevel: bool = False,
    action_noise: float = 0.0,
    expert_config: str = "",
    noise_relative: float = 0.0,
) -> RecordResult:
    """Record ``episodes`` scripted episodes (seeds ``seed``, ``seed + 1``...) as a dataset.

    The dataset is recorded in a staging folder under ``root`` and renamed into place when
    complete: a recording killed part-way leaves no dataset (or the previous one, with
    ``overwrite``), and its staging folder is removed by the next recording.

    Raises:
        DemoError: The dataset exists and ``overwrite`` is False.
    """
    env_id = ENV_ID
    kwargs = {**DEFAULT_ENV, **(env_kwargs or {})}
    if task:
        from envs.tasks import get_task  # noqa: PLC0415

        env_id = f"envs:{get_task(task).id}"
        kwargs = {"obs_mode": "rgb+state", **(env_kwargs or {})}
    if lowlevel:
        from envs.tasks import get_task  # noqa: PLC0415

        env_id = f"envs:{get_task(task or LOWLEVEL_TASK).id}"
        kwargs = dict(env_kwargs or {})
    if not DATASET_ID.fullmatch(dataset_id):
        raise DemoError(
            f"dataset id {dataset_id!r} is not Minari's form: [namespace/]name-vN "
            "(e.g. mosaic/my-decision6-v0)"
        )
    with datasets_root(root):
        top = Path(os.environ["MINARI_DATASETS_PATH"])
    path = top / dataset_id
    if path.exists() and not overwrite:
        raise DemoError(f"dataset {dataset_id} exists at {path}; pass --overwrite")
    clear_partials(top / STAGING_NAME)
    staging = partial_path(top / STAGING_NAME)
    try:
        with datasets_root(staging):
            rec = _collect(
                episodes,
                seed,
                dataset_id=dataset_id,
                env_id=env_id,
                kwargs=kwargs,
                calibrate=calibrate,
                expert="lowlevel" if lowlevel else "decision" if expert else "",
                lossless=lossless,
                action_noise=action_noise,
                expert_config=expert_config,
                noise_relative=noise_relative,
            )
        replace_dir(staging / dataset_id, path)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    size = sum(f.stat().st_size for f in path.rglob("*") if f.is_file()) / 1e6
    return RecordResult(dataset_id, path, *rec, size)


def _noisy(env: gym.Env, sigma: float, relative: float, seed: int) -> gym.Env:
    """``env`` with DART noise on its executed actions (`agents.learning.dart`), or as it is."""
    if not (sigma or relative):
        return env
    from agents.learning.dart import NoisyExecution  # noqa: PLC0415

    joint = env.get_wrapper_attr("task_spec").action_mode == "joint"
    return NoisyExecution(env, sigma, NOISY_MOVES["joint" if joint else ""], seed, relative)


def _play(env: gym.Env, agent: Any, seeds: Sequence[int]) -> int:
    """Play one episode per reset seed; the number that succeeded."""
    successes = 0
    for s in seeds:
        obs, _ = env.reset(seed=s)
        done, first = False, True
        info: dict[str, Any] = {}
        while not done:
            action, _ = agent.predict(obs, episode_start=np.array([first]))
            obs, _, terminated, truncated, info = env.step(action)
            first, done = False, terminated or truncated
        successes += bool(info["is_success"])
    return successes


def _demonstrator(expert: str, env: gym.Env) -> str:
    """The first words of a dataset's description: who acted (and in what action mode)."""
    if expert == "lowlevel":
        mode = env.get_wrapper_attr("task_spec").action_mode
        return f"Scripted low-level controller ({_LOWLEVEL_ACTIONS.get(mode, mode)} and vacuum) "
    if expert:
        return "Privileged expert (every tile to its slot) "
    return "Scripted mosaic cell (perception + qualitative matching + planner cycles) "


def _collect(
    episodes: int,
    seed: int,
    *,
    dataset_id: str,
    env_id: str,
    kwargs: dict[str, Any],
    calibrate: bool,
    expert: str,
    lossless: bool,
    action_noise: float = 0.0,
    expert_config: str = "",
    noise_relative: float = 0.0,
) -> tuple[int, int, tuple[int, ...], float]:
    """Record the episodes as ``dataset_id`` under ``MINARI_DATASETS_PATH``.

    ``expert``: "" (the scripted agent), ``decision`` (`ExpertAgent`) or ``lowlevel``
    (`agents.experts.joint.lowlevel_controller`: the controller of the env's action
    mode with ``expert_config``, the env's own episode limit). ``action_noise`` (+
    ``noise_relative`` x the action's size): DART (`agents.learning.dart`).

    Returns:
        (episodes, steps, seeds, success rate).
    """
    import minari  # noqa: PLC0415 - optional heavy import

    from agents.scripted.agent import ScriptedAgent  # noqa: PLC0415

    base = gym.make(env_id, **kwargs)
    slots = len(base.unwrapped.task.slot_class)  # type: ignore[attr-defined]
    base.close()
    limit = None if expert == "lowlevel" else STEPS_PER_SLOT * slots  # None: the env's own
    inner = _noisy(
        gym.make(env_id, max_episode_steps=limit, **kwargs), action_noise, noise_relative, seed
    )
    env = minari.DataCollector(inner, jpeg_encoding=not lossless)
    try:
        agent: Any
        if expert == "lowlevel":
            from agents.experts.joint import lowlevel_controller  # noqa: PLC0415

            agent = lowlevel_controller(env, expert_config)
        elif expert:
            agent = ExpertAgent(env)
        else:
            agent = ScriptedAgent.from_env(env, calibrate=calibrate)
        seeds = tuple(range(seed, seed + episodes))
        successes = _play(env, agent, seeds)
        dataset = env.create_dataset(
            dataset_id=dataset_id,
            eval_env=env.spec,
            algorithm_name=type(agent).__name__,
            author="mosaic-cell project",
            author_email="n/a",
            code_permalink="apps/record_demos.py",
            description=(
                _demonstrator(expert, env)
                + f"on {env_id.removeprefix('envs:')} with {json.dumps(kwargs)}; seeds "
                f"{seeds[0]}..{seeds[-1]}"
                + (
                    f"; executed moves with N(0, ({action_noise} + {noise_relative} |a|)^2) "
                    "noise, clean labels."
                    if action_noise or noise_relative
                    else "."
                )
            ),
        )
    finally:
        env.close()
    return dataset.total_episodes, dataset.total_steps, seeds, successes / max(episodes, 1)


def load(dataset_id: str = DEFAULT_ID, root: Path = DEFAULT_ROOT) -> Any:
    """Load a local dataset (never downloads).

    Raises:
        DemoError: No complete dataset ``dataset_id`` under ``root``.
    """
    try:
        return load_dataset(dataset_id, root)
    except DemoDatasetError as exc:
        raise DemoError(str(exc)) from exc


def _state_error(recorded: dict[str, np.ndarray], step: int, obs: dict[str, Any]) -> float:
    """Largest difference of the state keys between a recorded and a replayed observation."""
    err = 0.0
    for key in STATE_KEYS:
        if key in recorded:
            diff = np.abs(np.asarray(recorded[key][step], float) - np.asarray(obs[key], float))
            err = max(err, float(diff.max(initial=0.0)))
    return err


def replay(dataset: Any) -> ReplayResult:
    """Re-run every episode's actions from its recorded seed and compare.

    Raises:
        DemoError: An episode without a recorded seed.
    """
    env = dataset.recover_environment()
    ids = list(dataset.episode_indices)
    metadata = list(dataset.storage.get_episode_metadata(ids))
    matching = steps = success = 0
    worst_state = worst_reward = 0.0
    try:
        for ep, meta in zip(dataset.iterate_episodes(ids), metadata, strict=True):
            if meta.get("seed") is None:
                raise DemoError(f"episode {ep.id} has no recorded seed")
            obs, _ = env.reset(seed=int(meta["seed"]))
            state_err = _state_error(ep.observations, 0, obs)
            reward_err, flags_ok = 0.0, True
            info: dict[str, Any] = {}
            for t in range(len(ep)):
                obs, reward, terminated, truncated, info = env.step(ep.actions[t])
                state_err = max(state_err, _state_error(ep.observations, t + 1, obs))
                reward_err = max(reward_err, abs(float(reward) - float(ep.rewards[t])))
                flags_ok &= bool(terminated) == bool(ep.terminations[t])
                flags_ok &= bool(truncated) == bool(ep.truncations[t])
            steps += len(ep)
            success += bool(info.get("is_success", False))
            worst_state = max(worst_state, state_err)
            worst_reward = max(worst_reward, reward_err)
            matching += flags_ok and state_err <= REPLAY_ATOL and reward_err <= REPLAY_ATOL
    finally:
        env.close()
    return ReplayResult(len(ids), steps, matching, worst_state, worst_reward, success)


def _pairs(pairs: Sequence[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for pair in pairs:
        if "=" not in pair:
            raise DemoError(f"--env wants KEY=VALUE, got {pair!r}")
        key, value = pair.split("=", 1)
        out[key] = yaml.safe_load(value)
    return out


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0, help="first reset seed")
    ap.add_argument("--root", type=Path, default=DEFAULT_ROOT, help="datasets folder")
    ap.add_argument("--dataset-id", default=DEFAULT_ID)
    ap.add_argument("--env", nargs="*", default=[], metavar="KEY=VALUE", help="env overrides")
    ap.add_argument("--no-calibrate", action="store_true", help="true camera model")
    ap.add_argument("--overwrite", action="store_true")
    ap.add_argument("--replay", action="store_true", help="load back and replay")
    ap.add_argument("--task", default="", help="a ladder id (MosaicDecision6-v0)")
    ap.add_argument("--expert", action="store_true", help="privileged expert (discrete modes)")
    ap.add_argument("--lossless", action="store_true", help="raw images, no JPEG")
    ap.add_argument(
        "--lowlevel",
        action="store_true",
        help="scripted low-level controller (cartesian or joint rung)",
    )
    ap.add_argument(
        "--action-noise",
        type=float,
        default=0.0,
        help="DART: noise (std, action units) on the executed moves; labels stay clean",
    )
    ap.add_argument(
        "--expert-config",
        default="",
        help="low-level controller settings (configs/ name or path; default lowlevel_expert)",
    )
    ap.add_argument(
        "--noise-relative",
        type=float,
        default=0.0,
        help="DART: extra noise std per unit of the action's size (large at full speed)",
    )
    args = ap.parse_args(argv)
    use_headless_rendering()
    rec = record(
        args.episodes,
        seed=args.seed,
        root=args.root,
        dataset_id=args.dataset_id,
        env_kwargs=_pairs(args.env),
        calibrate=not args.no_calibrate,
        overwrite=args.overwrite,
        expert=args.expert,
        lossless=args.lossless,
        task=args.task,
        lowlevel=args.lowlevel,
        action_noise=args.action_noise,
        expert_config=args.expert_config,
        noise_relative=args.noise_relative,
    )
    report: dict[str, Any] = {"record": {**asdict(rec), "path": str(rec.path)}}
    print(
        f"{rec.dataset_id}: {rec.episodes} episodes, {rec.steps} steps, success "
        f"{rec.success_rate:.0%}, {rec.size_mb:.1f} MB at {rec.path}"
    )
    if args.replay:
        rep = replay(load(args.dataset_id, args.root))
        report["replay"] = asdict(rep)
        print(
            f"replay: {rep.matching_episodes}/{rep.episodes} episodes match "
            f"(state error {rep.max_state_error:.2e}, reward error "
            f"{rep.max_reward_error:.2e}), {rep.replayed_success} successful"
        )
    write_json(rec.path / "record_report.json", report)
    return report


__all__ = [
    "DemoError",
    "ExpertAgent",
    "RecordResult",
    "ReplayResult",
    "datasets_root",
    "load",
    "main",
    "record",
    "replay",
]

if __name__ == "__main__":
    run_cli(main)
