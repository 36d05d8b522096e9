#!/usr/bin/env bash
# Builds every fuzz/<name>_fuzz.cpp with Debian's clang 14 (libFuzzer + ASan + UBSan) and runs
# each for a bounded time: the project's fuzzing smoke run (ctest: fuzz_smoke, label `fuzz`).
#
# usage: fuzz/run_fuzzers.sh [SECONDS_PER_HARNESS=15] [OUT_DIR=build/fuzz] [NAME...]
#
# A harness names the project sources it needs in a comment line
#   // fuzz-sources: io/canlog/candump.cpp io/can/signal.cpp
# and optionally extra link flags in
#   // fuzz-libs: -lyaml-cpp
# so no second CMake build is needed. Seeds come from fuzz/seeds/<name>/ when it exists; the
# corpus grows in OUT_DIR/<name>/corpus, and a crash leaves OUT_DIR/<name>/crash-* behind.
# Exit: 0 no crash, 1 a harness failed to build or crashed, 77 clang/libFuzzer not available.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-15}
out=${2:-$root/build/fuzz}
shift $(( $# > 2 ? 2 : $# ))
cxx=${LEAKMON_FUZZ_CXX:-clang++-14}
command -v "$cxx" >/dev/null || { echo "SKIP: $cxx not installed (apt-get install clang)"; exit 77; }
mkdir -p "$out"
echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' \
  > "$out/probe.cpp"
"$cxx" -fsanitize=fuzzer "$out/probe.cpp" -o "$out/probe" 2>/dev/null ||
  { echo "SKIP: $cxx cannot link libFuzzer (apt-get install libclang-rt-14-dev)"; exit 77; }

harnesses=()
if [ $# -gt 0 ]; then
  for name in "$@"; do harnesses+=("$root/fuzz/${name}_fuzz.cpp"); done
else
  harnesses=("$root"/fuzz/*_fuzz.cpp)
fi

failed=0
for harness in "${harnesses[@]}"; do
  name=$(basename "$harness" _fuzz.cpp)
  dir=$out/$name
  mkdir -p "$dir/corpus"
  sources=$(sed -n 's|^// fuzz-sources:||p' "$harness")
  libs=$(sed -n 's|^// fuzz-libs:||p' "$harness")
  source_paths=()
  for s in $sources; do source_paths+=("$root/$s"); done
  echo "== $name: building with $cxx (${sources:-no project sources})"
  # shellcheck disable=SC2086
  if ! "$cxx" -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined \
       -fno-sanitize-recover=undefined -I"$root" "$harness" "${source_paths[@]}" $libs \
       -o "$dir/$name"; then
    echo "FAIL: $name does not build"
    failed=1
    continue
  fi
  seeds=()
  [ -d "$root/fuzz/seeds/$name" ] && seeds=("$root/fuzz/seeds/$name")
  echo "== $name: fuzzing for ${seconds}s"
  if (cd "$dir" && "./$name" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
        -print_final_stats=1 corpus "${seeds[@]}" > run.log 2>&1); then
    echo "$name: no crash ($(grep -o 'stat::number_of_executed_units: *[0-9]*' "$dir/run.log" |
      grep -o '[0-9]*$') inputs, corpus $(ls "$dir/corpus" | wc -l) files)"
  else
    echo "FAIL: $name crashed; the reproducer is in $dir; last lines of its log:"
    tail -40 "$dir/run.log"
    failed=1
  fi
done
exit $failed
