#!/usr/bin/env bash
# Builds scripts/slp_probe.cpp with the project's flags (CMakeLists.txt impact_flags,
# Release: -O3 -march=native -fno-math-errno -fopenmp-simd, contraction on) and again
# with -fno-tree-slp-vectorize, runs both and compares their output hashes.
# Usage: scripts/slp_probe.sh [extra g++ flags, e.g. -ffp-contract=off or -O2]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${TMPDIR:-/tmp}/impact_slp_probe
mkdir -p "$out"
flags=(-std=c++20 -O3 -DNDEBUG -march=native -fno-math-errno -fopenmp-simd -I"$root" -I"$root/include" -I"$root/tests"
       -I/usr/include/eigen3 "$@")
g++ "${flags[@]}" "$root/scripts/slp_probe.cpp" -o "$out/slp" -lgtest -lpthread
g++ "${flags[@]}" -fno-tree-slp-vectorize "$root/scripts/slp_probe.cpp" -o "$out/noslp" -lgtest -lpthread
a=$("$out/slp" | tee "$out/slp.txt" | sed -n 's/^hash //p')
b=$("$out/noslp" | tee "$out/noslp.txt" | sed -n 's/^hash //p')
echo "== slp";   cat "$out/slp.txt"
echo "== noslp"; cat "$out/noslp.txt"
if [[ "$a" == "$b" ]]; then echo "same hash $a"; else echo "DIFFERENT: $a vs $b"; exit 1; fi
