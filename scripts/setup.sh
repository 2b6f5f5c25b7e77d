#!/usr/bin/env bash
# Idempotent set-up on a fresh Debian machine: system libraries for headless rendering,
# a virtual environment in .venv with the exact dependency versions of requirements.lock.
# Re-running is cheap: each step is skipped when already done.
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PKGS=(libegl1 libopengl0 libgl1-mesa-dri libosmesa6 ffmpeg)
missing=()
for p in "${APT_PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] installing system packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  echo "[setup] creating .venv"
  "$PY" -m venv .venv
fi

# The exact versions of requirements.lock (every dependency of pyproject.toml with its dev and
# docs extras, torch the CPU 2.13.0 wheel of this machine's wheel folder; bash scripts/lock.sh
# re-resolves it). The project itself runs from this checkout (every command is `python -m`
# from the repository root), so it is not installed: an editable install of this flat layout is
# what made setuptools warn that folders of the working directory shadow installed packages.
stamp=.venv/.mosaic-installed
want=$(cat requirements.lock | sha256sum | cut -d' ' -f1)
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  echo "[setup] installing the locked Python dependencies (first run takes a few minutes)"
  # -qq: pip's own warnings about this machine's package indexes are not the project's.
  # --no-compile: pip would byte-compile all ~22,000 installed modules (about 45 s of CPU,
  # most of them never imported); Python compiles a module on its first import instead.
  .venv/bin/python -m pip install -qq --no-compile --disable-pip-version-check \
    -r requirements.lock
  echo "$want" > "$stamp"
  echo "[setup] done: $(.venv/bin/python -m pip list --disable-pip-version-check 2>/dev/null | tail -n +3 | wc -l) packages in .venv"
fi
