#!/usr/bin/env bash
# Sets up, builds and runs a parameter sweep: `python3 -m spinning_top.sweep ARGS...` (issue 11;
# README "Parameter sweeps and stability maps"). No ROS master is needed. Example:
#   bash scripts/sweep.sh --config config/fixed_tip.yaml --vary initial/spin=0:200:201 \
#     --vary initial/tilt=0:1.4:141 --output map.csv --plot map.png
# `bash scripts/sweep.sh --help` prints the sweep's options (once built) without installing or
# building anything.
set -euo pipefail
source "$(dirname "$0")/env.sh"

for arg in "$@"; do
  case "$arg" in
    -h|--help)
      echo "bash scripts/sweep.sh ARGS...: installs what is missing (as root), builds, then runs"
      echo "python3 -m spinning_top.sweep ARGS..."
      if [ -f "$SPINNING_TOP_DEVEL/setup.bash" ]; then
        spinning_top_source_devel
        echo
        exec /usr/bin/python3 -m spinning_top.sweep --help
      fi
      echo "(After a build, --help also lists the sweep's options: bash scripts/build.sh.)"
      exit 0 ;;
  esac
done

"$SPINNING_TOP_ROOT/scripts/setup.sh" >&2
"$SPINNING_TOP_ROOT/scripts/build.sh" >&2
spinning_top_source_devel
exec /usr/bin/python3 -m spinning_top.sweep "$@"
