# The demo's world, sourced by scripts/demo.sh and bench/refactor_identity.sh: the passive sensors see false alarms
# (the simulator's 1 per sensor and scan) in their fields of view over the targets' region, and the 4 targets.  The
# daemon runs config/default.yaml told the same: the region, that rate (per-sensor false-alarm densities) and the
# target prior, as tests/e2e/daemon_bus.sh does.  With the default's scalar density and no prior, in-view false alarms
# pass as targets (offline replay of this run at b7308dc: 119 ghost TARGETS of 514 estimates instead of 18 of 412).
region_min=(-30 -20 4) region_max=(30 20 16) false_alarms=1 targets=4

# demo_config DEFAULT_YAML OUT_YAML: a copy of config/default.yaml with the demo's association settings.
demo_join() { local IFS=,; echo "$*"; }
demo_config() {
  sed -e "s/^\(    region_min: \)\[\]/\1[$(demo_join "${region_min[@]}")]/" \
      -e "s/^\(    region_max: \)\[\]/\1[$(demo_join "${region_max[@]}")]/" \
      -e "s/^\(    false_alarms_per_scan: \)0\b/\1$false_alarms/" -e "s/^\(    target_prior: \)false\b/\1true/" \
      -e "s/^\(    expected_targets: \)1\b/\1$targets/" "$1" > "$2"
  if [ "$(diff "$1" "$2" | grep -c '^>')" != 5 ]; then
    echo "demo: could not set association.region_min/region_max/false_alarms_per_scan/target_prior/expected_targets" >&2
    echo "      in a copy of config/default.yaml ($2); has the file's layout changed?" >&2
    return 1
  fi
}
