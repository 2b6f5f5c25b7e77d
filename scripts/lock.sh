#!/usr/bin/env bash
# Re-resolve requirements.lock: exact versions of every dependency in pyproject.toml (with the
# dev and docs extras) for Python 3.11 on Linux x86_64, torch the CPU 2.13.0 build
# (scripts/lock-overrides.txt). Needs uv 0.13 (in the dev set-up: .venv/bin/uv) and the
# package registries. Commit the new requirements.lock; the next set-up installs it.
set -euo pipefail
cd "$(dirname "$0")/.."
UV=${UV:-.venv/bin/uv}
WHEELS=${WHEELS:-/opt/wheels}
"$UV" pip compile pyproject.toml --extra dev --extra docs \
  --python-version 3.11 --python-platform x86_64-manylinux_2_28 \
  --find-links "$WHEELS" --override scripts/lock-overrides.txt \
  --no-emit-find-links --custom-compile-command "bash scripts/lock.sh" \
  --quiet -o requirements.lock "$@"
echo "[lock] wrote requirements.lock ($(grep -c '==' requirements.lock) pinned packages)"
