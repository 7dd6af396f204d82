#!/usr/bin/env bash
# Build loopfarm and run the whole test suite. Exits non-zero on any failure.
#
#   scripts/test.sh              optimised build with assertions on (build/test):
#                              every test, a small subset again under the
#                              sanitizers (build/sanitize-subset), the
#                              benchmarks once briefly, and the fuzzers for a
#                              short bounded run
#   scripts/test.sh --sanitize   the same suite built with AddressSanitizer and
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
      [ $# -ge 2 ] || { echo "scripts/test.sh: --fuzz-seconds needs a number" >&2; exit 2; }
      fuzz_seconds="$2"
      shift ;;
    -h|--help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "scripts/test.sh: unknown option '$1' (see scripts/test.sh --help)" >&2; exit 2 ;;
  esac
  shift
done
case "$fuzz_seconds" in
  ''|*[!0-9]*) echo "scripts/test.sh: --fuzz-seconds wants a whole number of seconds, not '$fuzz_seconds'" >&2; exit 2 ;;
esac

scripts/deps.sh --test

# The MPI tests run mpirun, which refuses to run as root (CI containers)
# without these.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

jobs="$(nproc)"

# The sanitizer builds. clang, not gcc: with both sanitizers on, gcc 12 took
# 694 s to compile src/core/cycle.cpp and clang 14 took 344 s with full debug
# information and about 85 s of CPU with line tables only, which is all a
# report's stack needs (docs/quality/reliability.md). -O1 keeps the instrumented
# suite fast enough; every UB report aborts (so the test fails) instead of
# printing and going on.
configure_sanitized() {  # DIR [CMAKE ARGS...]
  local dir="$1"
  shift
  command -v clang++ >/dev/null || { echo "scripts/test.sh: clang++ not found (scripts/deps.sh installs clang)" >&2; exit 1; }
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=all" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" "$@"
}

# Runs ctest in DIR under the sanitizers' settings; fails if a test fails or
# any sanitizer report was written. Every report goes to a file of its own in
# DIR/reports (report.<program>.<pid>), whatever the test does with the
# program's stderr: a report from a run whose exit code a script tolerates
# (a killed farm, a setup step) is counted too. Open MPI's own allocations
# that live until exit are not loopfarm's leaks (lsan.supp); to be told apart
# they need whole allocation stacks (lsan.supp says why), which the loopfarm
# program asks for itself (__asan_default_options in tools/run_command.cpp):
# set here for all, full unwinding made allocation-heavy test programs up to
# 25 times slower (FamilyDistance 19 -> 487 s).
ctest_sanitized() {  # DIR [CTEST ARGS...]
  local dir="$1"
  shift
  (
    reports="$PWD/$dir/reports"
    rm -rf "$reports"
    mkdir -p "$reports"
    log="log_path=$reports/report:log_exe_name=1"
    export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:strict_string_checks=1:check_initialization_order=1:$log"
    export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:$log"
    export LSAN_OPTIONS="suppressions=$PWD/scripts/sanitizers/lsan.supp:print_suppressions=0"
    # The instrumented code runs many times slower: the robustness sweep
    # draws a tenth of its geometries, the fault tests' job has a quarter of
    # its starts (still a dozen commits or more), and hangs get more time.
    export LOOPFARM_ROBUSTNESS_GEOMETRIES=10000
    export LOOPFARM_FAULT_STARTS=150
    status=0
    start=$SECONDS
    ctest --test-dir "$dir" --output-on-failure -j"$jobs" --timeout 900 "$@" || status=$?
    echo "== sanitized tests in $dir: $((SECONDS - start)) s"
    # A report says "ERROR: AddressSanitizer|LeakSanitizer" or "runtime
    # error:" (UBSan); other files hold warnings only (a rank killed by a
    # fault test while its llvm-symbolizer ran: "Can't read from
    # symbolizer"), shown but not counted.
    for report in "$reports"/*; do
      [ -e "$report" ] || continue
      echo "== $report"
      cat "$report"
    done
    count="$(grep -l -E 'ERROR: [A-Za-z]+Sanitizer|runtime error:' "$reports"/* 2>/dev/null | wc -l || true)"
    if [ "$count" -gt 0 ]; then
      echo "scripts/test.sh: $count sanitizer reports (above, and in $reports)" >&2
      exit 1
    fi
    echo "== sanitizer reports: 0"
    exit "$status"
  )
}

if [ "$sanitize" -eq 1 ]; then
  configure_sanitized build/sanitize -DLOOPFARM_FAULT_TEST_TIMEOUT=900
  start=$SECONDS
  cmake --build build/sanitize -j"$jobs"
  echo "== sanitized build: $((SECONDS - start)) s"
  ctest_sanitized build/sanitize
  exit 0
fi

# RelWithDebInfo adds -DNDEBUG by default; overriding its flags keeps assert()
# active while still testing optimised code.
cmake -S . -B build/test -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g"
cmake --build build/test -j"$jobs"

# A test that hangs fails after 300 s instead of stalling CI.
ctest --test-dir build/test --output-on-failure -j"$jobs" --timeout 300

# A small sanitized subset (tests/sanitized_subset.cmake names it and says
# why): the test programs that need only a few library sources, compiled with
# them, so that it costs about a minute instead of the half hour of
# scripts/test.sh --sanitize.
echo "== sanitized subset"
start=$SECONDS
configure_sanitized build/sanitize-subset -DLOOPFARM_SANITIZED_SUBSET=ON -DLOOPFARM_BUILD_TESTS=OFF \
  -DLOOPFARM_BUILD_TOOLS=OFF -DLOOPFARM_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build build/sanitize-subset -j"$jobs" --target sanitized_subset
ctest_sanitized build/sanitize-subset
echo "== sanitized subset, build and run: $((SECONDS - start)) s"

# Smoke run of the benchmarks. Debian 12 has Google Benchmark 1.7.1, whose
# --benchmark_min_time takes plain seconds (1.8 and later want "0.01s").
echo "== benchmark smoke run"
build/test/bench/loopfarm_bench --benchmark_min_time=0.01

if [ "$fuzz_seconds" -gt 0 ]; then
  echo "== fuzzing, ${fuzz_seconds} s a target"
  scripts/fuzz.sh --seconds "$fuzz_seconds"
fi
