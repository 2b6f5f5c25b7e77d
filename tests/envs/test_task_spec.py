"""The env's task description: the one boundary agents read."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import envs  # noqa: F401
from agents.scripted.agent import ScriptedAgent
from envs.errors import EnvError
from envs.task import Evaluation
from envs.task_spec import ActionError, PickPlaceCommand, TaskSpec
from planners.robot import robot_joint_speeds

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def env():
    e = gym.make("envs:MosaicAssembly-v0", action_mode="pick_place", max_slots=4)
    yield e
    e.close()


def test_spec_slots_are_the_cells_world_slots(env) -> None:
    spec: TaskSpec = env.get_wrapper_attr("task_spec")
    poses = env.unwrapped.cell.slot_poses_world()
    assert len(spec.slots) == 4
    for s in spec.slots:
        np.testing.assert_allclose([*s.xy, s.yaw], poses[s.index])
        assert s.class_name == env.unwrapped.cell.slots[s.index].shape.name
    np.testing.assert_allclose(spec.mesh_centre, env.unwrapped.cell.geometry.output_centre[:2])


def test_heights_carry_the_one_tile_thickness(env) -> None:
    spec: TaskSpec = env.get_wrapper_attr("task_spec")
    cell = env.unwrapped.cell
    assert spec.tile_thickness == cell.cfg.tiles.thickness
    assert spec.pick.tile_top_z - spec.pick.surface_z == pytest.approx(spec.tile_thickness)
    assert spec.place.tile_top_z - spec.place.surface_z == pytest.approx(spec.tile_thickness)
    assert spec.pick.surface_z == cell.geometry.belt_top
    assert spec.place.surface_z == cell.geometry.mesh_top


def test_codec_round_trip_and_area_check(env) -> None:
    spec: TaskSpec = env.get_wrapper_attr("task_spec")
    codec = spec.codec
    assert codec is not None
    rng = np.random.default_rng(0)
    for _ in range(20):
        cmd = PickPlaceCommand(
            tuple(rng.uniform(codec.pick.lo, codec.pick.hi)),
            float(rng.uniform(-np.pi, np.pi)),
            tuple(rng.uniform(codec.place.lo, codec.place.hi)),
            float(rng.uniform(-np.pi, np.pi)),
        )
        a = codec.encode(cmd)
        assert a.dtype == np.float32 and np.all(np.abs(a) <= 1.0)
        back = codec.decode(a)
        np.testing.assert_allclose(back.pick_xy, cmd.pick_xy, atol=1e-6)
        np.testing.assert_allclose(back.place_xy, cmd.place_xy, atol=1e-6)
        assert back.rotation == pytest.approx(cmd.rotation, abs=1e-5)
    outside = PickPlaceCommand((5.0, 5.0), 0.0, tuple(codec.place.centre), 0.0)
    turned = PickPlaceCommand.between_yaws((0.0, 0.0), 3.0, (0.0, 0.0), -3.0)
    assert turned.rotation == pytest.approx(2 * np.pi - 6.0)  # wrapped once
    with pytest.raises(ActionError, match="outside the areas"):
        codec.encode(outside)


def test_camera_models_are_at_the_observation_size(env) -> None:
    spec: TaskSpec = env.get_wrapper_attr("task_spec")
    h, w = spec.image_size
    assert env.observation_space["input_camera"].shape[:2] == (h, w)
    cam = spec.camera("input_camera")
    assert (cam.height, cam.width) == (h, w)
    with pytest.raises(KeyError, match="allowed"):
        spec.camera("overview")  # type: ignore[arg-type]


def test_agent_is_built_from_the_spec_alone(env) -> None:
    agent = ScriptedAgent.from_env(env, calibrate=False)
    assert agent.spec is env.get_wrapper_attr("task_spec")
    assert [s.index for s in agent.slots] == [0, 1, 2, 3]
    assert agent.tile_top == agent.spec.pick.tile_top_z


def test_agents_know_no_simulator() -> None:
    """The spec carries no cell configuration; no agent module builds or imports the scene."""
    assert "cell" not in {f.name for f in dataclasses.fields(TaskSpec)}
    for path in sorted((ROOT / "agents").glob("*.py")):
        text = path.read_text()
        for banned in ("import mujoco", "build_spec", "envs.cell.scene", "CameraRig"):
            assert banned not in text, f"{path.name} uses {banned}"


def test_the_info_evaluation_is_the_typed_record(env) -> None:
    env.reset(seed=0)
    _, _, _, _, info = env.step(env.unwrapped.expert_action(0, 0))
    ev = Evaluation.from_info(info)
    assert ev.as_dict() == info["evaluation"] and ev.correct == 1
    assert info["tiles_per_min"] == ev.tiles_per_min(info["sim_time"])
    # A failed episode is measured over the horizon when that is longer than its own time.
    late = dataclasses.replace(ev, success=False)
    assert late.tiles_per_min(info["sim_time"], 600.0) == pytest.approx(0.1)
    with pytest.raises(EnvError, match="evaluation"):
        Evaluation.from_info({"sim_time": 1.0})


@pytest.mark.parametrize(
    "path",
    [
        "agents/scripted/agent.py",
        "agents/scripted/perception.py",
        "agents/scripted/placement.py",
        "agents/scripted/calibration.py",
        "apps/main.py",
    ],
)
def test_the_policy_and_the_main_job_never_reach_into_the_env(path: str) -> None:
    text = (ROOT / path).read_text()
    assert not re.search(r"\.unwrapped\b", text), f"{path} reads env.unwrapped"
    assert "set_qpos" not in text, f"{path} teleports the arm"


def test_move_home_plans_a_real_move() -> None:
    e = gym.make("envs:MosaicAssembly-v0", action_mode="pick_place", obs_mode="state", max_slots=1)
    try:
        e.reset(seed=0)
        e.step(e.unwrapped.expert_action(0, 0))
        cell = e.unwrapped.cell
        home = np.asarray(cell.cfg.robot.home)
        assert np.abs(cell.qpos - home).max() > 0.1
        t0 = cell.time
        obs = e.get_wrapper_attr("move_home")()
        assert np.abs(cell.qpos - home).max() < 2e-3  # tracked to rest at home
        assert cell.time - t0 > 0.2  # a planned, timed move, not a teleport
        assert "robot" in obs
    finally:
        e.close()


def test_move_home_observes_in_the_action_order() -> None:
    e = gym.make(
        "envs:MosaicDecision6-v1", obs_mode="state", execution="kinematic", design="paper_mixed"
    )
    try:
        obs, _ = e.reset(seed=3)
        home = e.get_wrapper_attr("move_home")()  # the arm starts at home: nothing moves
        np.testing.assert_allclose(home["tiles"], obs["tiles"], atol=1e-6)
        np.testing.assert_allclose(home["slots"], obs["slots"], atol=1e-6)
    finally:
        e.close()


def test_joint_step_is_the_joint_move_of_a_full_action() -> None:
    """``joint_step`` = speed limits x control period; a full action moves a joint that far."""
    e = gym.make("envs:MosaicAssembly-v0", action_mode="joint", obs_mode="state", max_slots=1)
    spec: TaskSpec = e.get_wrapper_attr("task_spec")
    assert spec.joint_step is not None and spec.tool_step is None
    period = 0.04  # the default control period [s]
    np.testing.assert_allclose(spec.joint_step, np.asarray(robot_joint_speeds()) * period)
    obs, _ = e.reset(seed=0)
    q0 = obs["robot"][:6].copy()
    full = np.array([1.0, 0.0, 0.0, 0.0, 0.0, -1.0, -1.0], np.float32)
    for _ in range(3):
        e.step(full)
    for _ in range(10):  # the servo settles on the target
        obs = e.step(np.array([0.0] * 6 + [-1.0], np.float32))[0]
    e.close()
    moved = obs["robot"][:6] - q0
    expected = np.array([3.0, 0.0, 0.0, 0.0, 0.0, -3.0]) * np.asarray(spec.joint_step)
    np.testing.assert_allclose(moved, expected, atol=2e-3)
    cartesian = gym.make("envs:MosaicAssembly-v0", action_mode="cartesian", max_slots=1)
    assert cartesian.get_wrapper_attr("task_spec").joint_step is None
    cartesian.close()
