r"""Why the behaviour clone of the joint controller does not place on ``MosaicOneTileJoint-v1``.

The RLPD row of the joint rung (``configs/train/rlpd_one_tile_joint.yaml``) starts from an
actor cloned from the scripted joint controller's DART demonstrations. This script measures, at
the pad, in millimetres and degrees, what the clone does differently from its teacher:

1. **Clone.** The actor is cloned as ``apps.train`` does before RL (the same config, SAC model,
   standardised relative features and `apps.train_extras.clone_before_learning`) and saved
   (``--model``; reused when the file exists). ``--std-fit`` sets ``bc_std_fit``.
2. **Demonstrations.** The teacher's pad at its seals in the dataset (height above the tile's
   top, offset from its centre, tilt from the recorded joints through the arm model's forward
   kinematics), the share of saturated action labels per axis, and the clone's action
   distribution on the demonstrated states (SAC's squashed Gaussian: mean and standard deviation
   before the tanh).
3. **Rollouts** on held-out seeds of the scripted controller
   (`agents.experts.joint.LowLevelJointExpert`), the clone's deterministic action, and the
   clone's sampled action (what SAC's training episodes, the RLPD run's 35 included, execute).
   Per episode: placed, the pad's events (seal, release, drop) by control step, the pad at the
   seal (height [mm], offset [mm], tilt [deg], vacuum entry, joint target minus observed joint
   [deg]) and, over the steps near the tile before it, the share meeting each seal condition
   of `envs.cell.suction.Suction`. For the deterministic clone: the chance, under sampling, that
   the vacuum entry stays on over every held step (the product of ``1 - P(off)``).
4. A per-step trace near the tile for the first seed (controller and clone).

Run::

    export MUJOCO_GL=egl PYOPENGL_PLATFORM=egl
    nice -n 19 .venv/bin/python scripts/joint_clone_diagnosis.py \
        --model runs/joint_clone/clone.zip --seeds 1000 1001 1002 1003 1004
    nice -n 19 .venv/bin/python scripts/joint_clone_diagnosis.py --std-fit clipped \
        --model runs/joint_clone/clone_clipped.zip --seeds 1000 1001 1002 1003 1004

``--sweep-seeds`` adds, for every policy, one line over more seeds: placed, sealed, and how
the sealed but unplaced episodes ended (let go in the carry, dropped, still held at the time
limit). ``--model`` may also name an ``apps.train`` run's ``model.zip`` (a run stopped during
its ``hold_actor_steps`` saves the clone plus one SAC update: before `hold_actor` put the
actor back before every action, that is what acted in the hold).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import mujoco
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import envs  # noqa: E402, F401  registers the ladder
from agents.experts.joint import LowLevelJointExpert, load_joint_expert_config  # noqa: E402
from agents.learning.demos import DEFAULT_ROOT, load_dataset, transitions  # noqa: E402
from apps.train import build_model, load_train_config, make_vec  # noqa: E402
from apps.train_extras import clone_before_learning  # noqa: E402
from envs.observations.fields import ROBOT_FIELDS, SLOT_FIELDS, TILE_FIELDS  # noqa: E402
from planners.robot import ROBOT_XML  # noqa: E402

TASK = "MosaicOneTileJoint-v1"
"""The rung diagnosed."""
TRAIN_CONFIG = "rlpd_one_tile_joint"
"""The RLPD config whose clone is diagnosed (``configs/train/``)."""
TEACHER_CONFIG = "lowlevel_joint_expert_smooth"
"""The controller settings the demonstrations were recorded with."""
NEAR_XY = 6.0
"""Horizontal pad-to-tile offset [mm] within which a step counts as near the tile."""
NEAR_Z = 25.0
"""Pad height above the tile's top [mm] under which a step counts as near the tile."""
TRACE_BEFORE = 6
"""Steps of the per-step trace before the seal (or the first near step)."""
TRACE_AFTER = 4
"""Steps of the per-step trace after it."""
SATURATED = 0.999
"""An action label at least this large in magnitude counts as saturated."""
LET_GO_FAR = 20.0
"""A tile let go farther than this from its slot [mm] was let go in the carry, not at the slot."""
MM = 1000.0
"""Millimetres per metre."""
AXES = ("J1", "J2", "J3", "J4", "J5", "J6", "vacuum")
"""Names of the ``joint`` action's entries."""

Policy = Callable[[dict[str, np.ndarray]], np.ndarray]


@dataclass(frozen=True)
class StepLog:
    """The pad and the seal conditions after one control step.

    Attributes:
        step: Control step (0 is the first action).
        height: Pad face above the nearest tile's top [mm] (negative: pressed in).
        offset: Pad centre's horizontal distance from that tile's centre [mm].
        tilt: Tool axis from vertical [deg].
        vacuum_action: The action's vacuum entry (on when > 0).
        vacuum_on: The pad's vacuum is on.
        gap_ok: Height within the seal's gap band.
        tilt_ok: Tilt within the seal's tilt limit.
        over_tile: Pad centre over tile material.
        held: A tile is sealed.
        lag: Largest joint target minus observed joint [deg].
        to_slot: The observed tile's horizontal distance from its slot [mm].
    """

    step: int
    height: float
    offset: float
    tilt: float
    vacuum_action: float
    vacuum_on: bool
    gap_ok: bool
    tilt_ok: bool
    over_tile: bool
    held: bool
    lag: float
    to_slot: float

    @property
    def near(self) -> bool:
        """Within `NEAR_XY` of the tile's centre and under `NEAR_Z` above its top."""
        return self.offset <= NEAR_XY and self.height <= NEAR_Z


@dataclass(frozen=True)
class Episode:
    """One logged episode.

    Attributes:
        seed: Reset seed.
        logs: One `StepLog` per control step.
        success: The episode ended with the tile placed.
        events: The pad's events as (kind, control step): ``grasp`` (sealed), ``release``
            (vacuum switched off), ``drop`` (pull or shear over the vacuum's force).
    """

    seed: int
    logs: list[StepLog]
    success: bool
    events: list[tuple[str, int]]

    def first(self, kind: str) -> int | None:
        """Control step of the first event ``kind``, or None."""
        return next((step for k, step in self.events if k == kind), None)


def _tilt_deg(axis: np.ndarray) -> float:
    return math.degrees(math.acos(min(1.0, abs(float(axis[2])))))


def _pad_state(env: gym.Env) -> tuple[float, float, float, bool]:
    """Height [mm], offset [mm], tilt [deg] of the pad over the nearest tile; pad over it.

    Over it: the pad centre over the tile's material (the seal's outline test, whatever the
    gap). The nearest tile is the one whose centre is closest to the pad horizontally.
    """
    import shapely  # noqa: PLC0415

    u: Any = env.unwrapped
    cell = u.cell
    data = cell.data
    pos, rot = cell.tcp_pose()
    bodies = cell.ids.tile_body
    i = int(np.argmin(np.hypot(*(data.xpos[bodies, :2] - pos[:2]).T)))
    tile = data.xpos[bodies[i]]
    height = (pos[2] - tile[2] - u.task_spec.tile_thickness / 2) * MM
    offset = float(np.hypot(*(pos[:2] - tile[:2]))) * MM
    local = data.xmat[bodies[i]].reshape(3, 3).T @ (pos - tile)
    t = cell.tiles[i]
    over = bool(shapely.contains_xy(shapely.Polygon(t.outline, t.holes), local[0], local[1]))
    return height, offset, _tilt_deg(rot[:, 2]), over


def rollout(env: gym.Env, policy: Policy, seed: int) -> Episode:
    """One episode of ``policy`` from ``env.reset(seed=seed)``, logged per step."""
    obs, _ = env.reset(seed=seed)
    u: Any = env.unwrapped
    suction = u.cell.suction.cfg
    t0 = u.cell.time
    logs: list[StepLog] = []
    done, success = False, False
    while not done:
        action = np.asarray(policy(obs), np.float32)
        obs, _, term, trunc, info = env.step(action)
        done = bool(term or trunc)
        success = bool(info.get("is_success", success))
        height, offset, tilt, over = _pad_state(env)
        lag = float(np.degrees(np.max(np.abs(u.actions.target - u.cell.qpos))))
        tile, slot = obs["tiles"][TILE_FIELDS["xyz"]], obs["slots"][SLOT_FIELDS["xy"]]
        band = -u.task_spec.tile_thickness / 2 * MM <= height <= suction.seal_max_gap * MM
        logs.append(
            StepLog(
                len(logs),
                height,
                offset,
                tilt,
                float(action[-1]),
                bool(u.cell.vacuum_on),
                band,
                tilt <= suction.seal_max_tilt_deg,
                over,
                bool(u.cell.tile_held),
                lag,
                float(np.hypot(*(tile[:2] - slot))) * MM,
            )
        )
    period = u.config.control_dt
    events = [(e.kind, math.ceil((e.time - t0) / period - 1e-6) - 1) for e in u.cell.events]
    return Episode(seed, logs, success, events)


def _mean(values: Sequence[float]) -> float:
    return float(np.mean(values)) if len(values) else float("nan")


def summarise(name: str, episodes: Sequence[Episode]) -> None:
    """One row per episode: its events, the pad at the seal, the seal conditions near the tile."""
    print(f"\n### {name}: placed {sum(e.success for e in episodes)} of {len(episodes)}")
    print(
        "| seed | placed | steps | seal | release | drop | tile to slot at release mm | "
        "height mm | offset mm | tilt deg | vacuum | lag deg | near steps before | gap ok | "
        "tilt ok | over tile | vacuum on |"
    )
    print("|---|" * 1 + "---|" * 16)
    for ep in episodes:
        seal = ep.first("grasp")
        before = [g for g in ep.logs[: seal if seal is not None else None] if g.near]
        shares = [
            _mean([float(getattr(g, k)) for g in before])
            for k in ("gap_ok", "tilt_ok", "over_tile", "vacuum_on")
        ]
        cells = ["-"] * 5
        if seal is not None:
            g = ep.logs[seal]
            cells = [
                f"{g.height:.2f}",
                f"{g.offset:.2f}",
                f"{g.tilt:.2f}",
                f"{g.vacuum_action:+.2f}",
                f"{g.lag:.2f}",
            ]
        steps = [ep.first(k) for k in ("grasp", "release", "drop")]
        let_go = steps[1] if steps[1] is not None else steps[2]
        print(
            f"| {ep.seed} | {'yes' if ep.success else 'no'} | {len(ep.logs)} | "
            + " | ".join("-" if s is None else str(s) for s in steps)
            + (f" | {ep.logs[let_go].to_slot:.1f} | " if let_go is not None else " | - | ")
            + " | ".join(cells)
            + f" | {len(before)} | "
            + " | ".join(f"{v:.2f}" for v in shares)
            + " |"
        )


def sweep_line(episodes: Sequence[Episode]) -> str:
    """Placed, sealed, and how the unplaced sealed ones ended, over ``episodes``."""
    n = len(episodes)
    sealed = [e for e in episodes if e.first("grasp") is not None]
    missed = [e for e in sealed if not e.success]
    far = [e for e in missed if _let_go_far(e)]
    dropped = [e for e in missed if e.first("drop") is not None]
    kept = [e for e in missed if e.first("release") is None and e.first("drop") is None]
    return (
        f"placed {sum(e.success for e in episodes)} of {n}; sealed {len(sealed)} of {n}; of the "
        f"sealed, not placed: {len(missed)} ({len(far)} let go over {LET_GO_FAR:.0f} mm from "
        f"the slot, {len(dropped)} by a drop, {len(kept)} still held at the episode's end)"
    )


def _let_go_far(ep: Episode) -> bool:
    steps = [s for s in (ep.first("release"), ep.first("drop")) if s is not None]
    return bool(steps) and ep.logs[min(steps)].to_slot > LET_GO_FAR


def trace(name: str, ep: Episode) -> None:
    """The steps around the seal (or the first near step) of one episode."""
    seal = ep.first("grasp")
    near = [g.step for g in ep.logs if g.near]
    centre = seal if seal is not None else (near[0] if near else None)
    print(f"\n#### {name}, seed {ep.seed}: per step near the tile")
    if centre is None:
        print("never near the tile")
        return
    print("| step | height mm | offset mm | tilt deg | vacuum | vac on | held | lag deg |")
    print("|---|---|---|---|---|---|---|---|")
    for g in ep.logs[max(0, centre - TRACE_BEFORE) : centre + TRACE_AFTER]:
        print(
            f"| {g.step} | {g.height:.2f} | {g.offset:.2f} | {g.tilt:.2f} | "
            f"{g.vacuum_action:+.2f} | {int(g.vacuum_on)} | {int(g.held)} | {g.lag:.2f} |"
        )


def _stats(x: np.ndarray, digits: int = 2) -> str:
    q = np.percentile(x, [5, 50, 95])
    return f"median {q[1]:.{digits}f} [5-95 %: {q[0]:.{digits}f}, {q[2]:.{digits}f}]"


def demo_seals(dataset: Any, thickness: float) -> None:
    """The teacher's pad at its seals (the first observation with the held flag on)."""
    model = mujoco.MjModel.from_xml_path(str(ROBOT_XML))
    data = mujoco.MjData(model)
    site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "tcp")
    held, tool = ROBOT_FIELDS["held"].start, ROBOT_FIELDS["tool_pos"]
    joints, xyz = ROBOT_FIELDS["joint_pos"], TILE_FIELDS["xyz"]
    rows = []
    for ep in dataset.iterate_episodes():
        robot = np.asarray(ep.observations["robot"])
        tiles = np.asarray(ep.observations["tiles"])
        on = np.flatnonzero(robot[:, held] > 0.5)
        if len(on) == 0:
            continue
        k = int(on[0])
        data.qpos[:] = robot[k, joints]
        mujoco.mj_kinematics(model, data)
        d = robot[k, tool] - tiles[k, xyz]
        rows.append(
            (
                (d[2] - thickness / 2) * MM,
                float(np.hypot(d[0], d[1])) * MM,
                _tilt_deg(data.site_xmat[site].reshape(3, 3)[:, 2]),
                k - 1,
            )
        )
    arr = np.array(rows)
    print(
        f"- teacher at its {len(arr)} seals: height {_stats(arr[:, 0])} mm, offset "
        f"{_stats(arr[:, 1])} mm, tilt {_stats(arr[:, 2])} deg, step {_stats(arr[:, 3], 0)}"
    )


def action_table(model: Any, demos: Any) -> None:
    """Per action axis: saturated labels and the clone's distribution on the demo states."""
    import torch  # noqa: PLC0415

    obs, _ = model.policy.obs_to_tensor(demos.observations)
    with torch.no_grad():
        mean, log_std, _ = model.actor.get_action_dist_params(obs)
    mean, std = mean.numpy(), log_std.exp().numpy()
    act = demos.actions
    err = np.abs(np.tanh(mean) - act)
    print(
        "\n| axis | labels saturated | clone error, median | |mean| (pre-tanh), median | "
        "std (pre-tanh), median | std at its upper clip |"
    )
    print("|---|---|---|---|---|---|")
    top = math.exp(2.0)  # SB3 SAC's LOG_STD_MAX
    for i, name in enumerate(AXES):
        print(
            f"| {name} | {np.mean(np.abs(act[:, i]) >= SATURATED):.2f} | "
            f"{np.median(err[:, i]):.3f} | {np.median(np.abs(mean[:, i])):.2f} | "
            f"{np.median(std[:, i]):.3f} | {np.mean(std[:, i] >= top * 0.999):.2f} |"
        )


def vacuum_keep_odds(model: Any, env: gym.Env, seed: int) -> tuple[float, float, int]:
    """Along the deterministic clone's episode: the chance that a sampled vacuum stays on.

    Counted over the steps that start with a tile held and the deterministic vacuum entry on
    (the carry; the release step itself is meant to switch it off).

    Returns:
        The product of ``1 - P(sampled vacuum entry <= 0)`` over those steps, the largest
        single-step P(off) among them, and their number.
    """
    import torch  # noqa: PLC0415

    obs, _ = env.reset(seed=seed)
    keep, worst, n, done = 1.0, 0.0, 0, False
    while not done:
        tensor, _ = model.policy.obs_to_tensor(obs)
        with torch.no_grad():
            mean, log_std, _ = model.actor.get_action_dist_params(tensor)
        mu = float(mean[0, -1])
        if cast(Any, env.unwrapped).cell.tile_held and mu > 0:
            sd = float(log_std[0, -1].exp())
            p_off = 0.5 * (1 + math.erf(-mu / (sd * math.sqrt(2))))
            keep *= 1 - p_off
            worst = max(worst, p_off)
            n += 1
        obs, _, term, trunc, _ = env.step(np.tanh(mean[0].numpy()).astype(np.float32))
        done = bool(term or trunc)
    return keep, worst, n


def clone(model_path: Path, std_fit: str) -> Any:
    """The config's cloned actor (built and cloned as ``apps.train`` does), saved, reloaded."""
    import torch  # noqa: PLC0415

    from agents.learning.rlpd import load_without_demos  # noqa: PLC0415

    if model_path.exists():
        print(f"- clone: {model_path} (reused)")
        return load_without_demos(model_path)
    cfg = load_train_config(TRAIN_CONFIG, bc_std_fit=std_fit)
    torch.set_num_threads(cfg.torch_threads)
    venv = make_vec(cfg, None)
    model = build_model(cfg, venv)
    c0 = time.process_time()
    clone_before_learning(model, cfg.demos, DEFAULT_ROOT, cfg.bc_epochs, cfg.seed, std_fit=std_fit)
    print(
        f"- clone: {cfg.bc_epochs} epochs, std_fit {std_fit}, "
        f"{time.process_time() - c0:.0f} CPU-s, saved to {model_path}"
    )
    model_path.parent.mkdir(parents=True, exist_ok=True)
    model.save(str(model_path))
    venv.close()
    return load_without_demos(model_path)


def policies(model: Any, teacher: LowLevelJointExpert) -> dict[str, Callable[[int], Policy]]:
    """Policy factories by name (the seed seeds the sampled clone's noise)."""
    import torch  # noqa: PLC0415

    def deterministic(_: int) -> Policy:
        return lambda obs: np.asarray(model.predict(obs, deterministic=True)[0])

    def sampled(seed: int) -> Policy:
        torch.manual_seed(seed)
        return lambda obs: np.asarray(model.predict(obs, deterministic=False)[0])

    return {
        "scripted joint controller": lambda _: teacher.act,
        "clone, deterministic": deterministic,
        "clone, sampled (as SAC's training episodes act)": sampled,
    }


def main(argv: list[str] | None = None) -> int:
    """Command line (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", type=Path, default=Path("runs/joint_clone/clone.zip"))
    ap.add_argument("--std-fit", default="mean", help="bc_std_fit of the clone (mean, clipped)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1000, 1001, 1002, 1003, 1004])
    ap.add_argument("--sweep-seeds", type=int, nargs="*", default=[])
    args = ap.parse_args(argv)

    env = gym.make(TASK)
    u: Any = env.unwrapped
    seal = u.cell.suction.cfg
    print(
        f"# {TASK}: the pad seals within {seal.seal_max_gap * MM:.1f} mm of the tile's top, "
        f"{seal.seal_max_tilt_deg:.1f} deg of vertical, centre over the tile, vacuum on"
    )
    cfg = load_train_config(TRAIN_CONFIG)
    dataset = load_dataset(cfg.demos, DEFAULT_ROOT)
    demo_seals(dataset, u.task_spec.tile_thickness)
    model = clone(args.model, args.std_fit)
    action_table(model, transitions(dataset))

    teacher = LowLevelJointExpert(env, load_joint_expert_config(TEACHER_CONFIG))
    for name, make in policies(model, teacher).items():
        episodes = [rollout(env, make(s), s) for s in args.seeds]
        summarise(name, episodes)
        if "sampled" not in name:
            trace(name, episodes[0])
        if args.sweep_seeds:
            sweep = [rollout(env, make(s), s) for s in args.sweep_seeds]
            print(
                f"\n{name}, seeds {args.sweep_seeds[0]}-{args.sweep_seeds[-1]}: "
                + sweep_line(sweep)
            )
    print("\n| seed | P(sampled vacuum stays on over the carry) | worst step P(off) | steps |")
    print("|---|---|---|---|")
    for s in args.seeds:
        keep, worst, n = vacuum_keep_odds(model, env, s)
        print(f"| {s} | {keep:.3f} | {worst:.3f} | {n} |")
    env.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
