#!/usr/bin/env bash
# Runs a job on every core of this machine with mpirun, from where you stand
# (relative paths, the job's database included, are yours):
#
#   jobs/mpirun-local.sh                         # jobs/default.toml, into ./default.sqlite
#   jobs/mpirun-local.sh jobs/paper-table1.toml --starts 500
#   NP=4 jobs/mpirun-local.sh jobs/default.toml --db /tmp/default.sqlite
#
# Arguments after the job go to `loopfarm run`. The program is $LOOPFARM, else
# build/release/tools/loopfarm of this source tree. It reads like one
# process: a bad job or option is one line and exit 2 (mpirun's own banners
# are off, -q); Ctrl-C (or SIGTERM/SIGUSR1 to this script) stops every rank,
# the starts in hand are committed, and it exits 3 with the line that resumes
# the run (stop mpirun itself with SIGUSR1 only, as under any mpirun). Exit codes are loopfarm run's: 0 done, 1 failure, 2 bad input, 3
# stopped.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
loopfarm="${LOOPFARM:-$root/build/release/tools/loopfarm}"
job="${1:-$root/jobs/default.toml}"
shift || true
# Open MPI refuses root unless told (containers, CI); harmless otherwise.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Rank 0 writes its exit code here: once interrupted, mpirun exits 1 whatever
# its ranks said.
exit_file="$(mktemp "${TMPDIR:-/tmp}/loopfarm-exit.XXXXXX")"
trap 'rm -f "$exit_file"' EXIT
# mpirun runs in a session of its own, so that Ctrl-C reaches this script
# alone: mpirun answers SIGINT and SIGTERM by sending the ranks SIGTERM and,
# a moment later, SIGKILL, which may cut off the starts in hand. This script
# passes every stop on as SIGUSR1, which mpirun forwards and nothing follows:
# each rank finishes its starts, rank 0 commits them.
mpirun_pid=""
stop_mpirun() { [[ -n "$mpirun_pid" ]] && kill -USR1 "$mpirun_pid" 2>/dev/null; }
trap stop_mpirun INT TERM USR1
LOOPFARM_EXIT_FILE="$exit_file" setsid mpirun -q --oversubscribe -x LOOPFARM_EXIT_FILE -np "${NP:-$(nproc)}" \
  "$loopfarm" run "$job" "$@" &
mpirun_pid=$!
# wait returns early when a trapped signal arrives: wait again until mpirun ends.
while true; do
  wait "$mpirun_pid"
  code=$?
  kill -0 "$mpirun_pid" 2>/dev/null || break
done
if [[ -s "$exit_file" ]]; then
  code="$(<"$exit_file")"
fi
if [[ "$code" == 3 ]]; then
  printf 'jobs/mpirun-local.sh: stopped early; resume with: %s' "${NP:+NP=$NP }$0" >&2
  printf ' %q' "$job" "$@" >&2
  printf '\n' >&2
fi
exit "$code"
