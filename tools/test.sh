#!/usr/bin/env bash
# Build loopfarm with optimisation but with assertions on, run every test, and
# run the benchmarks once briefly so that they keep compiling and running.
# Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."

tools/deps.sh

# The MPI tests run mpirun, which refuses to run as root (CI containers)
# without these.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

jobs="$(nproc)"
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
