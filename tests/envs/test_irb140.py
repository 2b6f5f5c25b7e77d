"""The IRB 140 model against the public DH/OPW facts (ABB product specification), and the working
areas reachable with the tool pointing straight down, in both layouts."""

from __future__ import annotations

import itertools
from pathlib import Path

import mujoco
import numpy as np
import pytest

from envs.cell.cell import Cell
from envs.cell.config import CellConfig, InputBeltConfig, LayoutConfig
from envs.cell.tiles.shapes import basic_shapes
from tests.envs.cell_motion import ArmIKFor, tool_down

ASSET = Path(__file__).resolve().parents[2] / "assets" / "irb140"

# Standard DH of the IRB 140 (public kinematic data); theta_i = q_i + OFFSET_i.
DH_D = np.array([0.352, 0.0, 0.0, 0.380, 0.0, 0.065])
DH_A = np.array([0.070, 0.360, 0.0, 0.0, 0.0, 0.0])
DH_ALPHA = np.deg2rad([-90.0, 0.0, -90.0, 90.0, -90.0, 0.0])
OFFSET = np.array([0.0, -np.pi / 2, 0.0, 0.0, 0.0, 0.0])
ABB_OFFSET = OFFSET + [0.0, 0.0, 0.0, 0.0, 0.0, np.pi]
"""ABB's own convention: theta6 + 180 deg, whose frame 6 is ABB's tool0."""
RANGES_DEG = np.array([[-180, 180], [-90, 110], [-230, 50], [-200, 200], [-115, 115], [-400, 400]])
SPEEDS_DEG = np.array([200, 200, 260, 360, 360, 450])


def dh_fk(q: np.ndarray, offset: np.ndarray = OFFSET) -> np.ndarray:
    """Frame 6 pose (4x4) from the standard DH table with joint offsets ``offset`` [rad]."""
    t = np.eye(4)
    for i in range(6):
        th = q[i] + offset[i]
        ct, st = np.cos(th), np.sin(th)
        ca, sa = np.cos(DH_ALPHA[i]), np.sin(DH_ALPHA[i])
        t = t @ np.array(
            [
                [ct, -st * ca, st * sa, DH_A[i] * ct],
                [st, ct * ca, -ct * sa, DH_A[i] * st],
                [0.0, sa, ca, DH_D[i]],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )
    return t


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(ASSET / "scene.xml"))


def _site_pose(model: mujoco.MjModel, q: np.ndarray, site: str) -> np.ndarray:
    data = mujoco.MjData(model)
    data.qpos[:6] = q
    mujoco.mj_kinematics(model, data)
    t = np.eye(4)
    t[:3, :3] = data.site(site).xmat.reshape(3, 3)
    t[:3, 3] = data.site(site).xpos
    return t


def _configs() -> np.ndarray:
    rng = np.random.default_rng(0)
    lo, hi = np.deg2rad(RANGES_DEG[:, 0]), np.deg2rad(RANGES_DEG[:, 1])
    fixed = np.array([np.zeros(6), [0, 0, 0, 0, np.pi / 2, 0], [0.5, 0.3, -0.4, 1.0, -0.8, 2.0]])
    return np.vstack([fixed, rng.uniform(lo, hi, size=(12, 6))])


@pytest.mark.parametrize("q", list(_configs()))
def test_flange_fk_matches_dh(model: mujoco.MjModel, q: np.ndarray) -> None:
    got = _site_pose(model, q, "flange")
    want = dh_fk(q)
    assert np.linalg.norm(got[:3, 3] - want[:3, 3]) < 1e-4  # 0.1 mm
    assert np.allclose(got[:3, :3], want[:3, :3], atol=1e-5)


@pytest.mark.parametrize("q", list(_configs()))
def test_abb_tool0_matches_dh_with_the_theta6_offset(model: mujoco.MjModel, q: np.ndarray) -> None:
    got = _site_pose(model, q, "abb_tool0")
    want = dh_fk(q, ABB_OFFSET)
    assert np.linalg.norm(got[:3, 3] - want[:3, 3]) < 1e-4  # 0.1 mm
    assert np.allclose(got[:3, :3], want[:3, :3], atol=1e-5)
    flange = _site_pose(model, q, "flange")
    turned = flange[:3, :3] @ np.diag([-1.0, -1.0, 1.0])  # 180 deg about the tool axis
    assert np.allclose(got[:3, :3], turned, atol=1e-6)


def test_abb_tool0_at_zero_points_x_down_z_forward(model: mujoco.MjModel) -> None:
    r = _site_pose(model, np.zeros(6), "abb_tool0")[:3, :3]
    np.testing.assert_allclose(r[:, 0], [0.0, 0.0, -1.0], atol=1e-6)  # x down
    np.testing.assert_allclose(r[:, 2], [1.0, 0.0, 0.0], atol=1e-6)  # z out of the flange


def test_tcp_is_on_tool_axis(model: mujoco.MjModel) -> None:
    q = np.array([0.3, 0.2, -0.3, 0.5, 1.0, -0.7])
    flange = _site_pose(model, q, "flange")
    tcp = _site_pose(model, q, "tcp")
    offset = np.linalg.inv(flange) @ tcp
    assert np.allclose(offset[:3, :3], np.eye(3), atol=1e-9)
    assert np.allclose(offset[:3, 3], [0.0, 0.0, 0.1], atol=1e-9)


def test_home_points_tool_down(model: mujoco.MjModel) -> None:
    key = model.key("home")
    tcp = _site_pose(model, key.qpos[:6], "tcp")
    assert tcp[:3, 2] == pytest.approx([0.0, 0.0, -1.0], abs=1e-4)


def test_joint_ranges_and_speed_limits_match_facts(model: mujoco.MjModel) -> None:
    assert np.allclose(np.rad2deg(model.jnt_range[:6]), RANGES_DEG, atol=1e-3)
    vel = model.actuator_ctrlrange[6:12]
    assert np.allclose(np.rad2deg(vel[:, 1]), SPEEDS_DEG, atol=1e-3)
    assert np.allclose(vel[:, 0], -vel[:, 1])


def test_reach_is_810_mm(model: mujoco.MjModel) -> None:
    # Wrist centre at full stretch (upper arm and forearm aligned, pointing forward).
    data = mujoco.MjData(model)
    data.qpos[:6] = [0.0, np.pi / 2, -np.pi / 2, 0.0, 0.0, 0.0]
    mujoco.mj_kinematics(model, data)
    wrist = data.body("link5").xpos
    assert wrist[0] == pytest.approx(0.810, abs=1e-4)
    assert wrist[2] == pytest.approx(0.352, abs=1e-4)


def test_servo_tracks_fast_trajectory(model: mujoco.MjModel) -> None:
    """Position + velocity feed-forward tracks a 0.8x-speed, ~4x-acceleration sine closely."""
    data = mujoco.MjData(model)
    q0 = np.deg2rad([0.0, 10.0, -90.0, 0.0, 0.0, 0.0])
    data.qpos[:6] = q0
    data.qvel[:6] = np.deg2rad(SPEEDS_DEG) * 0.8
    speeds = np.deg2rad(SPEEDS_DEG) * 0.8
    omega = 2 * np.pi * 0.8  # amplitudes 27..72 degrees, accelerations 4-5x the speed limits
    amp = speeds / omega
    worst = 0.0
    for _ in range(1000):
        data.ctrl[:6] = q0 + amp * np.sin(omega * data.time)
        data.ctrl[6:] = amp * omega * np.cos(omega * data.time)
        mujoco.mj_step(model, data)
        want = q0 + amp * np.sin(omega * data.time)
        worst = max(worst, float(np.max(np.abs(data.qpos[:6] - want))))
    assert np.rad2deg(worst) < 0.15
    assert not np.any(data.warning.number)


# Public CAD-based mass splits of the 98 kg arm (kg), see assets/irb140/README.md.
LINK_MASS_RANGES = {
    "link1": (30.0, 38.0),
    "link2": (14.0, 18.0),
    "link3": (17.0, 21.0),
    "link4": (3.0, 4.5),
    "link5": (0.3, 1.0),
    "link6": (0.05, 0.2),
}


def test_link_masses_follow_the_public_splits(model: mujoco.MjModel) -> None:
    for name, (lo, hi) in LINK_MASS_RANGES.items():
        assert lo <= model.body(name).mass[0] <= hi, name
    moving = sum(model.body(n).mass[0] for n in (*LINK_MASS_RANGES, "vacuum_pad"))
    assert 70.0 <= moving <= 76.0
    # Link 2's inertia about its own length (z at zero) about 3x the earlier model's 0.02.
    assert model.body("link2").inertia[2] == pytest.approx(0.06, rel=0.1)


LAYOUTS = {
    "paper_1m": CellConfig(layout=LayoutConfig(belt_separation=1.0, work_x=0.0)),
    "compact_0.5m": CellConfig(
        layout=LayoutConfig(belt_separation=0.5, work_x=0.5),
        input_belt=InputBeltConfig(length=0.6),
    ),
}


@pytest.mark.parametrize("cfg", LAYOUTS.values(), ids=LAYOUTS.keys())
def test_tile_area_and_mesh_reachable_pointing_down(cfg: CellConfig, arm_ik: ArmIKFor) -> None:
    cell = Cell(cfg, basic_shapes()[:1], seed=0)
    ik = arm_ik(cell)
    geo = cell.geometry
    t = cfg.tiles.thickness
    try:
        areas = [
            (geo.input_centre + [0, 0, t], np.asarray(cfg.input_belt.tile_area) / 2),
            (geo.output_centre + [0, 0, t], geo.mesh_size / 2),  # the largest mesh
        ]
        worst_sv = np.inf
        for centre, half in areas:
            for sx, sy, dz, yaw in itertools.product(
                (-1, 0, 1), (-1, 0, 1), (0.0, 0.1), (-np.pi / 2, 0.0, np.pi / 2, np.pi)
            ):
                p = centre + [sx * half[0], sy * half[1], dz]
                q = ik.solve(p, tool_down(yaw), np.asarray(cfg.robot.home))
                pos, rot = ik.fk(q)
                assert np.linalg.norm(pos - p) < 1e-4
                assert np.allclose(rot, tool_down(yaw), atol=1e-4)
                assert np.all(q >= ik.lo) and np.all(q <= ik.hi)
                jp, jr = np.zeros((3, 6)), np.zeros((3, 6))
                mujoco.mj_comPos(ik.model, ik.data)
                mujoco.mj_jacSite(ik.model, ik.data, jp, jr, ik.site)
                worst_sv = min(worst_sv, np.linalg.svd(np.vstack([jp, jr]), compute_uv=False)[-1])
        assert worst_sv > 0.02  # away from singularities everywhere in the working areas
    finally:
        cell.close()
