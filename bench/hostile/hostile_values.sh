#!/usr/bin/env bash
# The "hostile values" table (bench/results/hostile_values.md): each case of hostile_values.py replayed offline
# through `sextant replay` (the same intake and engine as sextantd), with what was published and how long it took.
#   [CONFIG=FILE] bench/hostile/hostile_values.sh [BUILD_DIR] [CASE...]   (CONFIG: default config/default.yaml)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="${1:-$here/../../build}"
shift || true
cases=("$@")
[ ${#cases[@]} -gt 0 ] || cases=(clean position_1e308 increment_cov_1e300 planar_roll_180 range_1e308 unknown_4096_x5 second_sender)
export PYTHONPATH="$build/lcmtypes/python${PYTHONPATH:+:$PYTHONPATH}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$build/bin/sextant" simulate planar -o "$work/clean.lcm" --seed 1 --duration 30 >/dev/null
for c in "${cases[@]}"; do
  if [ "$c" = clean ]; then cp "$work/clean.lcm" "$work/case_$c.lcm"; else python3 "$here/hostile_values.py" make "$c" "$work/clean.lcm" "$work/case_$c.lcm"; fi
  start=$(date +%s.%N)
  if timeout 120 "$build/bin/sextant" replay "$work/case_$c.lcm" --config "${CONFIG:-$here/../../config/default.yaml}" --out-log "$work/$c.out.lcm" --json > "$work/$c.json" 2>/dev/null; then
    seconds=$(echo "$(date +%s.%N) - $start" | bc)
    printf '%s\t%.1f s\t%s\n' "$c" "$seconds" "$(python3 "$here/hostile_values.py" check "$work/$c.out.lcm")"
  else
    printf '%s\tdid not finish in 120 s\n' "$c"
  fi
done
