#!/usr/bin/env bash
# Thread scaling on a many-core machine: the main job, the broad phase at 1M (and 10M)
# bodies, whole-bucket narrow phase and camera picking, each at every thread count of
# the list, in one run, so the rows compare side by side. Prints one markdown table per
# part (scripts/scaling_table.py) and keeps the raw JSON in OUT_DIR.
#
# usage: scripts/scaling.sh [BUILD_DIR] [OUT_DIR]
#   BUILD_DIR  a Release build with the bench targets (default: build)
#   OUT_DIR    where the JSON goes (default: scaling-out)
# environment:
#   THREADS    comma-separated thread counts (default 1,2,4,8,16)
#   LARGE=1    also the 10M-body grid and LBVH from scratch
#   QUICK=1    shorter runs (fewer repetitions, shorter min time, fewer steps)
#   PARTS      which parts, comma-separated (default main,broad,narrow,ray)
# The main job must end in the same state hash at every thread count; the script exits
# 1 if it does not.
set -euo pipefail
build=${1:-build}
out=${2:-scaling-out}
threads=${THREADS:-1,2,4,8,16}
mkdir -p "$out"
reps=3 min_time=0.3 steps=300
if [[ "${QUICK:-0}" == 1 ]]; then reps=1 min_time=0.1 steps=60; fi
parts=",${PARTS:-main,broad,narrow,ray},"
want() { [[ "$parts" == *",$1,"* ]]; }
common=(--benchmark_repetitions="$reps" --benchmark_report_aggregates_only=true --benchmark_format=json)

if want main; then
  echo "== main job: scripts/run.sh's scene (box, 100k spheres), $steps steps"
  hashes=()
  for t in ${threads//,/ }; do
    "$build/bench/impact_bench" --threads "$t" --steps "$steps" --no-progress --json "$out/main_$t.json" >"$out/main_$t.txt"
    line=$(grep '^csv:' "$out/main_$t.txt" | tail -1)
    echo "$line"
    hashes+=("${line##*,}")
  done
  if [[ $(printf '%s\n' "${hashes[@]}" | sort -u | wc -l) -ne 1 ]]; then
    echo "state hash differs between thread counts: ${hashes[*]}" >&2
    exit 1
  fi
fi

if want broad; then
  echo "== broad phase, 1M bodies (and 10M with LARGE=1)"
  filter='BM_(Grid|Lbvh)(BroadPhase|Coherent|Clustered|MixedSizes)/1000000/[0-9]+/|BM_Lbvh(Build|Refit|Traverse)/1000000/[0-9]+/'
  if [[ "${LARGE:-0}" == 1 ]]; then
    filter="$filter|BM_(Grid|Lbvh)BroadPhase/10000000/[0-9]+/"
  fi
  IMPACT_BENCH_THREADS=$threads IMPACT_BENCH_LARGE=${LARGE:-0} "$build/bench/impact_microbench" \
    --benchmark_filter="$filter" --benchmark_min_time="$min_time" "${common[@]}" >"$out/broad.json"
fi

if want narrow; then
  echo "== narrow phase, 65536 pairs through NarrowPhase::collide"
  IMPACT_BENCH_THREADS=$threads "$build/bench/impact_narrowbench" \
    --benchmark_filter='BM_Collide/(sphere-sphere|box-box|capsule-triangle|convex-convex|ellipsoid-triangle)/65536/[0-9]+/' \
    --benchmark_min_time="$min_time" "${common[@]}" >"$out/narrow.json"
fi

if want ray; then
  echo "== raycasts: terrain camera picking and visibility"
  IMPACT_BENCH_THREADS=$threads "$build/bench/impact_raybench" \
    --benchmark_filter='Terrain1M/(pick|visibility)/(embree|embree_stream|lbvh)/threads:' --benchmark_min_time="$min_time" "${common[@]}" >"$out/ray.json"
fi

python3 "$(dirname "$0")/scaling_table.py" "$out"
