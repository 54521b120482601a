#!/usr/bin/env bash
# Sets up, builds and runs the simulator: `roslaunch spinning_top spinning_top.launch ARGS...`
# (headless default scene; pass rviz:=true to watch it, scene:=viscous to change scene, ...).
# roslaunch starts a ROS master if none is running. Ctrl-C stops it.
# `bash scripts/run.sh --help` says how to use it and lists the launch file's arguments (once
# built), without installing or building anything.
set -euo pipefail
source "$(dirname "$0")/env.sh"

usage() {
  cat <<USAGE
usage: bash scripts/run.sh [NAME:=VALUE ...] [roslaunch options]

Installs what is missing (Debian packages, as root: scripts/setup.sh), builds (scripts/build.sh)
and runs   roslaunch spinning_top spinning_top.launch NAME:=VALUE ...
Examples:  bash scripts/run.sh rviz:=true
           bash scripts/run.sh scene:=viscous record:=true
USAGE
  if [ -f "$SPINNING_TOP_DEVEL/setup.bash" ]; then
    spinning_top_source_devel
    echo
    echo "Arguments of spinning_top.launch (roslaunch --ros-args):"
    roslaunch --ros-args spinning_top spinning_top.launch
  else
    echo
    echo "(After a build, --help also lists the launch file's arguments.)"
  fi
}
for arg in "$@"; do
  case "$arg" in
    -h|--help) usage; exit 0 ;;
  esac
done

setup_options=()
for arg in "$@"; do
  [ "$arg" = "rviz:=true" ] && setup_options+=(--rviz)
done
"$SPINNING_TOP_ROOT/scripts/setup.sh" "${setup_options[@]}"
"$SPINNING_TOP_ROOT/scripts/build.sh"
spinning_top_source_devel
exec roslaunch spinning_top spinning_top.launch "$@"
