#!/usr/bin/env bash
# Runs a job on every core of this machine with mpirun, from where you stand
# (relative paths, the job's database included, are yours):
#
#   jobs/mpirun-local.sh                         # jobs/default.toml, into ./default.sqlite
#   jobs/mpirun-local.sh jobs/paper-table1.toml --starts 500
#   NP=4 jobs/mpirun-local.sh jobs/default.toml --db /tmp/default.sqlite
#
# Arguments after the job go to `loopfarm run`. The program is $LOOPFARM, else
# build/release/tools/loopfarm of this source tree. Stop it with Ctrl-C or
# `kill -USR1 <mpirun pid>`: the starts in hand finish and are committed, and
# the same command resumes (exit code 3 says it stopped early).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
loopfarm="${LOOPFARM:-$root/build/release/tools/loopfarm}"
job="${1:-$root/jobs/default.toml}"
shift || true
# Open MPI refuses root unless told (containers, CI); harmless otherwise.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
exec mpirun --oversubscribe -np "${NP:-$(nproc)}" "$loopfarm" run "$job" "$@"
