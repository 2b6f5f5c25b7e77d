"""Scripted pick_place with privileged correct poses, in dynamic and kinematic execution; frame
listeners: callbacks on a simulated-time schedule inside pick_place cycles."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401 - registers MosaicAssembly-v0
from envs.actions import transfer_poses
from envs.mosaic_env import MosaicAssemblyEnv, MosaicEnvError
from tests.presets import FAST_DISCRETE

OUT = Path(__file__).resolve().parents[2] / "out"
N_SLOTS = 3


def _correct_action(env: MosaicAssemblyEnv, tile: int, slot: int) -> np.ndarray:
    """The pick_place action moving ``tile`` (ground truth) into ``slot``."""
    cell = env.cell
    poses = cell.tile_poses()
    yaw = float(poses.yaw[tile])
    g = cell.tiles[tile].grasp
    slot_x, slot_y, slot_yaw = cell.slot_poses_world()[slot]

    def rot(v: np.ndarray, a: float) -> np.ndarray:
        return np.array(
            [math.cos(a) * v[0] - math.sin(a) * v[1], math.sin(a) * v[0] + math.cos(a) * v[1]]
        )

    pick = poses.pos[tile, :2] + rot(g, yaw)
    place = np.array([slot_x, slot_y]) + rot(g, slot_yaw)
    return env.pick_place_action(pick, yaw, place, float(slot_yaw))


def _run(execution: str) -> tuple[list[dict], list[float], MosaicAssemblyEnv]:
    env = MosaicAssemblyEnv(
        action_mode="pick_place",
        execution=execution,
        obs_mode="rgb",
        max_slots=N_SLOTS,
        render_mode="rgb_array",
    )
    env.reset(seed=5)
    infos, rewards = [], []
    for i in range(N_SLOTS):
        _, r, term, trunc, info = env.step(_correct_action(env, i, i))
        infos.append(info)
        rewards.append(r)
        assert not info["action_failed"], info["action_error"]
        assert term == (i == N_SLOTS - 1) and not trunc
    return infos, rewards, env


@pytest.mark.parametrize("execution", ["dynamic", "kinematic"])
def test_scripted_pick_place_places_every_tile(execution: str) -> None:
    infos, rewards, env = _run(execution)
    try:
        ev = infos[-1]["evaluation"]
        assert ev["success"] and ev["correct"] == N_SLOTS
        assert ev["misplaced"] == ev["dropped"] == ev["lost"] == 0
        assert ev["position_error_mm_max"] < 0.5 and ev["yaw_error_deg_max"] < 0.5
        assert [i["tiles_placed"] for i in infos] == [1, 2, 3]
        assert rewards[-1] == pytest.approx(env.config.reward_correct + env.config.reward_success)
        assert infos[-1]["reward_success"] == env.config.reward_success
        assert 0 < infos[-1]["sim_time"] and infos[-1]["tiles_per_min"] > 10
        assert env.cell.warnings() == 0
        OUT.mkdir(exist_ok=True)
        frame = env.render()
        assert frame is not None and frame.shape[2] == 3
        import cv2  # noqa: PLC0415

        cv2.imwrite(str(OUT / f"env_pick_place_{execution}.png"), frame[:, :, ::-1])
    finally:
        env.close()


def test_dynamic_and_kinematic_agree_on_clean_picks() -> None:
    dyn, _, e1 = _run("dynamic")
    kin, _, e2 = _run("kinematic")
    try:
        for a, b in zip(dyn, kin, strict=True):
            assert a["evaluation"]["slot_filled"] == b["evaluation"]["slot_filled"]
            assert a["tiles_placed"] == b["tiles_placed"]
        p1, p2 = e1.cell.tile_poses(), e2.cell.tile_poses()
        np.testing.assert_allclose(p1.pos[:N_SLOTS, :2], p2.pos[:N_SLOTS, :2], atol=5e-4)
    finally:
        e1.close()
        e2.close()


@pytest.fixture
def discrete_env() -> Iterator[MosaicAssemblyEnv]:
    """A kinematic ``pick_place_discrete`` env on the paper's mixed design, reset with seed 0."""
    env = MosaicAssemblyEnv(**FAST_DISCRETE)
    env.reset(seed=0)
    yield env
    env.close()


def test_wrong_slot_is_misplaced_and_penalised(discrete_env: MosaicAssemblyEnv) -> None:
    env = discrete_env
    classes = env.task.slot_class
    wrong = int(np.flatnonzero(classes != env.task.tile_class[0])[0])
    _, r, _, _, info = env.step(env.index.encode(0, wrong))  # cell indices -> agent's
    assert info["evaluation"]["misplaced"] == 1 and info["evaluation"]["correct"] == 0
    assert r == pytest.approx(-env.config.penalty_misplaced)
    # Picking the already placed tile again is a failed action, not a crash.
    _, r, _, _, info = env.step(env.index.encode(0, 0))
    assert info["action_failed"] and r < 0


def test_empty_pick_fails_cleanly() -> None:
    env = MosaicAssemblyEnv(execution="kinematic", obs_mode="state", max_slots=N_SLOTS)
    try:
        env.reset(seed=0)
        spec = env.task_spec
        corner = spec.pick.lo + 0.002  # the tile layout keeps clear of the area's edges
        a = env.pick_place_action(corner, 0.0, spec.place.centre, 0.0)
        _, r, term, _, info = env.step(a)
        assert info["action_failed"] and "no tile" in info["action_error"]
        assert r == pytest.approx(-env.config.penalty_failed_action) and not term
    finally:
        env.close()


def test_camera_models_at_observation_and_full_resolution() -> None:
    env = MosaicAssemblyEnv(obs_mode="rgb", max_slots=N_SLOTS, image_size=(48, 64))
    try:
        small = env.camera_model("input")
        full = env.camera_model("output_camera", 492, 656)
        assert (small.width, small.height) == (64, 48)
        assert (full.width, full.height) == (656, 492)
    finally:
        env.close()


def test_nothing_placeable_terminates() -> None:
    env = MosaicAssemblyEnv(execution="kinematic", obs_mode="state", max_slots=1)
    try:
        env.reset(seed=0)
        cmd = transfer_poses(env.cell, 0, 0)
        off = np.asarray(cmd.place_xy) + [env.config.position_tolerance * 3, 0.0]  # too far
        _, r, term, _, info = env.step(
            env.task_spec.codec.encode(dataclasses.replace(cmd, place_xy=tuple(off)))
        )
        ev = info["evaluation"]
        assert ev["misplaced"] == 1 and ev["correct"] == 0 and ev["placeable"] == 0
        assert term and not ev["success"] and ev["failure"]
        assert ev["position_error_mm"] == pytest.approx(
            3 * 1e3 * env.config.position_tolerance, abs=0.3
        )
    finally:
        env.close()


def test_distractor_placed_is_counted() -> None:
    env = MosaicAssemblyEnv(
        action_mode="pick_place_discrete",
        execution="kinematic",
        obs_mode="state",
        max_slots=3,
        distractor_rate=1.0,
    )
    try:
        env.reset(seed=0)
        d = int(np.flatnonzero(env.cell.is_distractor)[0])
        assert env.action_space.nvec[0] == len(env.cell.tiles) > 3
        _, r, _, _, info = env.step(env.index.encode(d, 0))
        assert not info["action_failed"], info["action_error"]
        assert info["evaluation"]["distractors_placed"] == 1
        assert info["reward_distractor"] == -env.config.penalty_distractor
    finally:
        env.close()


def test_stream_feed_large_design() -> None:
    env = MosaicAssemblyEnv(
        design="hexagon",
        feed="stream",
        action_mode="joint",
        obs_mode="state",
        stream_initial=6,
    )
    try:
        env.reset(seed=0)
        assert env.cell.on_stage.sum() == 6
        for _ in range(round(2.6 / env.config.control_dt)):  # past one stream period (2.5 s)
            env.step(np.zeros(7, np.float32))
        assert env.cell.on_stage.sum() > 6  # streamed in
        assert env.evaluate().placeable == len(env.cell.slots)
    finally:
        env.close()


def test_info_keys_and_dense_terms() -> None:
    from envs.task import REWARD_TERMS  # noqa: PLC0415

    env = MosaicAssemblyEnv(
        execution="kinematic", obs_mode="state", max_slots=2, reward_mode="dense"
    )
    try:
        _, info = env.reset(seed=0)
        _, r, _, _, info = env.step(env.expert_action(0, 0))
        for key in ("sim_time", "tiles_placed", "tiles_per_min", "evaluation", "is_success"):
            assert key in info
        terms = {t: info[f"reward_{t}"] for t in REWARD_TERMS}
        assert r == pytest.approx(sum(terms.values()))
        assert terms["correct"] == env.config.reward_correct and terms["reach"] < 0
        for key in ("success", "correct", "misplaced", "dropped", "lost", "distractors_placed"):
            assert key in info["evaluation"]
        assert info["evaluation"] == env.evaluate().as_dict()
    finally:
        env.close()


def test_tile_into_a_filled_slot_is_misplaced_and_penalised(
    discrete_env: MosaicAssemblyEnv,
) -> None:
    env = discrete_env
    task = env.task
    twin = int(np.flatnonzero(task.tile_class == task.tile_class[0])[1])  # same class
    _, r, _, _, info = env.step(env.expert_action(0, 0))
    assert info["evaluation"]["correct"] == 1 and r == pytest.approx(env.config.reward_correct)
    _, r, _, _, info = env.step(env.expert_action(twin, 0))
    ev = info["evaluation"]
    assert not info["action_failed"], info["action_error"]
    assert ev["misplaced"] == 1 and ev["correct"] == 1 and ev["slot_filled"][0]
    assert info["reward_misplaced"] == -env.config.penalty_misplaced
    assert r == pytest.approx(-env.config.penalty_misplaced)
    assert ev["placeable"] == len(env.cell.slots) - 2  # the twin's class has no open slot


def test_frame_listener_renders_inside_a_dynamic_cycle() -> None:
    env = gym.make("envs:MosaicAssembly-v0", max_slots=2, render_mode="rgb_array")
    u = env.unwrapped
    times: list[float] = []
    frames: list[np.ndarray] = []

    def grab() -> None:
        times.append(u.cell.time)
        frames.append(u.cell.render("overview", 48, 64))

    u.add_frame_listener(grab, 10.0)
    try:
        env.reset(seed=0)
        _, _, _, _, info = env.step(u.expert_action(0, 0))
        # one cycle of ~1.9 s simulated: a frame every 0.1 s of it, not one per step
        assert len(times) == pytest.approx(info["sim_time"] / 0.1, abs=2)
        assert np.allclose(np.diff(times), 0.1, atol=0.0025)
        assert not np.array_equal(frames[0], frames[len(frames) // 2])  # the arm moved
        n = len(times)
        env.reset(seed=1)  # the schedule restarts at reset
        env.step(u.expert_action(1, 1))
        assert len(times) > n + 5
    finally:
        env.close()


@pytest.mark.parametrize("fps", [0.0, -1.0, float("nan")])
def test_frame_listener_rejects_bad_rates(fps: float) -> None:
    env = gym.make("envs:MosaicAssembly-v0", max_slots=1, execution="kinematic")
    try:
        with pytest.raises(MosaicEnvError, match="fps"):
            env.unwrapped.add_frame_listener(lambda: None, fps)
    finally:
        env.close()


def test_executors_of_one_arm_share_its_planners_within_a_bound(kinematic_env: gym.Env) -> None:
    """A procedural env builds an executor per reset: the planner and tracker of its arm are
    made once (`arm_planners`), the last `ARM_PLANNERS` (arm, settings, timestep) kept."""
    from envs.cell.pick_place import ARM_PLANNERS, arm_planners  # noqa: PLC0415
    from planners.config import load_planner_config  # noqa: PLC0415

    ik = kinematic_env.unwrapped.ik  # type: ignore[attr-defined]
    cfg = load_planner_config("planner")
    first = arm_planners(ik, cfg, 0.002)
    assert arm_planners(ik, cfg, 0.002) == first
    assert arm_planners(ik, load_planner_config("planner"), 0.002)[0] is not first[0]
    for k in range(ARM_PLANNERS):
        arm_planners(ik, cfg, 0.001 * (k + 3))
    assert arm_planners(ik, cfg, 0.002)[0] is not first[0]  # dropped, made anew
