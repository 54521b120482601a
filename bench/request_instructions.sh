#!/usr/bin/env bash
# Instructions per second of simulated time (1000 requests of 1 ms), before against after, for
# each integrator: valgrind's callgrind counts instructions, which unlike CPU time do not depend
# on the load of the machine (issue 17: "no measurable slowdown").
# Usage: bench/request_instructions.sh OLD_DEVEL_LIB NEW_DEVEL_LIB
#   *_DEVEL_LIB: a build's devel/lib folder (copy it elsewhere first to keep an old build).
# Needs valgrind (apt-get install valgrind). Prints a Markdown table.
set -euo pipefail
old=$1 new=$2
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
g++ -O2 -std=c++17 -I"$here/../include" -I/usr/include/eigen3 "$here/request_instructions.cpp" -o "$work/requests" \
  -L"$new" -lspinning_top_core
count() {  # N LIB SCENE INTEGRATOR FRICTION
  N=$1 LD_LIBRARY_PATH=$2 valgrind --tool=callgrind --callgrind-out-file="$work/out" "$work/requests" "$3" "$4" "$5" 2>&1 |
    awk '/Collected/ {print $4}'
}
echo "| scene | integrator | instructions for 1 s, before | after | after / before |"
echo "|---|---|---|---|---|"
for m in "fixed_tip rk4 0" "frictionless gauss6 0" "fixed_tip splitting8 0" "fixed_tip dopri5 0" "fixed_tip dop853 0" \
         "viscous dop853 0.02" "viscous radau5 2000" "viscous rodas4 0.02" "fixed_tip exact 0" "frictionless exact 0"; do
  set -- $m
  a=$(( $(count 2000 "$old" "$@") - $(count 1000 "$old" "$@") ))
  b=$(( $(count 2000 "$new" "$@") - $(count 1000 "$new" "$@") ))
  echo "| $1 | $2 | $a | $b | $(awk -v a="$a" -v b="$b" 'BEGIN {printf "%.4f", b / a}') |"
done
