#!/usr/bin/env python3
"""How the peers' contacts compare with ours: a markdown table from one impact_narrowbench
JSON run of the peer benchmarks.

usage: build/bench/impact_narrowbench --benchmark_filter='BM_(Fcl|CcdGjkEpa|CcdMpr)/' \
         --benchmark_min_time=0.01 --benchmark_format=json > peers.json
       scripts/peer_accuracy_table.py peers.json
The counters come from the untimed pass after each timed loop (bench/narrowphase_peers.cpp,
class Agreement), on the lanes both the peer and our kernel report touching, so they do not
depend on the run's timing. One row per pair: for FCL and libccd's GJK + EPA, the angle
between the peer's normal and ours (median / 99th percentile, degrees) and the excess of
the peer's normal (the two bodies' overlap along it minus the overlap along ours, in % of
the pair's size: > 0 where ours is the better separating direction); libccd MPR's 99th
percentile excess; the least excess of any peer (negative: a peer's normal beat ours by
that much) and the largest gap between our depth and the overlap along our own normal.
Half-space pairs have no overlap columns (the half-space is unbounded), only FCL's depth
deviation in their notes' place.
"""
import json
import re
import sys

PEERS = {"Fcl": "fcl", "CcdGjkEpa": "epa", "CcdMpr": "mpr"}


def main(path):
    rows, order = {}, []
    for b in json.load(open(path))["benchmarks"]:
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
            continue
        m = re.match(r"BM_(Fcl|CcdGjkEpa|CcdMpr)/([a-z-]+)/", b.get("run_name", b["name"]))
        if not m or "both_hit" not in b:
            continue
        key = m.group(2)
        if key not in rows:
            rows[key] = {}
            order.append(key)
        rows[key][PEERS[m.group(1)]] = b

    def deg(v):
        return "" if v is None else (f"{v:.2g}" if v >= 0.01 else "0")

    def pct(v):
        if v is None:
            return ""
        p = 100 * v
        if abs(p) >= 10:
            return f"{p:.0f}"
        return f"{p:.2g}" if abs(p) >= 1e-3 else ("0" if abs(p) < 1e-6 else f"{p:.0e}")

    def pair(r, peer, a, b, f):
        c = r.get(peer)
        if c is None or a not in c:
            return ""
        return f"{f(c[a])} / {f(c[b])}"

    print("| pair | FCL normal, deg | FCL excess, % | GJK+EPA normal, deg | GJK+EPA excess, % "
          "| MPR excess p99, % | least excess, % | our gap, % |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for key in order:
        r = rows[key]
        mins = [c["excess_min"] for c in r.values() if "excess_min" in c]
        gaps = [c["self_gap_max"] for c in r.values() if "self_gap_max" in c]
        mpr = r.get("mpr", {}).get("excess_p99")
        fcl_excess = pair(r, "fcl", "excess_p50", "excess_p99", pct)
        if not fcl_excess and "fcl" in r:  # half-space pairs: FCL's depth deviation instead
            fcl_excess = "depth " + pair(r, "fcl", "depth_dev_p50", "depth_dev_p99", pct)
        print(f"| {key} | {pair(r, 'fcl', 'normal_dev_deg_p50', 'normal_dev_deg_p99', deg)} | {fcl_excess} | "
              f"{pair(r, 'epa', 'normal_dev_deg_p50', 'normal_dev_deg_p99', deg)} | "
              f"{pair(r, 'epa', 'excess_p50', 'excess_p99', pct)} | {pct(mpr)} | "
              f"{pct(min(mins)) if mins else ''} | {pct(max(gaps)) if gaps else ''} |")


if __name__ == "__main__":
    main(sys.argv[1])
