#!/usr/bin/env bash
# Faults of the farm, and reading while it writes.
#
#   tests/tools/fault_test.sh LOOPFARM CASE [MPIEXEC]
#
# CASE:
#   kill        A 2-rank `loopfarm run` gets SIGKILL, at rank 0 or at rank 1:
#               once as soon as rank 0 exists (before the database does),
#               once as soon as the file appears, then at up to six random
#               numbers of committed starts plus a random delay of up to
#               0.8 s (so that some kills land inside a commit). After each,
#               the same command resumes; on a fast machine the run may
#               complete before six, and a campaign on a fresh database
#               follows, until 2 early and 5 later faults were delivered. Every partial database must be whole (the
#               invariants below), and the end must equal an uninterrupted
#               run row for row, candidate ids included: no start lost, none
#               counted twice.
#   term        The same with SIGTERM, in turn to mpirun, rank 0 and rank 1.
#               A stop commits what finished, gaps included, so candidates
#               may be numbered in another order (docs/guide/database.md); every
#               other value must match, starts pointing at the same
#               candidates.
#   damage      A complete database truncated to half, with pages in the
#               middle overwritten, with a garbage header: `run` (1 and 2
#               ranks) and `report` (table, --summary, csv) exit 2 with one
#               line naming the file, and the file stays byte-identical.
#   full        The disk fills: once the first starts are committed, rank 0
#               (the writer) gets a file-size limit a little above its
#               database's files (prlimit; `loopfarm run` ignores SIGXFSZ,
#               so a write beyond it fails as on a full disk). The run must
#               exit 1 with a line naming the database, the database must be
#               whole (the invariants) and keep its commits, and the same
#               command must resume it to the end of an uninterrupted run.
#   concurrent  While a 2-rank run writes, `loopfarm report` and plain
#               `sqlite3` read in a loop: no error, no "database is locked",
#               counts that never decrease, invariants that hold in every
#               snapshot; afterwards the database equals an unread run's.
#
# The moments are random, the verdict is not: the assertions hold for every
# moment. FAULT_SEED=N replays a run's moments (its seed is printed first).
# Every wait is bounded. Exit 0 on success; on failure one line saying what
# differed, and exit 1.
set -euo pipefail
loopfarm="$1"
case_name="$2"
mpiexec="${3:-mpirun}"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
script_start=$SECONDS
tmp="$(mktemp -d)"
live_mp=""  # the mpirun started in the background and not yet reaped

say() { echo "fault_test $case_name: $*"; }
fail() {
  echo "fault_test $case_name: FAILED: $*" >&2
  exit 1
}

# The children of mpirun are the ranks (Open MPI starts local ranks itself).
rank_pids() { ps -o pid= --ppid "$1" 2>/dev/null | tr -d ' ' || true; }
rank_pid() {  # MPIRUN RANK
  local p
  for p in $(rank_pids "$1"); do
    if tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$2"; then
      echo "$p"
      return
    fi
  done
}
# Running (a reaped or zombie process is not).
alive() {
  local state
  state="$(awk '{ print $3 }' "/proc/$1/stat" 2>/dev/null)" || return 1
  [[ -n "$state" && "$state" != Z ]]
}

cleanup() {
  if [[ -n "$live_mp" ]] && alive "$live_mp"; then
    local p
    for p in $(rank_pids "$live_mp"); do kill -KILL "$p" 2>/dev/null || true; done
    kill -KILL "$live_mp" 2>/dev/null || true
    wait "$live_mp" 2>/dev/null || true
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT

seed="${FAULT_SEED:-$(($(date +%s%N) % 1000000))}"
RANDOM=$seed
say "seed $seed (replay the moments with FAULT_SEED=$seed)"

# A small generic 4R job (tests/tools/farm_test.sh's), 2,400 starts: about 8 s
# on 2 ranks of a fast day of the development machine, long enough for several
# commits (every 2 s) and so for faults at numbers of committed starts (with
# 600 starts, 2 s there, the run ended before most of them and too few were
# delivered). No time limit per start, so that results cannot depend on how
# loaded the machine is. LOOPFARM_FAULT_STARTS changes the count:
# scripts/test.sh --sanitize runs 150, since the instrumented farm took about
# 170 s for 600 (on a loaded machine).
total="${LOOPFARM_FAULT_STARTS:-2400}"
[[ "$total" =~ ^[0-9]+$ ]] && ((total >= 100)) || fail "LOOPFARM_FAULT_STARTS must be a whole number >= 100, not '$total'"
job="$tmp/job.toml"
cat >"$job" <<EOF
[loop]
joints = 4
samples = 16

[optimizer]
algorithm = "gauss-newton"
max_evaluations = 100
time_limit_s = 0

[search]
starts = $total
seed = 7

[output]
database = "job.sqlite"
report_threshold = 1e-3
EOF

# Foreground runs, bounded (timeout ends a hung mpirun and its ranks).
run1() { timeout -k 10 200 "$loopfarm" run "$job" --progress none "$@"; }
run2() { timeout -k 10 200 "$mpiexec" --oversubscribe -np 2 "$loopfarm" run "$job" --progress none "$@"; }

# A 2-rank run of the job on DB in the background: sets mp (and live_mp).
launch() {  # DB ERRLOG
  "$mpiexec" --oversubscribe -np 2 "$loopfarm" run "$job" --progress none --db "$1" 2>>"$2" &
  mp=$!
  live_mp=$mp
}

# Waits at most LIMIT s for PID to end; sets code to its exit code.
finish() {  # PID LIMIT
  local deadline=$((SECONDS + $2)) p
  while alive "$1"; do
    if ((SECONDS >= deadline)); then
      for p in $(rank_pids "$1"); do kill -KILL "$p" 2>/dev/null || true; done
      kill -KILL "$1" 2>/dev/null || true
      fail "mpirun $1 still running after $2 s"
    fi
    sleep 0.05
  done
  set +e
  wait "$1"
  code=$?
  set -e
  [[ "$1" != "$live_mp" ]] || live_mp=""
}

wait_gone() {  # "PIDS" LIMIT
  local deadline=$((SECONDS + $2)) p
  for p in $1; do
    while alive "$p"; do
      ((SECONDS < deadline)) || fail "rank $p still running $2 s after mpirun ended"
      sleep 0.05
    done
  done
}

# Committed starts, 0 while there is no file or no schema. Read-only, so
# that polling never creates the file (plain sqlite3 would).
count() {
  local n
  [[ -e "$1" ]] || { echo 0; return; }
  n="$(sqlite3 -readonly "$1" 'SELECT COUNT(*) FROM starts' 2>/dev/null)" || n=0
  echo "${n:-0}"
}

# What the schema promises in every committed state, in one statement (one
# snapshot): every start counted once in runs and sessions, every verified
# start in the hits of the candidate it names, which exists and whose first
# start is its earliest.
invariant_sql="SELECT
  (SELECT COUNT(*) FROM starts),
  (SELECT COUNT(*) FROM candidates),
  (SELECT COALESCE(SUM(starts_done), 0) FROM runs),
  (SELECT COALESCE(SUM(starts_done), 0) FROM sessions),
  (SELECT COUNT(*) FROM starts WHERE verified = 1),
  (SELECT COALESCE(SUM(hits), 0) FROM candidates),
  (SELECT COUNT(*) FROM starts AS s WHERE s.candidate_id IS NOT NULL
     AND NOT EXISTS (SELECT 1 FROM candidates AS c WHERE c.candidate_id = s.candidate_id)),
  (SELECT COUNT(*) FROM starts WHERE verified = 1 AND candidate_id IS NULL),
  (SELECT COUNT(*) FROM candidates AS c WHERE c.hits <> (SELECT COUNT(*) FROM starts AS s WHERE s.candidate_id = c.candidate_id)
     OR c.first_start IS NOT (SELECT MIN(s.start_index) FROM starts AS s WHERE s.candidate_id = c.candidate_id)),
  (SELECT COUNT(*) FROM starts AS s WHERE s.start_index < 0
     OR s.start_index >= (SELECT r.starts FROM runs AS r WHERE r.run_id = s.run_id));"

# Checks one snapshot's line of invariant_sql; sets snap_starts, snap_candidates.
check_snapshot() {  # LINE WHERE
  local starts candidates runs_done sessions_done verified hits dangling unplaced bad_hits out_of_range
  IFS='|' read -r starts candidates runs_done sessions_done verified hits dangling unplaced bad_hits out_of_range <<<"$1"
  [[ "$starts" =~ ^[0-9]+$ && "$out_of_range" =~ ^[0-9]+$ ]] || fail "$2: cannot read the invariants: $1"
  ((runs_done == starts && sessions_done == starts)) ||
    fail "$2: $starts starts, but runs count $runs_done and sessions $sessions_done"
  ((hits == verified)) || fail "$2: $verified verified starts, but candidates count $hits hits"
  ((dangling == 0 && unplaced == 0)) || fail "$2: $dangling starts name a missing candidate, $unplaced verified have none"
  ((bad_hits == 0)) || fail "$2: $bad_hits candidates disagree with their starts (hits or first start)"
  ((out_of_range == 0)) || fail "$2: $out_of_range start indices outside the run"
  snap_starts=$starts
  snap_candidates=$candidates
}

check_invariants() {  # DB [TOTAL]
  local line integrity
  integrity="$(sqlite3 -readonly "$1" 'PRAGMA integrity_check' 2>&1)" || true
  [[ "$integrity" == ok ]] || fail "$1: integrity_check: $(echo "$integrity" | head -2)"
  line="$(sqlite3 -readonly "$1" "$invariant_sql")" || fail "$1: the invariant query failed"
  check_snapshot "$line" "$(basename "$1")"
  [[ -z "${2:-}" ]] || ((snap_starts == $2)) || fail "$1: $snap_starts starts, not $2"
}

# Every column of the candidates table, and of the starts table but for the
# wall time and session, in key order (tests/tools/farm_test.sh's dump).
dump() {  # DB OUT
  sqlite3 -readonly "$1" "SELECT * FROM candidates ORDER BY candidate_id;" >"$2"
  local columns
  columns="$(sqlite3 -readonly "$1" "SELECT group_concat(name, ', ') FROM pragma_table_info('starts') WHERE name NOT IN ('seconds', 'session_id');")"
  sqlite3 -readonly "$1" "SELECT $columns FROM starts ORDER BY run_id, start_index;" >>"$2"
}

# The same with candidates named by their first start instead of their id:
# what must not depend on the order of commits.
dump_mapped() {  # DB OUT
  local columns
  columns="$(sqlite3 -readonly "$1" "SELECT group_concat(name, ', ') FROM pragma_table_info('candidates') WHERE name <> 'candidate_id';")"
  sqlite3 -readonly "$1" "SELECT $columns FROM candidates ORDER BY first_run, first_start;" >"$2"
  columns="$(sqlite3 -readonly "$1" "SELECT group_concat('s.' || name, ', ') FROM pragma_table_info('starts') WHERE name NOT IN ('seconds', 'session_id', 'candidate_id');")"
  sqlite3 -readonly "$1" "SELECT $columns, (SELECT c.first_run || ':' || c.first_start FROM candidates AS c
    WHERE c.candidate_id = s.candidate_id) FROM starts AS s ORDER BY s.run_id, s.start_index;" >>"$2"
}

same() {  # A B WHAT
  if ! cmp -s "$1" "$2"; then
    diff "$1" "$2" | grep "^[<>]" | head -4 | cut -c1-300 >&2 || true
    fail "$3"
  fi
}

# One interrupted invocation: launch the 2-rank run on DB, wait until WHEN
# holds, sleep DELAY_MS, send SIGNAL to VICTIM (0 or 1: that rank; mpirun),
# wait for the end. WHEN: rank0 (rank 0's process exists), file (the
# database file exists), or a number of committed starts. Sets code (mpirun's
# exit code), at_signal and after_signal (committed starts then and after).
interrupt() {  # DB SIGNAL VICTIM WHEN DELAY_MS ERRLOG
  local db="$1" signal="$2" victim="$3" when="$4" delay_ms="$5" log="$6"
  launch "$db" "$log"
  local deadline=$((SECONDS + 120)) reached=0 target="" ranks
  while alive "$mp"; do
    # The victim first: a rank exists some 0.1 s after mpirun.
    if [[ -z "$target" ]]; then
      case "$victim" in
        mpirun) target="$mp" ;;
        *) target="$(rank_pid "$mp" "$victim")" ;;
      esac
    fi
    if [[ -n "$target" ]]; then
      case "$when" in
        rank0) [[ -z "$(rank_pid "$mp" 0)" ]] || reached=1 ;;
        file) [[ ! -e "$db" ]] || reached=1 ;;
        *) (($(count "$db") < when)) || reached=1 ;;
      esac
    fi
    ((reached == 0)) || break
    ((SECONDS < deadline)) || fail "the moment '$when' did not come within 120 s"
    sleep 0.02
  done
  ((delay_ms == 0)) || sleep "$((delay_ms / 1000)).$(printf '%03d' $((delay_ms % 1000)))"
  at_signal="$(count "$db")"
  ranks="$(rank_pids "$mp")"
  if [[ -n "$target" ]] && alive "$target"; then
    kill -"$signal" "$target" 2>/dev/null || true
    delivered=yes
  else
    delivered=no  # the run ended first; the verdict does not depend on it
  fi
  finish "$mp" 90
  # Every rank gone before the next invocation opens the file.
  wait_gone "$ranks" 30
  after_signal="$(count "$db")"
}

case "$case_name" in
kill | term)
  t0=$SECONDS
  run2 --db "$tmp/straight.sqlite" 2>"$tmp/straight.err" || fail "the uninterrupted run exited with $?"
  check_invariants "$tmp/straight.sqlite" "$total"
  say "uninterrupted run: $total starts in $((SECONDS - t0)) s"

  if [[ "$case_name" == kill ]]; then
    signal=KILL
    victims=(0 1)
  else
    signal=TERM
    victims=(mpirun 0 1)
  fi
  faults=0
  early=0  # delivered at an early moment
  later=0  # delivered at a number of committed starts
  # Campaigns on fresh databases until at least 2 early faults and 5 later
  # ones have been delivered: how many fit in one run depends on the speed
  # of the machine (a commit every 2 s), the count of faults must not.
  # At most 12 campaigns: on a fast machine a campaign's run may complete
  # after one later fault (since the search reuses the nearby cycle, the 600
  # starts take a few seconds), so the count of campaigns, not the verdict,
  # depends on the machine's speed.
  for ((campaign = 1; campaign <= 12 && (early < 2 || later < 5); ++campaign)); do
    db="$tmp/faulted$campaign.sqlite"
    in_campaign=0
    # Two early moments, then six at numbers of committed starts, the
    # victims in turn.
    for moment in rank0 file starts starts starts starts starts starts; do
      done_now="$(count "$db")"
      ((done_now < total - 40)) || break
      victim="${victims[$((faults % ${#victims[@]}))]}"
      delay=0
      if [[ "$moment" == starts ]]; then
        # 1 to 20 starts after those committed, then up to 0.8 s later: in
        # the next commit or just after it, sometimes inside it.
        moment=$((done_now + 1 + RANDOM % 20))
        delay=$((RANDOM % 800))
      fi
      [[ "$moment" != rank0 ]] || victim=0
      existed=no
      [[ ! -e "$db" ]] || existed=yes
      t0=$SECONDS
      : >"$tmp/faulted.err"
      interrupt "$db" "$signal" "$victim" "$moment" "$delay" "$tmp/faulted.err"
      faults=$((faults + 1))
      in_campaign=$((in_campaign + 1))
      if [[ "$delivered" == yes ]]; then
        if [[ "$moment" =~ ^[0-9]+$ ]]; then later=$((later + 1)); else early=$((early + 1)); fi
      fi
      # The run's status says whether the ranks stopped cleanly (stopped) or
      # were killed (running); under mpirun, SIGTERM is followed by SIGKILL
      # after about 1 s, so either may follow SIGTERM to mpirun: reported.
      status="$(sqlite3 -readonly "$db" 'SELECT status FROM runs' 2>/dev/null || true)"
      say "fault $faults (campaign $campaign): SIG$signal to $victim at '$moment' + $delay ms (file before: $existed;" \
        "delivered: $delivered): $at_signal starts committed at the signal, $after_signal after;" \
        "mpirun exit $code; run ${status:-absent}; $((SECONDS - t0)) s"
      # Nothing committed is lost, and what is there is whole.
      ((after_signal >= at_signal)) || fail "fault $faults: $at_signal starts committed at the signal, $after_signal after"
      if [[ "$(sqlite3 -readonly "$db" "SELECT COUNT(*) FROM sqlite_schema WHERE name = 'starts'" 2>/dev/null)" == 1 ]]; then
        check_invariants "$db"
        # The report reads what the fault left (a WAL to recover, a run still
        # marked running) and lists every candidate.
        timeout 60 "$loopfarm" report "$db" --format csv --limit 100000000 >"$tmp/report.csv" 2>"$tmp/report.err" ||
          fail "fault $faults: report exited with $?: $(head -1 "$tmp/report.err")"
        (($(wc -l <"$tmp/report.csv") == snap_candidates + 1)) ||
          fail "fault $faults: report does not list $snap_candidates candidates"
      fi
      if ((code == 0)); then
        ((after_signal == total)) || fail "fault $faults: exit 0 with $after_signal of $total starts"
      elif [[ "$signal" == TERM && "$victim" != mpirun && "$moment" =~ ^[0-9]+$ && "$delivered" == yes ]]; then
        # A rank that gets SIGTERM while the run is under way stops it.
        ((code == 3)) || fail "fault $faults: SIGTERM to rank $victim: mpirun exited with $code, not 3"
        grep -q "resume with: mpirun -np 2 loopfarm run" "$tmp/faulted.err" || fail "fault $faults: no resume line"
        [[ "$status" == stopped ]] || fail "fault $faults: exit 3 but the run is '$status', not stopped"
      fi
    done
    # The first resume without a fault completes.
    t0=$SECONDS
    run2 --db "$db" 2>"$tmp/resume.err" || fail "the final resume exited with $?: $(tail -1 "$tmp/resume.err")"
    check_invariants "$db" "$total"
    [[ "$(sqlite3 -readonly "$db" 'SELECT status FROM runs')" == complete ]] || fail "the run is not complete"
    say "campaign $campaign: resumed to $total starts in $((SECONDS - t0)) s after $in_campaign faults;" \
      "$(sqlite3 -readonly "$db" 'SELECT COUNT(*) FROM sessions') sessions"
    dump_mapped "$tmp/straight.sqlite" "$tmp/straight.mapped"
    dump_mapped "$db" "$tmp/faulted.mapped"
    same "$tmp/straight.mapped" "$tmp/faulted.mapped" "campaign $campaign: the resumed run differs from the uninterrupted one"
    stopped_sessions="$(sqlite3 -readonly "$db" "SELECT COUNT(*) FROM sessions WHERE status = 'stopped'")"
    if [[ "$case_name" == kill && "$stopped_sessions" != 0 ]]; then
      # SIGKILL to rank 1 makes mpirun send rank 0 SIGTERM before its SIGKILL:
      # a rank 0 quick enough commits the records it holds, gaps and all, as
      # any stop does, and candidate ids may then follow another order.
      say "campaign $campaign: $stopped_sessions sessions stopped by mpirun's SIGTERM; candidates compared by content only"
    elif [[ "$case_name" == kill ]]; then
      # With every session killed outright the committed starts are a prefix
      # every time, so candidate ids match too.
      dump "$tmp/straight.sqlite" "$tmp/straight.txt"
      dump "$db" "$tmp/faulted.txt"
      same "$tmp/straight.txt" "$tmp/faulted.txt" "campaign $campaign: candidate ids differ after SIGKILL and resume"
    fi
  done
  ((early >= 2 && later >= 5)) || fail "only $early early and $later later faults delivered in 12 campaigns"
  say "$faults faults, $early early and $later later ones delivered, in $((campaign - 1)) campaigns: every resumed run" \
    "equals the uninterrupted one"
  ;;
damage)
  run1 --db "$tmp/good.sqlite" --starts 120 2>/dev/null || fail "the run that makes the database exited with $?"
  # A run that ends cleanly leaves everything in the file itself (an empty
  # WAL companion may stay): the damaged copies below are whole databases.
  [[ ! -s "$tmp/good.sqlite-wal" ]] || fail "a cleanly ended run left commits in the WAL"
  page_size="$(sqlite3 -readonly "$tmp/good.sqlite" 'PRAGMA page_size')"
  size="$(stat -c %s "$tmp/good.sqlite")"
  pages=$((size / page_size))
  ((pages >= 9)) || fail "the database has only $pages pages"
  # Truncated to half (a copy cut short, a full disk).
  cp "$tmp/good.sqlite" "$tmp/truncated.sqlite"
  truncate -s $((size / 2)) "$tmp/truncated.sqlite"
  # Two whole pages in the middle overwritten with one byte value (a bad block).
  cp "$tmp/good.sqlite" "$tmp/middle.sqlite"
  head -c $((2 * page_size)) /dev/zero | tr '\0' '\245' |
    dd of="$tmp/middle.sqlite" bs="$page_size" seek=$((pages / 2)) conv=notrunc status=none
  # Scattered bytes: 64 bytes at a fixed place of each of 8 pages spread
  # over the file, from a fixed generator (the same damage every time).
  cp "$tmp/good.sqlite" "$tmp/scattered.sqlite"
  for ((k = 1; k <= 8; ++k)); do
    LC_ALL=C awk -v k="$k" 'BEGIN { x = 12345 + k; for (i = 0; i < 64; ++i) { x = (x * 16807) % 2147483647; printf "%c", 1 + x % 255 } }' |
      LC_ALL=C dd of="$tmp/scattered.sqlite" bs=1 seek=$(((k * pages / 9) * page_size)) conv=notrunc status=none
  done
  # The 100-byte header overwritten with text.
  cp "$tmp/good.sqlite" "$tmp/header.sqlite"
  printf '%0100d' 0 | tr 0 x | dd of="$tmp/header.sqlite" conv=notrunc status=none
  refusals=0
  for name in truncated middle scattered header; do
    file="$tmp/$name.sqlite"
    # The damage is there to find: SQLite itself says so.
    verdict="$(sqlite3 -readonly "$file" 'PRAGMA integrity_check' 2>&1 | head -1 || true)"
    [[ "$verdict" != ok ]] || fail "$name: SQLite finds no damage (the test did not damage the file)"
    rm -f "$file-wal" "$file-shm"
    before="$(sha256sum <"$file")"
    for how in run1 run2 report summary csv; do
      set +e
      case "$how" in
        run1) run1 --db "$file" >"$tmp/out" 2>"$tmp/err" ;;
        run2) run2 --db "$file" >"$tmp/out" 2>"$tmp/err" ;;
        report) timeout 60 "$loopfarm" report "$file" >"$tmp/out" 2>"$tmp/err" ;;
        summary) timeout 60 "$loopfarm" report "$file" --summary >"$tmp/out" 2>"$tmp/err" ;;
        csv) timeout 60 "$loopfarm" report "$file" --format csv --limit 1000 >"$tmp/out" 2>"$tmp/err" ;;
      esac
      got=$?
      set -e
      [[ $got -eq 2 ]] || fail "$name: $how exited with $got, not 2: $(head -2 "$tmp/err")"
      # mpirun adds its own banner about the non-zero exit, which it may
      # write in the middle of a line it forwards; loopfarm's message is one
      # line.
      if [[ "$how" == run2 ]]; then
        grep -ao "loopfarm run: .*" "$tmp/err" >"$tmp/msg" || true
      else
        cp "$tmp/err" "$tmp/msg"
      fi
      [[ "$(wc -l <"$tmp/msg")" -eq 1 ]] || fail "$name: $how printed not one line: $(head -3 "$tmp/err")"
      grep -qF "$file" "$tmp/msg" || fail "$name: $how does not name the file: $(cat "$tmp/msg")"
      grep -Eq "damaged|not an SQLite database" "$tmp/msg" || fail "$name: $how does not say what is wrong: $(cat "$tmp/msg")"
      [[ ! -s "$tmp/out" ]] || fail "$name: $how wrote to stdout: $(head -1 "$tmp/out")"
      [[ "$(sha256sum <"$file")" == "$before" ]] || fail "$name: $how changed the file"
      # SQLite may leave an empty WAL companion, never one with content;
      # a file refused for what its first page says gets none at all.
      [[ ! -s "$file-wal" ]] || fail "$name: $how wrote a WAL file"
      if [[ "$name" == truncated || "$name" == header ]] && [[ -e "$file-wal" || -e "$file-shm" ]]; then
        fail "$name: $how created companion files"
      fi
      refusals=$((refusals + 1))
    done
    say "$name (integrity_check: ${verdict:0:60}): refused 5 ways, exit 2, unchanged: $(cut -c1-160 "$tmp/msg")"
  done
  # The undamaged original still reads and resumes: the checks do not
  # refuse everything.
  timeout 60 "$loopfarm" report "$tmp/good.sqlite" --summary >/dev/null || fail "report on the undamaged database exited with $?"
  run1 --db "$tmp/good.sqlite" --starts 130 2>/dev/null || fail "resuming the undamaged database exited with $?"
  check_invariants "$tmp/good.sqlite" 130
  say "$refusals refusals checked"
  ;;
full)
  command -v prlimit >/dev/null || fail "prlimit not found (util-linux)"
  run2 --db "$tmp/straight.sqlite" 2>"$tmp/straight.err" || fail "the uninterrupted run exited with $?"
  db="$tmp/full.sqlite"
  launch "$db" "$tmp/full.err"
  deadline=$((SECONDS + 120))
  until (($(count "$db") > 0)); do
    alive "$mp" || fail "the run ended before its first commit"
    ((SECONDS < deadline)) || fail "no start committed after 120 s"
    sleep 0.02
  done
  writer="$(rank_pid "$mp" 0)"
  [[ -n "$writer" ]] || fail "no rank 0 under mpirun $mp"
  held=$(stat -c %s "$db")
  [[ ! -e "$db-wal" ]] || held=$(( $(stat -c %s "$db-wal") > held ? $(stat -c %s "$db-wal") : held ))
  # The database cannot hold all the job's starts under this limit: its
  # files must grow by far more than 32 KiB before the run ends.
  prlimit --pid "$writer" --fsize=$((held + 32768)) || fail "prlimit on rank 0 ($writer) failed"
  at_limit="$(count "$db")"
  finish "$mp" 120
  ranks="$(rank_pids "$mp")"
  ((code == 1)) || fail "the run whose disk filled exited with $code, not 1: $(grep -m1 'loopfarm run' "$tmp/full.err" || true)"
  grep -q "loopfarm run: .*results database $db: .*disk I/O error" "$tmp/full.err" ||
    fail "no line naming the database and the failed write: $(head -2 "$tmp/full.err")"
  kept="$(count "$db")"
  ((kept >= at_limit && kept < total)) || fail "$kept starts kept ($at_limit when the limit was set, $total in all)"
  check_invariants "$db"
  say "stopped at $kept of $total starts, limit $((held + 32768)) bytes"
  # Room again: the same command resumes to the end of an uninterrupted run.
  run2 --db "$db" 2>"$tmp/resume.err" || fail "resuming exited with $?: $(tail -1 "$tmp/resume.err")"
  check_invariants "$db" "$total"
  dump_mapped "$tmp/straight.sqlite" "$tmp/straight.txt"
  dump_mapped "$db" "$tmp/full.txt"
  same "$tmp/straight.txt" "$tmp/full.txt" "the resumed run differs from an uninterrupted one"
  ;;
concurrent)
  db="$tmp/live.sqlite"
  t0=$SECONDS
  launch "$db" "$tmp/live.err"
  # From the moment the schema is committed (before it, report rightly
  # refuses the file).
  deadline=$((SECONDS + 60))
  until sqlite3 -readonly "$db" 'SELECT COUNT(*) FROM runs' >/dev/null 2>&1; do
    alive "$mp" || fail "the run ended before its database had a schema"
    ((SECONDS < deadline)) || fail "no schema after 60 s"
    sleep 0.02
  done
  reads=0
  reports=0
  while_running=0
  after=0
  prev_starts=0
  prev_candidates=0
  deadline=$((SECONDS + 180))
  # Read until the run has ended and 10 rounds more, at most 3000 rounds.
  for ((round = 0; round < 3000; ++round)); do
    ((SECONDS < deadline)) || fail "still reading after 180 s"
    running=0
    ! alive "$mp" || running=1
    # Plain sqlite3 (a read-write connection, no busy timeout), one snapshot.
    line="$(sqlite3 "$db" "$invariant_sql" 2>"$tmp/rerr")" || fail "round $round: sqlite3 exited with $?: $(head -1 "$tmp/rerr")"
    [[ ! -s "$tmp/rerr" ]] || fail "round $round: sqlite3 said: $(head -1 "$tmp/rerr")"
    check_snapshot "$line" "round $round"
    ((snap_starts >= prev_starts)) || fail "round $round: starts went down from $prev_starts to $snap_starts"
    ((snap_candidates >= prev_candidates)) ||
      fail "round $round: candidates went down from $prev_candidates to $snap_candidates"
    prev_starts=$snap_starts
    prev_candidates=$snap_candidates
    # loopfarm report, then the counts once more: the report's snapshot lies
    # between the two reads.
    timeout 60 "$loopfarm" report "$db" --format csv --limit 100000000 >"$tmp/report.csv" 2>"$tmp/rerr" ||
      fail "round $round: report exited with $?: $(head -1 "$tmp/rerr")"
    [[ ! -s "$tmp/rerr" ]] || fail "round $round: report said: $(head -1 "$tmp/rerr")"
    listed=$(($(wc -l <"$tmp/report.csv") - 1))
    ((listed >= prev_candidates)) || fail "round $round: report lists $listed candidates, sqlite3 counted $prev_candidates before"
    n="$(sqlite3 "$db" 'SELECT COUNT(*) FROM starts' 2>"$tmp/rerr")" || fail "round $round: sqlite3 exited with $?: $(head -1 "$tmp/rerr")"
    [[ ! -s "$tmp/rerr" ]] || fail "round $round: sqlite3 said: $(head -1 "$tmp/rerr")"
    ((n >= prev_starts)) || fail "round $round: starts went down from $prev_starts to $n"
    prev_starts=$n
    c="$(sqlite3 "$db" 'SELECT COUNT(*) FROM candidates' 2>"$tmp/rerr")" || fail "round $round: sqlite3 exited with $?: $(head -1 "$tmp/rerr")"
    [[ ! -s "$tmp/rerr" ]] || fail "round $round: sqlite3 said: $(head -1 "$tmp/rerr")"
    ((c >= listed)) || fail "round $round: report listed $listed candidates, sqlite3 counts $c after"
    prev_candidates=$c
    reads=$((reads + 3))
    reports=$((reports + 1))
    ((running == 0)) || while_running=$((while_running + 1))
    if ((running == 0)); then
      after=$((after + 1))
      ((after < 10)) || break
    fi
  done
  ((after >= 10)) || fail "the run did not end within 3000 rounds"
  finish "$mp" 30
  ((code == 0)) || fail "the run read from exited with $code: $(tail -1 "$tmp/live.err")"
  ((while_running >= 5)) || fail "only $while_running rounds overlapped the run"
  check_invariants "$db" "$total"
  say "$reads sqlite3 reads and $reports reports in $((round + 1)) rounds, $while_running of them while the run wrote;" \
    "run and reads took $((SECONDS - t0)) s"
  # The readers changed nothing the writer wrote.
  run2 --db "$tmp/straight.sqlite" 2>/dev/null || fail "the unread run exited with $?"
  dump "$tmp/straight.sqlite" "$tmp/straight.txt"
  dump "$db" "$tmp/live.txt"
  same "$tmp/straight.txt" "$tmp/live.txt" "the run read from differs from an unread one"
  ;;
*)
  fail "unknown case"
  ;;
esac
say "passed in $((SECONDS - script_start)) s"
