"""Applications built on the library packages.

The main job (``apps.main``), the paper's experiment (``apps.paper_experiment``) and the
bundled-design generator (``apps.make_designs``).
"""

from envs.cell.rendering import use_headless_rendering

# Headless rendering by default, as `import envs` does: set before anything imports mujoco.
use_headless_rendering()
