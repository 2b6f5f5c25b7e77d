"""Benchmarks of the cell's packages: each module measures one and writes a JSON of figures.

``python -m benchmarks`` runs them all and prints one table against the targets
(``benchmarks.table``); ``python -m benchmarks.<name>`` runs one.
"""

from envs.cell.rendering import use_headless_rendering

# Headless rendering by default, as `import envs` does: set before anything imports mujoco.
use_headless_rendering()
