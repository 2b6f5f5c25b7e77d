#!/usr/bin/env bash
# Idempotent set-up on a fresh Debian machine: system libraries for headless rendering,
# a virtual environment in .venv with the exact dependency versions of requirements.lock.
# Re-running is cheap: each step is skipped when already done.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)

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
want=$(sha256sum < requirements.lock | cut -d' ' -f1)
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
echo "[setup] installing the locked Python dependencies"

# uv_sources: pip's package sources as uv options, one to a line. uv reads no pip
# configuration, and this machine's pip is configured (`pip config list`) with a local wheel
# folder (find-links: the CPU torch wheel) and local file indexes beside the registry; uv gets
# every one of them. Every package is pinned to one version (torch to 2.13.0+cpu, a build only
# the wheel folder has), so more sources can change where a wheel comes from, never which.
uv_sources() {
  local key value item
  while IFS= read -r line; do
    key=${line%%=*}
    value=${line#*=}
    value=${value#\'}
    value=${value%\'}
    for item in $value; do
      case $key in
        *.find-links) echo "--find-links=$item" ;;
        *.extra-index-url) echo "--extra-index-url=$item" ;;
        *.index-url) echo "--index-url=$item" ;;
      esac
    done
  done < <(.venv/bin/python -m pip config list 2>/dev/null) | sort -u
}

# pip's certificate bundle, for uv's downloads too (uv reads SSL_CERT_FILE).
if [ -z "${SSL_CERT_FILE:-}" ]; then
  cert=$(.venv/bin/python -m pip config list 2>/dev/null | sed -n "s/^[^=]*\.cert='\(.*\)'$/\1/p" | head -n 1)
  if [ -n "$cert" ]; then export SSL_CERT_FILE=$cert; fi
fi

if [ "${SETUP_INSTALLER:-uv}" = pip ]; then
  # The slower installer, on request (SETUP_INSTALLER=pip): one download at a time.
  # --no-compile: pip would byte-compile all ~22,000 installed modules (about 45 s of CPU).
  .venv/bin/python -m pip install -qq --no-compile --disable-pip-version-check \
    -r requirements.lock
else
  # uv, at the lock's version, installed by pip from the same sources; it then makes .venv
  # exactly the lock (`pip sync`: installs what is missing, changes what differs, removes
  # what the lock does not name), downloading in parallel. It does not byte-compile either:
  # Python compiles a module on its first import. unsafe-best-match is pip's rule: a pinned
  # version is taken from whichever source has it.
  uv_pin=$(grep -m 1 '^uv==' requirements.lock)
  .venv/bin/python -m pip install -qq --no-compile --disable-pip-version-check "$uv_pin"
  mapfile -t sources < <(uv_sources)
  .venv/bin/uv pip sync --quiet --python .venv/bin/python --index-strategy unsafe-best-match \
    "${sources[@]}" requirements.lock
  .venv/bin/uv pip check --quiet --python .venv/bin/python
fi

# .venv holds exactly the lock's versions (names normalised as PEP 503 says).
normalise() { awk -F'==' 'NF == 2 { n = tolower($1); gsub(/[-_.]+/, "-", n); print n "==" $2 }' | sort; }
off=$(comm -23 <(grep -E '^[A-Za-z0-9_.-]+==' requirements.lock | normalise) \
  <(.venv/bin/python -m pip freeze --all --disable-pip-version-check 2>/dev/null | normalise))
if [ -n "$off" ]; then
  echo "[setup] .venv does not hold these locked versions:" $off >&2
  exit 1
fi
echo "$want" > "$stamp"
echo "[setup] done: $(grep -c -E '^[A-Za-z0-9_.-]+==' requirements.lock) locked packages in .venv in $(( $(date +%s) - start )) s"
