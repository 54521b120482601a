#!/usr/bin/env bash
# Installs what the package needs from Debian bookworm's own ROS 1 packages (as root).
# Usage: scripts/setup.sh [--rviz]
#   --rviz   also rviz and Xvfb (to watch the top, or take screenshots headless)
set -euo pipefail
source "$(dirname "$0")/env.sh"

packages=(
  build-essential cmake pkg-config
  catkin ros-core-dev python3-catkin-pkg python3-rospkg python3-rostest python3-rosunit
  python3-roslaunch python3-rosbag librosbag-dev rosbash
  libeigen3-dev libboost-dev libyaml-cpp-dev libgtest-dev googletest
  ros-message-generation ros-message-runtime python3-genmsg python3-gencpp python3-genpy
  python3-rospy python3-std-msgs
  libtf2-ros-dev libtf2-eigen-dev python3-tf2-msgs python3-tf2-ros
  libgeometry-msgs-dev python3-geometry-msgs
  libvisualization-msgs-dev python3-visualization-msgs
  libstd-srvs-dev python3-std-srvs
  libros-rosgraph-msgs-dev python3-rosgraph-msgs
  libdiagnostic-msgs-dev python3-diagnostic-msgs libdiagnostic-updater-dev
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  # The Python module and sweeps (python/spinning_top): pybind11, numpy, pandas, scipy (Sobol),
  # matplotlib (maps), tqdm (progress), pytest (their tests).
  pybind11-dev python3-dev python3-pybind11 python3-setuptools python3-numpy python3-pandas python3-scipy
  python3-matplotlib python3-tqdm python3-pytest python3-yaml
  # Optional for users (no rosdep key; sweeps on a cluster, --scheduler), needed by the tests of
  # the scale-out: Dask.
  python3-dask python3-distributed
  # The tests' check of the package's CMake and package.xml (test/python/test_release.py).
  catkin-lint
)
for arg in "$@"; do
  case "$arg" in
    --rviz) packages+=(rviz xvfb xauth mesa-utils libgl1-mesa-dri imagemagick) ;;
    *) echo "setup.sh: unknown option '$arg' (use --rviz)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup.sh: missing packages (run as root to install): ${missing[*]}" >&2
    exit 1
  fi
  echo "setup.sh: installing ${#missing[@]} Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
echo "setup.sh: all dependencies installed"
