#!/usr/bin/env bash
# The README's rviz pictures of the hybrid model (issue 18), reproduced headless:
#   doc/rviz_hopping.png  the frictionless top of config/frictionless.yaml launched at tilt 0.8 rad
#                         with a precession of 60 rad/s, at t = 0.057 s: mid-flight, its tip
#                         10 mm above the floor (the first flight lasts 0.0094 ... 0.0924 s)
#   doc/rviz_fallen.png   the same top at 5 rad/s, at t = 0.1 s: fallen onto its rim at 0.087 s,
#                         shown at rest
# Each: the node starts paused and ~step takes it tick by tick to that time, so the picture does
# not depend on the machine's speed; rviz (software GL under Xvfb) looks from the side.
# Usage, after `bash scripts/setup.sh --rviz` and `bash scripts/build.sh`:
#   bash scripts/rviz_screenshots.sh [output directory, default doc]
set -euo pipefail
source "$(dirname "$0")/env.sh"
if [ -z "${SPINNING_TOP_UNDER_XVFB:-}" ]; then
  exec env SPINNING_TOP_UNDER_XVFB=1 xvfb-run -a -s "-screen 0 1280x800x24" bash "$0" "$@"
fi
export LIBGL_ALWAYS_SOFTWARE=1
set +u  # catkin's setup scripts read unset variables
source "$SPINNING_TOP_BUILD/devel/setup.bash"
set -u
output="$(cd "${1:-$SPINNING_TOP_ROOT/doc}" && pwd)"
work="$(mktemp -d)"
export ROS_HOME="$work/ros"
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

# The shipped view from the side and closer (the tip's height above the 1 cm grid must show),
# without the frames' axes and names (the world's sat on the tip).
sed -e 's/^      Distance: .*/      Distance: 0.12/' -e 's/^      Pitch: .*/      Pitch: 0.1/' \
    -e 's/^      Yaw: .*/      Yaw: 0.25/' -e 's/^        Z: 0.012$/        Z: 0.016/' \
    -e 's/^      Show Axes: true/      Show Axes: false/' -e 's/^      Show Names: true/      Show Names: false/' \
    "$SPINNING_TOP_ROOT/config/spinning_top.rviz" > "$work/side.rviz"

# shot NAME TICKS KEY=VALUE...: the frictionless scene with the keys, stepped TICKS ticks of 1 ms.
shot() {
  local name="$1" ticks="$2"
  shift 2
  local port=$((20000 + RANDOM % 20000))
  export ROS_MASTER_URI="http://localhost:$port"
  {
    echo "marker_rate: 1000  # markers at every tick, so the picture's are the last tick's"
    echo "initial:"
    for assignment in "$@"; do echo "  ${assignment%%=*}: ${assignment#*=}"; done
  } > "$work/$name.yaml"
  roslaunch -p "$port" spinning_top spinning_top.launch scene:=frictionless overrides:="$work/$name.yaml" \
    start_paused:=true > "$work/$name.launch.log" 2>&1 &
  local launch=$!
  pids+=("$launch")
  rosrun rviz rviz -d "$work/side.rviz" > "$work/$name.rviz.log" 2>&1 &
  local rviz=$!
  pids+=("$rviz")
  /usr/bin/python3 - "$ticks" <<'EOF'
import sys
import time

import rospy
from std_srvs.srv import Trigger

rospy.init_node("rviz_screenshots", anonymous=True)
rospy.wait_for_service("/spinning_top/step", timeout=60)
time.sleep(8)  # wall time: rviz starts (software GL) and subscribes
step = rospy.ServiceProxy("/spinning_top/step", Trigger)
for _ in range(int(sys.argv[1])):
    response = step()
    assert response.success, response.message
print(response.message)
EOF
  sleep 5  # rviz draws the last tick
  import -window root "$work/$name.raw.png"
  # The 3D view around the top (panels, toolbar and status bar cropped), 8-bit palette: a small PNG.
  convert "$work/$name.raw.png" -crop 900x520+364+130 +repage -colors 256 -strip "$output/rviz_$name.png"
  kill "$rviz" "$launch" 2>/dev/null || true
  wait "$rviz" "$launch" 2>/dev/null || true
  echo "rviz_screenshots: $output/rviz_$name.png ($(stat -c %s "$output/rviz_$name.png") bytes)"
}

shot hopping 57 tilt=0.8 precession_rate=60
shot fallen 100 spin=5
