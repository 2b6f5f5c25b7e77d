"""Agents driving the cell, by kind.

- `agents.scripted`: the scripted cell (perception, calibration, placement, the agent).
- `agents.experts`: scripted reference controllers of the low-level rungs, the theory policy.
- `agents.learning`: demonstrations, behaviour cloning, RL helpers and wrappers.
- `agents.pair`: the pair scorer, its observation rows, cloning and maskable RL policy.
- `agents.camera`: policies that read the two camera images.
- `agents.policies` (policies by name), `agents.protocol` (the evaluation protocol),
  `agents.errors` (`AgentError`), `agents.moved` (old module names, loading for one version).
"""

from agents.moved import install as _install_moved_names
from envs.cell.rendering import use_headless_rendering

# Headless rendering by default, as `import envs` does: set before anything imports mujoco.
use_headless_rendering()
_install_moved_names()
