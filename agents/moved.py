"""Old dotted paths of the agents' modules, kept loading for one version.

The agents were one flat folder before they were grouped by kind (``scripted``, ``experts``,
``learning``, ``pair``, ``camera``). Checkpoints (SB3 ``model.zip`` files pickle their policy
class by dotted path) and training YAMLs written before the move name the old modules, e.g.
``agents.pair_policy:PairScorerPolicy``. `install` puts a finder on `sys.meta_path` that
answers an import of an old name with the moved module (the same module object, so classes
compare equal) and warns once with a `DeprecationWarning` naming the new path.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import warnings
from types import ModuleType

MOVED: dict[str, str] = {
    "agents.actor_bc": "agents.learning.actor_bc",
    "agents.algorithms": "agents.learning.algorithms",
    "agents.bc": "agents.learning.decision_bc",
    "agents.calibration": "agents.scripted.calibration",
    "agents.camera_bc": "agents.camera.crop_bc",
    "agents.camera_continuous": "agents.camera.continuous",
    "agents.camera_features": "agents.camera.crops",
    "agents.camera_policy": "agents.camera.crop_scorer",
    "agents.classifier_fit": "agents.learning.classifier_fit",
    "agents.config": "agents.scripted.config",
    "agents.dart": "agents.learning.dart",
    "agents.demos": "agents.learning.demos",
    "agents.lowlevel_expert": "agents.experts.cartesian",
    "agents.lowlevel_joint_expert": "agents.experts.joint",
    "agents.obs_norm": "agents.learning.obs_norm",
    "agents.outline_fit": "agents.scripted.outline_fit",
    "agents.pair_bc": "agents.pair.state_bc",
    "agents.pair_objects": "agents.pair.objects_rows",
    "agents.pair_objects_bc": "agents.pair.objects_bc",
    "agents.pair_policy": "agents.pair.maskable_policy",
    "agents.pair_scorer": "agents.pair.scorer",
    "agents.pair_state": "agents.pair.state_rows",
    "agents.perception": "agents.scripted.perception",
    "agents.placement": "agents.scripted.placement",
    "agents.residual": "agents.learning.residual",
    "agents.rlpd": "agents.learning.rlpd",
    "agents.seen_slots": "agents.scripted.seen_slots",
    "agents.theory_policy": "agents.experts.theory",
    "agents.tile_fit": "agents.camera.tile_fit",
    "agents.white_balance": "agents.scripted.white_balance",
    "agents.wrappers": "agents.learning.wrappers",
}
"""Old module name -> the module it moved to (``agents.scripted`` is now the package)."""


class _AliasLoader(importlib.abc.Loader):
    """Loads an old name as the moved module itself."""

    def __init__(self, target: str) -> None:
        self._target = target

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        warnings.warn(
            f"{spec.name} moved to {self._target}; the old name loads until the next version",
            DeprecationWarning,
            stacklevel=2,
        )
        return importlib.import_module(self._target)

    def exec_module(self, module: ModuleType) -> None:
        """The moved module is executed already."""


class _MovedFinder(importlib.abc.MetaPathFinder):
    """Finds the old names of `MOVED`."""

    def find_spec(
        self, fullname: str, path: object = None, target: object = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in MOVED:
            return None
        return importlib.util.spec_from_loader(fullname, _AliasLoader(MOVED[fullname]))


def install() -> None:
    """Put the finder of old names on `sys.meta_path` (once)."""
    if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
        sys.meta_path.append(_MovedFinder())
