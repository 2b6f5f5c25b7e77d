"""Agents driving the cell: scripted baseline, perception, training, evaluation, benchmarks."""

import os

# Headless rendering by default, as `import envs` does: set before anything imports mujoco.
os.environ.setdefault("MUJOCO_GL", "egl")
