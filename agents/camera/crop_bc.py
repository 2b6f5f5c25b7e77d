"""Behaviour cloning of the camera policy (`agents.camera.crop_scorer`) from image demonstrations.

`demo_arrays` cuts every recorded step of a Minari dataset (``input_camera`` and
``output_camera`` images, ``pick_place_discrete`` expert actions) into crops once, drawing
the slot templates from each episode's own task description (`episode_specs`: a procedural
design is a new one at every reset); `join_demos` stacks several datasets (training designs);
`train_camera_bc` fits the scorer with a cross-entropy over every (tile, slot, turn) of a step,
where every turn the slot's symmetry makes equivalent to the demonstrated one counts as right.
`check_dataset_spaces` refuses a dataset recorded with other spaces than the env's.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from agents.camera.crop_scorer import TURNS, CameraBCConfig, build_scorer
from agents.camera.crops import CHANNELS, mesh_order, slot_templates, step_crops
from agents.errors import AgentError
from agents.learning.step_fit import fit_steps


@dataclass(frozen=True)
class DemoArrays:
    """Demonstrated steps as crops.

    Attributes:
        tiles: Tile crops, shape (N, n, CHANNELS, G, G) float32 (zeros past ``tile_valid``).
        tile_valid: Tiles seen at each step, shape (N, n) bool.
        mesh: Output-image crops per slot, shape (N, k, CHANNELS, G, G) float32.
        templates: Slot templates of each step's episode, shape (N, k, CHANNELS, G, G) float32.
        targets: Right answers, shape (N, n, k, TURNS) bool (the demonstrated tile and slot at
            every turn equivalent to the demonstrated one under the slot's symmetry).
        episodes: Episodes read.
        skipped: Steps left out because the demonstrated tile index had no blob.
    """

    tiles: np.ndarray
    tile_valid: np.ndarray
    mesh: np.ndarray
    templates: np.ndarray
    targets: np.ndarray
    episodes: int
    skipped: int


def equivalent_turns(turn: int, symmetry: int, turns: int = TURNS) -> np.ndarray:
    """Turns that place a tile of rotational ``symmetry`` as ``turn`` does, shape (turns,) bool.

    ``symmetry`` 0 is continuous (every turn is right); order ``m`` makes turns ``d`` quarter
    steps apart equivalent when ``d * m`` is a multiple of ``turns``.
    """
    d = (np.arange(turns) - turn) % turns
    if symmetry == 0:
        return np.ones(turns, bool)
    return (d * symmetry) % turns == 0


def check_dataset_spaces(dataset: Any, env: Any) -> None:
    """Raise `AgentError` unless a dataset's observation and action spaces equal the env's."""
    for what, mine, theirs in (
        ("observation", dataset.observation_space, env.observation_space),
        ("action", dataset.action_space, env.action_space),
    ):
        if mine != theirs:
            raise AgentError(
                f"the dataset's {what} space {mine} differs from the env's {theirs}; record the "
                "demonstrations with the env keys the policy trains on (task, obs_mode, image_size)"
            )


def episode_specs(dataset: Any, episodes: int = 0) -> list[Any]:
    """The `TaskSpec` of each of the first ``episodes`` episodes of a dataset (0: all).

    The env the dataset was recorded on (``dataset.recover_environment()``) is reset with each
    episode's recorded seed: what the policy reads after that reset (a procedural design's
    slots differ from episode to episode).

    Raises:
        AgentError: An episode without a recorded seed.
    """
    ids = list(dataset.episode_indices)[: episodes or None]
    env = dataset.recover_environment()
    specs = []
    try:
        for ep, meta in zip(ids, dataset.storage.get_episode_metadata(ids), strict=True):
            if meta.get("seed") is None:
                raise AgentError(f"episode {ep} has no recorded seed; cannot rebuild its design")
            env.reset(seed=int(meta["seed"]))
            specs.append(env.get_wrapper_attr("task_spec"))
    finally:
        env.close()
    return specs


def demo_arrays(dataset: Any, spec: Any, cfg: CameraBCConfig, episodes: int = 0) -> DemoArrays:
    """Crops and targets of the first ``episodes`` episodes of a dataset (0: all).

    Args:
        dataset: A Minari dataset of ``pick_place_discrete`` steps with both camera images.
        spec: The env's `TaskSpec` (cameras at the dataset's image size, the slots) for a
            fixed design, or one per episode read (`episode_specs`).
        cfg: Crop settings.
        episodes: Episodes to read (0: all).

    Raises:
        AgentError: The dataset lacks the camera images or discrete actions, or fewer specs
            than episodes.
    """
    crop = cfg.crop()
    n, k = (int(v) for v in np.asarray(dataset.action_space.nvec)[:2])
    ids = list(dataset.episode_indices)[: episodes or None]
    specs = list(spec) if isinstance(spec, Sequence) else [spec] * len(ids)
    if len(specs) != len(ids):
        raise AgentError(f"{len(specs)} task specs for {len(ids)} episodes; give one per episode")
    tiles, valid, mesh, templates, targets = [], [], [], [], []
    skipped = 0
    for ep, ep_spec in zip(dataset.iterate_episodes(ids), specs, strict=True):
        obs = ep.observations
        if "input_camera" not in obs or "output_camera" not in obs:
            raise AgentError("camera behaviour cloning needs input_camera and output_camera images")
        order = mesh_order(ep_spec)
        sym = np.array([ep_spec.slots[int(j)].symmetry for j in order])
        ep_templates = slot_templates(ep_spec, crop)
        for t, action in enumerate(np.asarray(ep.actions, np.int64)):
            seen = {key: obs[key][t] for key in ("input_camera", "output_camera")}
            crops, found = step_crops(seen, ep_spec, crop)
            m = min(len(found.xy), n)
            if action[0] >= m:
                skipped += 1
                continue
            pad = np.zeros((n, CHANNELS, crop.grid, crop.grid), np.float32)
            pad[:m] = crops.tiles[:m]
            target = np.zeros((n, k, TURNS), bool)
            target[action[0], action[1]] = equivalent_turns(int(action[2]), int(sym[action[1]]))
            tiles.append(pad)
            valid.append(np.arange(n) < m)
            mesh.append(crops.mesh)
            templates.append(ep_templates)
            targets.append(target)
    if not tiles:
        raise AgentError("no usable demonstrated step (no tile seen where the expert picked)")
    return DemoArrays(
        np.stack(tiles),
        np.stack(valid),
        np.stack(mesh),
        np.stack(templates),
        np.stack(targets),
        len(ids),
        skipped,
    )


def join_demos(parts: Sequence[DemoArrays]) -> DemoArrays:
    """Several datasets' steps as one (same tile and slot counts and crop grid).

    Raises:
        AgentError: No part, or parts of different shapes.
    """
    if not parts:
        raise AgentError("no demonstrations to join")
    shapes = {p.targets.shape[1:] + p.tiles.shape[2:] for p in parts}
    if len(shapes) > 1:
        raise AgentError(f"demonstrations of different (tiles, slots, turns, crop) shapes {shapes}")
    if len(parts) == 1:
        return parts[0]
    return DemoArrays(
        np.concatenate([p.tiles for p in parts]),
        np.concatenate([p.tile_valid for p in parts]),
        np.concatenate([p.mesh for p in parts]),
        np.concatenate([p.templates for p in parts]),
        np.concatenate([p.targets for p in parts]),
        sum(p.episodes for p in parts),
        sum(p.skipped for p in parts),
    )


def batch_loss(net: Any, data: DemoArrays, idx: np.ndarray, turn: int) -> tuple[Any, Any]:
    """Cross-entropy of the steps ``idx`` (every crop turned by ``turn`` quarter turns).

    Returns:
        (mean loss, per-step hit: whether the best-scored action is a right one).
    """
    import torch  # noqa: PLC0415

    tiles = torch.as_tensor(data.tiles[idx])
    tmpl = torch.as_tensor(data.templates[idx])
    slots = torch.cat([tmpl, torch.as_tensor(data.mesh[idx])], dim=2)
    if turn:
        tiles = torch.rot90(tiles, turn, dims=(-2, -1))
        slots = torch.rot90(slots, turn, dims=(-2, -1))
    logits = net(tiles, slots)
    valid = torch.as_tensor(data.tile_valid[idx])[:, :, None, None].expand_as(logits)
    flat = logits.masked_fill(~valid, -1e9).reshape(len(idx), -1)
    logp = torch.log_softmax(flat, dim=1)
    right = torch.as_tensor(data.targets[idx]).reshape(len(idx), -1)
    loss = -torch.logsumexp(logp.masked_fill(~right, -1e9), dim=1).mean()
    hit = right.gather(1, flat.argmax(1, keepdim=True))[:, 0]
    return loss, hit


def train_camera_bc(
    data: DemoArrays,
    cfg: CameraBCConfig,
    seed: int = 0,
    on_point: Callable[[int, Any], dict[str, float]] | None = None,
) -> tuple[Any, list[dict[str, float]]]:
    """Fit the scorer to the demonstrated steps.

    Args:
        data: The demonstrations as crops.
        cfg: Network and training settings.
        seed: Seed of the weights, the batches and the augmentation turns.
        on_point: Called every ``cfg.eval_every`` steps and at the end with (step, network);
            its values join that point of the curve.

    Returns:
        (the trained network in eval mode, the training curve: one dict per point with
        ``step``, ``loss``, ``train_hit``, ``cpu_s`` and ``on_point``'s values).
    """
    import torch  # noqa: PLC0415

    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    net = build_scorer(cfg)

    def batch() -> tuple[Any, Any]:
        idx = rng.choice(len(data.tiles), size=min(cfg.batch_size, len(data.tiles)), replace=False)
        turn = int(rng.integers(TURNS)) if cfg.augment else 0
        return batch_loss(net, data, idx, turn)

    curve = fit_steps(
        net,
        batch,
        steps=cfg.steps,
        learning_rate=cfg.learning_rate,
        weight_decay=cfg.weight_decay,
        every=cfg.eval_every,
        on_point=on_point,
    )
    return net, curve


__all__ = [
    "DemoArrays",
    "batch_loss",
    "check_dataset_spaces",
    "demo_arrays",
    "episode_specs",
    "equivalent_turns",
    "join_demos",
    "train_camera_bc",
]
