r"""The continuous camera policy's placement errors against the 1.5 mm / 2 deg tolerance.

Run::

    python -m benchmarks.learned.camera_continuous --sizes 96x128 192x256 492x656 \
        --out runs/camera_continuous

Plays `agents.camera.continuous.ContinuousCameraPolicy` (the shipped crop scorer plus the
figure fit; ``--checkpoint`` may also be the equivariant policy) on ``MosaicDecision6-v0``
(``--task``: another rung, its evaluation designs in turn) with ``action_mode=pick_place``,
``obs_mode=rgb`` at each image size, over the rung's evaluation seeds (1000-1019). Per size:
slots filled, success, and the error of every tile the policy put on the mesh against the slot
it aimed at (position of the tile's area centroid [mm], yaw modulo the tile's symmetry [deg];
median, 90th percentile, max, share within the tolerances), plus how far the picture put the
tile before the pick (the fit's own error). The errors are scored from the env's privileged
``ground_truth()`` (scoring only; ``info["evaluation"]`` carries only their mean and max over
the tiles on the mesh, checked against them). Writes ``results.json`` and ``errors.png``
(histograms) to ``--out``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from agents.camera.continuous import ContinuousCameraPolicy
from agents.policies import parse_pairs
from apps.cli import CommandParser, run_cli
from apps.evaluate import ENV_ID, task_protocol
from configs.files import write_json
from envs.task_spec import TaskSpec
from spatial.angles import yaw_error
from spatial.tolerance import PLACEMENT_POSITION_TOLERANCE_MM, PLACEMENT_YAW_TOLERANCE_DEG
from spatial.units import MM_PER_M

TASK = "MosaicDecision6-v0"
"""The rung played."""
CHECKPOINT = "checkpoints/MosaicDecision6-v0/BC_camera_crops_rgb/seed_0/camera.pt"
"""The shipped crop scorer."""
SIZES = ("96x128", "192x256", "492x656")
"""Image sizes (height x width) [px]: the training size and two larger ones."""
POSITION_TOL_MM = PLACEMENT_POSITION_TOLERANCE_MM
"""The env's default position tolerance [mm] (``position_tolerance``)."""
YAW_TOL_DEG = PLACEMENT_YAW_TOLERANCE_DEG
"""The env's default yaw tolerance [deg] (``yaw_tolerance_deg``)."""


@dataclass(frozen=True)
class Placement:
    """One tile the policy moved, scored against the slot it aimed at.

    Attributes:
        seed: Episode seed.
        step: Step in the episode.
        same_class: The tile is of the slot's class (its yaw error is meaningful).
        on_mesh: The tile ended on the mesh (inside the place area).
        position_mm: Tile's area centroid to the slot's after the step [mm].
        yaw_deg: Yaw error modulo the tile's symmetry after the step [deg] (NaN: other class).
        fit_position_mm: Fitted centroid to the tile's true one before the pick [mm].
        fit_yaw_deg: Fitted yaw error modulo symmetry before the pick [deg] (NaN: other class).
        turn_overruled: The rotation sent is more than 45 deg from the scorer's quarter turn
            (the fit chose another turn than the scorer; never for a round slot).
    """

    seed: int
    step: int
    same_class: bool
    on_mesh: bool
    position_mm: float
    yaw_deg: float
    fit_position_mm: float
    fit_yaw_deg: float
    turn_overruled: bool


def parse_size(text: str) -> tuple[int, int]:
    """``"96x128"`` -> (96, 128)."""
    h, _, w = text.partition("x")
    return int(h), int(w)


def mm_per_px(spec: TaskSpec) -> float:
    """Size of one input-camera pixel on the tiles' top plane at the image's centre [mm]."""
    cam = spec.camera("input_camera")
    c = np.array([[cam.width / 2, cam.height / 2], [cam.width / 2 + 1, cam.height / 2]])
    p = cam.unproject_to_plane(c, spec.pick.tile_top_z)
    return float(np.linalg.norm(p[1] - p[0]) * MM_PER_M)


def _yaw_deg(yaw: float, target: float, symmetry: int) -> float:
    return 0.0 if symmetry <= 0 else math.degrees(float(yaw_error(yaw, target, symmetry)))


def play_episode(
    env: gym.Env, policy: ContinuousCameraPolicy, seed: int, max_steps: int
) -> tuple[dict[str, Any], list[Placement]]:
    """One episode; its final evaluation and every placement scored."""
    obs, info = env.reset(seed=seed)
    policy.reset()
    base: Any = env.unwrapped
    spec: TaskSpec = env.get_wrapper_attr("task_spec")
    out: list[Placement] = []
    for step in range(max_steps):
        decision = policy.decide(obs, spec)
        if decision is None:
            break
        before = base.ground_truth()  # scoring only
        tile, _ = before.nearest(np.asarray(decision.command.pick_xy))
        slot = spec.slots[decision.slot]
        sym = int(before.symmetry[tile])
        same = before.class_name[tile] == slot.class_name
        fit_yaw = slot.yaw + decision.fit.theta
        scorer_turn = decision.quarter_turns * math.pi / 2
        gap = abs(math.remainder(decision.command.rotation - scorer_turn, 2 * math.pi))
        overruled = slot.symmetry > 0 and gap > math.pi / 4  # a round tile is never turned
        obs, _, terminated, truncated, info = env.step(decision.action)
        after = base.ground_truth()
        xy = after.xy[tile]
        on_mesh = bool(np.all(xy >= spec.place.lo) and np.all(xy <= spec.place.hi))
        out.append(
            Placement(
                seed,
                step,
                bool(same),
                on_mesh,
                float(np.linalg.norm(xy - slot.xy) * MM_PER_M),
                _yaw_deg(float(after.yaw[tile]), slot.yaw, sym) if same else math.nan,
                float(np.linalg.norm(decision.fit.xy - before.xy[tile]) * MM_PER_M),
                _yaw_deg(fit_yaw, float(before.yaw[tile]), sym) if same else math.nan,
                overruled,
            )
        )
        if terminated or truncated:
            break
    return dict(info["evaluation"]), out


def distribution(values: np.ndarray, tol: float) -> dict[str, float]:
    """Median, 90th percentile, max and share within ``tol`` of finite values."""
    v = values[np.isfinite(values)]
    if not len(v):
        return {"n": 0}
    return {
        "n": len(v),
        "median": float(np.median(v)),
        "p90": float(np.percentile(v, 90)),
        "max": float(v.max()),
        "within": float(np.mean(v <= tol)),
    }


def run_size(
    policy: ContinuousCameraPolicy,
    size: tuple[int, int],
    seeds: Sequence[int],
    env_overrides: dict[str, Any] | None = None,
    task: str = TASK,
) -> dict[str, Any]:
    """Every episode at one image size; the row's figures and its placements.

    Args:
        policy: The policy.
        size: Image (height, width) [px].
        seeds: Episode seeds.
        env_overrides: Further env keys (e.g. ``execution``, ``camera_position_jitter``).
        task: The rung whose held-out protocol is played (episodes alternate over its
            evaluation designs, as `apps.evaluate` does).
    """
    overrides, protocol = task_protocol(task)
    overrides = {
        **overrides,
        "action_mode": "pick_place",
        "obs_mode": "rgb",
        **(env_overrides or {}),
    }
    designs: Sequence[str | None] = protocol.designs or (None,)
    envs = [
        gym.make(
            ENV_ID,
            **{**overrides, "image_size": list(size), **({"design": d} if d else {})},
        )
        for d in designs
    ]
    spec: TaskSpec = envs[0].get_wrapper_attr("task_spec")
    mode = str(envs[0].get_wrapper_attr("config").execution)
    t0 = time.process_time()
    evals, placements = [], []
    for i, seed in enumerate(seeds):
        ev, pl = play_episode(envs[i % len(envs)], policy, seed, protocol.max_steps)
        evals.append(ev)
        placements += pl
    cpu = time.process_time() - t0
    for env in envs:
        env.close()
    placed = [p for p in placements if p.on_mesh]
    right = [p for p in placed if p.same_class]  # errors against a slot of the tile's class
    pos = np.array([p.position_mm for p in right])
    yaw = np.array([p.yaw_deg for p in right])
    both = np.array([p.position_mm <= POSITION_TOL_MM and p.yaw_deg <= YAW_TOL_DEG for p in placed])
    return {
        "size": list(size),
        "execution": mode,
        "env": dict(env_overrides or {}),
        "mm_per_px": mm_per_px(spec),
        "episodes": len(seeds),
        "filled": float(np.mean([e["correct"] / max(e["slots"], 1) for e in evals])),
        "success": float(np.mean([e["success"] for e in evals])),
        "placed": len(placed),
        "wrong_class": sum(not p.same_class for p in placed),
        "turn_overruled": sum(p.turn_overruled for p in placements),
        "wrong_class_position_mm": [p.position_mm for p in placed if not p.same_class],
        "position_mm": distribution(pos, POSITION_TOL_MM),
        "yaw_deg": distribution(yaw, YAW_TOL_DEG),
        "within_both": float(both.mean()) if len(both) else math.nan,
        "fit_position_mm": distribution(
            np.array([p.fit_position_mm for p in placements if p.same_class]), POSITION_TOL_MM
        ),
        "fit_yaw_deg": distribution(np.array([p.fit_yaw_deg for p in placements]), YAW_TOL_DEG),
        "env_mean_position_mm": {
            str(seed): e["position_error_mm"] for seed, e in zip(seeds, evals, strict=True)
        },
        "cpu_s": cpu,
        "placements": [asdict(p) for p in placements],
    }


def env_check_mm(row: dict[str, Any]) -> float:
    """Largest gap between the env's mean position error and ours, per episode end [mm].

    The env averages over the tiles on the mesh, each against its nearest slot; ours over the
    tiles placed, each against the slot aimed at (the same slot when the error is small).
    """
    gaps = []
    for seed, env_mean in row["env_mean_position_mm"].items():
        ours = [
            p["position_mm"] for p in row["placements"] if p["seed"] == int(seed) and p["on_mesh"]
        ]
        if ours and env_mean is not None:
            gaps.append(abs(float(np.mean(ours)) - env_mean))
    return max(gaps) if gaps else math.nan


def table(rows: Sequence[dict[str, Any]]) -> str:
    """The rows as a Markdown table."""

    def d(x: dict[str, float], fmt: str) -> str:
        if not x.get("n"):
            return "-"
        return f"{x['median']:{fmt}} / {x['p90']:{fmt}} / {x['max']:{fmt}} ({x['within']:.2f})"

    head = (
        "image (h x w)",
        "execution",
        "env",
        "mm/px",
        "filled",
        "success",
        "placed (wrong class)",
        "position mm: median / p90 / max (within 1.5), right class",
        "yaw deg: median / p90 / max (within 2), right class",
        "within both, all placed",
        "turns overruled",
        "fit position mm",
        "fit yaw deg",
        "CPU-s",
    )
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        h, w = r["size"]
        cells = (
            f"{h} x {w}",
            r["execution"],
            ", ".join(f"{k}={v}" for k, v in r["env"].items() if k != "execution") or "-",
            f"{r['mm_per_px']:.2f}",
            f"{r['filled']:.2f}",
            f"{r['success']:.2f}",
            f"{r['placed']} ({r['wrong_class']})",
            d(r["position_mm"], ".2f"),
            d(r["yaw_deg"], ".2f"),
            f"{r['within_both']:.2f}",
            str(r["turn_overruled"]),
            d(r["fit_position_mm"], ".2f"),
            d(r["fit_yaw_deg"], ".2f"),
            f"{r['cpu_s']:.0f}",
        )
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plot(rows: Sequence[dict[str, Any]], path: Path, task: str = TASK) -> None:
    """Histograms of the position and yaw errors per image size, tolerances marked."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    for key, tol, ax, unit in (
        ("position_mm", POSITION_TOL_MM, axes[0], "position error [mm]"),
        ("yaw_deg", YAW_TOL_DEG, axes[1], "yaw error modulo symmetry [deg]"),
    ):
        top = tol * 1.5
        bins = np.linspace(0.0, top, 31)
        for r in rows:
            v = np.array([p[key] for p in r["placements"] if p["on_mesh"]], float)
            v = np.clip(v[np.isfinite(v)], 0.0, top)  # the last bin holds everything beyond
            h, w = r["size"]
            ax.hist(v, bins=bins, histtype="step", linewidth=1.5, label=f"{h} x {w}")
        ax.axvline(tol, color="k", linestyle="--", linewidth=1, label=f"tolerance {tol:g}")
        ax.set_xlabel(unit)
        ax.set_ylabel("tiles placed")
        ax.legend(fontsize=8)
    fig.suptitle(f"{task}, pick_place from the cameras: every tile placed (last bin: beyond)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    """Play each size, print the table, write ``results.json`` and ``errors.png``."""
    assert __doc__ is not None
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--checkpoint", default=CHECKPOINT, help="camera policy (crop scorer or equivariant .pt)"
    )
    ap.add_argument("--task", default=TASK, help="rung whose held-out protocol is played")
    ap.add_argument("--sizes", nargs="+", default=list(SIZES), help="image sizes HxW [px]")
    ap.add_argument("--seeds", nargs="+", type=int, help="episode seeds (default: the rung's)")
    ap.add_argument(
        "--env", nargs="*", default=[], metavar="KEY=VALUE", help="env overrides (e.g. execution)"
    )
    ap.add_argument("--out", type=Path, default=Path("runs/camera_continuous"))
    args = ap.parse_args(argv)
    _, protocol = task_protocol(args.task)
    seeds = args.seeds or list(protocol.seeds)
    policy = ContinuousCameraPolicy.load(args.checkpoint)
    rows = []
    for text in args.sizes:
        row = run_size(policy, parse_size(text), seeds, parse_pairs(args.env), args.task)
        row["env_check_mm"] = env_check_mm(row)
        rows.append(row)
        print(
            f"{text}: {row['cpu_s']:.0f} CPU-s, env mean check {row['env_check_mm']:.3f} mm",
            flush=True,
        )
    print(table(rows))
    write_json(
        args.out / "results.json",
        {"task": args.task, "checkpoint": args.checkpoint, "seeds": seeds, "rows": rows},
    )
    plot(rows, args.out / "errors.png", args.task)
    print(f"wrote {args.out / 'results.json'} and {args.out / 'errors.png'}")
    return rows


if __name__ == "__main__":
    run_cli(main)
