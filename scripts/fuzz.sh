#!/usr/bin/env bash
# Runs every fuzz harness of a `make fuzz` build (libFuzzer under ASan/UBSan) for FUZZ_SECONDS each (default 60),
# starting from the seed corpus and the past crash inputs in tests/fuzz/.  New corpus entries stay in
# BUILD/fuzz-corpus/<name>/; a crash leaves its input in BUILD/fuzz-crashes/<name>/ (copy it into
# tests/fuzz/crashes/<name>/ with the fix, so that `make test` replays it for ever) and makes this script fail.
# Prints one line per harness: executions, executions per second, coverage (libFuzzer's cov: edges and ft: features
# at the end), corpus size.  FUZZ_ONLY="codec lcm_log" runs
# those harnesses only; FUZZ_RUNS=N stops each after N executions (then FUZZ_SECONDS is only an upper bound).
# Allocation stacks are not recorded (malloc_context_size=0): recording them took a third of the parsers' time; a
# crash input reproduces its report with full stacks when its harness is run on it alone.
set -euo pipefail
build=${1:-build-fuzz}
seconds=${FUZZ_SECONDS:-${2:-60}}
src=$(cd "$(dirname "$0")/.." && pwd)/tests/fuzz
failed=0
for bin in "$build"/bin/fuzz_*; do
  name=$(basename "$bin"); name=${name#fuzz_}
  if [ -n "${FUZZ_ONLY:-}" ] && ! [[ " $FUZZ_ONLY " == *" $name "* ]]; then continue; fi
  corpus="$build/fuzz-corpus/$name"; crashes="$build/fuzz-crashes/$name"
  mkdir -p "$corpus" "$crashes"
  log="$build/fuzz-$name.log"
  seeds=()  # libFuzzer refuses a folder that does not exist (a harness with no past crash has none)
  for d in "$src/corpus/$name" "$src/crashes/$name"; do [ -d "$d" ] && seeds+=("$d"); done
  rc=0
  ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1:malloc_context_size=0 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    "$bin" -max_total_time="$seconds" -runs="${FUZZ_RUNS:--1}" -rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=10 -print_final_stats=1 \
    -artifact_prefix="$crashes/" "$corpus" "${seeds[@]}" > "$log" 2>&1 || rc=$?
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  rate=$(grep -o 'exec/s: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1 || echo "cov: ?")
  if [ "$rc" -ne 0 ]; then
    failed=1
    echo "fuzz $name: FAILED after $runs executions (log: $log, inputs: $crashes)"
    grep -m3 -E 'ERROR|SUMMARY|runtime error' "$log" || true
  else
    took=$(grep -o 'Done [0-9]* runs in [0-9]* second' "$log" | grep -o '[0-9]* second' | grep -o '[0-9]*' || echo "$seconds")
    echo "fuzz $name: $runs executions in ${took} s ($rate exec/s), $cov, corpus $(ls "$corpus" | wc -l) files, no failure"
  fi
done
exit $failed
