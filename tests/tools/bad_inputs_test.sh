#!/usr/bin/env bash
# The bad-input corpus (tests/tools/bad-inputs/): every case must be refused with
# exit code 2, exactly one line on stderr that contains the case's expected
# text (the file, key or value at fault), nothing on stdout, and every file in
# the case's directory left byte-identical (no file added, removed, changed or
# re-permissioned; databases and existing output files included).
#
# Usage: bad_inputs_test.sh LOOPFARM CORPUS_DIR [CASE...]
#   LOOPFARM    the loopfarm binary
#   CORPUS_DIR  tests/tools/bad-inputs
#   CASE        case directory names; default: every case
#
# A case is a directory holding
#   cmd    "args: ARGS" (the loopfarm command line, shell words), one or more
#          "expect: TEXT" (each must occur in the error line), '#' comments;
#   setup  optional sh script run first in the scratch copy, with $LOOPFARM
#          set, to make what cannot be committed as text (databases, binary);
#   anything else: the case's input files.
# The case runs in a scratch copy of its directory (without cmd and setup),
# so the committed corpus is never touched. Prints PASS/FAIL per case and a
# total; exits 1 if any case failed.
set -uo pipefail

if [[ $# -lt 2 ]]; then
  echo "usage: $0 LOOPFARM CORPUS_DIR [CASE...]" >&2
  exit 2
fi
loopfarm="$(realpath "$1")"
corpus="$(realpath "$2")"
shift 2
export LOOPFARM="$loopfarm"
# A singleton MPI run as root (loopfarm run) needs these.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Messages are compared in English.
export LC_ALL=C

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

if [[ $# -gt 0 ]]; then
  names=("$@")
else
  names=()
  for dir in "$corpus"/*/; do names+=("$(basename "$dir")"); done
fi

# Every path with its type and mode, then every file's checksum.
snapshot() {
  (cd "$1" && find . -mindepth 1 -printf '%y %m %p\n' | sort && find . -type f -print0 | sort -z | xargs -0 -r sha256sum)
}

passed=0
failed=()
for name in "${names[@]}"; do
  case_dir="$corpus/$name"
  problems=()
  if [[ ! -f "$case_dir/cmd" ]]; then
    failed+=("$name")
    echo "FAIL $name: no cmd file in $case_dir"
    continue
  fi
  args_line="$(sed -n 's/^args: //p' "$case_dir/cmd")"
  mapfile -t expects < <(sed -n 's/^expect: //p' "$case_dir/cmd")
  if [[ -z "$args_line" || ${#expects[@]} -eq 0 ]]; then
    failed+=("$name")
    echo "FAIL $name: cmd needs an 'args:' line and at least one 'expect:' line"
    continue
  fi

  work="$tmp/$name"
  mkdir -p "$work"
  (cd "$case_dir" && find . -mindepth 1 -maxdepth 1 ! -name cmd ! -name setup -exec cp -a {} "$work/" \;)
  if [[ -f "$case_dir/setup" ]]; then
    if ! (cd "$work" && timeout 120 sh "$case_dir/setup") >"$tmp/setup.out" 2>&1; then
      failed+=("$name")
      echo "FAIL $name: setup failed: $(tr '\n' ' ' <"$tmp/setup.out")"
      rm -rf "$work"
      continue
    fi
  fi
  before="$(snapshot "$work")"

  # The arguments are the case's own shell words (quotes allowed).
  eval "set -- $args_line"
  (cd "$work" && timeout 120 "$loopfarm" "$@") >"$tmp/stdout" 2>"$tmp/stderr"
  code=$?

  after="$(snapshot "$work")"
  [[ $code -eq 2 ]] || problems+=("exit code $code, not 2")
  lines="$(wc -l <"$tmp/stderr")"
  if [[ "$lines" -ne 1 || -n "$(tail -c1 "$tmp/stderr" | tr -d '\n')" ]]; then
    problems+=("stderr is not exactly one line ($lines newlines)")
  fi
  [[ -s "$tmp/stdout" ]] && problems+=("stdout is not empty")
  error_line="$(head -n1 "$tmp/stderr")"
  for text in "${expects[@]}"; do
    [[ "$error_line" == *"$text"* ]] || problems+=("error line lacks '$text'")
  done
  if [[ "$before" != "$after" ]]; then
    problems+=("files changed: $(diff <(echo "$before") <(echo "$after") | grep '^[<>]' | tr '\n' ' ')")
  fi

  if [[ ${#problems[@]} -eq 0 ]]; then
    passed=$((passed + 1))
    echo "PASS $name: $error_line"
  else
    failed+=("$name")
    echo "FAIL $name: loopfarm $args_line"
    for p in "${problems[@]}"; do echo "    $p"; done
    echo "    stderr: $(head -c 2000 "$tmp/stderr" | tr '\n' '|')"
    [[ -s "$tmp/stdout" ]] && echo "    stdout: $(head -c 500 "$tmp/stdout" | tr '\n' '|')"
  fi
  rm -rf "$work"
done

echo "bad inputs: $passed of ${#names[@]} cases passed"
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "failed: ${failed[*]}"
  exit 1
fi
exit 0
