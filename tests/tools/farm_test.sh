#!/usr/bin/env bash
# The farm as users run it: `loopfarm run` alone and under mpirun, resume,
# stop by signal, refusal of another job, `loopfarm report`, and where
# relative paths lead.
#
#   tests/tools/farm_test.sh LOOPFARM SOURCE_DIR CASE [MPIEXEC]
#
# CASE: ranks | resume | signal | refuse | report | paths | script | slurm | unwritable. Each case makes its own
# temporary directory and removes it. Exit 0 on success; on failure one line
# saying what differed, and exit 1.
set -euo pipefail
loopfarm="$1"
source_dir="$2"
case_name="$3"
mpiexec="${4:-mpirun}"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

fail() {
  echo "farm_test $case_name: FAILED: $*" >&2
  exit 1
}

# A small generic 4R job: its zeros include planar, trivial and Bennett loops,
# so de-duplication and every family's columns are exercised.
job="$tmp/job.toml"
cat >"$job" <<'EOF'
[loop]
joints = 4
samples = 16

[optimizer]
algorithm = "gauss-newton"
max_evaluations = 100
# No wall-clock limit: the comparisons below are row by row, and a start cut
# short by a loaded machine would differ from the same start run unhurried.
time_limit_s = 0

[search]
starts = 40
seed = 7

[output]
database = "job.sqlite"
report_threshold = 1e-3
EOF

run1() { "$loopfarm" run "$job" --progress none "$@"; }
run2() { "$mpiexec" --oversubscribe -np 2 "$loopfarm" run "$job" --progress none "$@"; }

# Every column of the candidates table, and of the starts table but for the
# wall time, in key order: what must not depend on ranks, chunks or timing.
dump() {
  sqlite3 "$1" "SELECT * FROM candidates ORDER BY candidate_id;" >"$2"
  local columns
  columns="$(sqlite3 "$1" "SELECT group_concat(name, ', ') FROM pragma_table_info('starts') WHERE name NOT IN ('seconds', 'session_id');")"
  sqlite3 "$1" "SELECT $columns FROM starts ORDER BY run_id, start_index;" >>"$2"
}

# Waits until DB holds a committed start, at most TENTHS tenths of a second.
wait_for_first_commit() {  # DB TENTHS
  local i n
  for ((i = 0; i < $2; ++i)); do
    n="$(sqlite3 "$1" 'SELECT COUNT(*) FROM starts' 2>/dev/null || echo 0)"
    [[ "${n:-0}" -gt 0 ]] && return 0
    sleep 0.1
  done
}

same() {  # same A B WHAT
  if ! cmp -s "$1" "$2"; then
    diff "$1" "$2" | grep "^>" | head -3 | cut -c1-400 >&2
    fail "$3"
  fi
}

case "$case_name" in
ranks)
  # 1 rank with chunks of 7 against 2 ranks with chunks of 1.
  "$loopfarm" run "$job" --db "$tmp/one.sqlite" --chunk 7 --progress log 2>"$tmp/err" || fail "1 rank exited with $?"
  # Batch-log progress: the final line at least, with counts, rate and ETA.
  grep -q "^loopfarm run: 40/40 starts (100.0%), .* starts/s, ETA 0s, [0-9]* zero minima, [0-9]* candidates$" \
    "$tmp/err" || fail "no progress line: $(head -1 "$tmp/err")"
  run2 --db "$tmp/two.sqlite" --chunk 1 || fail "2 ranks exited with $?"
  dump "$tmp/one.sqlite" "$tmp/one.txt"
  dump "$tmp/two.sqlite" "$tmp/two.txt"
  [[ "$(sqlite3 "$tmp/one.sqlite" 'SELECT COUNT(*) FROM starts')" == 40 ]] || fail "not 40 starts"
  [[ "$(sqlite3 "$tmp/one.sqlite" 'SELECT COUNT(*) FROM candidates')" -ge 2 ]] || fail "fewer than 2 candidates"
  [[ "$(sqlite3 "$tmp/two.sqlite" 'SELECT ranks FROM runs')" == 2 ]] || fail "runs.ranks is not 2"
  same "$tmp/one.txt" "$tmp/two.txt" "the databases of 1 and 2 ranks differ"
  # 8 ranks on this machine's cores (oversubscribed), chunks of 2: 7 workers
  # and rank 0 hand out, compute and commit in an order of their own, and
  # every start and candidate row is the same as 1 rank's.
  "$mpiexec" --oversubscribe -np 8 "$loopfarm" run "$job" --progress none --db "$tmp/eight.sqlite" --chunk 2 ||
    fail "8 ranks exited with $?"
  [[ "$(sqlite3 "$tmp/eight.sqlite" 'SELECT ranks FROM runs')" == 8 ]] || fail "runs.ranks is not 8"
  dump "$tmp/eight.sqlite" "$tmp/eight.txt"
  same "$tmp/one.txt" "$tmp/eight.txt" "the databases of 1 and 8 ranks differ"
  ;;
resume)
  # 15 starts, then the same job to 40: the same database as 40 at once.
  run1 --db "$tmp/whole.sqlite"
  # --quiet: nothing on stderr; --format json: the summary as one object on stdout.
  "$loopfarm" run "$job" --db "$tmp/parts.sqlite" --starts 15 --quiet --format json >"$tmp/summary.json" 2>"$tmp/err" ||
    fail "--quiet --format json exited with $?"
  [[ ! -s "$tmp/err" ]] || fail "--quiet wrote to stderr: $(head -1 "$tmp/err")"
  [[ "$(wc -l <"$tmp/summary.json")" -eq 1 ]] || fail "the JSON summary is not one line: $(cat "$tmp/summary.json")"
  for field in '"status":"complete"' '"starts_done":15,"starts_total":15' '"ranks":1' '"resume_command":null}'; do
    grep -qF "$field" "$tmp/summary.json" || fail "the JSON summary has no $field: $(cat "$tmp/summary.json")"
  done
  [[ "$(sqlite3 "$tmp/parts.sqlite" 'SELECT COUNT(*) FROM starts')" == 15 ]] || fail "--quiet did not run 15 starts"
  "$loopfarm" run "$job" --db "$tmp/parts.sqlite" --starts 15 --quiet 2>"$tmp/err" || fail "--quiet resume exited with $?"
  [[ ! -s "$tmp/err" ]] || fail "--quiet wrote its resume note: $(head -1 "$tmp/err")"
  [[ "$(sqlite3 "$tmp/parts.sqlite" 'SELECT COUNT(*) FROM starts')" == 15 ]] || fail "first part is not 15 starts"
  run2 --db "$tmp/parts.sqlite" --starts 40 2>"$tmp/err" || fail "resume exited with $?"
  grep -q "15 of 40 starts already committed" "$tmp/err" || fail "no resume message: $(head -1 "$tmp/err")"
  # Three sessions: the first 15, the quiet call with nothing left, the rest.
  [[ "$(sqlite3 "$tmp/parts.sqlite" 'SELECT COUNT(*) FROM sessions')" == 3 ]] || fail "not 3 sessions"
  [[ "$(sqlite3 "$tmp/parts.sqlite" 'SELECT status FROM runs')" == complete ]] || fail "run not complete"
  # A third call has nothing left to do and changes no start.
  run1 --db "$tmp/parts.sqlite" || fail "a complete run's rerun exited with $?"
  dump "$tmp/whole.sqlite" "$tmp/whole.txt"
  dump "$tmp/parts.sqlite" "$tmp/parts.txt"
  same "$tmp/whole.txt" "$tmp/parts.txt" "a run in two parts differs from one in one go"
  ;;
signal)
  # SIGUSR1 (as Slurm's --signal sends it, forwarded by mpirun) while 2
  # ranks run: exit 3, a line saying how to resume, and the resumed run
  # equals an uninterrupted one. 400 starts, or LOOPFARM_FAULT_STARTS as in
  # fault_test.sh (scripts/test.sh --sanitize: 150; the instrumented farm took
  # 124 s for 400, and this case runs the job four times under 240 s).
  long="${LOOPFARM_FAULT_STARTS:-400}"
  [[ "$long" =~ ^[0-9]+$ ]] && ((long >= 100)) || fail "LOOPFARM_FAULT_STARTS must be a whole number >= 100, not '$long'"
  sed -i "s/^starts = 40\$/starts = $long/" "$job"
  # A run that finishes before the signal arrives (a fast machine) proves
  # nothing: it is tried again with four times the starts, twice at most,
  # and the case fails if it still finishes first.
  for attempt in 1 2 3; do
    rm -f "$tmp/stopped.sqlite"*
    set +e
    # mpirun itself in the background (not a function's subshell), so that
    # the signal reaches it.
    "$mpiexec" --oversubscribe -np 2 "$loopfarm" run "$job" --progress none --db "$tmp/stopped.sqlite" 2>"$tmp/err" &
    pid=$!
    # Wait for the first commit (at most 20 s), then signal.
    wait_for_first_commit "$tmp/stopped.sqlite" 200
    kill -USR1 "$pid"
    wait "$pid"
    code=$?
    set -e
    # Finished before the signal: every start committed, whatever the exit
    # code (0; or 128 + SIGUSR1 when the signal reached mpirun itself as it
    # shut down after its ranks: the first commit can come late in a short,
    # fast run).
    status="$(sqlite3 "$tmp/stopped.sqlite" 'SELECT status FROM runs' 2>/dev/null || true)"
    [[ "$status" == complete ]] || break
    [[ $attempt -lt 3 ]] || fail "the run finished before the signal three times, the last with $long starts"
    long=$((long * 4))
    echo "farm_test signal: the run finished before the signal; again with $long starts" >&2
    sed -i "s/^starts = [0-9]*\$/starts = $long/" "$job"
  done
  [[ $code -eq 3 ]] || fail "a stopped run exited with $code, not 3: $(tail -2 "$tmp/err")"
  grep -q "resume with: mpirun -np 2 loopfarm run" "$tmp/err" || fail "no resume line: $(tail -1 "$tmp/err")"
  done_before="$(sqlite3 "$tmp/stopped.sqlite" 'SELECT COUNT(*) FROM starts')"
  [[ "$done_before" -lt "$long" ]] || fail "the run was not stopped early ($done_before starts)"
  [[ "$(sqlite3 "$tmp/stopped.sqlite" 'SELECT status FROM runs')" == stopped ]] || fail "run status is not stopped"
  run2 --db "$tmp/stopped.sqlite" || fail "resume after the signal exited with $?"
  run2 --db "$tmp/straight.sqlite" || fail "uninterrupted run exited with $?"
  [[ "$(sqlite3 "$tmp/stopped.sqlite" 'SELECT COUNT(*) FROM starts')" == "$long" ]] || fail "resumed run lacks starts"
  # Candidate ids may come in another order after a stop with gaps; compare
  # the candidates by their first start, and every start.
  for db in stopped straight; do
    sqlite3 "$tmp/$db.sqlite" "SELECT first_run, first_start, family, canonical_key, hits FROM candidates ORDER BY first_run, first_start;" >"$tmp/$db.txt"
    columns="$(sqlite3 "$tmp/$db.sqlite" "SELECT group_concat(name, ', ') FROM pragma_table_info('starts') WHERE name NOT IN ('seconds', 'candidate_id', 'session_id');")"
    sqlite3 "$tmp/$db.sqlite" "SELECT $columns FROM starts ORDER BY start_index;" >>"$tmp/$db.txt"
  done
  same "$tmp/stopped.txt" "$tmp/straight.txt" "a stopped and resumed run differs from an uninterrupted one"
  # SIGTERM and SIGINT stop a run alike (one rank: without mpirun, which
  # follows its SIGTERM with SIGKILL, both leave time): exit 3, the resume
  # line, and the resumed run equals the uninterrupted one.
  for signal in TERM INT; do
    set +e
    "$loopfarm" run "$job" --progress none --db "$tmp/$signal.sqlite" 2>"$tmp/err" &
    pid=$!
    for ((i = 0; i < 200; ++i)); do
      n="$(sqlite3 "$tmp/$signal.sqlite" 'SELECT COUNT(*) FROM starts' 2>/dev/null || echo 0)"
      [[ "${n:-0}" -gt 0 ]] && break
      sleep 0.1
    done
    kill -"$signal" "$pid"
    wait "$pid"
    code=$?
    set -e
    [[ $code -eq 3 ]] || fail "SIG$signal: exited with $code, not 3: $(tail -2 "$tmp/err")"
    grep -q "stopped by SIG$signal; resume with: loopfarm run" "$tmp/err" || fail "SIG$signal: no resume line: $(tail -1 "$tmp/err")"
    [[ "$(sqlite3 "$tmp/$signal.sqlite" 'SELECT status FROM runs')" == stopped ]] || fail "SIG$signal: run status is not stopped"
    [[ "$(sqlite3 "$tmp/$signal.sqlite" 'SELECT COUNT(*) FROM starts')" -lt "$long" ]] || fail "SIG$signal: not stopped early"
    run2 --db "$tmp/$signal.sqlite" || fail "resume after SIG$signal exited with $?"
    sqlite3 "$tmp/$signal.sqlite" "SELECT first_run, first_start, family, canonical_key, hits FROM candidates ORDER BY first_run, first_start;" >"$tmp/$signal.txt"
    sqlite3 "$tmp/$signal.sqlite" "SELECT $columns FROM starts ORDER BY start_index;" >>"$tmp/$signal.txt"
    same "$tmp/$signal.txt" "$tmp/straight.txt" "a run stopped by SIG$signal and resumed differs from an uninterrupted one"
  done
  ;;
refuse)
  # --seed overrides [search] seed: the same starts and candidates as the
  # job file with that seed, and the run records it.
  run1 --db "$tmp/flag.sqlite" --starts 8 --seed 8 || fail "--seed 8 exited with $?"
  sed 's/^seed = 7$/seed = 8/' "$job" >"$tmp/job8.toml"
  "$loopfarm" run "$tmp/job8.toml" --progress none --db "$tmp/file.sqlite" --starts 8 || fail "seed 8 exited with $?"
  dump "$tmp/flag.sqlite" "$tmp/flag.txt"
  dump "$tmp/file.sqlite" "$tmp/file.txt"
  same "$tmp/flag.txt" "$tmp/file.txt" "--seed 8 differs from a job with seed = 8"
  run1 --db "$tmp/seven.sqlite" --starts 8
  dump "$tmp/seven.sqlite" "$tmp/seven.txt"
  ! cmp -s "$tmp/seven.txt" "$tmp/flag.txt" || fail "--seed 8 gave the starts of seed 7"
  [[ "$(sqlite3 "$tmp/flag.sqlite" 'SELECT seed FROM runs')" == 8 ]] || fail "--seed 8: runs.seed is not 8"
  run1 --db "$tmp/a.sqlite" --starts 5
  before="$(sha256sum "$tmp/a.sqlite")"
  sed -i 's/^seed = 7/seed = 8/' "$job"
  set +e
  run1 --db "$tmp/a.sqlite" 2>"$tmp/err"
  code=$?
  set -e
  [[ $code -eq 2 ]] || fail "another job on the database exited with $code, not 2"
  [[ "$(wc -l <"$tmp/err")" -eq 1 ]] || fail "the refusal is not one line: $(cat "$tmp/err")"
  grep -q -- "--new-run" "$tmp/err" || fail "the refusal does not mention --new-run: $(cat "$tmp/err")"
  [[ "$(sha256sum "$tmp/a.sqlite")" == "$before" ]] || fail "the refused run changed the database"
  run1 --db "$tmp/a.sqlite" --starts 5 --new-run || fail "--new-run exited with $?"
  [[ "$(sqlite3 "$tmp/a.sqlite" 'SELECT COUNT(*) FROM runs')" == 2 ]] || fail "--new-run did not add a run"
  # Bad input never touches the database: a broken job file, bad options.
  before="$(sha256sum "$tmp/a.sqlite")"
  printf '[search]\nstarts = 0\n' >"$tmp/bad.toml"
  for args in "$tmp/bad.toml --db $tmp/a.sqlite" "$job --db $tmp/a.sqlite --chunk 0" "$job --db $tmp/a.sqlite --starts x"; do
    set +e
    # shellcheck disable=SC2086
    "$loopfarm" run $args 2>"$tmp/err"
    code=$?
    set -e
    [[ $code -eq 2 ]] || fail "'run $args' exited with $code, not 2"
    [[ "$(wc -l <"$tmp/err")" -eq 1 ]] || fail "'run $args' printed more than one line"
  done
  [[ "$(sha256sum "$tmp/a.sqlite")" == "$before" ]] || fail "bad input changed the database"
  # Not a loopfarm database: refused, untouched.
  echo "not a database" >"$tmp/junk.sqlite"
  set +e
  run1 --db "$tmp/junk.sqlite" 2>"$tmp/err"
  code=$?
  set -e
  [[ $code -eq 2 ]] || fail "a junk database exited with $code, not 2"
  [[ "$(cat "$tmp/junk.sqlite")" == "not a database" ]] || fail "the junk file was changed"
  ;;
report)
  run1 --db "$tmp/r.sqlite"
  # A finished run's database is one file, and a report keeps it one file
  # (before any sqlite3 below, whose read-write connection would tidy up).
  companions() { find "$tmp" -maxdepth 1 -name 'r.sqlite-*' -printf '%f ' | sed 's/ $//'; }
  [[ -z "$(companions)" ]] || fail "after the run the database is not one file: $(companions)"
  "$loopfarm" report "$tmp/r.sqlite" --summary >/dev/null || fail "report --summary exited with $?"
  "$loopfarm" report "$tmp/r.sqlite" --format json >/dev/null || fail "report --format json exited with $?"
  [[ -z "$(companions)" ]] || fail "reading the database left $(companions) beside it"
  n="$(sqlite3 "$tmp/r.sqlite" 'SELECT COUNT(*) FROM candidates')"
  "$loopfarm" report "$tmp/r.sqlite" >"$tmp/table.txt" || fail "report exited with $?"
  [[ "$(wc -l <"$tmp/table.txt")" -eq $((n + 1)) ]] || fail "the table has not $n rows and a header"
  "$loopfarm" report "$tmp/r.sqlite" --format csv >"$tmp/c.csv"
  [[ "$(wc -l <"$tmp/c.csv")" -eq $((n + 1)) ]] || fail "the CSV has not $n rows and a header"
  head -1 "$tmp/c.csv" | grep -q '^candidate_id,family,families,setup,' || fail "CSV header: $(head -1 "$tmp/c.csv")"
  # The order: unclassified candidates first, then by energy from zero
  # upwards, ties by id (docs/guide/database.md), as SQLite orders them.
  cut -d, -f1 "$tmp/c.csv" | sed 1d >"$tmp/order.txt"
  sqlite3 "$tmp/r.sqlite" "SELECT candidate_id FROM candidates ORDER BY family <> 'unclassified', E_mean, candidate_id" >"$tmp/expected_order.txt"
  same "$tmp/order.txt" "$tmp/expected_order.txt" "the candidates are not in the documented order"
  # The CSV parses: SQLite's own CSV reader takes it back as a table with
  # the same values as the database (ids, families, energies to the bit).
  sqlite3 "$tmp/csv.sqlite" ".import --csv $tmp/c.csv report" || fail "the CSV does not import"
  [[ "$(sqlite3 "$tmp/csv.sqlite" 'SELECT COUNT(*) FROM report')" -eq "$n" ]] || fail "the CSV imports to not $n rows"
  sqlite3 "$tmp/csv.sqlite" "ATTACH '$tmp/r.sqlite' AS db; SELECT COUNT(*) FROM report r JOIN db.candidates c
    ON c.candidate_id = CAST(r.candidate_id AS INTEGER) AND c.family = r.family
    AND c.E_mean = CAST(r.E_mean AS REAL) AND c.a1 = CAST(r.a1 AS REAL);" >"$tmp/matched"
  [[ "$(cat "$tmp/matched")" -eq "$n" ]] || fail "CSV rows do not match the database ($(cat "$tmp/matched") of $n)"
  # The JSON parses (SQLite's JSON parser) to an array of n objects.
  "$loopfarm" report "$tmp/r.sqlite" --format json >"$tmp/j.json"
  parsed="$(sqlite3 :memory: "SELECT json_valid(CAST(readfile('$tmp/j.json') AS TEXT)),
    json_array_length(CAST(readfile('$tmp/j.json') AS TEXT)),
    json_extract(CAST(readfile('$tmp/j.json') AS TEXT), '\$[0].family');")"
  first_family="$(sqlite3 "$tmp/r.sqlite" "SELECT family FROM candidates ORDER BY family <> 'unclassified', E_mean, candidate_id LIMIT 1")"
  [[ "$parsed" == "1|$n|$first_family" ]] || fail "the JSON does not parse to $n objects: $parsed"
  "$loopfarm" report "$tmp/r.sqlite" --format markdown --limit 1 | grep -q '^| id | family' || fail "markdown header"
  [[ "$("$loopfarm" report "$tmp/r.sqlite" --format csv --limit 1 | wc -l)" -eq 2 ]] || fail "--limit 1"
  fam="$(sqlite3 "$tmp/r.sqlite" 'SELECT family FROM candidates ORDER BY candidate_id LIMIT 1')"
  m="$(sqlite3 "$tmp/r.sqlite" "SELECT COUNT(*) FROM candidates WHERE family = '$fam'")"
  [[ "$("$loopfarm" report "$tmp/r.sqlite" --family "$fam" --format csv | wc -l)" -eq $((m + 1)) ]] || fail "--family"
  # --max-energy at the median energy keeps exactly the candidates at or below it.
  median="$(sqlite3 "$tmp/r.sqlite" "SELECT printf('%.17g', E_mean) FROM candidates ORDER BY E_mean LIMIT 1 OFFSET $((n / 2))")"
  below="$(sqlite3 "$tmp/r.sqlite" "SELECT COUNT(*) FROM candidates WHERE E_mean <= $median")"
  [[ "$below" -lt "$n" ]] || fail "--max-energy: no candidate above the median energy to leave out"
  [[ "$("$loopfarm" report "$tmp/r.sqlite" --max-energy "$median" --format csv | wc -l)" -eq $((below + 1)) ]] ||
    fail "--max-energy $median: not the $below candidates at or below it"
  # --run: only what that run found first (a second run, another seed, on a
  # database of its own).
  run1 --db "$tmp/two_runs.sqlite" --starts 15
  sed 's/^seed = 7$/seed = 9/' "$job" >"$tmp/job9.toml"
  "$loopfarm" run "$tmp/job9.toml" --progress none --db "$tmp/two_runs.sqlite" --new-run --starts 25 ||
    fail "a second run exited with $?"
  for run in 1 2; do
    k="$(sqlite3 "$tmp/two_runs.sqlite" "SELECT COUNT(*) FROM candidates WHERE first_run = $run")"
    [[ "$k" -gt 0 ]] || fail "--run $run: the run found no candidate of its own to select"
    [[ "$("$loopfarm" report "$tmp/two_runs.sqlite" --run $run --format csv | wc -l)" -eq $((k + 1)) ]] ||
      fail "--run $run: not its $k candidates"
  done
  # The documented sqlite3 examples (docs/guide/database.md) run on a real database.
  mkdir "$tmp/doc"
  sed -n '/^## Examples/,/^```$/p' "$source_dir/docs/guide/database.md" | sed -n '/^```sh$/,/^```$/p' | sed '1d;$d' |
    sed "s|loopfarm.sqlite|$tmp/r.sqlite|g" >"$tmp/doc/examples.sh"
  [[ "$(grep -c '^sqlite3' "$tmp/doc/examples.sh")" -ge 5 ]] || fail "no sqlite3 examples found in docs/guide/database.md"
  (cd "$tmp/doc" && bash -euo pipefail examples.sh >out.txt 2>err.txt) || fail "docs/guide/database.md examples: $(head -1 "$tmp/doc/err.txt")"
  [[ ! -s "$tmp/doc/err.txt" ]] || fail "docs/guide/database.md examples: $(head -1 "$tmp/doc/err.txt")"
  grep -q "^\[loop\]" "$tmp/doc/job.toml" || fail "the documented job_text query did not give the job back"
  "$loopfarm" report "$tmp/r.sqlite" --summary >"$tmp/s.txt" || fail "--summary exited with $?"
  grep -q "histogram of log10(E_mean)" "$tmp/s.txt" || fail "--summary has no histogram"
  grep -q "candidates by family" "$tmp/s.txt" || fail "--summary has no family counts"
  "$loopfarm" report "$tmp/r.sqlite" --limit 1 --plot "$tmp/plots" >/dev/null 2>&1 || fail "--plot exited with $?"
  [[ -s "$tmp/plots/minima_histogram.png" ]] || fail "no histogram PNG"
  ls "$tmp"/plots/candidate_*_cycle.png >/dev/null 2>&1 || fail "no cycle PNG"
  # The report reads while a run writes (WAL): start a long run, report during it.
  sed -i 's/^starts = 40/starts = 400/' "$job"
  "$loopfarm" run "$job" --progress none --db "$tmp/live.sqlite" --new-run &
  pid=$!
  for ((i = 0; i < 200; ++i)); do
    [[ "$(sqlite3 "$tmp/live.sqlite" 'SELECT COUNT(*) FROM starts' 2>/dev/null || echo 0)" -gt 0 ]] && break
    sleep 0.1
  done
  "$loopfarm" report "$tmp/live.sqlite" --summary >/dev/null || fail "report during a run exited with $?"
  kill -INT "$pid"
  set +e
  wait "$pid"
  code=$?
  set -e
  [[ $code -eq 3 || $code -eq 0 ]] || fail "SIGINT: exit $code"
  # Bad input.
  for args in "$tmp/nothing.sqlite" "$tmp/r.sqlite --format xml" "$tmp/r.sqlite --family conic" "$tmp/r.sqlite --limit -1" "$job"; do
    set +e
    # shellcheck disable=SC2086
    "$loopfarm" report $args >/dev/null 2>"$tmp/err"
    code=$?
    set -e
    [[ $code -eq 2 ]] || fail "'report $args' exited with $code, not 2"
    [[ "$(wc -l <"$tmp/err")" -eq 1 ]] || fail "'report $args' printed $(wc -l <"$tmp/err") lines"
  done
  ;;
paths)
  # Relative paths are the user's: the job's database lands in the working
  # directory, not beside the job file, run alone and through
  # jobs/mpirun-local.sh (which must not change directory).
  mkdir -p "$tmp/jobs" "$tmp/here"
  sed 's/^starts = 40/starts = 6/' "$job" >"$tmp/jobs/small.toml"
  (cd "$tmp/here" && "$loopfarm" run ../jobs/small.toml --progress none) || fail "run from another directory exited with $?"
  [[ -f "$tmp/here/job.sqlite" ]] || fail "the job's database is not in the working directory: $(ls "$tmp/here" "$tmp/jobs")"
  [[ ! -e "$tmp/jobs/job.sqlite" ]] || fail "the job's database was written beside the job file"
  rm -f "$tmp/here/job.sqlite"
  realpath_loopfarm="$(realpath "$loopfarm")"
  (cd "$tmp/here" && LOOPFARM="$realpath_loopfarm" NP=2 "$source_dir/jobs/mpirun-local.sh" ../jobs/small.toml \
    --progress none --db rel.sqlite) || fail "jobs/mpirun-local.sh exited with $?"
  [[ "$(sqlite3 "$tmp/here/rel.sqlite" 'SELECT COUNT(*) FROM starts')" == 6 ]] ||
    fail "jobs/mpirun-local.sh did not write --db rel.sqlite where it was called: $(ls "$tmp/here")"
  [[ "$(sqlite3 "$tmp/here/rel.sqlite" 'SELECT ranks FROM runs')" == 2 ]] || fail "jobs/mpirun-local.sh did not run 2 ranks"
  ;;
script)
  # jobs/mpirun-local.sh reads like one process: a bad option is one line and
  # exit 2 (no Open MPI banner); Ctrl-C (SIGINT to the script's process group,
  # as a terminal sends it) stops every rank with the starts in hand
  # committed, exit 3, and a line naming the script that resumes the run.
  script="$source_dir/jobs/mpirun-local.sh"
  real_loopfarm="$(realpath "$loopfarm")"
  cd "$tmp"
  set +e
  LOOPFARM="$real_loopfarm" NP=2 "$script" "$job" --starts x 2>"$tmp/err"
  code=$?
  set -e
  [[ $code -eq 2 ]] || fail "a bad option through the script exited with $code, not 2"
  [[ "$(cat "$tmp/err")" == 'loopfarm run: --starts: "x" is not an integer' ]] ||
    fail "a bad option through the script printed more than rank 0's line: $(head -c 300 "$tmp/err")"
  sed -i 's/^starts = 40$/starts = 3000/' "$job"
  set +e
  # In a group of its own with SIGINT at its default, as a terminal's
  # foreground job (a background job of a script starts with SIGINT ignored).
  LOOPFARM="$real_loopfarm" NP=2 setsid env --default-signal=INT "$script" "$job" --db stopped.sqlite --progress none \
    2>"$tmp/err" &
  pid=$!
  wait_for_first_commit stopped.sqlite 300
  kill -INT -- "-$pid"
  wait "$pid"
  code=$?
  set -e
  [[ $code -eq 3 ]] || fail "Ctrl-C to the script exited with $code, not 3: $(tail -2 "$tmp/err")"
  [[ "$(sqlite3 stopped.sqlite 'SELECT status FROM runs')" == stopped ]] || fail "the run is not 'stopped'"
  done_before="$(sqlite3 stopped.sqlite 'SELECT COUNT(*) FROM starts')"
  ((done_before > 0 && done_before < 3000)) || fail "$done_before starts committed at the stop"
  resume="$(grep -o 'jobs/mpirun-local.sh: stopped early; resume with: .*' "$tmp/err" | sed 's/.*resume with: //')"
  [[ "$resume" == "NP=2 $script $job --db stopped.sqlite --progress none" ]] || fail "the resume line is '$resume'"
  LOOPFARM="$real_loopfarm" NP=2 "$script" "$job" --db stopped.sqlite --progress none 2>"$tmp/err" ||
    fail "the resume exited with $?"
  [[ "$(sqlite3 stopped.sqlite 'SELECT COUNT(*) FROM starts')" == 3000 ]] || fail "the resumed run lacks starts"
  ;;
slurm)
  # jobs/slurm.sbatch run as Slurm runs it (SLURM_* set, scontrol a stand-in
  # that records its arguments): a bad option is rank 0's one line and exit 2;
  # SIGUSR1 before the time limit stops every rank with the starts in hand
  # committed, the script exits 3 (loopfarm's code, though mpirun's own is 1
  # after a signal) and requeues the job.
  script="$source_dir/jobs/slurm.sbatch"
  bash -n "$script" || fail "bash -n $script"
  mkdir -p "$tmp/bin"
  printf '#!/bin/sh\necho "$@" >>"%s/requeued"\n' "$tmp" >"$tmp/bin/scontrol"
  chmod +x "$tmp/bin/scontrol"
  # As Slurm starts it: env execs bash, so $! below is the script's own pid.
  slurm_env=(env PATH="$tmp/bin:$PATH" SLURM_JOB_ID=4242 SLURM_NTASKS=2 SLURM_SUBMIT_DIR="$tmp" LOOPFARM="$loopfarm"
    MPIRUN="$mpiexec --oversubscribe" bash "$script")
  slurm() { "${slurm_env[@]}" "$@"; }
  set +e
  slurm "$job" --starts x 2>"$tmp/err"
  code=$?
  set -e
  [[ $code -eq 2 ]] || fail "a bad option through the script exited with $code, not 2"
  [[ "$(cat "$tmp/err")" == 'loopfarm run: --starts: "x" is not an integer' ]] ||
    fail "a bad option through the script printed more than rank 0's line: $(head -c 300 "$tmp/err")"
  [[ ! -e "$tmp/requeued" ]] || fail "a bad option requeued the job"
  sed -i 's/^starts = 40$/starts = 3000/' "$job"
  set +e
  "${slurm_env[@]}" "$job" --db "$tmp/slurm.sqlite" 2>"$tmp/err" &
  pid=$!
  wait_for_first_commit "$tmp/slurm.sqlite" 300
  kill -USR1 "$pid"
  wait "$pid"
  code=$?
  set -e
  [[ $code -eq 3 ]] || fail "SIGUSR1 to the script exited with $code, not 3: $(tail -2 "$tmp/err")"
  grep -q "slurm.sbatch: time limit near, asking loopfarm to stop" "$tmp/err" || fail "no stop line"
  [[ "$(cat "$tmp/requeued")" == "requeue 4242" ]] || fail "the job was not requeued: $(cat "$tmp/requeued" 2>&1)"
  [[ "$(sqlite3 "$tmp/slurm.sqlite" 'SELECT status FROM runs')" == stopped ]] || fail "the run is not 'stopped'"
  ls -A "$tmp" | grep -q '^\.loopfarm-exit' && fail "the script left its exit file behind"
  # That a stopped run resumes to the same database as an uninterrupted one,
  # farm_signal and farm_script show; here only that the script requeued it.
  ;;
unwritable)
  # A database its user may read but not write: in a directory it cannot
  # write (a shared results directory, an archive), or made read-only in its
  # own. The readers (report, bonds, merge's inputs) read it and leave
  # nothing beside it; the writers (run, bonds --store) are refused with
  # exit 2 and a line naming what they cannot write. Root is not stopped by
  # permissions, so as root the commands run as nobody (setpriv, util-linux);
  # as anyone else, as themselves.
  if [[ "$(id -u)" -eq 0 ]]; then
    command -v setpriv >/dev/null || fail "running as root, and no setpriv (util-linux) to run as nobody"
    as_user() { setpriv --reuid=65534 --regid=65534 --clear-groups -- "$@"; }
    own() { chown 65534:65534 "$@"; }
  else
    as_user() { "$@"; }
    own() { :; }
  fi
  # Everything the user needs to reach: the binary (copied, in case the
  # build directory is closed to it), the job, the directories.
  chmod 755 "$tmp"
  cp "$loopfarm" "$tmp/loopfarm"
  chmod 755 "$tmp/loopfarm"
  chmod 644 "$job"
  run1 --db "$tmp/r.sqlite"
  # The summary but for its first line, the database's path.
  "$loopfarm" report "$tmp/r.sqlite" --summary | sed 1d >"$tmp/expected.txt"
  companions() { find "$1" -maxdepth 1 -name '*.sqlite-*' -printf '%f ' | sed 's/ $//'; }
  # Exit code ($2), one line on stderr containing $3; stdout to $tmp/out.txt.
  expect_exit() {  # WHAT CODE TEXT COMMAND...
    local what="$1" want="$2" text="$3" code
    shift 3
    set +e
    as_user "$@" >"$tmp/out.txt" 2>"$tmp/err"
    code=$?
    set -e
    [[ $code -eq $want ]] || fail "$what exited with $code, not $want: $(head -c 300 "$tmp/err")"
    if [[ -n "$text" ]]; then
      [[ "$(wc -l <"$tmp/err")" -eq 1 ]] || fail "$what printed not one line: $(head -c 300 "$tmp/err")"
      grep -qF -- "$text" "$tmp/err" || fail "$what: the message lacks '$text': $(cat "$tmp/err")"
    fi
  }

  # In a directory the user cannot write.
  mkdir "$tmp/shelf" "$tmp/out"
  cp "$tmp/r.sqlite" "$tmp/shelf/in.sqlite"
  own "$tmp/shelf" "$tmp/shelf/in.sqlite" "$tmp/out"
  chmod 555 "$tmp/shelf"
  as_user test -w "$tmp/shelf" && fail "the shelf directory is writable by the user"
  before="$(sha256sum <"$tmp/shelf/in.sqlite")"
  expect_exit "report in an unwritable directory" 0 "" "$tmp/loopfarm" report "$tmp/shelf/in.sqlite" --summary
  sed -i 1d "$tmp/out.txt"
  same "$tmp/out.txt" "$tmp/expected.txt" "report in an unwritable directory printed another summary"
  expect_exit "bonds in an unwritable directory" 0 "" "$tmp/loopfarm" bonds "$tmp/shelf/in.sqlite" --family all \
    --limit 1
  expect_exit "merge of an input in an unwritable directory" 0 "" "$tmp/loopfarm" merge "$tmp/out/m.sqlite" \
    "$tmp/shelf/in.sqlite"
  [[ "$(sqlite3 "$tmp/out/m.sqlite" 'SELECT COUNT(*) FROM candidates')" == \
    "$(sqlite3 "$tmp/r.sqlite" 'SELECT COUNT(*) FROM candidates')" ]] || fail "the merge holds other candidates"
  expect_exit "run in an unwritable directory" 2 "its directory $tmp/shelf is not writable" \
    "$tmp/loopfarm" run "$job" --progress none --starts 50 --db "$tmp/shelf/in.sqlite"
  expect_exit "run of a new database in an unwritable directory" 2 "its directory $tmp/shelf is not writable" \
    "$tmp/loopfarm" run "$job" --progress none --db "$tmp/shelf/new.sqlite"
  expect_exit "bonds --store in an unwritable directory" 2 "its directory $tmp/shelf is not writable" \
    "$tmp/loopfarm" bonds "$tmp/shelf/in.sqlite" --store
  [[ "$(sha256sum <"$tmp/shelf/in.sqlite")" == "$before" ]] || fail "the database in the shelf changed"
  [[ "$(ls -A "$tmp/shelf")" == in.sqlite ]] || fail "the shelf holds more than in.sqlite: $(ls -A "$tmp/shelf")"

  # Made read-only in a directory the user can write.
  mkdir "$tmp/own"
  cp "$tmp/r.sqlite" "$tmp/own/r.sqlite"
  own "$tmp/own" "$tmp/own/r.sqlite"
  chmod 444 "$tmp/own/r.sqlite"
  expect_exit "report of a read-only file" 0 "" "$tmp/loopfarm" report "$tmp/own/r.sqlite" --summary
  sed -i 1d "$tmp/out.txt"
  same "$tmp/out.txt" "$tmp/expected.txt" "report of a read-only file printed another summary"
  [[ -z "$(companions "$tmp/own")" ]] || fail "report of a read-only file left $(companions "$tmp/own")"
  expect_exit "bonds of a read-only file" 0 "" "$tmp/loopfarm" bonds "$tmp/own/r.sqlite" --family all --limit 1
  [[ -z "$(companions "$tmp/own")" ]] || fail "bonds of a read-only file left $(companions "$tmp/own")"
  # A plain read-only connection leaves both companions, read-only like the
  # file; made writable again, the file is refused naming them.
  as_user sqlite3 -readonly "$tmp/own/r.sqlite" 'SELECT COUNT(*) FROM starts' >/dev/null
  [[ "$(companions "$tmp/own")" == *r.sqlite-wal* ]] || fail "sqlite3 -readonly left no companions to test with"
  as_user chmod u+w "$tmp/own/r.sqlite"
  before="$(sha256sum <"$tmp/own/r.sqlite")"
  expect_exit "run beside read-only companions" 2 "$tmp/own/r.sqlite-wal and $tmp/own/r.sqlite-shm beside it are not writable" \
    "$tmp/loopfarm" run "$job" --progress none --starts 50 --db "$tmp/own/r.sqlite"
  expect_exit "bonds --store beside read-only companions" 2 "$tmp/own/r.sqlite-wal and $tmp/own/r.sqlite-shm beside it are not writable" \
    "$tmp/loopfarm" bonds "$tmp/own/r.sqlite" --store
  [[ "$(sha256sum <"$tmp/own/r.sqlite")" == "$before" ]] || fail "the refused file changed"
  # Removed as the message says, the run goes on.
  rm "$tmp/own/r.sqlite-wal" "$tmp/own/r.sqlite-shm"
  expect_exit "run once the companions are gone" 0 "" "$tmp/loopfarm" run "$job" --progress none --starts 50 \
    --db "$tmp/own/r.sqlite"
  [[ "$(sqlite3 "$tmp/own/r.sqlite" 'SELECT starts_done FROM runs')" == 50 ]] || fail "the resumed run did not reach 50 starts"
  ;;
*)
  fail "unknown case"
  ;;
esac
echo "farm_test $case_name: passed"
