#!/usr/bin/env bash
# Build loopfarm (Release, every core), run the default job on all cores and
# print its report.
#
#   scripts/run.sh                        # jobs/default.toml into build/default.sqlite
#   scripts/run.sh jobs/paper-table1.toml # another job, into build/paper-table1.sqlite
#
# A second call resumes the same run (nothing repeated); delete the database
# to start afresh. Arguments after the job go to `loopfarm run`.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/deps.sh
cmake -S . -B build/release -DCMAKE_BUILD_TYPE=Release
cmake --build build/release -j"$(nproc)"

loopfarm=build/release/tools/loopfarm
job="${1:-jobs/default.toml}"
shift || true
# The database goes to build/JOBNAME.sqlite (out of the source tree) unless
# --db is given.
db="build/$(basename "$job" .toml).sqlite"
db_args=(--db "$db")
for ((i = 1; i <= $#; ++i)); do
  if [[ "${!i}" == --db ]]; then j=$((i + 1)); db="${!j}"; db_args=(); fi
  if [[ "${!i}" == --db=* ]]; then db="${!i#--db=}"; db_args=(); fi
done

echo "== loopfarm run $job on $(nproc) cores (database $db)"
set +e
LOOPFARM="$loopfarm" jobs/mpirun-local.sh "$job" "${db_args[@]}" "$@"
code=$?
set -e
if [[ $code -ne 0 && $code -ne 3 ]]; then
  echo "scripts/run.sh: loopfarm run failed with exit code $code" >&2
  exit "$code"
fi
echo
echo "== loopfarm report $db --summary"
"$loopfarm" report "$db" --summary
echo
echo "== loopfarm report $db --limit 20 (the zero-minimum cases, from zero energy upwards)"
"$loopfarm" report "$db" --limit 20
exit "$code"
