#!/usr/bin/env bash
# `loopfarm report DB --atlas DIR` on a small database made by a short run of
# jobs/goldberg-5r.toml (40 starts, one process): atlas.md and every family's
# chart and motion strip exist, the counts in atlas.md are the database's, and
# a bad output directory is refused with one line and exit 2, the database
# left byte-identical.
#
#   tests/tools/atlas_test.sh LOOPFARM SOURCE_DIR
#
# Exit 0 on success, 77 (skipped) without gnuplot; on failure one line saying
# what differed, and exit 1.
set -euo pipefail
loopfarm="$1"
source_dir="$2"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

fail() {
  echo "atlas_test: FAILED: $*" >&2
  exit 1
}
command -v gnuplot >/dev/null || { echo "atlas_test: skipped, no gnuplot"; exit 77; }

sed -e 's/^starts = .*/starts = 40/' -e "s|^database = .*|database = \"$tmp/a.sqlite\"|" \
  "$source_dir/jobs/goldberg-5r.toml" >"$tmp/job.toml"
"$loopfarm" run "$tmp/job.toml" --progress none >"$tmp/run.log" 2>&1 || fail "the run exited with $?: $(tail -1 "$tmp/run.log")"
db="$tmp/a.sqlite"
total="$(sqlite3 "$db" 'SELECT COUNT(*) FROM candidates')"
((total > 0)) || fail "the run found no candidates"

"$loopfarm" report "$db" --atlas "$tmp/atlas" >"$tmp/out" 2>"$tmp/err" || fail "--atlas exited with $?: $(tail -1 "$tmp/err")"
index="$tmp/atlas/atlas.md"
[[ -s "$index" ]] || fail "no atlas.md"
[[ ! -s "$tmp/out" ]] || fail "--atlas printed on stdout"

# Every family: its row in the index with the database's counts, its section,
# a PNG chart and an SVG strip of 8 frames.
families=0
while IFS='|' read -r family joints count hits; do
  families=$((families + 1))
  stem="${joints}r_${family}"
  grep -qF "| [$family](#$stem) | $joints | $count | $hits |" "$index" ||
    fail "atlas.md has no row '$family $joints $count $hits': $(grep -F "[$family]" "$index" | head -1)"
  candidates="$count candidates"; [[ "$count" -eq 1 ]] && candidates="1 candidate"
  hit_count="$hits hits"; [[ "$hits" -eq 1 ]] && hit_count="1 hit"
  grep -q "^## $family (${joints}R): $candidates, $hit_count\$" "$index" || fail "no section for $family"
  [[ "$(head -c 8 "$tmp/atlas/${stem}_cycle.png" | od -An -tx1 | tr -d ' \n')" == 89504e470d0a1a0a ]] ||
    fail "${stem}_cycle.png is not a PNG"
  grep -qF "](${stem}_cycle.png)" "$index" || fail "atlas.md does not link ${stem}_cycle.png"
  grep -qF "](${stem}_motion.svg)" "$index" || fail "atlas.md does not link ${stem}_motion.svg"
  svg="$tmp/atlas/${stem}_motion.svg"
  [[ "$(head -c 4 "$svg")" == "<svg" && "$(tail -1 "$svg")" == "</svg>" ]] || fail "${stem}_motion.svg is not an SVG"
  [[ "$(grep -c '<polyline' "$svg")" -eq 8 ]] || fail "${stem}_motion.svg has $(grep -c '<polyline' "$svg") frames, not 8"
  grep -q 'nan' "$svg" && fail "${stem}_motion.svg has NaN coordinates"
done < <(sqlite3 -separator '|' "$db" 'SELECT family, joints, COUNT(*), SUM(hits) FROM candidates GROUP BY family, joints')
[[ "$(grep -c '^## ' "$index")" -eq $families ]] || fail "atlas.md has $(grep -c '^## ' "$index") sections, not $families"
# The index's candidate counts add up to the table's rows.
sum="$(grep '^| \[' "$index" | awk -F'|' '{s += $4} END {print s}')"
[[ "$sum" -eq "$total" ]] || fail "atlas.md counts $sum candidates, the database $total"
# Unclassified candidates, if any, come first.
if [[ "$(sqlite3 "$db" "SELECT COUNT(*) FROM candidates WHERE family = 'unclassified'")" -gt 0 ]]; then
  grep '^## ' "$index" | head -1 | grep -q '^## unclassified' || fail "unclassified is not the first family"
fi
# --family selects: one family, its count.
family="$(sqlite3 "$db" 'SELECT family FROM candidates ORDER BY candidate_id LIMIT 1')"
count="$(sqlite3 "$db" "SELECT COUNT(*) FROM candidates WHERE family = '$family'")"
"$loopfarm" report "$db" --atlas "$tmp/one" --family "$family" 2>/dev/null || fail "--atlas --family exited with $?"
[[ "$(grep -c '^## ' "$tmp/one/atlas.md")" -eq 1 ]] || fail "--family $family: not one section"
grep -q "^## $family (5R): $count candidates" "$tmp/one/atlas.md" || fail "--family $family: not $count candidates"

# Bad output directories: exit 2, one line naming --atlas, nothing on stdout,
# the database byte-identical and no file added or removed.
cp "$db" "$tmp/before.sqlite"
touch "$tmp/plain"
ls "$tmp" >"$tmp/files.before"
for bad in "$tmp/plain" "$tmp/plain/sub"; do
  set +e
  "$loopfarm" report "$db" --atlas "$bad" >"$tmp/out" 2>"$tmp/err"
  code=$?
  set -e
  [[ $code -eq 2 ]] || fail "--atlas $bad exited with $code, not 2"
  [[ "$(wc -l <"$tmp/err")" -eq 1 ]] || fail "--atlas $bad printed $(wc -l <"$tmp/err") lines: $(head -3 "$tmp/err")"
  grep -q '^loopfarm report: --atlas: ' "$tmp/err" || fail "--atlas $bad: message does not name --atlas: $(cat "$tmp/err")"
  [[ ! -s "$tmp/out" ]] || fail "--atlas $bad printed on stdout"
  cmp -s "$db" "$tmp/before.sqlite" || fail "--atlas $bad changed the database"
  ls "$tmp" | cmp -s - "$tmp/files.before" || fail "--atlas $bad added or removed files: $(ls "$tmp" | diff - "$tmp/files.before" | tr '\n' ' ')"
done
# --atlas with --summary is a usage error too.
set +e
"$loopfarm" report "$db" --atlas "$tmp/x" --summary >/dev/null 2>"$tmp/err"
code=$?
set -e
[[ $code -eq 2 && "$(wc -l <"$tmp/err")" -eq 1 ]] || fail "--atlas --summary exited with $code: $(cat "$tmp/err")"
cmp -s "$db" "$tmp/before.sqlite" || fail "the database changed"
echo "atlas_test: ok ($families families, $total candidates)"
