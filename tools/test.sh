#!/usr/bin/env bash
# Build loopfarm and run the whole test suite. Exits non-zero on any failure.
#
#   tools/test.sh              optimised build with assertions on (build/test):
#                              every test, the benchmarks once briefly, and
#                              the fuzzers for a short bounded run
#   tools/test.sh --sanitize   the same suite built with AddressSanitizer and
#                              UndefinedBehaviorSanitizer (build/sanitize);
#                              any report fails the test that made it
#
# --fuzz-seconds N sets each fuzzer's run (default 30; 0 skips fuzzing).
set -euo pipefail
cd "$(dirname "$0")/.."

sanitize=0
fuzz_seconds=30
while [ $# -gt 0 ]; do
  case "$1" in
    --sanitize) sanitize=1 ;;
    --fuzz-seconds)
      [ $# -ge 2 ] || { echo "tools/test.sh: --fuzz-seconds needs a number" >&2; exit 2; }
      fuzz_seconds="$2"
      shift ;;
    -h|--help) sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "tools/test.sh: unknown option '$1' (see tools/test.sh --help)" >&2; exit 2 ;;
  esac
  shift
done
case "$fuzz_seconds" in
  ''|*[!0-9]*) echo "tools/test.sh: --fuzz-seconds wants a whole number of seconds, not '$fuzz_seconds'" >&2; exit 2 ;;
esac

tools/deps.sh

# The MPI tests run mpirun, which refuses to run as root (CI containers)
# without these.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

jobs="$(nproc)"

if [ "$sanitize" -eq 1 ]; then
  # -O1 keeps the instrumented suite fast enough; every UB report aborts (so
  # the test fails) instead of printing and going on. Open MPI's own
  # allocations that live until exit are not loopfarm's leaks (lsan.supp).
  flags="-O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=all"
  cmake -S . -B build/sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$flags" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined"
  cmake --build build/sanitize -j"$jobs"
  export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:strict_string_checks=1:check_initialization_order=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  export LSAN_OPTIONS="suppressions=$PWD/tools/sanitizers/lsan.supp:print_suppressions=0"
  # The instrumented code runs a few times slower: the robustness sweep
  # draws a tenth of its geometries, and hangs get more time.
  export LOOPFARM_ROBUSTNESS_GEOMETRIES=10000
  ctest --test-dir build/sanitize --output-on-failure -j"$jobs" --timeout 900
  exit 0
fi

# RelWithDebInfo adds -DNDEBUG by default; overriding its flags keeps assert()
# active while still testing optimised code.
cmake -S . -B build/test -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g"
cmake --build build/test -j"$jobs"

# A test that hangs fails after 300 s instead of stalling CI.
ctest --test-dir build/test --output-on-failure -j"$jobs" --timeout 300

# Smoke run of the benchmarks. Debian 12 has Google Benchmark 1.7.1, whose
# --benchmark_min_time takes plain seconds (1.8 and later want "0.01s").
echo "== benchmark smoke run"
build/test/bench/loopfarm_bench --benchmark_min_time=0.01

if [ "$fuzz_seconds" -gt 0 ]; then
  echo "== fuzzing, ${fuzz_seconds} s a target"
  tools/fuzz.sh --seconds "$fuzz_seconds"
fi
