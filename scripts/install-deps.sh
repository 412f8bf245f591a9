#!/usr/bin/env bash
# Installs every Debian package sextant needs to build, test, benchmark and demo.
# Idempotent and quiet when everything is present; works as root or through sudo.
set -euo pipefail

packages=(
  build-essential cmake pkg-config make
  liblcm-dev liblcm-bin liblcm-java libjchart2d-java libglib2.0-dev default-jdk-headless
  libeigen3-dev libsuitesparse-dev libgeographiclib-dev
  libspdlog-dev libyaml-cpp-dev libcli11-dev doctest-dev libbenchmark-dev
  iproute2 util-linux procps python3
  nftables   # the fleet's multi-host test drops a share of datagrams at each test host (no netem in this kernel)
  pybind11-dev python3-dev python3-pytest   # the sextant Python module and its tests
  chromium   # the report test renders the HTML report in headless Chromium
  libzstd-dev zlib1g-dev libboost-dev nlohmann-json3-dev   # viewer/: MCAP chunks and CRCs, the Foxglove bridge, JSON
  # `sextant convert rosbag`: ROS 1's bag reader and message headers (cmake/rosbag.cmake says why the ROS 2
  # pluginlib and class_loader headers are here); python3-rosbag is the test's independent reader.
  librosbag-storage-dev libsensor-msgs-dev libnav-msgs-dev libgeometry-msgs-dev
  pluginlib-dev libclass-loader-dev librcpputils-dev librcutils-dev libament-index-cpp-dev python3-rosbag
)
# Optional extras: installed when asked for (benchmarks against Ceres).
if [[ "${SEXTANT_WITH_BENCH:-0}" == 1 ]]; then packages+=(libceres-dev libopenblas0 time); fi
# `make fuzz`: clang with libFuzzer and the sanitizer runtimes.
if [[ "${SEXTANT_WITH_FUZZ:-0}" == 1 ]]; then packages+=(clang libclang-rt-dev); fi

# The reference-client tests (tests/viewer/) run on Node.js; a machine whose node comes from elsewhere keeps it.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then packages+=(nodejs npm); fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [[ ${#missing[@]} -gt 0 ]]; then
  if [[ $(id -u) -eq 0 ]]; then sudo=(); elif command -v sudo >/dev/null; then sudo=(sudo); else
    echo "install-deps: missing packages: ${missing[*]}; run as root or install sudo" >&2; exit 1
  fi
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# npm packages of the reference-client tests, pinned by tests/viewer/package-lock.json.
"$(dirname "$0")/install-node-deps.sh"
