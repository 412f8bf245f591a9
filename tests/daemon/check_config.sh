#!/usr/bin/env bash
# sextantd --check-config FILE: 0 and "FILE: ok" for the bundled configs; 2 with FILE:LINE:COLUMN on stderr for an
# unknown key, a value of the wrong type, a value out of range and broken YAML, each on the line it is on; 2 naming
# the file when it cannot be read.  --version: the same string as `sextant --version`.  No bus is touched (the
# checks run with an LCM URL that cannot work).
set -euo pipefail
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
d=$SEXTANT_BIN/sextantd
export LCM_DEFAULT_URL="udpm://0.0.0.0:1?this-would-fail"
fail() { echo "check_config: $*" >&2; exit 1; }

for c in "$SEXTANT_SOURCE_DIR"/config/*.yaml; do
  out=$("$d" --check-config "$c") || fail "$c: exit $? (expected 0)"
  [[ $out == "$c: ok"* ]] || fail "$c: unexpected output '$out'"
done

# expect_error NAME EXPECTED_PREFIX YAML: the file must be refused with exit 2 and stderr starting with the prefix.
expect_error() {
  local name=$1 prefix=$2 file=$work/$1.yaml
  printf '%b' "$3" > "$file"
  local rc=0
  "$d" --check-config "$file" > "$work/out" 2> "$work/err" || rc=$?
  [ "$rc" -eq 2 ] || fail "$name: exit $rc (expected 2); stderr: $(cat "$work/err")"
  [ ! -s "$work/out" ] || fail "$name: printed on stdout: $(cat "$work/out")"
  [[ $(head -1 "$work/err") == "$file:$prefix"* ]] || fail "$name: stderr '$(cat "$work/err")' does not start with $file:$prefix"
}
expect_error unknown_key "4:" 'daemon:\n  name: a\nengine:\n  filtr:\n    type: ekf\n'
expect_error wrong_type "3:" 'daemon:\n  name: a\n  queue_capacity: many\n'
expect_error out_of_range "2:" 'daemon:\n  status_period_s: -1\n'
expect_error broken_yaml "3:" 'daemon:\n  name: a\n   bad: 1\n'

rc=0
"$d" --check-config "$work/missing.yaml" 2> "$work/err" || rc=$?
[ "$rc" -eq 2 ] && grep -q "$work/missing.yaml" "$work/err" || fail "a missing file: exit $rc, stderr $(cat "$work/err")"
rc=0
"$d" > /dev/null 2> "$work/err" || rc=$?
[ "$rc" -eq 2 ] && grep -q -- "--config" "$work/err" || fail "no --config: exit $rc, stderr $(cat "$work/err")"
rc=0
"$d" --config "$SEXTANT_SOURCE_DIR/config/default.yaml" --check-config "$SEXTANT_SOURCE_DIR/config/default.yaml" \
    > /dev/null 2>&1 || rc=$?
[ "$rc" -ne 0 ] || fail "--config with --check-config was accepted"

v=$("$d" --version)
[ "$v" = "$("$SEXTANT_BIN/sextant" --version)" ] || fail "sextantd --version '$v' differs from sextant --version"
[[ $v =~ ^v?[0-9]+\.[0-9]+\.[0-9]+ ]] || fail "version '$v' does not start with a version number"
echo "check_config: ok"
