#!/usr/bin/env bash
# Build loopfarm (Release, every core) and run it.
#
# Until the search farm exists this shows the energy core on the paper's
# example: the Bennett loop (a movable linkage: zero cycle energy) and the same
# loop with a1 changed from 2 to 2.03 (no longer movable: positive energy).
# Arguments are passed on to `loopfarm energy`, e.g. tools/run.sh --samples 64.
set -euo pipefail
cd "$(dirname "$0")/.."

tools/deps.sh
cmake -S . -B build/release -DCMAKE_BUILD_TYPE=Release
cmake --build build/release -j"$(nproc)"

loopfarm=build/release/tools/loopfarm

# ---------------------------------------------------------------------------
# DEFAULT JOB GOES HERE: once `loopfarm run` and the report exist, this
# becomes
#   "$loopfarm" run jobs/default.toml
#   "$loopfarm" report ...
# and the two examples below can go.
# ---------------------------------------------------------------------------

echo "== the paper's Bennett loop: a = 2,4,2,4, alpha = 30,90,30,90 deg, at theta = 120,90,-120,-90 deg"
"$loopfarm" energy --a 2,4,2,4 --alpha-deg 30,90,30,90 --theta-deg 120,90,-120,-90 "$@"
echo
echo "== the same loop perturbed: a1 = 2.03"
"$loopfarm" energy --a 2.03,4,2,4 --alpha-deg 30,90,30,90 --theta-deg 120,90,-120,-90 "$@"
