#!/usr/bin/env bash
# `cmake --install` as a user runs it, into a scratch prefix: PREFIX/bin holds
# the program, and it runs from there (its version, a job's energy) with no
# file of the build tree on its path.
#
#   tests/tools/install_test.sh CMAKE BUILD_DIR VERSION
#
# Exit 0 on success; on failure one line saying what was wrong, and exit 1.
set -euo pipefail
cmake="$1"
build_dir="$2"
version="$3"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

fail() {
  echo "install_test: FAILED: $*" >&2
  exit 1
}

"$cmake" --install "$build_dir" --prefix "$tmp/prefix" >"$tmp/install.log" 2>&1 ||
  fail "cmake --install exited non-zero: $(tail -n 3 "$tmp/install.log")"
installed="$(cd "$tmp/prefix" && find . -type f | sort)"
[[ "$installed" == "./bin/loopfarm" ]] || fail "installed files are not exactly ./bin/loopfarm: $installed"
[[ -x "$tmp/prefix/bin/loopfarm" ]] || fail "bin/loopfarm is not executable"

# Run from a directory outside the build tree, found on PATH.
cd "$tmp"
out="$(PATH="$tmp/prefix/bin:/usr/bin:/bin" loopfarm --version)" || fail "loopfarm --version exited non-zero"
[[ "$out" == *"$version"* ]] || fail "loopfarm --version printed '$out', not version $version"
PATH="$tmp/prefix/bin:/usr/bin:/bin" loopfarm energy --a 1,1,1,1 --alpha-deg 0,0,0,0 --d 0,0,0,0 >"$tmp/energy.txt" 2>&1 ||
  fail "the installed loopfarm energy failed: $(head -n 3 "$tmp/energy.txt")"
echo "install_test: ok ($(wc -c <"$tmp/prefix/bin/loopfarm") bytes in bin/loopfarm)"
