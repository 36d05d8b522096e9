#!/usr/bin/env bash
# Runs one gtest binary N times with fresh seeds and reports how many runs failed and the
# seeds that reproduce them: the way the quorums of the random-draw tests (tests/model/) were
# set. A test whose failure rate is not well below 1 in 500 runs does not belong in CI.
#   scripts/repeat-test.sh build/bin/model_fit_test 'Calibration.*' 100
set -u
binary=${1:?usage: repeat-test.sh BINARY GTEST_FILTER [RUNS]}
filter=${2:?usage: repeat-test.sh BINARY GTEST_FILTER [RUNS]}
runs=${3:-50}
log=$(mktemp)
trap 'rm -f "$log"' EXIT
failed=0
for ((i = 1; i <= runs; i++)); do
  if ! "$binary" --gtest_filter="$filter" >"$log" 2>&1; then
    failed=$((failed + 1))
    echo "run $i failed:"
    grep -E "LEAKMON_TEST_SEED=|Failure" "$log" | sed 's/^/  /'
  fi
done
echo "$failed of $runs runs failed ($binary $filter)"
[[ $failed -eq 0 ]]
