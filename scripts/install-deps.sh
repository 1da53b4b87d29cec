#!/usr/bin/env bash
# Installs every Debian package the project needs. Debian 12 (bookworm), as
# root (no sudo needed); with sudo available it is used when not root.
set -euo pipefail
PKGS=(
  build-essential cmake git ccache pkg-config file
  libmrpt-dev mrpt-apps mrpt-common
  liboctomap-dev libeigen3-dev
  libwxgtk3.2-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  xvfb xauth
  clang libclang-rt-14-dev clang-format
  python3-rosbag python3-sensor-msgs python3-nav-msgs python3-tf2-msgs python3-geometry-msgs
  python3-matplotlib  # only for the plot of rawlog_tools/gam-detection-range (doc/figures/detection-range.png)
)
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "[install-deps] all ${#PKGS[@]} packages present"
  exit 0
fi
echo "[install-deps] installing: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
