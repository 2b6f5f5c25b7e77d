#!/usr/bin/env bash
# Build the documentation site offline into docs/_build/html, warnings as errors.
# The set-up's lock has Sphinx, MyST and furo (the docs extra); run after scripts/setup.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
export MUJOCO_GL="${MUJOCO_GL:-egl}" PYOPENGL_PLATFORM="${PYOPENGL_PLATFORM:-egl}"
start=$(date +%s)
# -j auto: Sphinx reads and writes the ~300 pages in one process per core (writing is most of
# the build: each page gets the whole navigation tree of the site's sidebar).
.venv/bin/python -m sphinx -W --keep-going -q -j auto -b html docs docs/_build/html "$@"
echo "[docs] built docs/_build/html in $(( $(date +%s) - start )) s"
