r"""Evaluate policies (scripted, trained checkpoints, random) on the same held-out seeds.

Run::

    python -m agents.evaluate --policies scripted random runs/ppo/model.zip \\
        --seeds 1000-1019 --env-config configs/eval/pick_place_kinematic.yaml [--out out]

Every policy plays one episode per seed in an env built from the same base configuration
(``--env-config``: an env YAML with `EnvConfig` keys, or a ``configs/train`` YAML whose ``env``
is used; ``--env KEY=VALUE`` overrides). Only the keys that define a policy's spaces change per
policy: the scripted agent gets ``action_mode: pick_place`` with camera images at
``--scripted-image-size``; a trained model gets the action/observation keys of its
``train_config.yaml``; ``random`` samples the base env's action space. Episodes end at success,
when nothing is placeable, or after ``--max-steps`` (default 2 x slots) steps.

Prints one table and writes ``<out>/eval.json``, ``<out>/eval.md`` and ``<out>/eval.png``
(matplotlib when installed, else drawn with OpenCV). Columns: success rate, tiles correctly
placed, misplaced and dropped (means per episode), tiles/min (per simulated minute, from
``info["sim_time"]``) and wall seconds per correctly placed tile (policy + simulation).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import yaml

from agents.wrappers import FlatDiscreteActions
from configs import ConfigError, load_yaml

ENV_ID = "envs:MosaicAssembly-v0"
"""Gymnasium id of the environment."""
SCRIPTED_IMAGE_SIZE = (492, 656)
"""Default camera image size of the scripted agent (the camera's full resolution) [px]."""
SPACE_KEYS = ("action_mode", "obs_mode", "image_size", "depth", "rotation_bins")
"""Env keys that define a policy's action and observation spaces (taken from a model's run)."""
STEPS_PER_SLOT = 2
"""Default episode step limit per slot of the design."""
COLUMNS = (
    ("policy", "policy", "{}"),
    ("success_rate", "success", "{:.0%}"),
    ("correct", "correct/ep", "{:.2f}"),
    ("slots", "slots", "{:.0f}"),
    ("misplaced", "misplaced/ep", "{:.2f}"),
    ("dropped", "dropped/ep", "{:.2f}"),
    ("tiles_per_min", "tiles/min (sim)", "{:.1f}"),
    ("wall_s_per_tile", "wall s/tile", "{:.3f}"),
)
"""(key, header, format) of the printed table."""


class EvaluateError(ConfigError):
    """A policy name, seed range or env configuration that cannot be evaluated."""


@dataclass(frozen=True)
class EpisodeResult:
    """One episode of one policy.

    Attributes:
        seed: Reset seed.
        success: Every slot filled correctly.
        correct: Slots filled correctly.
        slots: Slots of the design.
        misplaced: Real tiles on the mesh filling no slot.
        dropped: Tiles the pad lost in transit.
        steps: Env steps.
        sim_s: Simulated time [s].
        wall_s: Wall time of the policy and the env steps (reset excluded) [s].
        episode_return: Sum of rewards.
    """

    seed: int
    success: bool
    correct: int
    slots: int
    misplaced: int
    dropped: int
    steps: int
    sim_s: float
    wall_s: float
    episode_return: float


@dataclass(frozen=True)
class PolicyRow:
    """Aggregate of one policy over the seeds (one table row).

    Attributes:
        policy: Label (``scripted``, ``random`` or the run name).
        episodes: Episodes played.
        success_rate: Fraction of successful episodes.
        correct: Mean slots filled correctly per episode.
        slots: Slots per episode.
        misplaced: Mean misplaced tiles per episode.
        dropped: Mean dropped tiles per episode.
        tiles_per_min: Correct tiles per simulated minute over all episodes.
        wall_s_per_tile: Wall seconds per correct tile over all episodes (None: no tile).
        mean_return: Mean episode return.
        mean_steps: Mean episode length [steps].
        env: Env overrides the policy ran with.
    """

    policy: str
    episodes: int
    success_rate: float
    correct: float
    slots: float
    misplaced: float
    dropped: float
    tiles_per_min: float
    wall_s_per_tile: float | None
    mean_return: float
    mean_steps: float
    env: dict[str, Any]


def parse_seeds(specs: Sequence[str]) -> list[int]:
    """Non-negative seeds from ``1000-1019``, ``1,2,3`` or separate numbers.

    Raises:
        EvaluateError: Not integers or an empty range.
    """
    seeds: list[int] = []
    for spec in specs:
        for part in filter(None, (p.strip() for p in spec.split(","))):
            match = re.fullmatch(r"(\d+)(?:-(\d+))?", part)
            if match is None:
                raise EvaluateError(f"bad seed {part!r}: use 1000-1019 or 1,2,3")
            lo = int(match[1])
            hi = int(match[2]) if match[2] else lo
            if hi < lo:
                raise EvaluateError(f"empty seed range {part!r}")
            seeds.extend(range(lo, hi + 1))
    if not seeds:
        raise EvaluateError("no seeds given")
    return seeds


def load_env_overrides(path: str | Path | None, pairs: Sequence[str] = ()) -> dict[str, Any]:
    """Base env overrides from a YAML (env keys, or a train config's ``env``) and KEY=VALUE.

    Raises:
        EvaluateError: Unknown env key or a malformed pair.
    """
    from envs.env_config import load_env_config  # noqa: PLC0415

    data: dict[str, Any] = {}
    if path is not None:
        raw = load_yaml(path)
        data = dict(raw["env"]) if isinstance(raw.get("env"), dict) else raw
    data.update(_pairs(pairs))
    try:
        load_env_config(**data)
    except ConfigError as exc:
        raise EvaluateError(str(exc)) from exc
    return data


def _run_config(model_path: Path) -> dict[str, Any]:
    """The ``train_config.yaml`` of a run (beside the model or one folder up), or {}."""
    for folder in (model_path.parent, model_path.parent.parent):
        cfg = folder / "train_config.yaml"
        if cfg.is_file():
            data = yaml.safe_load(cfg.read_text(encoding="utf-8"))
            return data if isinstance(data, dict) else {}
    return {}


def _label(model_path: Path) -> str:
    """A short name of a checkpoint: the run folder (plus the file stem if not model.zip)."""
    run = model_path.parent.parent if model_path.parent.name == "checkpoints" else model_path.parent
    return run.name if model_path.name == "model.zip" else f"{run.name}/{model_path.stem}"


Predict = Callable[[dict[str, Any], bool], np.ndarray]
"""A policy step: (observation, episode start) -> action."""


@dataclass
class Policy:
    """A policy bound to its env.

    Attributes:
        label: Table label.
        env_kwargs: Env overrides of its env.
        factory: Builds the per-env predict function (called once the env exists).
        wrap: Wrapper applied to its env (a trained model's `FlatDiscreteActions`), or None.
    """

    label: str
    env_kwargs: dict[str, Any]
    factory: Callable[[gym.Env], Predict]
    wrap: Callable[[gym.Env], gym.Env] | None = None


def _scripted(base: dict[str, Any], image_size: tuple[int, int], calibrate: bool) -> Policy:
    env_kwargs = {
        **base,
        "action_mode": "pick_place",
        "obs_mode": "rgb",
        "image_size": list(image_size),
    }

    def factory(env: gym.Env) -> Predict:
        from agents.scripted import ScriptedAgent  # noqa: PLC0415 - vision stack

        agent = ScriptedAgent.from_env(env, calibrate=calibrate)

        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            return agent.predict(obs, episode_start=np.array([start]))[0]

        return predict

    return Policy("scripted", env_kwargs, factory)


def _random(base: dict[str, Any]) -> Policy:
    def factory(env: gym.Env) -> Predict:
        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            del obs, start
            return np.asarray(env.action_space.sample())

        return predict

    return Policy("random", dict(base), factory)


def _trained(base: dict[str, Any], model_path: Path) -> Policy:
    if not model_path.is_file():
        raise EvaluateError(
            f"unknown policy {str(model_path)!r}: use 'scripted', 'random' or a model .zip path"
        )
    run = _run_config(model_path)
    run_env = dict(run.get("env") or {})
    env_kwargs = {**base, **{k: run_env[k] for k in SPACE_KEYS if k in run_env}}
    algo_name = str(run.get("algo", ""))

    def factory(env: gym.Env) -> Predict:
        from agents.train import algorithm_class  # noqa: PLC0415

        names = [algo_name] if algo_name else ["PPO", "A2C", "DQN", "SAC", "TD3", "DDPG"]
        model = None
        for name in names:
            try:
                model = algorithm_class(name).load(str(model_path), device="cpu")
                break
            except (ValueError, KeyError, RuntimeError, AttributeError):
                continue
        if model is None:
            raise EvaluateError(f"cannot load {model_path} with any of {names}")

        def predict(obs: dict[str, Any], start: bool) -> np.ndarray:
            del start
            return np.asarray(model.predict(obs, deterministic=True)[0])

        return predict

    wrap = FlatDiscreteActions if run.get("flatten_actions") else None
    return Policy(_label(model_path), env_kwargs, factory, wrap)


def make_policies(
    names: Sequence[str],
    base: dict[str, Any],
    scripted_image_size: tuple[int, int] = SCRIPTED_IMAGE_SIZE,
    calibrate: bool = True,
) -> list[Policy]:
    """`Policy` objects for ``scripted``, ``random`` and model paths.

    A name may end with ``@KEY=VALUE[,KEY=VALUE]``: env overrides of that policy only (its
    label keeps them), e.g. ``scripted@execution=dynamic``.

    Raises:
        EvaluateError: A name that is none of those, or a malformed override.
    """
    out = []
    for spec in names:
        name, _, extra = spec.partition("@")
        overrides = _pairs(extra.split(",")) if extra else {}
        if name == "scripted":
            pol = _scripted(base, scripted_image_size, calibrate)
        elif name == "random":
            pol = _random(base)
        else:
            pol = _trained(base, Path(name))
        if overrides:
            pol = Policy(
                spec if name in ("scripted", "random") else f"{pol.label}@{extra}",
                {**pol.env_kwargs, **overrides},
                pol.factory,
                pol.wrap,
            )
        out.append(pol)
    return out


def _pairs(pairs: Sequence[str]) -> dict[str, Any]:
    """``KEY=VALUE`` strings -> a dict (values parsed as YAML).

    Raises:
        EvaluateError: A string without ``=``.
    """
    out: dict[str, Any] = {}
    for pair in pairs:
        if "=" not in pair:
            raise EvaluateError(f"env overrides want KEY=VALUE, got {pair!r}")
        key, value = pair.split("=", 1)
        out[key.strip()] = yaml.safe_load(value)
    return out


def run_episode(env: gym.Env, predict: Predict, seed: int, max_steps: int) -> EpisodeResult:
    """Play one episode from ``reset(seed=seed)`` for at most ``max_steps`` steps."""
    obs, info = env.reset(seed=seed)
    env.action_space.seed(seed)
    total, steps, wall = 0.0, 0, 0.0
    done = False
    while not done and steps < max_steps:
        t0 = time.perf_counter()
        action = predict(obs, steps == 0)
        obs, reward, terminated, truncated, info = env.step(action)
        wall += time.perf_counter() - t0
        total += float(reward)
        steps += 1
        done = terminated or truncated
    ev = info["evaluation"]
    return EpisodeResult(
        seed=seed,
        success=bool(ev["success"]),
        correct=int(ev["correct"]),
        slots=int(ev["slots"]),
        misplaced=int(ev["misplaced"]),
        dropped=int(ev["dropped"]),
        steps=steps,
        sim_s=float(info["sim_time"]),
        wall_s=wall,
        episode_return=total,
    )


def aggregate(label: str, episodes: Sequence[EpisodeResult], env: dict[str, Any]) -> PolicyRow:
    """One table row from a policy's episodes."""
    n = max(len(episodes), 1)
    correct = sum(e.correct for e in episodes)
    sim = sum(e.sim_s for e in episodes)
    wall = sum(e.wall_s for e in episodes)
    return PolicyRow(
        policy=label,
        episodes=len(episodes),
        success_rate=sum(e.success for e in episodes) / n,
        correct=correct / n,
        slots=sum(e.slots for e in episodes) / n,
        misplaced=sum(e.misplaced for e in episodes) / n,
        dropped=sum(e.dropped for e in episodes) / n,
        tiles_per_min=60.0 * correct / sim if sim > 0 else 0.0,
        wall_s_per_tile=wall / correct if correct else None,
        mean_return=sum(e.episode_return for e in episodes) / n,
        mean_steps=sum(e.steps for e in episodes) / n,
        env=env,
    )


def evaluate_policy_set(
    policies: Sequence[Policy],
    seeds: Sequence[int],
    max_steps: int = 0,
    progress: bool = False,
) -> tuple[list[PolicyRow], dict[str, list[EpisodeResult]]]:
    """Play every policy on every seed.

    Args:
        policies: From `make_policies`.
        seeds: Reset seeds (the same for every policy).
        max_steps: Step limit per episode; 0: `STEPS_PER_SLOT` x slots.
        progress: Print one line per episode.

    Returns:
        (rows, episodes by policy label).
    """
    rows: list[PolicyRow] = []
    per: dict[str, list[EpisodeResult]] = {}
    for pol in policies:
        env = gym.make(ENV_ID, **pol.env_kwargs)
        if pol.wrap is not None:
            env = pol.wrap(env)
        try:
            predict = pol.factory(env)
            limit = max_steps or STEPS_PER_SLOT * len(env.unwrapped.task.slot_class)  # type: ignore[attr-defined]
            eps = []
            for seed in seeds:
                ep = run_episode(env, predict, seed, limit)
                eps.append(ep)
                if progress:
                    print(
                        f"  {pol.label} seed {seed}: {ep.correct}/{ep.slots} correct, "
                        f"{ep.misplaced} misplaced, {ep.steps} steps, {ep.wall_s:.2f} s"
                    )
        finally:
            env.close()
        per[pol.label] = eps
        rows.append(aggregate(pol.label, eps, pol.env_kwargs))
    return rows, per


def _fmt(value: Any, spec: str) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return spec.format(value)


def markdown_table(rows: Sequence[PolicyRow]) -> str:
    """The rows as a Markdown table (`COLUMNS`)."""
    head = "| " + " | ".join(h for _, h, _ in COLUMNS) + " |"
    sep = "|" + "|".join("---" for _ in COLUMNS) + "|"
    body = ["| " + " | ".join(_fmt(getattr(r, k), f) for k, _, f in COLUMNS) + " |" for r in rows]
    return "\n".join([head, sep, *body])


def plot(rows: Sequence[PolicyRow], path: Path) -> None:
    """Bar charts of success rate, correct tiles and tiles/min per policy (PNG)."""
    labels = [r.policy for r in rows]
    panels = (
        ("success rate", [r.success_rate for r in rows]),
        ("correct tiles / episode", [r.correct for r in rows]),
        ("tiles / min (simulated)", [r.tiles_per_min for r in rows]),
    )
    try:
        import matplotlib as mpl  # noqa: PLC0415 - optional

        mpl.use("Agg")
        import matplotlib.pyplot as plt  # noqa: PLC0415
    except ImportError:
        _plot_cv(labels, panels, path)
        return
    height = 1.2 + 0.45 * len(labels)
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), height), sharey=True)
    colors = [f"C{i % 10}" for i in range(len(labels))]
    for ax, (title, values) in zip(axes, panels, strict=True):
        ax.barh(labels, values, color=colors)
        ax.set_title(title)
        ax.invert_yaxis()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _plot_cv(labels: list[str], panels: Any, path: Path) -> None:
    """OpenCV fallback of `plot`."""
    import cv2  # noqa: PLC0415

    w, h, pad = 360, 300, 40
    img = np.full((h, w * len(panels), 3), 255, np.uint8)
    for p, (title, values) in enumerate(panels):
        x0 = p * w
        cv2.putText(img, title, (x0 + 10, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1)
        top = max(*values, 1e-9)
        bw = (w - 2 * pad) // max(len(values), 1)
        for i, (lab, v) in enumerate(zip(labels, values, strict=True)):
            bh = int((h - 2 * pad - 20) * v / top)
            x = x0 + pad + i * bw
            cv2.rectangle(img, (x + 4, h - pad - bh), (x + bw - 4, h - pad), (180, 110, 40), -1)
            cv2.putText(
                img,
                f"{v:.2f}",
                (x + 4, h - pad - bh - 4),
                cv2.FONT_HERSHEY_SIMPLEX,
                0.4,
                (0, 0, 0),
                1,
            )
            cv2.putText(
                img, lab[:12], (x + 2, h - pad + 15), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (0, 0, 0), 1
            )
    cv2.imwrite(str(path), img)


def write_outputs(
    rows: Sequence[PolicyRow],
    episodes: dict[str, list[EpisodeResult]],
    seeds: Sequence[int],
    out: Path,
    extra: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Write ``eval.json``, ``eval.md`` and ``eval.png`` under ``out``; return the JSON dict."""
    out.mkdir(parents=True, exist_ok=True)
    report = {
        "date": datetime.now(UTC).isoformat(timespec="seconds"),
        "machine": {
            "node": platform.node(),
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
        },
        "seeds": list(seeds),
        "columns": [k for k, _, _ in COLUMNS],
        "rows": [asdict(r) for r in rows],
        "episodes": {k: [asdict(e) for e in v] for k, v in episodes.items()},
        **(extra or {}),
    }
    (out / "eval.json").write_text(json.dumps(report, indent=2), encoding="utf-8")
    seed_text = f"{seeds[0]}-{seeds[-1]}" if len(seeds) > 1 else str(seeds[0])
    md = (
        f"Evaluation on {len(seeds)} seeds ({seed_text}), {report['date']}\n\n"
        + markdown_table(rows)
        + "\n"
    )
    (out / "eval.md").write_text(md, encoding="utf-8")
    plot(rows, out / "eval.png")
    return report


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--policies",
        nargs="+",
        required=True,
        help="'scripted', 'random' and/or model .zip paths, each optionally with "
        "@KEY=VALUE[,KEY=VALUE] env overrides (scripted@execution=dynamic)",
    )
    ap.add_argument("--seeds", nargs="+", default=["1000-1019"], help="e.g. 1000-1019 or 1,2")
    ap.add_argument(
        "--env-config",
        default=None,
        help="env YAML (EnvConfig keys) or a configs/train YAML (its env)",
    )
    ap.add_argument("--env", nargs="*", default=[], metavar="KEY=VALUE", help="env overrides")
    ap.add_argument("--max-steps", type=int, default=0, help="0: 2 x slots")
    ap.add_argument(
        "--scripted-image-size", type=int, nargs=2, default=SCRIPTED_IMAGE_SIZE, metavar=("H", "W")
    )
    ap.add_argument(
        "--no-calibrate", action="store_true", help="scripted agent uses the true camera model"
    )
    ap.add_argument("--out", type=Path, default=Path("out"))
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    os.environ.setdefault("MUJOCO_GL", "egl")
    import torch  # noqa: PLC0415

    torch.set_num_threads(1)
    seeds = parse_seeds(args.seeds)
    base = load_env_overrides(args.env_config, args.env)
    policies = make_policies(
        args.policies, base, tuple(args.scripted_image_size), calibrate=not args.no_calibrate
    )
    rows, episodes = evaluate_policy_set(policies, seeds, args.max_steps, not args.quiet)
    report = write_outputs(rows, episodes, seeds, args.out, {"base_env": base})
    print(markdown_table(rows))
    print(f"wrote {args.out / 'eval.json'}, eval.md, eval.png")
    return report


__all__ = [
    "COLUMNS",
    "EpisodeResult",
    "EvaluateError",
    "Policy",
    "PolicyRow",
    "aggregate",
    "evaluate_policy_set",
    "load_env_overrides",
    "main",
    "make_policies",
    "markdown_table",
    "parse_seeds",
    "plot",
    "run_episode",
    "write_outputs",
]

if __name__ == "__main__":
    main()
