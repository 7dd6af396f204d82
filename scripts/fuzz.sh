#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/) with clang, AddressSanitizer and
# UndefinedBehaviorSanitizer into build/fuzz, and runs each for a while.
#
#   scripts/fuzz.sh                  # every target 30 s
#   scripts/fuzz.sh --seconds 600    # every target 600 s
#   scripts/fuzz.sh --seconds 60 job_file_fuzzer   # one target
#
# Each target starts from its seed corpus fuzz/corpus/<target>/ (the job
# fuzzer also from the job files of tests/tools/bad-inputs/) and keeps what it finds
# in build/fuzz/corpus/<target>/, so later runs go on from there. A crash, a
# sanitizer report or a broken contract (see the targets' comments) leaves
# its input in build/fuzz/artifacts/<target>/ and makes this script exit 1.
# Prints, per target, the executions and seconds run.
set -euo pipefail

seconds=30
targets=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seconds)
      [[ $# -ge 2 && "$2" =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: --seconds needs a whole number > 0" >&2; exit 2; }
      seconds="$2"
      shift 2
      ;;
    --seconds=*)
      seconds="${1#--seconds=}"
      [[ "$seconds" =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: --seconds needs a whole number > 0" >&2; exit 2; }
      shift
      ;;
    -h|--help)
      sed -n '2,15p' "$0"
      exit 0
      ;;
    job_file_fuzzer|geometry_fuzzer)
      targets+=("$1")
      shift
      ;;
    *)
      echo "fuzz.sh: unknown argument \"$1\"; expected --seconds N or a target (job_file_fuzzer, geometry_fuzzer)" >&2
      exit 2
      ;;
  esac
done
[[ ${#targets[@]} -gt 0 ]] || targets=(job_file_fuzzer geometry_fuzzer)

source_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$source_dir/build/fuzz"
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ not found (scripts/deps.sh installs clang)" >&2; exit 1; }

# Only the library and the fuzzers: no tests, tools or benchmarks here.
CC=clang CXX=clang++ cmake -S "$source_dir" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DLOOPFARM_BUILD_FUZZERS=ON -DLOOPFARM_BUILD_TESTS=OFF \
  -DLOOPFARM_BUILD_TOOLS=OFF -DLOOPFARM_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$build" -j"$(nproc)" --target "${targets[@]}" >/dev/null

# Leaks are not crashes of a parser that returns normally; UBSan reports stop
# the run (the targets are built with -fno-sanitize-recover).
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"

status=0
summary=()
for target in "${targets[@]}"; do
  corpus="$build/corpus/$target"
  artifacts="$build/artifacts/$target/"
  mkdir -p "$corpus" "$artifacts"
  seeds=("$source_dir/fuzz/corpus/$target")
  [[ "$target" == job_file_fuzzer ]] && seeds+=("$source_dir/tests/tools/bad-inputs")
  log="$build/$target.log"
  echo "fuzz.sh: $target for $seconds s (log: $log)"
  started=$SECONDS
  set +e
  # -timeout: one input taking 10 s is a hang, reported like a crash.
  # -rss_limit_mb: an input that eats memory is reported too.
  "$build/fuzz/$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=8192 \
    -print_final_stats=1 -artifact_prefix="$artifacts" "$corpus" "${seeds[@]}" >"$log" 2>&1
  code=$?
  set -e
  elapsed=$((SECONDS - started))
  runs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n1)"
  spent="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n1)"
  if [[ $code -ne 0 ]]; then
    status=1
    echo "fuzz.sh: $target FAILED (exit $code); the input is in $artifacts, the report in $log:" >&2
    grep -m5 -E 'ERROR|runtime error|contract broken|Test unit written' "$log" >&2 || tail -n 20 "$log" >&2
  fi
  summary+=("$target: ${runs:-?} executions in $elapsed s (${spent:-?} per second), exit $code")
done
for line in "${summary[@]}"; do echo "fuzz.sh: $line"; done
exit $status
