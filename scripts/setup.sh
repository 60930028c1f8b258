#!/usr/bin/env bash
# Installs what physbench needs and is missing: Debian packages (apt-get), the report
# builder's Python packages (a project-local .venv) and the replay viewer's npm packages
# (reports/viewer/node_modules, from its package-lock.json), then bundles the viewer. Safe to run
# again: it only installs what is not there. Sourced by bench.sh and test.sh.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libboost-dev nlohmann-json3-dev libcli11-dev libgtest-dev libbenchmark-dev
  libbullet-dev libode-dev libbox2d-dev libmujoco-dev libqhull-dev
  clang  # physx-sys (the PhysX worker, workers/physx) compiles PhysX with clang++
  python3 python3-venv
  chromium  # the report's browser test (reports/viewer/tests) drives /usr/bin/chromium headless
)
# node and npm for the replay viewer: Debian's when the machine has none
command -v npm >/dev/null 2>&1 || packages+=(nodejs npm)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing Debian packages: ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -q
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# the report builder's virtual environment, rebuilt when requirements.txt changes
venv="$root/.venv"
stamp="$venv/.requirements.sha256"
want=$(sha256sum "$root/reports/requirements.txt" | cut -d' ' -f1)
if [ ! -x "$venv/bin/python" ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "setup: creating $venv with reports/requirements.txt" >&2
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install -q --upgrade pip
  "$venv/bin/python" -m pip install -q -r "$root/reports/requirements.txt"
  echo "$want" > "$stamp"
fi

# the replay viewer's npm packages, reinstalled when package-lock.json changes, then its bundle
viewer="$root/reports/viewer"
stamp="$viewer/node_modules/.package-lock.sha256"
want=$(sha256sum "$viewer/package-lock.json" | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "setup: npm ci in $viewer" >&2
  (cd "$viewer" && npm ci --no-audit --no-fund --loglevel=error)
  echo "$want" > "$stamp"
fi
(cd "$viewer" && npm run --silent build)
