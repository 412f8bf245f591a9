#!/usr/bin/env bash
# Installs the npm packages of the reference-client tests (tests/viewer/: @mcap/core, @foxglove/ws-protocol,
# @foxglove/schemas and what they need) exactly as tests/viewer/package-lock.json pins them, with `npm ci`.
# Quiet and quick when they are installed already (a stamp holds the hash of the lock file they came from).
# Called by scripts/install-deps.sh; needs node and npm (Debian's nodejs and npm packages).
# Usage: scripts/install-node-deps.sh [DIR]   (DIR: another folder with a package-lock.json, e.g.
# scripts/foxglove_screenshot for scripts/foxglove_screenshot.sh; default tests/viewer)
set -euo pipefail
dir="$(cd "${1:-$(dirname "$0")/../tests/viewer}" && pwd)"
stamp="$dir/node_modules/.sextant-lock-sha256"
want=$(sha256sum "$dir/package-lock.json" | cut -d' ' -f1)
if [[ -f "$stamp" && "$(cat "$stamp")" == "$want" ]]; then exit 0; fi
echo "install-node-deps: npm ci in $dir"
(cd "$dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
echo "$want" > "$stamp"
