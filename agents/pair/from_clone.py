"""Start the pair-scorer MaskablePPO policy from a pair-scorer clone: at step 0 it IS the clone.

A clone file (`agents.pair.state_bc`, ``bc.pt``) holds the scorer's weights, its shape, the
name of its row adapter and the adapter's settings (a ``stream`` clone's belt timing). The
MaskablePPO policy of `agents.pair.maskable_policy` reads the same rows with the same network,
so loading the clone's weights into the policy's actor makes the policy's logits over the flat
(tile, slot, rotation) actions the clone's logits; with the env's action masks
(`agents.learning.wrappers.FlatDiscreteActions`) its greedy action is the clone's action.

- `read_clone`: the clone file as a `CloneFile` (refused with `AgentError` if it is none);
- `clone_policy_kwargs`: the policy's ``policy_kwargs`` with the clone's scorer shape, adapter
  and adapter settings (a setting given that differs from the clone's is refused);
- `load_clone`: the clone's weights into a built policy's actor (and into an unshared critic's
  scorer, as the critic's starting features), after checking every shape.

``apps.train`` does all three for a preset with ``init_clone`` (``configs/train/
maskable_ppo_stream_finetune.yaml``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from agents.camera.crop_scorer import read_policy_file
from agents.errors import AgentError
from agents.pair.adapters import ADAPTERS, FEATURE_DIMS
from agents.pair.scorer import PairScorerConfig
from agents.pair.state_bc import ARCH

EXTRACTOR_KEYS = ("hidden", "layers", "rotation_bins", "adapter", "adapter_args")
"""``features_extractor_kwargs`` of `agents.pair.maskable_policy.PairFeatures` a clone sets."""


@dataclass(frozen=True)
class CloneFile:
    """A pair-scorer clone read from its file.

    Attributes:
        path: The file.
        adapter: Name of its row adapter (`agents.pair.adapters.ADAPTERS`).
        adapter_args: The adapter's settings (a ``stream`` clone's `BeltTiming` as a dict), or
            None.
        scorer: The scorer's shape.
        nvec: Sizes of the ``pick_place_discrete`` action it was trained on (tiles, slots,
            rotation bins).
        state_dict: The scorer's weights (`agents.pair.scorer.PairScorer` parameter names).
    """

    path: Path
    adapter: str
    adapter_args: Mapping[str, Any] | None
    scorer: PairScorerConfig
    nvec: tuple[int, int, int]
    state_dict: Mapping[str, torch.Tensor]

    @property
    def action_dim(self) -> int:
        """Flat actions it scores: tiles x slots x rotation bins."""
        return int(np.prod(self.nvec))

    def extractor_kwargs(self) -> dict[str, Any]:
        """`PairFeatures` keyword arguments that rebuild its scorer on its rows."""
        out: dict[str, Any] = {
            "hidden": self.scorer.hidden,
            "layers": self.scorer.layers,
            "rotation_bins": self.scorer.rotation_bins,
            "adapter": self.adapter,
        }
        if self.adapter_args:
            out["adapter_args"] = dict(self.adapter_args)
        return out


def read_clone(path: str | Path) -> CloneFile:
    """The pair-scorer clone saved at ``path``.

    Raises:
        AgentError: No such file, not a torch file, or not a pair-scorer clone (another
            ``arch``, an unknown adapter, a missing entry); the message says what was expected.
    """
    path = Path(path)
    expected = (
        "a pair-scorer clone .pt (arch 'pair', written by apps.bc.decision --arch pair, "
        "apps.bc.objects or benchmarks.learned.stream)"
    )
    try:
        blob = read_policy_file(path)
    except AgentError as exc:  # unreadable, missing, or no dict inside
        raise AgentError(f"{exc}; expected {expected}") from exc
    if blob.get("arch") != ARCH:
        arch = blob.get("arch")
        raise AgentError(f"{path} is not a pair-scorer clone (arch {arch!r}); expected {expected}")
    try:
        adapter = str(blob["adapter"])
        scorer = PairScorerConfig(**blob["scorer"])
        nvec = tuple(int(v) for v in blob["nvec"])
        state_dict = dict(blob["state_dict"])
    except (KeyError, TypeError, ValueError) as exc:
        raise AgentError(
            f"{path}: missing or wrong entry ({type(exc).__name__}: {exc}); expected {expected}"
        ) from exc
    if adapter not in ADAPTERS or len(nvec) != len(("tiles", "slots", "rotations")):
        raise AgentError(
            f"{path}: adapter {adapter!r} (allowed: {sorted(ADAPTERS)}) and action sizes {nvec} "
            "(expected three: tiles, slots, rotation bins)"
        )
    args = blob.get("adapter_args")
    return CloneFile(path, adapter, args, scorer, nvec, state_dict)  # type: ignore[arg-type]


def clone_policy_kwargs(clone: CloneFile, policy_kwargs: Mapping[str, Any]) -> dict[str, Any]:
    """``policy_kwargs`` of a `PairScorerPolicy` whose scorer has the clone's shape and rows.

    The clone's scorer shape, adapter and adapter settings fill
    ``features_extractor_kwargs``; any other key of ``policy_kwargs`` (``share_features_extractor``,
    ``optimizer_kwargs``) is kept.

    Raises:
        AgentError: ``policy_kwargs`` sets one of `EXTRACTOR_KEYS` to another value than the
            clone's, or an unknown extractor key.
    """
    given = dict(policy_kwargs.get("features_extractor_kwargs") or {})
    wanted = clone.extractor_kwargs()
    unknown = sorted(set(given) - set(EXTRACTOR_KEYS))
    if unknown:
        raise AgentError(
            f"features_extractor_kwargs {unknown} are not pair-scorer settings; allowed: "
            f"{list(EXTRACTOR_KEYS)}"
        )
    clash = {k: (v, wanted.get(k)) for k, v in given.items() if v != wanted.get(k)}
    if clash:
        raise AgentError(
            f"features_extractor_kwargs differ from the clone {clone.path} "
            f"(given, clone's): {clash}; leave them out to take the clone's"
        )
    return {**dict(policy_kwargs), "features_extractor_kwargs": wanted}


def load_clone(policy: Any, clone: CloneFile, *, critic: bool = True) -> None:
    """Put the clone's weights into the actor of a built `PairScorerPolicy`.

    Args:
        policy: The policy (``model.policy`` of a MaskablePPO model).
        clone: From `read_clone`.
        critic: Also start an unshared critic's scorer (``share_features_extractor: false``)
            from the clone's weights: the pair embeddings the clone learned are the critic's
            first features. Its value head stays as initialised.

    Raises:
        AgentError: Not a pair-scorer policy, or its action count, rows or scorer shape differ
            from the clone's (the message names both).
    """
    from agents.pair.maskable_policy import PairFeatures  # noqa: PLC0415 - sb3-contrib import

    actor = getattr(policy, "pi_features_extractor", None)
    if not isinstance(actor, PairFeatures):
        raise AgentError(
            f"a pair-scorer clone loads into agents.pair.maskable_policy:PairScorerPolicy, "
            f"not {type(policy).__name__}"
        )
    n = getattr(policy.action_space, "n", None)
    if n != clone.action_dim:
        raise AgentError(
            f"the clone {clone.path} scores Discrete({clone.action_dim}) actions "
            f"({' x '.join(map(str, clone.nvec))}); the policy has {policy.action_space}"
        )
    kwargs = dict(getattr(policy, "features_extractor_kwargs", None) or {})
    rows = (kwargs.get("adapter", "state"), kwargs.get("adapter_args"))
    want_rows = (clone.adapter, dict(clone.adapter_args) if clone.adapter_args else None)
    if rows != want_rows:
        raise AgentError(
            f"the policy reads {rows[0]!r} rows with {rows[1]}; the clone {clone.path} was "
            f"trained on {want_rows[0]!r} rows with {want_rows[1]} (clone_policy_kwargs)"
        )
    dims = FEATURE_DIMS[clone.adapter]
    if actor.scorer.cfg != clone.scorer or tuple(dims) != (
        clone.scorer.tile_dim,
        clone.scorer.slot_dim,
        clone.scorer.pair_dim,
    ):
        raise AgentError(
            f"the policy's scorer {asdict(actor.scorer.cfg)} differs from the clone's "
            f"{asdict(clone.scorer)} ({clone.path}); build it with clone_policy_kwargs"
        )
    targets = [actor.scorer]
    critic_feats = getattr(policy, "vf_features_extractor", actor)
    if critic and critic_feats is not actor and isinstance(critic_feats, PairFeatures):
        targets.append(critic_feats.scorer)
    for scorer in targets:
        try:
            scorer.load_state_dict(dict(clone.state_dict))
        except RuntimeError as exc:
            raise AgentError(
                f"the clone {clone.path}'s weights do not fit the policy's scorer: "
                f"{' '.join(str(exc).split())[:300]}"
            ) from exc


__all__ = ["EXTRACTOR_KEYS", "CloneFile", "clone_policy_kwargs", "load_clone", "read_clone"]
