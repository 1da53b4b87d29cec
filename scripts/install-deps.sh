#!/usr/bin/env bash
# Installs the Debian packages the project needs, by group. Debian 12 (bookworm),
# as root (no sudo needed); with sudo available it is used when not root.
# usage: scripts/install-deps.sh [--check] [GROUP ...]   (default: all)
#   demo   what scripts/run-demo.sh needs to configure and build the libraries,
#          ground-aware-mapper, gam-simulate and gam-evaluate: the compiler,
#          cmake, ccache, Eigen, octomap and only the MRPT modules the
#          configure step asks for (not the libmrpt-dev meta-package, which
#          pulls ROS 1, OpenCV, Qt 5 and GTK: on a bare system the group is
#          ~280 packages, ~210 MB, instead of ~740, ~430 MB).
#   all    everything: the demo's packages plus the whole MRPT (its apps and
#          data, its sensor drivers for ground-aware-mapper --live), wxWidgets (ground-aware-viewer), GoogleTest, Google
#          Benchmark, Xvfb, GNU time, clang (sanitizers, fuzzers, clang-format) and the
#          Python modules of rawlog_tools. scripts/run-tests.sh and CI need all.
#   --check  install nothing: exit 0 if every package of the groups is
#          installed, 1 if not.
set -euo pipefail
DEMO_PKGS=(
  build-essential cmake ccache
  libeigen3-dev liboctomap-dev
  libmrpt-maps-dev libmrpt-obs-dev libmrpt-opengl-dev libmrpt-img-dev libmrpt-io-dev
  libmrpt-tclap-dev libmrpt-nav-dev  # mrpt-nav: ground-aware-nav-example is always configured
)
REST_PKGS=(
  git pkg-config file
  libmrpt-dev mrpt-apps mrpt-common
  libmrpt-hwdrivers-dev  # ground-aware-mapper --live (MRPT's sensor drivers; CMake looks for mrpt-hwdrivers)
  libwxgtk3.2-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  xvfb xauth
  time  # /usr/bin/time -v: rawlog_tools/gam-long-traversal (test LongTraversal.*)
  clang libclang-rt-14-dev clang-format
  python3-rosbag python3-sensor-msgs python3-nav-msgs python3-tf2-msgs python3-geometry-msgs
  python3-matplotlib  # only for the plot of rawlog_tools/gam-detection-range (doc/figures/detection-range.png)
)
check=0
if [ "${1:-}" = "--check" ]; then check=1; shift; fi
[ $# -gt 0 ] || set -- all
PKGS=()
for g in "$@"; do
  case "$g" in
    demo) PKGS+=("${DEMO_PKGS[@]}") ;;
    all) PKGS+=("${DEMO_PKGS[@]}" "${REST_PKGS[@]}") ;;
    *) echo "[install-deps] unknown group '$g' (demo, all)" >&2; exit 2 ;;
  esac
done
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ $check -eq 1 ]; then
  if [ ${#missing[@]} -eq 0 ]; then exit 0; else exit 1; fi
fi
if [ ${#missing[@]} -eq 0 ]; then
  echo "[install-deps] $* : all ${#PKGS[@]} packages present"
  exit 0
fi
echo "[install-deps] $* : installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
