#!/usr/bin/env bash
# `cmake --install` into a temporary prefix from the finished build (nothing is rebuilt), then what an adopter does
# with it: the installed tools run and report the build's version, the installed configs validate, the systemd unit
# names the prefix, the examples/consumer project configures against the installed CMake package
# (find_package(sextant)) and builds; its optimize_g2o (sextant::estimators) optimizes a shared g2o file to the same
# chi2, the same iteration count and a byte-identical optimized graph as `sextant optimize`, its log_summary
# (sextant::runtime) counts a simulated log's events per channel as an independent reader does; the installed Python module imports
# from the prefix.  Environment: SEXTANT_BUILD_DIR, SEXTANT_SOURCE_DIR, SEXTANT_SHARED_DIR, SEXTANT_PYTHON (the
# interpreter the module was built for; empty when it was not built).
set -euo pipefail
prefix=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$prefix"' EXIT
fail() { echo "install_consumer: $*" >&2; exit 1; }

cmake --install "$SEXTANT_BUILD_DIR" --prefix "$prefix/usr" > "$prefix/install.log" || { cat "$prefix/install.log"; fail "cmake --install failed"; }
p=$prefix/usr
for f in bin/sextantd bin/sextant lib/libsextant_estimators.a lib/libsextant_assoc.a lib/libsextant_engine.a \
         lib/cmake/sextant/sextantConfig.cmake lib/cmake/sextant/sextantConfigVersion.cmake \
         lib/cmake/sextant/sextantTargets.cmake include/sextant/estimators/graph/optimizer.hpp \
         include/sextant/assoc/sd_assignment.hpp include/sextant/daemon/engine/engine.hpp \
         include/sextant/sextant/odometry_t.hpp include/sextant/sextant/status_t.hpp \
         share/sextant/lcmtypes/sextant/odometry_t.lcm share/sextant/config/default.yaml \
         share/sextant/config/mrclam.yaml lib/systemd/system/sextantd.service; do
  [ -e "$p/$f" ] || fail "not installed: $f"
done
[ ! -e "$p/include/sextant/cli/command.hpp" ] || fail "the CLI's private headers were installed"
# `sextant convert rosbag` finds its module where it was installed (not a bag: the bag library's own error).
[ -e "$p/lib/sextant/libsextant_rosbag.so" ] || fail "not installed: lib/sextant/libsextant_rosbag.so"
rosbag_out=$("$p/bin/sextant" convert rosbag "$prefix/install.log" -o "$prefix/x.lcm" 2>&1 || true)
case "$rosbag_out" in *"version line"*) ;; *) fail "installed sextant convert rosbag: $rosbag_out" ;; esac
[ ! -e "$p/include/sextant/estimators/graph/smoother" ] || fail "the smoother's internal headers were installed"
[ -e "$p/include/sextant/estimators/graph/incremental_smoother.hpp" ] || fail "not installed: the smoother's public header"
# The public graph headers a consumer includes reach no internal smoother header and no CHOLMOD (their dependency
# list, from the installed headers only).
for h in estimators/graph/optimizer.hpp estimators/graph/incremental_smoother.hpp; do
  deps=$(echo "#include \"$h\"" | ${CXX:-c++} -std=c++17 -I"$p/include/sextant" -isystem /usr/include/eigen3 -M -x c++ - 2>&1) ||
    fail "$h does not compile from the installed headers alone: $deps"
  ! grep -q "cholmod\|graph/smoother/" <<< "$deps" || fail "$h reaches CHOLMOD or a smoother step"
done
n_lcm=$(ls "$SEXTANT_SOURCE_DIR"/lcmtypes/sextant/*.lcm | wc -l)
[ "$(ls "$p"/share/sextant/lcmtypes/sextant/*.lcm | wc -l)" -eq "$n_lcm" ] || fail "not every .lcm file was installed"
[ "$(ls "$p"/include/sextant/sextant/*.hpp | wc -l)" -eq "$n_lcm" ] || fail "not every message header was installed"
if [ -e "$SEXTANT_BUILD_DIR/lcmtypes/sextant_types.jar" ]; then
  [ -e "$p/share/java/sextant_types.jar" ] || fail "the Java jar was not installed"
fi

# The installed tools: the build's version, and the installed configs validate.
v_build=$("$SEXTANT_BUILD_DIR/bin/sextant" --version)
[ -n "$v_build" ] || fail "sextant --version printed nothing"
[ "$("$p/bin/sextant" --version)" = "$v_build" ] || fail "installed sextant --version differs from the build's"
[ "$("$p/bin/sextantd" --version)" = "$v_build" ] || fail "installed sextantd --version differs from sextant's"
for c in "$p"/share/sextant/config/*.yaml; do
  "$p/bin/sextantd" --check-config "$c" > /dev/null || fail "installed $c does not validate"
done

# The unit names this prefix, not the default one.
unit=$p/lib/systemd/system/sextantd.service
grep -q "^ExecStart=$p/bin/sextantd --config" "$unit" || fail "the installed unit's ExecStart does not name $p/bin"
grep -q "^Environment=SEXTANT_CONFIG=$p/share/sextant/config/default.yaml" "$unit" || fail "the unit's config path is not under $p"
! grep -q "/usr/local/" "$unit" || fail "the installed unit still names /usr/local"
# systemd's own parser must accept every line (it only warns, on stderr, about keys or values it ignores).
if command -v systemd-analyze > /dev/null; then
  out=$(timeout 60 systemd-analyze verify "$unit" 2>&1) || fail "systemd-analyze verify failed: $out"
  [ -z "$out" ] || fail "systemd-analyze verify: $out"
else
  echo "install_consumer: systemd-analyze not installed; the unit's syntax is not checked"
fi

# The consumer project, built against the installed package only (the launcher of the main build, if any, is reused).
launcher=()
[ -n "${SEXTANT_CXX_LAUNCHER:-}" ] && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER="$SEXTANT_CXX_LAUNCHER")
cmake -S "$SEXTANT_SOURCE_DIR/examples/consumer" -B "$prefix/example" -DCMAKE_PREFIX_PATH="$p" \
      "${launcher[@]}" > "$prefix/example.log" 2>&1 || { cat "$prefix/example.log"; fail "the example does not configure against $p"; }
grep -q "sextant_DIR:PATH=$p/lib/cmake/sextant" "$prefix/example/CMakeCache.txt" || fail "the example found another sextant package"
cmake --build "$prefix/example" > "$prefix/example.log" 2>&1 || { cat "$prefix/example.log"; fail "the example does not build"; }

g2o=$SEXTANT_SHARED_DIR/data/posegraph/CSAIL.g2o
[ -e "$g2o" ] || fail "no $g2o"
"$prefix/example/optimize_g2o" "$g2o" "$prefix/example.g2o" > "$prefix/example.json"
"$p/bin/sextant" optimize "$g2o" --json -o "$prefix/cli.g2o" > "$prefix/cli.json"
python3 - "$prefix/example.json" "$prefix/cli.json" <<'PY'
import json, sys
ex, cli = (json.load(open(f)) for f in sys.argv[1:3])
for k in ("vertices", "edges", "dimension", "iterations", "converged"):
    assert ex[k] == cli[k], f"{k}: example {ex[k]} != sextant optimize {cli[k]}"
for k in ("initial_chi2", "final_chi2"):
    assert abs(ex[k] - cli[k]) <= 1e-12 * max(1.0, abs(cli[k])), f"{k}: example {ex[k]!r} != sextant optimize {cli[k]!r}"
assert ex["final_chi2"] < 0.5 * ex["initial_chi2"], f"nothing was optimized: {ex}"
print(f"example: {ex['vertices']} vertices, chi2 {ex['initial_chi2']:.3f} -> {ex['final_chi2']:.6f} in {ex['iterations']} iterations, as sextant optimize")
PY
cmp -s "$prefix/example.g2o" "$prefix/cli.g2o" || fail "the example's optimized graph differs from sextant optimize -o"

"$p/bin/sextant" simulate planar -o "$prefix/sim.lcm" --seed 1 --duration 10 > /dev/null
"$prefix/example/log_summary" "$prefix/sim.lcm" > "$prefix/summary.txt"
python3 - "$prefix/summary.txt" "$prefix/sim.lcm" "$SEXTANT_SOURCE_DIR/tests/e2e" <<'PY'
import collections, sys
sys.path.insert(0, sys.argv[3])
from lcmlog import read_log
want = collections.Counter(c for _, c, _ in read_log(sys.argv[2]))
got = {}
for line in open(sys.argv[1]):
    name, events, accepted = line.split()
    got[name] = (int(events), int(accepted))
assert {k: v[0] for k, v in got.items()} == dict(want), f"log_summary {got} != {dict(want)}"
assert got["ODOMETRY"][1] == want["ODOMETRY"] > 0, "every simulated odometry message passes the daemon's checks"
assert all(v[1] == 0 for k, v in got.items() if k != "ODOMETRY"), "only odometry decodes as odometry"
print("log_summary:", got)
PY

# The Python module, from the prefix.
if [ -n "${SEXTANT_PYTHON:-}" ]; then
  site=$(cd "$p" && ls -d lib/python3*/dist-packages)
  PYTHONPATH="$p/$site" "$SEXTANT_PYTHON" -c "
import sextant, sys
assert sextant.__file__.startswith('$p/'), sextant.__file__
assert sextant.__version__ == '$v_build', sextant.__version__
r = sextant.optimize('$g2o')
print('python from the prefix:', sextant.__file__, r['summary']['final_chi2'])
" || fail "the installed Python module does not work"
fi
echo "install_consumer: ok"
