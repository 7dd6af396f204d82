#!/usr/bin/env bash
# `loopfarm report DB --html FILE.html` on a small database made by a short run
# of jobs/default.toml (300 starts, one process). Two cases:
#   page     the page is written (nothing on stdout), is one self-contained
#            file (no http://, https://, src=, no link to another file) and
#            has a section, a 3D view and a cycle-energy chart per family of
#            the database; bad input is refused with exit 2 and one line
#            naming the option (an unwritable path, --html with --atlas or
#            --summary, a family the database lacks), leaving no file, not
#            even a temporary one, and a page already there unchanged;
#            --family selects one family.
#   browser  in headless Chromium (tests/tools/html_browser.py) the page loads
#            with no console error, and a click on the slider, a drag on the
#            3D view, and Play each change the drawing; Pause stops it.
#
#   tests/tools/html_test.sh LOOPFARM SOURCE_DIR page|browser [CHROMIUM]
#
# CHROMIUM defaults to chromium on the path; without a browser or python3 the
# browser case fails (scripts/deps.sh --test installs both), it is never
# skipped. Exit 0 on success; on failure one line saying what differed, and
# exit 1.
set -euo pipefail
loopfarm="$1"
source_dir="$2"
case_name="$3"
chromium="${4:-$(command -v chromium || true)}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

fail() {
  echo "html_test: FAILED: $*" >&2
  exit 1
}
case "$case_name" in
  page) ;;
  browser)
    [[ -n "$chromium" && -x "$chromium" ]] || fail "no chromium on the path (scripts/deps.sh --test installs it)"
    command -v python3 >/dev/null || fail "no python3 (scripts/deps.sh --test installs it)" ;;
  *) fail "unknown case '$case_name' (page or browser)" ;;
esac

db="$tmp/a.sqlite"
"$loopfarm" run "$source_dir/jobs/default.toml" --starts 300 --db "$db" --progress none >"$tmp/run.log" 2>&1 ||
  fail "the run exited with $?: $(tail -1 "$tmp/run.log")"
families="$(sqlite3 "$db" 'SELECT COUNT(DISTINCT family || joints) FROM candidates')"
((families > 0)) || fail "the run found no candidates"

page="$tmp/out/atlas.html"
mkdir -p "$tmp/out"
"$loopfarm" report "$db" --html "$page" >"$tmp/stdout" 2>"$tmp/err" || fail "--html exited with $?: $(tail -1 "$tmp/err")"
[[ -s "$page" ]] || fail "no page written"
[[ ! -s "$tmp/stdout" ]] || fail "--html printed on stdout"
[[ "$(ls -A "$tmp/out")" == atlas.html ]] || fail "--html left other files: $(ls -A "$tmp/out" | tr '\n' ' ')"
head -1 "$page" | grep -q '^<!DOCTYPE html>$' || fail "the page does not start with <!DOCTYPE html>"
tail -1 "$page" | grep -q '^</html>$' || fail "the page does not end with </html>"

# Self-contained: nothing fetched, no other file named.
if grep -qiE 'https?://|src=|@import|url\(' "$page"; then
  fail "the page refers to something outside it: $(grep -oiE '.{0,30}(https?://|src=|@import|url\().{0,30}' "$page" | head -1)"
fi
if grep -oiE 'href="[^"]*"' "$page" | grep -viqE 'href="(#[^"]*|data:,)"'; then
  fail "the page links outside itself: $(grep -oiE 'href="[^"]*"' "$page" | grep -viE 'href="(#[^"]*|data:,)"' | head -1)"
fi
# Per family: a section, a 3D view and an energy chart with the zero threshold.
[[ "$(grep -c '<section id=' "$page")" -eq "$families" ]] ||
  fail "the page has $(grep -c '<section id=' "$page") family sections, the database $families families"
[[ "$(grep -o '<canvas' "$page" | wc -l)" -eq "$families" ]] || fail "not one 3D view per family"
[[ "$(grep -o '<svg class="chart energy"' "$page" | wc -l)" -eq "$families" ]] || fail "not one energy chart per family"
grep -q 'class="threshold"' "$page" || fail "no zero threshold line"
grep -q 'id="loopfarm-data"' "$page" || fail "no embedded motion data"
grep -qiE 'nan|null' <(grep -o 'id="loopfarm-data">.*</script>' "$page") && fail "the motion data hold NaN or null"

if [[ "$case_name" == browser ]]; then
  python3 "$source_dir/tests/tools/html_browser.py" "$chromium" "$page" >"$tmp/browser.log" 2>&1 ||
    fail "in the browser: $(grep -m1 FAILED "$tmp/browser.log" || tail -1 "$tmp/browser.log")"
  echo "html_test: ok ($families families; $(cat "$tmp/browser.log"))"
  exit 0
fi

# Bad input: exit 2, one line naming the option, nothing on stdout, no file left.
cp "$db" "$tmp/before.sqlite"
bad() {  # EXPECTED-TEXT ARGS...
  local expected="$1"
  shift
  local code=0
  "$loopfarm" report "$db" "$@" >"$tmp/stdout" 2>"$tmp/err" || code=$?
  [[ $code -eq 2 ]] || fail "report $*: exit $code, not 2"
  [[ "$(wc -l <"$tmp/err")" -eq 1 ]] || fail "report $*: $(wc -l <"$tmp/err") lines: $(head -3 "$tmp/err")"
  grep -qF -- "$expected" "$tmp/err" || fail "report $*: message does not name $expected: $(cat "$tmp/err")"
  [[ ! -s "$tmp/stdout" ]] || fail "report $*: printed on stdout"
}
bad "--html" --html "$tmp/no-such-dir/atlas.html"
touch "$tmp/plain"
bad "--html" --html "$tmp/plain/atlas.html"
bad "--html" --html "$tmp/out"
chmod a-w "$tmp/out"
if [[ ! -w "$tmp/out" ]]; then  # root writes anywhere: then this case says nothing
  bad "--html" --html "$tmp/out/other.html"
fi
chmod u+w "$tmp/out"
bad "--html" --html "$tmp/out/other.html" --atlas "$tmp/atlas"
bad "--html" --html "$tmp/out/other.html" --summary
bad "--family" --html "$tmp/out/other.html" --family goldberg
# A refused command leaves a page already at the path as it was.
cp "$page" "$tmp/page.before"
bad "--family" --html "$page" --family goldberg
cmp -s "$page" "$tmp/page.before" || fail "a refused --html changed the page already there"
[[ "$(ls -A "$tmp/out")" == atlas.html ]] || fail "a refused --html left files: $(ls -A "$tmp/out" | tr '\n' ' ')"
[[ ! -e "$tmp/no-such-dir" && ! -e "$tmp/atlas" ]] || fail "a refused --html made a directory"
cmp -s "$db" "$tmp/before.sqlite" || fail "the database changed"

# --family selects one family: one section.
family="$(sqlite3 "$db" 'SELECT family FROM candidates ORDER BY candidate_id LIMIT 1')"
"$loopfarm" report "$db" --html "$tmp/one.html" --family "$family" 2>/dev/null || fail "--html --family exited with $?"
[[ "$(grep -c '<section id=' "$tmp/one.html")" -eq 1 ]] || fail "--family $family: not one section"

echo "html_test: ok ($families families; self-contained; bad input refused)"
