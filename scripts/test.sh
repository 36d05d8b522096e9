#!/usr/bin/env bash
# The whole test suite, each test run once where it tells the most:
# - a Release build (tests and benchmarks; the build type a packager uses, so that it keeps
#   compiling under GCC's -O3 warnings) runs the tests labelled 'long' (full-length
#   simulations, minutes under ASan) and 'packaging' (whole-tree configures and cpack); its
#   Debian package is installed, verified and purged;
# - an ASan+UBSan build (Clang, so that both GCC and Clang build the tests with warnings as
#   errors) runs every other test;
# - a TSan build runs the threaded ones (label 'threads') again.
# Run from the repository root (as root, or with sudo for the package step).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

# README's first command installed what building needs; the tests and benchmarks need more
# (GoogleTest, pymodbus, chromium, qemu, ...), installed here when something is missing.
bash scripts/install-deps.sh --check 2>/dev/null || bash scripts/install-deps.sh --test

# Tests and benchmarks are off by default (README's first command builds the binary only).
# Release (GCC -O3, whose false positives once broke it) with warnings as errors; its package is
# the one a user installs: install it, check it, purge it.
# lld links the ~110 test executables several times faster than ld.bfd; without it, the default.
linker=()
if command -v ld.lld >/dev/null; then
  linker=(-DCMAKE_EXE_LINKER_FLAGS=-fuse-ld=lld -DCMAKE_SHARED_LINKER_FLAGS=-fuse-ld=lld)
fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=ON \
  -DLEAKMON_BUILD_BENCH=ON "${linker[@]}"
cmake --build build -j"$jobs"
ctest --test-dir build --output-on-failure -j"$jobs" -L 'long|packaging'
rm -f build/leakmon_*.deb
(cd build && cpack -G DEB)
bash scripts/check-package.sh build/leakmon_*.deb

# Sanitizer builds skip the benchmarks. Line tables (-g1) are all a sanitizer's report needs
# (file and line per frame); full debug info would double the compile and link time.
# The ASan+UBSan build is Clang's (warnings as errors, as in every build with the tests), so that
# both compilers build every target but the benchmarks each run, at no extra build: GCC the
# Release one above, Clang this one. The compiler is named on the command line (CXX would be
# ignored by an existing cache); a directory configured for another compiler is removed first,
# because CMake's own switch deletes the cache and then configures without the -D options.
if [ -f build-asan/CMakeCache.txt ] &&
  ! grep -Eq '^CMAKE_CXX_COMPILER:[A-Z]+=(/usr/bin/)?clang\+\+$' build-asan/CMakeCache.txt; then
  rm -rf build-asan
fi
cmake -S . -B build-asan -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Debug \
  -DLEAKMON_SANITIZE=address,undefined -DBUILD_TESTING=ON -DLEAKMON_BUILD_BENCH=OFF \
  -DCMAKE_CXX_FLAGS=-O1 -DCMAKE_CXX_FLAGS_DEBUG=-g1 "${linker[@]}"
cmake --build build-asan -j"$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan --output-on-failure -j"$jobs" -LE 'long|packaging'

cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DLEAKMON_SANITIZE=thread \
  -DBUILD_TESTING=ON -DLEAKMON_BUILD_BENCH=OFF -DCMAKE_CXX_FLAGS=-O1 -DCMAKE_CXX_FLAGS_DEBUG=-g1 \
  "${linker[@]}"
cmake --build build-tsan -j"$jobs" --target leakmon_tsan_tests
TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 \
  ctest --test-dir build-tsan --output-on-failure -j"$jobs" -L threads
