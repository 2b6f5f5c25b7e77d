r"""Evaluate policies (scripted, random, open-loop, checkpoints, your own) on held-out seeds.

Run::

    python -m apps.evaluate --task MosaicDecision6-v0 \\
        --policies scripted random openloop runs/ppo/model.zip mypkg.mypolicy:Policy [--out out]
    python -m apps.evaluate --policies scripted random --seeds 1000-1019 \\
        --env-config pick_place_flat        # a configs/train preset (its env) or an env YAML

With ``--task`` (a rung of `envs.tasks`) the protocol is the task's: its held-out seeds, its
held-out designs (episodes alternate over them), its episode limit and throughput horizon.
Otherwise ``--env-config`` (a preset name in ``configs/train/``, a train YAML whose ``env`` is
used, or an env YAML) plus ``--env KEY=VALUE`` give the base env, ``--seeds`` the seeds.
Policy names: `agents.policies`. Only the keys that define a policy's spaces change per policy.

Every policy is bound to its env before any episode is played: a checkpoint whose spaces do not
match, or a name that does not resolve, fails at start-up. Each finished episode is appended
to ``<out>/episodes.jsonl`` at once; a rerun with the same ``--out`` skips the (policy, seed)
pairs already there, so results already computed are never lost or recomputed. At the end:
one table, ``<out>/eval.json``, ``<out>/eval.md`` and ``<out>/eval.png``. Columns (protocol of
`agents.protocol`): success rate, slots filled, misplaced, dropped (events), lost and stranded
tiles per episode, tiles/min (correct tiles per simulated minute, to completion or over the
horizon, the mean of the episodes' figures) and wall seconds per correct tile.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import time
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import gymnasium as gym

from agents.policies import (
    SCRIPTED_IMAGE_SIZE,
    Policy,
    PolicyError,
    Predict,
    make_policies,
    parse_pairs,
)
from agents.protocol import EpisodeMetrics
from apps.cli import CommandParser, run_cli
from apps.evaluate_results import (
    COLUMNS,
    EpisodeResult,
    PolicyRow,
    Protocol,
    aggregate,
    env_key,
    markdown_table,
    plot,
    write_outputs,
)
from configs import ConfigError, load_yaml
from configs.files import append_line, complete_lines
from envs import ENV_ID
from envs.cell.rendering import use_headless_rendering
from envs.task import Evaluation

"""Gymnasium id of the environment."""
STEPS_PER_SLOT = 2
"""Default episode step limit per slot of the design (without a task)."""
HORIZON_S_PER_SLOT = 5.0
"""Default throughput horizon per slot [s] (two 2.5 s cycles), without a task."""
DEFAULT_SEEDS = "1000-1019"
"""Seeds without ``--task`` or ``--seeds``."""
EPISODES_FILE = "episodes.jsonl"
"""Per-episode results, appended as they finish."""
EvaluateError = PolicyError
"""A policy name, seed range, task or env configuration that cannot be evaluated."""


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


def seed_argument(spec: str) -> list[int]:
    """``--seeds`` argument type: `parse_seeds` of one spec, a usage error if malformed."""
    try:
        return parse_seeds([spec])
    except EvaluateError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from exc


def load_env_overrides(path: str | Path | None, pairs: Sequence[str] = ()) -> dict[str, Any]:
    """Base env overrides from a train preset, a YAML (env keys or its ``env``) and KEY=VALUE.

    Raises:
        EvaluateError: Unknown preset or env key, or a malformed pair.
    """
    from envs.env_config import load_env_config  # noqa: PLC0415

    data: dict[str, Any] = {}
    try:
        if path is not None:
            raw = load_yaml(path, "train")
            data = dict(raw["env"]) if isinstance(raw.get("env"), dict) else raw
        data.update(parse_pairs(pairs))
        load_env_config(**data)
    except EvaluateError:
        raise
    except ConfigError as exc:
        raise EvaluateError(str(exc)) from exc
    return data


def task_protocol(task_id: str) -> tuple[dict[str, Any], Protocol]:
    """Base env overrides and the protocol of a rung of the task ladder (held-out split).

    Raises:
        EvaluateError: Unknown task (lists the ids).
    """
    from envs.tasks import TaskError, get_task  # noqa: PLC0415

    try:
        task = get_task(task_id)
    except TaskError as exc:
        raise EvaluateError(str(exc)) from exc
    protocol = Protocol(
        tuple(task.seeds), task.designs("eval"), task.max_episode_steps, task.horizon_s
    )
    return task.env_kwargs("eval"), protocol


def run_episode(
    env: gym.Env,
    predict: Predict,
    seed: int,
    max_steps: int,
    horizon_s: float,
    *,
    label: str = "",
) -> EpisodeResult:
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
    ev = Evaluation.from_info(info)
    sim = float(info["sim_time"])
    metrics = EpisodeMetrics.from_evaluation(ev, sim, horizon_s)
    return EpisodeResult(
        policy=label,
        seed=seed,
        design=str(env.unwrapped.config.design),  # type: ignore[attr-defined]
        success=ev.success,
        correct=ev.correct,
        slots=ev.slots,
        misplaced=ev.misplaced,
        dropped=ev.dropped,
        lost=ev.lost,
        stranded=ev.stranded,
        left=int(metrics.left),
        steps=steps,
        sim_s=sim,
        span_s=metrics.span_s,
        wall_s=wall,
        episode_return=total,
    )


def _read_done(path: Path | None) -> list[EpisodeResult]:
    """Episodes already in a JSONL log (none if it does not exist; a torn last line skipped)."""
    if path is None:
        return []
    return [EpisodeResult(**json.loads(line)) for line in complete_lines(path)]


def bind(pol: Policy, designs: Sequence[str]) -> list[tuple[gym.Env, Predict]]:
    """Build the policy's env for each design and bind it (raises before any episode)."""
    bound = []
    for design in designs or [""]:
        kwargs = {**pol.env_kwargs, "design": design} if design else dict(pol.env_kwargs)
        try:
            env = gym.make(ENV_ID, **kwargs)
        except ConfigError as exc:
            raise EvaluateError(f"policy {pol.label!r}: {exc}") from exc
        if pol.wrap is not None:
            env = pol.wrap(env)
        try:
            bound.append((env, pol.factory(env)))
        except Exception:
            env.close()
            for e, _ in bound:
                e.close()
            raise
    return bound


def evaluate_policy_set(
    policies: Sequence[Policy],
    seeds: Sequence[int] | Protocol,
    max_steps: int = 0,
    progress: bool = False,
    log: Path | None = None,
) -> tuple[list[PolicyRow], dict[str, list[EpisodeResult]]]:
    """Play every policy on every seed (see the module docstring).

    Args:
        policies: From `agents.policies.make_policies`.
        seeds: Reset seeds, or a `Protocol` (seeds, designs, limits).
        max_steps: Step limit per episode when ``seeds`` is a list; 0: 2 x slots.
        progress: Print one line per episode.
        log: JSONL file the episodes are appended to as they finish (and read back to skip
            the ones already played); None: not written.

    Returns:
        (rows, episodes by policy label).

    Raises:
        EvaluateError: A policy that cannot be bound to its env (before any episode).
    """
    proto = seeds if isinstance(seeds, Protocol) else Protocol(tuple(seeds), (), max_steps)
    done = _read_done(log)
    envs = []
    try:
        for pol in policies:  # bind everything first: a bad policy fails before any episode
            envs.append(bind(pol, proto.designs))
        per: dict[str, list[EpisodeResult]] = {}
        for pol, bound in zip(policies, envs, strict=True):
            key = env_key(pol.env_kwargs)
            eps = [
                e for e in done if e.policy == pol.label and e.seed in proto.seeds and e.env == key
            ]
            have = {e.seed for e in eps}
            for i, seed in enumerate(proto.seeds):
                if seed in have:
                    continue
                env, predict = bound[i % len(bound)]
                slots = len(env.unwrapped.task.slot_class)  # type: ignore[attr-defined]
                limit = proto.max_steps or STEPS_PER_SLOT * slots
                horizon = proto.horizon_s or HORIZON_S_PER_SLOT * slots
                ep = run_episode(env, predict, seed, limit, horizon, label=pol.label)
                ep = dataclasses.replace(ep, env=key)
                eps.append(ep)
                if log is not None:
                    append_line(log, json.dumps(asdict(ep)))
                if progress:
                    print(
                        f"  {pol.label} seed {seed} ({ep.design}): {ep.correct}/{ep.slots} "
                        f"correct, {ep.misplaced} misplaced, {ep.steps} steps, {ep.wall_s:.2f} s",
                        flush=True,
                    )
            eps.sort(key=lambda e: proto.seeds.index(e.seed))
            per[pol.label] = eps
        rows = [aggregate(p.label, per[p.label], p.env_kwargs) for p in policies]
    finally:
        for bound in envs:
            for env, _ in bound:
                env.close()
    return rows, per


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line (see the module docstring)."""
    ap = CommandParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--policies",
        nargs="+",
        required=True,
        help="scripted, random, openloop, identity, SB3 model .zip paths, behaviour clone .pt "
        "paths (apps.bc.decision) or module:callable, each optionally with "
        "@KEY=VALUE[,KEY=VALUE] env "
        "overrides (scripted@execution=dynamic)",
    )
    ap.add_argument(
        "--task", default=None, help="a ladder id (MosaicDecision6-v0, ...-v1): its protocol"
    )
    ap.add_argument(
        "--seeds", nargs="+", type=seed_argument, default=None, help="e.g. 1000-1019 or 1,2"
    )
    ap.add_argument(
        "--env-config",
        default=None,
        help="configs/train preset name or YAML (its env), or an env YAML",
    )
    ap.add_argument("--env", nargs="*", default=[], metavar="KEY=VALUE", help="env overrides")
    ap.add_argument("--max-steps", type=int, default=0, help="0: the task's, else 2 x slots")
    ap.add_argument(
        "--scripted-image-size", type=int, nargs=2, default=SCRIPTED_IMAGE_SIZE, metavar=("H", "W")
    )
    ap.add_argument(
        "--no-calibrate", action="store_true", help="scripted agent uses the true camera model"
    )
    ap.add_argument("--out", type=Path, default=Path("out"))
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    use_headless_rendering()
    import torch  # noqa: PLC0415

    torch.set_num_threads(1)
    if args.task:
        base, proto = task_protocol(args.task)
        base.update(load_env_overrides(args.env_config, args.env))
        if args.seeds:
            seeds = tuple(s for spec in args.seeds for s in spec)
            proto = Protocol(seeds, proto.designs, proto.max_steps, proto.horizon_s)
    else:
        base = load_env_overrides(args.env_config, args.env)
        specs = args.seeds or [parse_seeds([DEFAULT_SEEDS])]
        proto = Protocol(tuple(s for spec in specs for s in spec))
    if args.max_steps:
        proto = Protocol(proto.seeds, proto.designs, args.max_steps, proto.horizon_s)
    policies = make_policies(
        args.policies, base, tuple(args.scripted_image_size), calibrate=not args.no_calibrate
    )
    rows, episodes = evaluate_policy_set(
        policies, proto, progress=not args.quiet, log=args.out / EPISODES_FILE
    )
    extra = {"base_env": base, "task": args.task, "protocol": asdict(proto)}
    report = write_outputs(rows, episodes, list(proto.seeds), args.out, extra)
    print(markdown_table(rows))
    print(f"wrote {args.out / 'eval.json'}, eval.md, eval.png, {EPISODES_FILE}")
    return report


__all__ = [
    "COLUMNS",
    "EPISODES_FILE",
    "EpisodeResult",
    "EvaluateError",
    "Policy",
    "PolicyRow",
    "Protocol",
    "aggregate",
    "evaluate_policy_set",
    "load_env_overrides",
    "main",
    "make_policies",
    "markdown_table",
    "parse_seeds",
    "plot",
    "run_episode",
    "task_protocol",
    "write_outputs",
]

if __name__ == "__main__":
    run_cli(main)
