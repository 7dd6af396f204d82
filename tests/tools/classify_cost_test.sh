#!/usr/bin/env bash
# bench/classify_cost as its header says to run it: loops on standard input,
# the family counts on standard output; a bad line refused.
#
#   tests/tools/classify_cost_test.sh CLASSIFY_COST CASE
#
# CASE: families (the paper's Bennett loop written as sqlite3 prints it and a
# line-symmetric Bricard 6R separated by spaces: two loops, one of each
# family) | bad_line (a line that is not a loop, after a good one: exit 2,
# one line on stderr naming line 2 and what is wrong, nothing on stdout).
# Exit 0 on success; on failure one line saying what differed, and exit 1.
set -euo pipefail
program="$1"
case_name="$2"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
export LC_ALL=C

fail() {
  echo "classify_cost_test $case_name: FAILED: $*" >&2
  exit 1
}

bennett='2|4|2|4|30|90|30|90|0|0|0|0'
bricard='1 1.5 2 1 1.5 2  40 75 110 40 75 110  0.3 0.5 0.2 0.3 0.5 0.2'

case "$case_name" in
  families)
    printf '%s\n%s\n' "$bennett" "$bricard" >"$tmp/in"
    status=0
    "$program" <"$tmp/in" >"$tmp/out" 2>"$tmp/err" || status=$?
    [[ $status -eq 0 ]] || fail "exit $status: $(cat "$tmp/err")"
    [[ ! -s "$tmp/err" ]] || fail "stderr: $(cat "$tmp/err")"
    # Every line but the time's, which differs from run to run.
    got="$(grep -v '^wall time ' "$tmp/out")"
    want="$(printf '%s\n%-32s %6d\n%-32s %6d' '2 loops' bennett 1 bricard_line_symmetric 1)"
    [[ "$got" == "$want" ]] || fail "printed '$got', expected '$want'"
    grep -Eq '^wall time [0-9.]+ s, [0-9.]+ ms a loop$' "$tmp/out" || fail "no time a loop in '$(cat "$tmp/out")'"
    ;;
  bad_line)
    # Each bad second line, and the text its message must hold.
    checks=(
      "1 2 3 4 5 6 7 8 9 10 11|11 numbers; a loop of n joints is 3n"
      "2 4 2 4 30 90 30 90 0 0 0 x|\"x\" (number 12) is not a number"
      "2 4 2 4 30 90 30 90 0 0 0 nan|\"nan\" (number 12) is not finite"
      "2 4 2 4 30 90 30 90 0 0 0 1e999|\"1e999\" (number 12) is out of a double's range"
      "2 -4 2 4 30 90 30 90 0 0 0 0|not a loop: "
    )
    for check in "${checks[@]}"; do
      bad="${check%%|*}"
      expect="${check#*|}"
      printf '%s\n%s\n%s\n' "$bennett" "$bad" "$bricard" >"$tmp/in"
      status=0
      "$program" <"$tmp/in" >"$tmp/out" 2>"$tmp/err" || status=$?
      [[ $status -eq 2 ]] || fail "'$bad': exit $status, expected 2"
      [[ ! -s "$tmp/out" ]] || fail "'$bad': printed '$(cat "$tmp/out")' on stdout"
      [[ $(wc -l <"$tmp/err") -eq 1 ]] || fail "'$bad': stderr is not one line: '$(cat "$tmp/err")'"
      grep -qF "classify_cost: line 2: $expect" "$tmp/err" || fail "'$bad': stderr '$(cat "$tmp/err")' lacks '$expect'"
    done
    ;;
  *)
    fail "unknown case (families | bad_line)"
    ;;
esac
echo "classify_cost_test $case_name: passed"
