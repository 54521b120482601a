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
make -C "$SPINNING_TOP_BUILD" run_tests -j1 2>&1 | tee "$SPINNING_TOP_BUILD/run_tests.log" | \
  grep -E --line-buffered '^\[ *(RUN|OK|FAILED|PASSED) *\]|^\[ROSTEST\]|^\[Testcase|FAILURE|ERROR|Error [0-9]'
make_status=${PIPESTATUS[0]}
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
