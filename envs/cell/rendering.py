"""The rendering back-end: one home for the ``MUJOCO_GL`` setting.

MuJoCo reads ``MUJOCO_GL`` once, when it is first imported, so the setting must be made before
anything imports ``mujoco``. Headless machines have no display: the default is EGL (Mesa's
software renderer when there is no GPU); a user's own ``MUJOCO_GL`` (``osmesa``, ``glfw``) is
always kept. This module imports nothing of MuJoCo.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

RENDER_ENV_VAR = "MUJOCO_GL"
"""The environment variable MuJoCo reads to choose its OpenGL back-end."""
DEFAULT_BACKEND = "egl"
"""Back-end used when ``MUJOCO_GL`` is not set: headless EGL."""


def rendering_backend(environ: Mapping[str, str] | None = None) -> str:
    """The back-end in force: ``MUJOCO_GL`` of ``environ`` (default `os.environ`), else EGL."""
    return (os.environ if environ is None else environ).get(RENDER_ENV_VAR, DEFAULT_BACKEND)


def use_headless_rendering() -> str:
    """Set ``MUJOCO_GL`` to the default unless the user set it; return the back-end in force."""
    return os.environ.setdefault(RENDER_ENV_VAR, DEFAULT_BACKEND)


def child_environment(environ: Mapping[str, str] | None = None) -> dict[str, str]:
    """A copy of ``environ`` (default `os.environ`) for a child process, with the back-end set."""
    env = dict(os.environ if environ is None else environ)
    env[RENDER_ENV_VAR] = rendering_backend(env)
    return env
