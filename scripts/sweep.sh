#!/usr/bin/env bash
# Sets up, builds and runs a parameter sweep: `python3 -m spinning_top.sweep ARGS...` (issue 11;
# README "Parameter sweeps and stability maps"). No ROS master is needed. Example:
#   bash scripts/sweep.sh --config config/fixed_tip.yaml --vary initial/spin=0:200:201 \
#     --vary initial/tilt=0:1.4:141 --output map.csv --plot map.png
set -euo pipefail
source "$(dirname "$0")/env.sh"
"$SPINNING_TOP_ROOT/scripts/setup.sh" >&2
"$SPINNING_TOP_ROOT/scripts/build.sh" >&2
set +u  # ROS's setup scripts read unset variables
source "$SPINNING_TOP_BUILD/devel/setup.bash"
set -u
exec /usr/bin/python3 -m spinning_top.sweep "$@"
