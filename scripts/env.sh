# Sourced by every script: Debian's python3 (with catkin_pkg, rospy) must win over a pyenv
# python3 earlier on PATH, or catkin's configure and rostest's helper nodes break.
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
SPINNING_TOP_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SPINNING_TOP_BUILD="${SPINNING_TOP_BUILD:-$SPINNING_TOP_ROOT/build}"
export SPINNING_TOP_ROOT SPINNING_TOP_BUILD
