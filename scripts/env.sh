# Sourced by every script: Debian's python3 (with catkin_pkg, rospy) must win over a pyenv
# python3 earlier on PATH, or catkin's configure and rostest's helper nodes break.
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
SPINNING_TOP_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SPINNING_TOP_BUILD="${SPINNING_TOP_BUILD:-$SPINNING_TOP_ROOT/build}"
# The devel space (catkin's setup.bash): build/devel of the standalone build.
SPINNING_TOP_DEVEL="${SPINNING_TOP_DEVEL:-$SPINNING_TOP_BUILD/devel}"
export SPINNING_TOP_ROOT SPINNING_TOP_BUILD SPINNING_TOP_DEVEL

# Sources the devel space's setup.bash, so that roslaunch, rosrun and `import spinning_top` find
# the package. Call it, do not inline it: catkin's setup.sh reads the positional parameters of
# whoever sources it as its own options, so that a script's `--help` made it print a usage and
# then run it ("usage:: command not found"). Inside this function they are the function's own:
# none. catkin's scripts also read unset variables: `set -u` is lifted while they run.
spinning_top_source_devel() {
  local restore_nounset=false
  if [[ $- == *u* ]]; then restore_nounset=true; set +u; fi
  # shellcheck source=/dev/null
  source "$SPINNING_TOP_DEVEL/setup.bash"
  if $restore_nounset; then set -u; fi
}
