#!/usr/bin/env bash
# The one place that lists the Debian packages loopfarm needs (docs/guide/building.md
# says why each is there). Installs only what is missing, so on a prepared machine
# it is a quick no-op; the other scripts call it first.
#
#   scripts/deps.sh          what building and running loopfarm needs (scripts/run.sh)
#   scripts/deps.sh --test   that and what only the tests need (scripts/test.sh)
set -euo pipefail

test_packages=0
case "${1:-}" in
  '') ;;
  --test) test_packages=1 ;;
  *) echo "deps.sh: unknown option '$1' (--test adds the packages only the tests need)" >&2; exit 2 ;;
esac

packages=(
  build-essential      # g++ and make
  cmake                # the build
  libeigen3-dev        # linear algebra (and the LevenbergMarquardt module)
  libnlopt-dev         # optimisation algorithms to compare against
  libnlopt-cxx-dev     # NLopt's C++ header nlopt.hpp
  libopenmpi-dev       # the search farm (mpirun)
  openmpi-bin          # mpirun itself
  libsqlite3-dev       # the results database
  sqlite3              # to query it from the shell
  libgtest-dev         # the tests
  libbenchmark-dev     # the benchmarks in bench/
  libcli11-dev         # the command line
  nlohmann-json3-dev   # JSON output of the command line
  libtomlplusplus-dev  # geometry and job files
  librandom123-dev     # counter-based random streams, one per start
  gnuplot-nox          # plots (loopfarm energy --plot, reports)
  clang                # libFuzzer targets (scripts/fuzz.sh)
  libclang-rt-14-dev   # libFuzzer's and the sanitizers' runtimes for clang
  clang-format         # the house style (.clang-format), checked by the test format_check
)

# Only the tests: the HTML atlas (loopfarm report --html) is opened and driven
# in a headless browser by tests/tools/html_test.sh.
if [ "$test_packages" -eq 1 ]; then
  packages+=(
    chromium           # the headless browser that loads and drives the HTML atlas
    python3            # tests/tools/html_browser.py, which speaks to the browser over a pipe
    fonts-dejavu-core  # a font for the page's text in the browser
  )
fi

missing=()
for package in "${packages[@]}"; do
  if ! dpkg -s "$package" >/dev/null 2>&1; then
    missing+=("$package")
  fi
done

if [ "${#missing[@]}" -eq 0 ]; then
  exit 0
fi

echo "deps.sh: installing ${missing[*]}" >&2
as_root=()
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    as_root=(sudo)
  else
    echo "deps.sh: missing packages (${missing[*]}) and not root, without sudo; install them as root" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
