#!/usr/bin/env bash
# Slices and merging as users run them: `loopfarm run --slice I/K` and
# `loopfarm merge`, and jobs/slurm-array.sbatch run as Slurm would run its
# array tasks, one after another on this machine.
#
#   tests/tools/slice_test.sh LOOPFARM SOURCE_DIR CASE [MPIEXEC]
#
# CASE: merge | array. Each case makes its own temporary directory and removes
# it. Exit 0 on success; on failure one line saying what differed, and exit 1.
set -euo pipefail
loopfarm="$(realpath "$1")"
source_dir="$2"
case_name="$3"
mpiexec="${4:-mpirun}"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

fail() {
  echo "slice_test $case_name: FAILED: $*" >&2
  exit 1
}

# A 4R space with every length fixed and one twist: its zeros are two Bennett
# linkages, each found by many starts, so every slice finds both and the
# duplicates straddle the slices.
job="$tmp/job.toml"
cat >"$job" <<'EOF'
[loop]
joints = 4
samples = 16

[space]
a1 = 1.0
a2 = 1.5
a3 = 1.0
a4 = 1.5
d = 0
alpha1_deg = 30
alpha_deg = [10, 170]

[optimizer]
algorithm = "gauss-newton"
max_evaluations = 100
# No wall-clock limit: the comparisons below are row by row.
time_limit_s = 0

[search]
starts = 30
seed = 3

[output]
database = "job.sqlite"
report_threshold = 1e-3
EOF

# One run of the job by content: every candidates column, and every starts
# column but the wall time and the session.
dump() {
  sqlite3 "$1" "SELECT * FROM candidates ORDER BY candidate_id;" >"$2"
  local columns
  columns="$(sqlite3 "$1" "SELECT group_concat(name, ', ') FROM pragma_table_info('starts') WHERE name NOT IN ('seconds', 'session_id');")"
  sqlite3 "$1" "SELECT $columns FROM starts ORDER BY run_id, start_index;" >>"$2"
}

same() {  # same A B WHAT
  if ! cmp -s "$1" "$2"; then
    diff "$1" "$2" | head -6 | cut -c1-300 >&2
    fail "$3"
  fi
}

"$loopfarm" run "$job" --progress none --db "$tmp/whole.sqlite" || fail "the whole run exited with $?"
dump "$tmp/whole.sqlite" "$tmp/whole.txt"
[[ "$(sqlite3 "$tmp/whole.sqlite" 'SELECT COUNT(*) FROM candidates')" -ge 2 ]] || fail "fewer than 2 candidates"
[[ "$(sqlite3 "$tmp/whole.sqlite" 'SELECT MIN(hits) FROM candidates')" -ge 3 ]] || fail "a candidate with fewer than 3 hits"

case "$case_name" in
merge)
  # Three slices, the middle one under mpirun with 2 ranks, each job file
  # naming its own database (as node-local paths would).
  for i in 0 1 2; do
    sed "s|^database = .*|database = \"$tmp/node$i.sqlite\"|" "$job" >"$tmp/job$i.toml"
  done
  "$loopfarm" run "$tmp/job0.toml" --slice 0/3 --progress none 2>"$tmp/err" || fail "slice 0 exited with $?"
  grep -q "10 of 10 starts of slice 0/3 (start indices \[0, 10) of 30)" "$tmp/err" || fail "slice 0 said: $(head -1 "$tmp/err")"
  "$mpiexec" --oversubscribe -np 2 "$loopfarm" run "$tmp/job1.toml" --slice 1/3 --progress none || fail "slice 1 exited with $?"
  "$loopfarm" run "$tmp/job2.toml" --slice 2/3 --progress none || fail "slice 2 exited with $?"
  for i in 0 1 2; do
    [[ "$(sqlite3 "$tmp/node$i.sqlite" 'SELECT COUNT(*) FROM starts')" == 10 ]] || fail "slice $i does not hold 10 starts"
    [[ "$(sqlite3 "$tmp/node$i.sqlite" 'SELECT COUNT(*) FROM candidates')" -ge 2 ]] || fail "slice $i found fewer than 2 linkages"
  done
  # Resuming a slice into another slice's database is refused, and changes nothing.
  cp "$tmp/node1.sqlite" "$tmp/before.sqlite"
  set +e
  "$loopfarm" run "$tmp/job1.toml" --slice 2/3 --progress none 2>"$tmp/err"
  code=$?
  set -e
  [[ $code -eq 2 ]] || fail "slice 2 into slice 1's database exited with $code, not 2"
  grep -q "slice 1/3 of 30 starts" "$tmp/err" || fail "no slice in the refusal: $(cat "$tmp/err")"
  cmp -s "$tmp/node1.sqlite" "$tmp/before.sqlite" || fail "the refused run changed slice 1's database"
  # The same slice again: nothing left to do.
  "$loopfarm" run "$tmp/job1.toml" --slice 1/3 --progress none || fail "slice 1 again exited with $?"

  "$loopfarm" merge "$tmp/merged.sqlite" "$tmp/node2.sqlite" "$tmp/node0.sqlite" "$tmp/node1.sqlite" 2>"$tmp/err" ||
    fail "merge exited with $?: $(cat "$tmp/err")"
  grep -q "3 databases into .*: 30 starts (0 held by more than one input, kept once)" "$tmp/err" || fail "merge said: $(head -1 "$tmp/err")"
  grep -q "the run is complete" "$tmp/err" || fail "merge said: $(tail -1 "$tmp/err")"
  dump "$tmp/merged.sqlite" "$tmp/merged.txt"
  same "$tmp/whole.txt" "$tmp/merged.txt" "three slices merged differ from one run of the same starts"
  # Where each start came from.
  provenance="$(sqlite3 "$tmp/merged.sqlite" "SELECT i.slice_index || ':' || MIN(s.start_index) || '-' || MAX(s.start_index) FROM starts AS s JOIN sessions AS e USING (session_id) JOIN merge_inputs AS i USING (input_id) GROUP BY i.input_id ORDER BY i.slice_index;" | tr '\n' ' ')"
  [[ "$provenance" == "0:0-9 1:10-19 2:20-29 " ]] || fail "provenance: $provenance"
  [[ "$(sqlite3 "$tmp/merged.sqlite" "SELECT COUNT(*) FROM sessions WHERE input_id = (SELECT input_id FROM merge_inputs WHERE slice_index = 1)")" == 2 ]] ||
    fail "slice 1's two sessions are not both recorded"
  "$loopfarm" report "$tmp/merged.sqlite" --summary >"$tmp/report" || fail "report exited with $?"
  grep -q "30/30 starts  complete  merged from 3 databases" "$tmp/report" || fail "report: $(sed -n 3p "$tmp/report")"

  # A slice merged with the whole run it overlaps: every start once, the same run.
  "$loopfarm" merge "$tmp/overlap.sqlite" "$tmp/node1.sqlite" "$tmp/whole.sqlite" 2>"$tmp/err" || fail "overlapping merge exited with $?"
  grep -q "30 starts (10 held by more than one input" "$tmp/err" || fail "overlapping merge said: $(head -1 "$tmp/err")"
  dump "$tmp/overlap.sqlite" "$tmp/overlap.txt"
  same "$tmp/whole.txt" "$tmp/overlap.txt" "a slice merged with the whole run differs from the whole run"

  # Two of three slices, then the third computed by resuming the merged database.
  "$loopfarm" merge "$tmp/partial.sqlite" "$tmp/node0.sqlite" "$tmp/node2.sqlite" 2>"$tmp/err" || fail "partial merge exited with $?"
  grep -q "20 of the job's 30 starts are there" "$tmp/err" || fail "partial merge said: $(tail -1 "$tmp/err")"
  "$loopfarm" run "$tmp/job0.toml" --db "$tmp/partial.sqlite" --progress none 2>"$tmp/err" || fail "resuming the merge exited with $?"
  grep -q "20 of 30 starts already committed" "$tmp/err" || fail "resume said: $(head -1 "$tmp/err")"
  dump "$tmp/partial.sqlite" "$tmp/partial.txt"
  sort "$tmp/whole.txt" >"$tmp/whole.sorted"
  # Candidate ids follow commit order, which a resume with a gap changes: compare by content.
  sqlite3 "$tmp/partial.sqlite" "SELECT first_start, family, canonical_key, hits FROM candidates ORDER BY first_start;" >"$tmp/a"
  sqlite3 "$tmp/whole.sqlite" "SELECT first_start, family, canonical_key, hits FROM candidates ORDER BY first_start;" >"$tmp/b"
  same "$tmp/b" "$tmp/a" "two slices merged and the third resumed differ from one run"
  ;;
array)
  script="$source_dir/jobs/slurm-array.sbatch"
  bash -n "$script" || fail "bash -n $script"
  # Slurm's environment for task I of a 3-task array; TMPDIR is each node's local disk.
  for i in 2 0 1; do
    mkdir -p "$tmp/node$i"
    (
      cd "$tmp"
      env SLURM_ARRAY_TASK_ID="$i" SLURM_ARRAY_TASK_COUNT=3 SLURM_ARRAY_JOB_ID=77 SLURM_NTASKS=2 \
        SLURM_SUBMIT_DIR="$tmp" TMPDIR="$tmp/node$i" LOOPFARM="$loopfarm" MPIRUN="$mpiexec --oversubscribe" \
        bash "$script" "$job" results
    ) >"$tmp/task$i.log" 2>&1 || fail "array task $i exited with $?: $(tail -2 "$tmp/task$i.log")"
    [[ -f "$tmp/results/slice-$i-of-3.sqlite" ]] || fail "task $i left no results/slice-$i-of-3.sqlite"
    [[ -z "$(ls -A "$tmp/node$i")" ]] || fail "task $i left files on its node: $(ls "$tmp/node$i")"
    [[ "$(sqlite3 "$tmp/results/slice-$i-of-3.sqlite" 'SELECT slice_index || "/" || slice_count || " " || COUNT(*) FROM runs, starts')" == "$i/3 10" ]] ||
      fail "task $i did not run slice $i/3"
  done
  (cd "$tmp" && env SLURM_SUBMIT_DIR="$tmp" LOOPFARM="$loopfarm" bash "$script" --merge results) >"$tmp/merge.log" 2>&1 ||
    fail "the merge step exited with $?: $(tail -1 "$tmp/merge.log")"
  dump "$tmp/results/merged.sqlite" "$tmp/merged.txt"
  same "$tmp/whole.txt" "$tmp/merged.txt" "the array's merged database differs from one run of the same starts"
  ;;
*)
  fail "unknown case"
  ;;
esac
echo "slice_test $case_name: passed"
