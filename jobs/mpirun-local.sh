#!/usr/bin/env bash
# Runs a job on every core of this machine with mpirun:
#
#   jobs/mpirun-local.sh                         # jobs/default.toml
#   jobs/mpirun-local.sh jobs/paper-table1.toml --starts 500
#   NP=4 jobs/mpirun-local.sh jobs/default.toml --db /tmp/default.sqlite
#
# Arguments after the job go to `loopfarm run`. Stop it with Ctrl-C or
# `kill -USR1 <mpirun pid>`: the starts in hand finish and are committed, and
# the same command resumes (exit code 3 says it stopped early).
set -euo pipefail
cd "$(dirname "$0")/.."
loopfarm="${LOOPFARM:-build/release/tools/loopfarm}"
job="${1:-jobs/default.toml}"
shift || true
# Open MPI refuses root unless told (containers, CI); harmless otherwise.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
exec mpirun --oversubscribe -np "${NP:-$(nproc)}" "$loopfarm" run "$job" "$@"
