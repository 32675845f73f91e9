#!/usr/bin/env bash
# Quick start 2: build and run the whole test suite (ctest).
#   scripts/test.sh             Release build in build/
#   scripts/test.sh --sanitize  ASan + UBSan build in build-asan/ (-O1 -g1: line tables for
#                               the reports, and about half the compile time of -O2 -g), the
#                               test suite without the benchmark tools and their smoke runs
#                               (those run in the Release suite)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install_deps.sh"
if [ "${1:-}" = "--sanitize" ]; then
  build="${IMPACT_BUILD_DIR:-$root/build-asan}"
  flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1" -DIMPACT_SANITIZE=ON
         -DIMPACT_BUILD_BENCH=OFF)
  export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
  export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
else
  build="${IMPACT_BUILD_DIR:-$root/build}"
  flags=(-DCMAKE_BUILD_TYPE=Release)
fi
cmake -S "$root" -B "$build" "${flags[@]}" -DIMPACT_WERROR=ON >/dev/null
cmake --build "$build" -j"$(nproc)"
ctest --test-dir "$build" --output-on-failure -j"$(nproc)" --timeout 1500
