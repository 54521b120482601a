#!/usr/bin/env bash
# The benchmark command (doc/benchmark.md): builds the benchmark executables in Release, runs the
# work-precision benchmark (ours vs Boost.Odeint, the default at the node's 1 ms sampling against
# RKF78, long-run energy), the default's re-initialisation cost, the viscous default from k = 0 to
# m/k = 1e-8 s (bench/viscous_default) and the extreme-cases table,
# then writes CSVs, PNG plots and bench/results/summary.md, and splices the tables into README.md
# and doc/benchmark.md. 4 min 24 s on 2 cores before the default's 1 ms series and reinit_cost
# were added (not timed since).
# Usage: scripts/bench.sh [--quick]   (--quick: fewer points and states, 1e5-step long runs; 6 min
# 49 s measured with other builds on the 2 cores, 4 min 58 s of CPU, two benchmarks compiled)
# Set SPINNING_TOP_BUILD to build elsewhere than build/.
set -euo pipefail
source "$(dirname "$0")/env.sh"
start=$(date +%s)
quick=()
for arg in "$@"; do
  case "$arg" in
    --quick) quick=(--quick) ;;
    *) echo "bench.sh: unknown option '$arg' (use --quick)" >&2; exit 2 ;;
  esac
done

# Debian packages (plots need matplotlib): installs what is missing when run as root.
if [ "$(id -u)" -eq 0 ]; then "$SPINNING_TOP_ROOT/scripts/setup.sh"; fi

echo "bench.sh: building the benchmarks in $SPINNING_TOP_BUILD (Release)"
cmake -S "$SPINNING_TOP_ROOT" -B "$SPINNING_TOP_BUILD" \
  -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE="${CMAKE_BUILD_TYPE:-Release}" >/dev/null
targets=(work_precision reinit_cost fallback_tolerance viscous_default fuzz_soak budget_time spinning_top_python)
grep -q "add_executable(extreme_cases" "$SPINNING_TOP_ROOT/bench/CMakeLists.txt" && targets+=(extreme_cases)
cmake --build "$SPINNING_TOP_BUILD" --target "${targets[@]}" -- -j"$(nproc)"

bin="$SPINNING_TOP_BUILD/devel/lib/spinning_top"
results="$SPINNING_TOP_ROOT/bench/results"
mkdir -p "$results"

echo "bench.sh: work-precision benchmark (progress below)"
"$bin/work_precision" --output-dir "$results" "${quick[@]}"

echo "bench.sh: the default's re-initialisation cost (progress below)"
"$bin/reinit_cost" --output-dir "$results" "${quick[@]}" >/dev/null

echo "bench.sh: the viscous default from k = 0 to m/k = 1e-8 s, and its peers (progress below)"
# One run per CPU figure: the runs take 0.01-40 s each, long enough for one to be representative.
"$bin/viscous_default" --output-dir "$results" --repeats 1 "${quick[@]}" > "$results/viscous_default.md"

echo "bench.sh: auto's fallback tolerance (dop853 against exact)"
"$bin/fallback_tolerance" --output-dir "$results"

if [ -x "$bin/extreme_cases" ]; then
  echo "bench.sh: extreme cases"
  "$bin/extreme_cases" --output-dir "$results"
fi

echo "bench.sh: fuzz (1e5 cases) and a one-hour soak of each scene (issue 10)"
if [ ${#quick[@]} -eq 0 ]; then
  "$bin/fuzz_soak" --output-dir "$results"
else
  "$bin/fuzz_soak" --output-dir "$results" --cases 10000 --hours 0.1
fi

echo "bench.sh: CPU per step of the work budget, method by method (issue 19)"
"$bin/budget_time" "$results/budget_time.md"

echo "bench.sh: sweep throughput: cases per second per core, a 1e6-case map, Dask's overhead (issue 11)"
(
  spinning_top_source_devel
  /usr/bin/python3 "$SPINNING_TOP_ROOT/bench/sweep_throughput.py" "$results" "${quick[@]}"
)

echo "bench.sh: the node's CPU at 1 kHz with one and five tops, ticks per second at real-time factor 0 (issue 9)"
cmake --build "$SPINNING_TOP_BUILD" --target spinning_top_node -- -j"$(nproc)"
(
  spinning_top_source_devel
  SPINNING_TOP_NODE="$bin/spinning_top_node" /usr/bin/python3 "$SPINNING_TOP_ROOT/bench/node_load.py" "$results" "${quick[@]}"
)

echo "bench.sh: the node's CPU as launched against a bare roscpp node beside it (issue 20); spawn and exit with 1000 tops (issue 19)"
cmake --build "$SPINNING_TOP_BUILD" --target bare_tf_node --target bare_spawner -- -j"$(nproc)"
(
  spinning_top_source_devel
  /usr/bin/python3 "$SPINNING_TOP_ROOT/bench/node_cpu.py" "$results" $([ ${#quick[@]} -gt 0 ] && echo "--window 3 --repeat 1")
  /usr/bin/python3 "$SPINNING_TOP_ROOT/bench/node_scale.py" "$results" --per-top none --per-top state,event_stamped --per-top all --also-paused --bare --repeat 2 $([ ${#quick[@]} -gt 0 ] && echo "--count 200")
)

echo "bench.sh: wall-clock lag and pacing diagnostics, quiet and beside two busy loops (issue 19)"
(
  spinning_top_source_devel
  SPINNING_TOP_NODE="$bin/spinning_top_node" /usr/bin/python3 "$SPINNING_TOP_ROOT/bench/wall_clock_lag.py" "$results" "${quick[@]}"
)

echo "bench.sh: plots and summary"
/usr/bin/python3 "$SPINNING_TOP_ROOT/bench/plot_results.py" "$results"
# The README shows the measured tables; a --quick run's coarse figures do not replace them.
if [ ${#quick[@]} -eq 0 ]; then
  /usr/bin/python3 "$SPINNING_TOP_ROOT/bench/update_readme.py" "$results" "$SPINNING_TOP_ROOT/README.md" \
    "$SPINNING_TOP_ROOT/doc/benchmark.md"
fi
# The issue's two measurements, last on screen.
echo
cat "$results/default_ratio.md" "$results/reinit_cost.md"
echo "bench.sh: done in $(( $(date +%s) - start )) s; results in $results (summary.md)"
