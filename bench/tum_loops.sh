#!/usr/bin/env bash
# The Kinect visual-odometry paper's experiment without a camera: TUM RGB-D ground truths -> simulated visual
# odometry with drift
# (`sextant convert tum`), played over a real LCM bus (private network namespace) into sextantd's graph back end,
# with `sextant matcher` answering its loop proposals from the ground truth.  Reports ATE (TUM semantics, `sextant
# eval`) of the raw odometry and of the optimized keyframes, at the keyframe times.
# Usage: bench/tum_loops.sh BUILD [SEQUENCES...]; env: N1 (3), N2 (-1: 2 N1), WRONG (0.05), K1 (0.1), K2 (1.0),
# FAIL (0.1), SPEED (4), matcher noise SIGMA_T (0.01 m) and SIGMA_R (0.005 rad), DRIFT_YAW (0.002 rad/m), the loops'
# kernel ROBUST (dcs) and its width PHI (auto, the daemon's default: for these 3-D loops the 6-DOF chi-square 0.999
# quantile as the gate computes it, 22.46; with phi = 1 a true 6-DOF loop at its median chi2 5.3 keeps a weight of
# (2 / 6.3)^2 = 0.1, see RESULTS); SEED (1) of the converter's noise and of the matcher; REANCHOR (10, the daemon's
# default: keyframing restarts after that many consistent implausible poses, e.g. over fr2_desk's 12 s mocap gap;
# 0: never);
# KEEP=DIR keeps each sequence's vo.lcm, gt.txt and bus.lcm in DIR/SEQUENCE (for bench/tum_graph_diagnosis.py);
# VO_FROM=DIR plays DIR/SEQUENCE/vo.lcm and gt.txt (kept by an earlier KEEP run) instead of converting anew.
set -euo pipefail
build=${1:-build}; shift || true
root=$(cd "$(dirname "$0")/.." && pwd)
seqs=${*:-fr1_desk fr1_xyz fr2_desk fr3_long_office_household}
source "$root/tests/e2e/netns.bash"
bin="$root/$build/bin"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '| sequence | n1 | n2 | k1 | k2 | wrong | keyframes | ATE odometry [m] | ATE keyframes [m] | ratio | RPE odometry [m/s, deg/s] | RPE keyframes [m/s, deg/s] | loops accepted / rejected | keyframes re-anchored |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n'
for s in $seqs; do
  gt="$root/../shared/data/tum/$s/groundtruth.txt"
  if [ -n "${VO_FROM:-}" ]; then
    cp "$VO_FROM/$s/vo.lcm" "$VO_FROM/$s/gt.txt" "$work/"
  else
    "$bin/sextant" convert tum "$gt" -o "$work/vo.lcm" --gt-out "$work/gt.txt" --seed ${SEED:-1} --drift-yaw ${DRIFT_YAW:-0.002} > /dev/null
  fi
  cat > "$work/config.yaml" <<EOC
daemon:
  status_period_s: 0.5
engine:
  primary_estimator: graph
  filter: {type: none}
  association: {enabled: false}
  graph:
    keyframes: {k1: ${K1:-0.1}, k2: ${K2:-1.0}, reanchor_after: ${REANCHOR:-10}}
    loops: {n1: ${N1:-3}, n2: ${N2:--1}, robust: ${ROBUST:-dcs}, kernel_width: ${PHI:-auto}}
EOC
  cat > "$work/run.sh" <<EOS
set -euo pipefail
"$bin/sextantd" --config "$work/config.yaml" > "$work/daemon.log" 2>&1 &
d=\$!
"$bin/sextant" matcher --truth "$work/vo.lcm" --sigma-t ${SIGMA_T:-0.01} --sigma-r ${SIGMA_R:-0.005} --failure-rate ${FAIL:-0.1} --wrong-rate ${WRONG:-0.05} --seed ${SEED:-1} > /dev/null 2>&1 &
m=\$!
lcm-logger -f "$work/bus.lcm" > /dev/null 2>&1 &
l=\$!
sleep 0.7
lcm-logplayer -s ${SPEED:-4} "$work/vo.lcm" > /dev/null
sleep 2
kill -TERM \$d; wait \$d || true
kill -TERM \$m; wait \$m || true
kill -INT \$l; wait \$l || true
EOS
  rm -f "$work/bus.lcm"
  in_netns bash "$work/run.sh"
  n=$(python3 "$root/bench/tum_loops_extract.py" "$work/bus.lcm" "$work/kf.txt" "$work/odo.txt" "$root/$build/lcmtypes/python" "$root/tests/e2e" | cut -d' ' -f1)
  score() {  # ATE, then RPE over 1 s (translation, rotation)
    "$bin/sextant" eval --gt "$work/gt.txt" --est "$1" --json |
      python3 -c 'import json,sys; j=json.load(sys.stdin); print("%.4f %.4f, %.2f" % (j["ate_rmse"], j["rpe_trans_rmse"], j["rpe_rot_rmse_deg"]))'
  }
  read -r a_odo r_odo <<< "$(score "$work/odo.txt")"
  read -r a_kf r_kf <<< "$(score "$work/kf.txt")"
  if [ -n "${KEEP:-}" ]; then mkdir -p "$KEEP/$s" && cp "$work/vo.lcm" "$work/gt.txt" "$work/bus.lcm" "$KEEP/$s/"; fi
  loops=$(python3 - "$work/bus.lcm" "$root/$build/lcmtypes/python" "$root/tests/e2e" <<'EOP'
import sys
sys.path.insert(0, sys.argv[2]); sys.path.insert(0, sys.argv[3])
from lcmlog import read_log
from sextant import status_t
c = {}
for _, ch, b in read_log(sys.argv[1]):
    if ch == "SEXTANT_STATUS":
        for st in status_t.decode(b).stages:
            if st.name == "graph":
                c = dict(zip(st.counter_names, st.counter_values))
print(f"{c.get('loops_accepted', 0)} / {c.get('loops_rejected', 0)} | {c.get('keyframes_reanchored', 0)}")
EOP
)
  ratio=$(python3 -c "print('%.2f' % ($a_kf / $a_odo))")
  n2=${N2:--1}; [ "$n2" = -1 ] && n2=$((2 * ${N1:-3}))
  echo "| $s | ${N1:-3} | $n2 | ${K1:-0.1} | ${K2:-1.0} | ${WRONG:-0.05} | $n | $a_odo | $a_kf | $ratio | $r_odo | $r_kf | $loops |"
done
