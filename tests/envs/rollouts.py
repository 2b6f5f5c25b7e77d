"""Seeded rollouts and their fingerprints: the same seed must give the same episode forever.

A fingerprint is the SHA-256 of every observation array (dtype, shape, bytes), the reward, the
termination and the filled-slot count of each step of a short rollout of the privileged expert
(tile i into slot i, design order). `CASES` covers the procedural design source (state and
camera images), fixed designs with both camera images and the kinematic ``pick_place`` step.

``tests/data/rollout_fingerprints.json`` holds the fingerprints recorded before the speed work
of the reset, the step and the renders (issue 38); ``test_rollout_fingerprints.py`` asserts
equality. Rewrite them only for a change meant to alter episodes:
``python -m tests.envs.rollouts --write``.
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

DATA = Path(__file__).resolve().parents[1] / "data" / "rollout_fingerprints.json"
PROCEDURAL = {"design_source": "procedural", "exclude_designs": ["hexagon", "trencadis"]}
CASES: dict[str, tuple[str, dict[str, Any], tuple[int, ...], int]] = {
    # name: (env id, overrides, seeds, expert steps per seed)
    "held_out_procedural_state": ("MosaicHeldOutDesigns-v1", PROCEDURAL, (0, 5, 1003), 6),
    "held_out_procedural_rgb": (
        "MosaicHeldOutDesigns-v1",
        {**PROCEDURAL, "obs_mode": "rgb+state"},
        (1, 1010),
        3,
    ),
    "decision6_procedural_rgb": (
        "MosaicDecision6-v1",
        {**PROCEDURAL, "obs_mode": "rgb", "design_generator": "design_generator_train"},
        (2, 1017),
        2,
    ),
    "decision6_fixed_rgb": ("MosaicDecision6-v1", {"obs_mode": "rgb+state"}, (1000, 1001), 6),
    "decision16_fixed_rgb": ("MosaicDecision16-v1", {"obs_mode": "rgb"}, (1000,), 5),
    "pick_place_kinematic": (
        "MosaicAssembly-v0",
        {"action_mode": "pick_place", "execution": "kinematic", "max_slots": 6},
        (3, 4),
        6,
    ),
}


def digest(obs: dict[str, Any]) -> dict[str, str]:
    """SHA-256 (hex, first 16 digits) of each observation array: dtype, shape and bytes."""
    out = {}
    for key in sorted(obs):
        a = np.ascontiguousarray(obs[key])
        h = hashlib.sha256(f"{a.dtype}{a.shape}".encode())
        h.update(a.tobytes())
        out[key] = h.hexdigest()[:16]
    return out


def rollout(name: str) -> list[dict[str, Any]]:
    """The fingerprints of case ``name``: per seed, the reset's and each step's."""
    env_id, overrides, seeds, steps = CASES[name]
    env = gym.make(env_id, **overrides)
    u: Any = env.unwrapped
    records: list[dict[str, Any]] = []
    try:
        for seed in seeds:
            obs, _ = env.reset(seed=seed)
            records.append({"seed": seed, "step": 0, "obs": digest(obs)})
            n = len(u.cell.slots)
            for k in range(steps):
                obs, reward, term, trunc, info = env.step(u.expert_action(k % n, k % n))
                records.append(
                    {
                        "seed": seed,
                        "step": k + 1,
                        "obs": digest(obs),
                        "reward": round(float(reward), 9),
                        "done": bool(term or trunc),
                        "placed": int(info["tiles_placed"]),
                    }
                )
                if term or trunc:
                    break
    finally:
        env.close()
    return records


def read_fingerprints(path: Path) -> dict[str, list[dict[str, Any]]]:
    """Recorded fingerprints by case name, from a JSON file under ``tests/data``."""
    return json.loads(path.read_text())


def record_or_compare(argv: list[str], path: Path, found: dict[str, list[dict[str, Any]]]) -> None:
    """``--write`` in ``argv``: record ``found`` to ``path``; otherwise compare with it, print
    the cases that differ and exit 1 if any does."""
    if "--write" in argv:
        path.write_text(json.dumps(found, indent=1) + "\n")
        print(f"wrote {path}")
        return
    want = read_fingerprints(path)
    bad = [name for name in found if found[name] != want.get(name)]
    print("identical" if not bad else f"DIFFERENT: {bad}")
    sys.exit(1 if bad else 0)


def load() -> dict[str, list[dict[str, Any]]]:
    """The recorded fingerprints (``tests/data/rollout_fingerprints.json``)."""
    return read_fingerprints(DATA)


def main(argv: list[str]) -> None:
    """``--write``: record every case; otherwise compare and print the cases that differ."""
    record_or_compare(argv, DATA, {name: rollout(name) for name in CASES})


if __name__ == "__main__":
    main(sys.argv[1:])
