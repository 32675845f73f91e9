#!/usr/bin/env bash
# Quick start 1: install what is missing, build (Release), run the throughput
# benchmark on its built-in default scene. Extra arguments go to impact_bench
# (try --help).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install_deps.sh"
build="${IMPACT_BUILD_DIR:-$root/build}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target impact_bench
exec "$build/bench/impact_bench" "$@"
