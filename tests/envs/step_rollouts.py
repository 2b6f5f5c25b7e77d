"""Seeded kinematic pick_place rollouts with right, wrong and invalid actions, fingerprinted whole.

Where `tests.envs.rollouts` follows the privileged expert and keeps the filled-slot count of
each step, these cases mix the actions a learning agent sends (the expert's, a tile into the
wrong slot, a wrong rotation, a random one, one outside the action space) and fingerprint all
that a step returns: every observation array, the exact reward, ``terminated``, ``truncated``
and the whole ``info`` (the evaluation dict, every reward term, the action error), or the
`ActionError` a refused action raises. Observation modes ``state`` and ``objects``, reward modes
``sparse``, ``dense`` and ``staged``, action and observation noise, the discrete action mode.

``tests/data/step_fingerprints.json`` was recorded before the step's overhead was cut (issue 38);
``test_step_fingerprints.py`` asserts equality. Rewrite it only for a change meant to alter
episodes: ``python -m tests.envs.step_rollouts --write``.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import envs  # noqa: F401 - registers the ids
from envs.task_spec import ActionError
from tests.envs.rollouts import digest, read_fingerprints, record_or_compare

DATA = Path(__file__).resolve().parents[1] / "data" / "step_fingerprints.json"
KINEMATIC = {"action_mode": "pick_place", "execution": "kinematic", "max_slots": 6}
CASES: dict[str, tuple[dict[str, Any], tuple[int, ...], int]] = {
    # name: (MosaicAssembly-v0 overrides, seeds, steps per seed)
    "state_sparse": ({**KINEMATIC, "obs_mode": "state"}, (3,), 10),
    "state_dense_noise": (
        {**KINEMATIC, "obs_mode": "state", "reward_mode": "dense"}
        | {"action_noise": 0.002, "obs_noise": 0.01},
        (4,),
        10,
    ),
    "objects_staged": ({**KINEMATIC, "obs_mode": "objects", "reward_mode": "staged"}, (5,), 8),
    "discrete_state_dense": (
        {**KINEMATIC, "action_mode": "pick_place_discrete", "obs_mode": "state"}
        | {"reward_mode": "dense"},
        (6,),
        8,
    ),
}
KINDS = 5
"""Action kinds, in turn: the expert's, wrong slot, random, outside the space, wrong rotation."""


def canonical(x: Any) -> Any:
    """``x`` as JSON values: arrays as digests, floats exact (hex), dict keys sorted."""
    if isinstance(x, dict):
        return {str(k): canonical(x[k]) for k in sorted(x, key=str)}
    if isinstance(x, list | tuple):
        return [canonical(v) for v in x]
    if isinstance(x, np.ndarray):
        return digest({"a": x})["a"]
    if isinstance(x, bool | np.bool_):
        return bool(x)
    if isinstance(x, int | np.integer):
        return int(x)
    if isinstance(x, float | np.floating):
        return f"{float(x).hex()} {type(x).__name__}"
    return x


def fingerprint(x: Any) -> str:
    """SHA-256 (hex, first 16 digits) of `canonical` ``x``."""
    text = json.dumps(canonical(x), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def action(env: Any, k: int, rng: np.random.Generator) -> np.ndarray:
    """Step ``k``'s action of kind ``k % KINDS`` (a random one where the expert's cannot be)."""
    u = env.unwrapped
    n = len(u.cell.slots)
    kind = k % KINDS
    space = env.action_space
    discrete = isinstance(space, gym.spaces.MultiDiscrete)
    random = rng.integers(0, space.nvec) if discrete else rng.uniform(-1, 1, space.shape)
    try:
        if kind == 2:  # noqa: PLR2004
            return random
        if kind == 1:
            return u.expert_action(k % n, (k + 1) % n)
        a = u.expert_action(k % n, k % n).copy()
    except ActionError:  # that tile lies outside the pick area now
        return random
    if kind == 3:  # noqa: PLR2004
        a[0] = space.nvec[0] + 1 if discrete else 1.5
    elif kind == 4:  # noqa: PLR2004
        a[-1] = (a[-1] + 1) % space.nvec[-1] if discrete else -a[-1]
    return a


def rollout(name: str) -> list[dict[str, Any]]:
    """The fingerprints of case ``name``: per seed, the reset's and each step's."""
    overrides, seeds, steps = CASES[name]
    env = gym.make("MosaicAssembly-v0", **overrides)
    records: list[dict[str, Any]] = []
    try:
        for seed in seeds:
            rng = np.random.default_rng(seed)
            obs, info = env.reset(seed=seed)
            records.append({"seed": seed, "step": 0, "obs": digest(obs), "info": fingerprint(info)})
            for k in range(steps):
                a = action(env, k, rng)
                try:
                    obs, reward, term, trunc, info = env.step(a)
                except ActionError as exc:
                    records.append({"seed": seed, "step": k + 1, "error": str(exc)})
                    continue
                records.append(
                    {
                        "seed": seed,
                        "step": k + 1,
                        "obs": digest(obs),
                        "reward": float(reward).hex(),
                        "terminated": bool(term),
                        "truncated": bool(trunc),
                        "info": fingerprint(info),
                    }
                )
                if term or trunc:
                    break
    finally:
        env.close()
    return records


def load() -> dict[str, list[dict[str, Any]]]:
    """The recorded fingerprints (``tests/data/step_fingerprints.json``)."""
    return read_fingerprints(DATA)


def main(argv: list[str]) -> None:
    """``--write``: record every case; otherwise compare and print the cases that differ."""
    record_or_compare(argv, DATA, {name: rollout(name) for name in CASES})


if __name__ == "__main__":
    main(sys.argv[1:])
