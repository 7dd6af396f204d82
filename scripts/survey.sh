#!/usr/bin/env bash
# Runs starts of a job with `loopfarm start --json` on all cores and
# summarises them: how many reach zero, how the zeros classify and verify,
# and the median time per start. A stand-in for the farm's report until
# `loopfarm run` exists; the JSON lines are kept for a closer look.
#
#   scripts/survey.sh JOB [STARTS] [ALGORITHM] [OUT.jsonl]
#
# e.g. scripts/survey.sh jobs/generic-4r.toml 200 LD_LBFGS
set -euo pipefail
cd "$(dirname "$0")/.."
job="${1:?usage: scripts/survey.sh JOB [STARTS] [ALGORITHM] [OUT.jsonl]}"
starts="${2:-200}"
algorithm="${3:-}"
out="${4:-$(mktemp --suffix=.jsonl)}"
loopfarm="${LOOPFARM:-build/release/tools/loopfarm}"
jobs_="${JOBS:-$(nproc)}"

chunk=$(((starts + jobs_ - 1) / jobs_))
: >"$out"
pids=()
for ((first = 0; first < starts; first += chunk)); do
  count=$((first + chunk > starts ? starts - first : chunk))
  "$loopfarm" start "$job" --index "$first" --count "$count" --json ${algorithm:+--algorithm "$algorithm"} >"$out.$first" &
  pids+=($!)
done
for pid in "${pids[@]}"; do wait "$pid"; done
for ((first = 0; first < starts; first += chunk)); do cat "$out.$first" >>"$out" && rm "$out.$first"; done

label="${algorithm:-as in the job}"
# Plain POSIX awk (Debian's default is mawk): fields by pattern, median by sort.
field() { sed -n "s/.*\"$1\":\"\{0,1\}\([^,\"}]*\).*/\1/p" "$out"; }
median=$(field seconds | sort -g | awk '{ v[NR] = $1 } END { print NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }')
awk -v job="$job" -v algorithm="$label" -v median="$median" '
  function field(name,   m) {
    if (!match($0, "\"" name "\":[^,}]*")) return ""
    m = substr($0, RSTART + length(name) + 3, RLENGTH - length(name) - 3); gsub(/"/, "", m); return m }
  { n++; evals += field("evaluations")
    if (field("zero") == "true") { zeros++; fam[field("family")]++; if (field("verified") == "true") verified++ }
    status[field("status")]++ }
  END {
    printf "%s, algorithm %s: %d starts\n", job, algorithm, n
    printf "  zeros        %d (%.1f%%), verified %d\n", zeros, 100 * zeros / n, verified
    for (f in fam) printf "    %-13s %d\n", f, fam[f]
    printf "  median time  %.4f s per start (mean %.1f cycle evaluations)\n", median, evals / n
    printf "  statuses    "; for (s in status) printf " %s %d", s, status[s]; printf "\n" }' "$out"
echo "  starts in $out"
