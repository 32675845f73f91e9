#!/usr/bin/env python3
"""The narrow-phase table of docs/results.md from one impact_narrowbench JSON run.

usage: build/bench/impact_narrowbench \
         --benchmark_filter='BM_(Kernel/[a-z-]+/(scalar|simd)/(512|4096)|Fcl/.*|Collide/[a-z-]+/65536/[12]/|StreamCopy.*)' \
         --benchmark_min_time=0.2 --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
         --benchmark_format=json > narrow.json
       scripts/narrow_table.py narrow.json
Prints one markdown row per pair (medians, ns per pair): scalar, SIMD, SIMD / scalar at
4096 lanes, the same ratio at 512 lanes (the block size the public call hands a kernel;
blank where the run has no 512 rows), collide on 1 and 2 threads, FCL, FCL / SIMD; pairs
in the order the benchmark ran them.
"""
import json
import re
import sys


def main(path):
    runs = json.load(open(path))["benchmarks"]
    rows, order = {}, []
    for b in runs:
        if b.get("aggregate_name") != "median":
            continue
        name = b["run_name"]
        ns = b.get("ns_per_pair")
        if ns is None:
            continue
        m = re.match(r"BM_Kernel/([a-z-]+)/(scalar|simd)/(512|4096)$", name)
        if m:
            key, col = m.group(1), m.group(2) + ("" if m.group(3) == "4096" else "512")
        else:
            m = re.match(r"BM_Collide/([a-z-]+)/65536/([12])/", name)
            if m:
                key, col = m.group(1), "collide" + m.group(2)
            else:
                m = re.match(r"BM_Fcl/([a-z-]+)/", name)
                if not m:
                    continue
                key, col = m.group(1), "fcl"
        if key not in rows:
            rows[key] = {}
            order.append(key)
        rows[key][col] = ns

    def fmt(v):
        if v is None:
            return ""
        return f"{v:.3g}" if v < 100 else f"{v:.0f}"

    print("| pair | scalar | SIMD | SIMD / scalar | SIMD / scalar, 512 | collide 1T | collide 2T | FCL "
          "| FCL / SIMD |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for key in order:
        r = rows[key]
        sc, si, fc = r.get("scalar"), r.get("simd"), r.get("fcl")
        ratio = f"{sc / si:.1f}x" if sc and si else ""
        sc5, si5 = r.get("scalar512"), r.get("simd512")
        ratio5 = f"{sc5 / si5:.1f}x" if sc5 and si5 else ""
        vs = f"{fc / si:.1f}x" if fc and si else ""
        print(f"| {key} | {fmt(sc)} | {fmt(si)} | {ratio} | {ratio5} | {fmt(r.get('collide1'))} | "
              f"{fmt(r.get('collide2'))} | {fmt(fc)} | {vs} |")


if __name__ == "__main__":
    main(sys.argv[1])
