#!/usr/bin/env bash
# The whole test suite: a normal build, an ASan+UBSan build and a TSan build of the threaded
# parts, each run by ctest. Run from the repository root.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build build -j"$jobs"
ctest --test-dir build --output-on-failure -j"$jobs"

# Sanitizer builds skip the benchmarks; tests labelled 'long' (full-length simulations that
# take minutes under ASan) run only in the normal build above.
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DLEAKMON_SANITIZE=address,undefined \
  -DLEAKMON_BUILD_BENCH=OFF -DCMAKE_CXX_FLAGS=-O1
cmake --build build-asan -j"$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan --output-on-failure -j"$jobs" -LE long

cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DLEAKMON_SANITIZE=thread \
  -DLEAKMON_BUILD_BENCH=OFF -DCMAKE_CXX_FLAGS=-O1
cmake --build build-tsan -j"$jobs" --target leakmon_tsan_tests
TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 \
  ctest --test-dir build-tsan --output-on-failure -j"$jobs" -L threads
