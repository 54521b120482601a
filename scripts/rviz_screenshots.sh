#!/usr/bin/env bash
# The README's rviz pictures, reproduced headless (software GL under Xvfb):
#   doc/rviz.png          spinning_top.launch scene:=viscous rviz:=true (rviz as the launch file
#                         starts it: in the node's namespace, config/spinning_top.rviz), at t = 2 s
#   doc/two_tops.png      two_tops.launch rviz:=true (config/two_tops.rviz), at t = 1.5 s
#   doc/rviz_hopping.png  the frictionless top of config/frictionless.yaml launched at tilt 0.8 rad
#                         with a precession of 60 rad/s, at t = 0.057 s: mid-flight, its tip
#                         10 mm above the floor (the first flight lasts 0.0094 ... 0.0924 s)
#   doc/rviz_fallen.png   the same top at 5 rad/s, at t = 0.1 s: fallen onto its rim at 0.087 s,
#                         shown at rest
# Each: the node starts paused and ~step takes it tick by tick to that time, so the picture does
# not depend on the machine's speed. The last two look from the side (spinning_top.rviz, closer).
# Usage, after `bash scripts/setup.sh --rviz` and `bash scripts/build.sh`:
#   bash scripts/rviz_screenshots.sh [output directory, default doc]
#   SPINNING_TOP_SHOTS="two_tops rviz_fallen" bash scripts/rviz_screenshots.sh   (some of them)
set -euo pipefail
source "$(dirname "$0")/env.sh"
if [ -z "${SPINNING_TOP_UNDER_XVFB:-}" ]; then
  exec env SPINNING_TOP_UNDER_XVFB=1 xvfb-run -a -s "-screen 0 1280x800x24" bash "$0" "$@"
fi
export LIBGL_ALWAYS_SOFTWARE=1
spinning_top_source_devel
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
# without the frames' axes (the world's sat on the tip).
sed -e 's/^      Distance: .*/      Distance: 0.12/' -e 's/^      Pitch: .*/      Pitch: 0.1/' \
    -e 's/^      Yaw: .*/      Yaw: 0.25/' -e 's/^        Z: 0.012$/        Z: 0.016/' \
    -e 's/^      Show Axes: true/      Show Axes: false/' \
    "$SPINNING_TOP_ROOT/config/spinning_top.rviz" > "$work/side.rviz"

# capture NAME TICKS CROP: steps the paused node TICKS ticks once rviz is up, then saves the
# screen as NAME.png (CROP: an ImageMagick geometry, or "full" for the whole window).
capture() {
  local name="$1" ticks="$2" crop="$3"
  /usr/bin/python3 - "$ticks" <<'EOF_PY'
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
EOF_PY
  sleep 5  # rviz draws the last tick
  import -window root "$work/$name.raw.png"
  # 8-bit palette: a small PNG; the 3D view alone (panels, toolbar and status bar cropped) or all.
  if [ "$crop" = full ]; then
    convert "$work/$name.raw.png" -colors 256 -strip "$output/$name.png"
  else
    convert "$work/$name.raw.png" -crop "$crop" +repage -colors 256 -strip "$output/$name.png"
  fi
  echo "rviz_screenshots: $output/$name.png ($(stat -c %s "$output/$name.png") bytes)"
}

# stop PID...: ends what a shot started.
stop() {
  kill -INT "$@" 2>/dev/null || true
  wait "$@" 2>/dev/null || true
}

# new_master: a free port for the next shot's master (sets port and ROS_MASTER_URI); a random
# one could be taken (roslaunch then fails and the stepping waits for a master for ever).
new_master() {
  port="$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
  export ROS_MASTER_URI="http://localhost:$port"
}

# launch_shot NAME TICKS LAUNCH_FILE ARGS...: the launch file with rviz:=true, as a user starts it.
launch_shot() {
  local name="$1" ticks="$2" file="$3"
  shift 3
  new_master
  roslaunch -p "$port" spinning_top "$file" rviz:=true start_paused:=true "$@" > "$work/$name.launch.log" 2>&1 &
  local launch=$!
  pids+=("$launch")
  capture "$name" "$ticks" full
  stop "$launch"
}

# side_shot NAME TICKS KEY=VALUE...: the frictionless scene with the initial keys, from the side.
side_shot() {
  local name="$1" ticks="$2"
  shift 2
  new_master
  {
    echo "initial:"
    for assignment in "$@"; do echo "  ${assignment%%=*}: ${assignment#*=}"; done
  } > "$work/$name.yaml"
  roslaunch -p "$port" spinning_top spinning_top.launch scene:=frictionless overrides:="$work/$name.yaml" \
    start_paused:=true marker_rate:=1000 > "$work/$name.launch.log" 2>&1 &
  local launch=$!
  pids+=("$launch")
  # Markers at every tick, so that the picture's are the last tick's. rviz in the node's namespace, as the launch file starts it: the config's topics are relative.
  rosrun rviz rviz -d "$work/side.rviz" __ns:=/spinning_top > "$work/$name.rviz.log" 2>&1 &
  local rviz=$!
  pids+=("$rviz")
  capture "$name" "$ticks" 900x520+364+130
  stop "$rviz" "$launch"
}

shots="${SPINNING_TOP_SHOTS:-rviz two_tops rviz_hopping rviz_fallen}"  # or a subset
for shot in $shots; do
  case "$shot" in
    rviz) launch_shot rviz 2000 spinning_top.launch scene:=viscous ;;
    two_tops) launch_shot two_tops 1500 two_tops.launch ;;
    rviz_hopping) side_shot rviz_hopping 57 tilt=0.8 precession_rate=60 ;;
    rviz_fallen) side_shot rviz_fallen 100 spin=5 ;;
    *) echo "rviz_screenshots: unknown shot $shot" >&2; exit 2 ;;
  esac
done
