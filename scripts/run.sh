#!/usr/bin/env bash
# Sets up, builds and runs the simulator: `roslaunch spinning_top spinning_top.launch ARGS...`
# (headless default scene; pass rviz:=true to watch it, scene:=viscous to change scene, ...).
# roslaunch starts a ROS master if none is running. Ctrl-C stops it.
set -euo pipefail
source "$(dirname "$0")/env.sh"
setup_options=()
for arg in "$@"; do
  [ "$arg" = "rviz:=true" ] && setup_options+=(--rviz)
done
"$SPINNING_TOP_ROOT/scripts/setup.sh" "${setup_options[@]}"
"$SPINNING_TOP_ROOT/scripts/build.sh"
set +u  # ROS's setup scripts read unset variables
source "$SPINNING_TOP_BUILD/devel/setup.bash"
set -u
exec roslaunch spinning_top spinning_top.launch "$@"
