#!/usr/bin/env bash
# Sets up, builds and runs every test (gtest and rostest through `make run_tests`), then
# exits non-zero on any failure. `make run_tests` itself exits 0 on failed tests, so the
# verdict comes from catkin_test_results and the JUnit files.
set -euo pipefail
source "$(dirname "$0")/env.sh"
"$SPINNING_TOP_ROOT/scripts/setup.sh"
"$SPINNING_TOP_ROOT/scripts/build.sh"
rm -rf "$SPINNING_TOP_BUILD/test_results"
set +e
# make writes to the log file and the progress is read from it until make exits: a process that a
# failed test leaves running (a node it started) keeps no pipe open that this script would wait on.
make -C "$SPINNING_TOP_BUILD" run_tests -j1 > "$SPINNING_TOP_BUILD/run_tests.log" 2>&1 &
make_pid=$!
tail --pid="$make_pid" -n +1 -f "$SPINNING_TOP_BUILD/run_tests.log" | \
  grep -E --line-buffered '^\[ *(RUN|OK|FAILED|PASSED) *\]|^\[ROSTEST\]|^\[Testcase|FAILURE|ERROR|Error [0-9]'
wait "$make_pid"
make_status=$?
# A node still running from this build is a test's leak: name it and stop it.
if command -v pgrep > /dev/null && leftovers=$(pgrep -a -f "$SPINNING_TOP_BUILD/devel/lib/spinning_top/"); then
  echo "test.sh: processes left running by the tests (killed):" >&2
  echo "$leftovers" >&2
  pkill -KILL -f "$SPINNING_TOP_BUILD/devel/lib/spinning_top/" || true
fi
# Still without -e: catkin_test_results and the count exit 1 on a failure, and their summaries
# (the failed tests, the 'N passed, N failed' line CI reads) must be printed all the same.
catkin_test_results "$SPINNING_TOP_BUILD/test_results" --verbose > "$SPINNING_TOP_BUILD/test_summary.log" 2>&1
results_status=$?
tail -n 30 "$SPINNING_TOP_BUILD/test_summary.log"
/usr/bin/python3 "$SPINNING_TOP_ROOT/scripts/count_results.py" "$SPINNING_TOP_BUILD/test_results"
count_status=$?
set -e
if [ "$make_status" -ne 0 ] || [ "$results_status" -ne 0 ] || [ "$count_status" -ne 0 ]; then
  echo "test.sh: FAILED (make run_tests: $make_status, catkin_test_results: $results_status, counts: $count_status)" >&2
  exit 1
fi
echo "test.sh: all tests passed"
