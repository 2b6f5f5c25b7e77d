#!/usr/bin/env bash
# Set up (idempotent) and run the default test suite (slow tests excluded; `-m slow` runs them)
# in parallel on the machine's cores (pytest-xdist: one worker per core, a test file per
# worker at a time so each module's fixtures are built once; TEST_WORKERS=1 for one process),
# then list the 30 slowest tests.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export MUJOCO_GL="${MUJOCO_GL:-egl}" PYOPENGL_PLATFORM="${PYOPENGL_PLATFORM:-egl}"
# One BLAS/OpenMP (torch) thread per worker: the workers fill the cores already; more threads
# per worker oversubscribe them (a 150-epoch behaviour-cloning fit ran 4x slower).
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}" MKL_NUM_THREADS="${MKL_NUM_THREADS:-1}"
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
# Python writes the bytecode of each module it imports, once: the set-up compiles none (most
# of the ~22,000 installed modules are never imported), and with PYTHONDONTWRITEBYTECODE set
# (this machine's environment sets it) every new interpreter (a worker, each command-line
# test's subprocess) compiled torch and the rest again from source: about 2 s of CPU each, 77 s
# of 188 on the tests of apps, benchmarks and the vector env in a fresh .venv.
unset PYTHONDONTWRITEBYTECODE
workers="${TEST_WORKERS:-auto}"
parallel=(-n "$workers" --dist loadfile)
if [ "$workers" = 1 ]; then parallel=(-p no:xdist); fi
exec .venv/bin/python -m pytest -q "${parallel[@]}" --durations=30 "$@"
