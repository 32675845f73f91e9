#!/usr/bin/env python3
"""Markdown tables from the JSON that scripts/scaling.sh writes.

usage: scripts/scaling_table.py OUT_DIR

One row per benchmark (or per main-job pass), one column per thread count: the median
time (ms per call, or ns per pair for the narrow phase), and the speed-up over the
smallest thread count of the run in brackets.
"""
import glob
import json
import os
import re
import sys

UNIT_TO_MS = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}


def split_name(name):
    """'BM_X/1000000/4/real_time' -> ('BM_X/1000000', 4); '.../threads:4/real_time' too."""
    parts = [p for p in name.split("/")
             if p not in ("real_time", "manual_time") and not p.startswith("iterations:")]
    last = parts[-1]
    m = re.fullmatch(r"(?:threads:)?(\d+)", last)
    if not m:
        return None, None
    return "/".join(parts[:-1]), int(m.group(1))


def table(title, unit, rows, threads):
    print(f"\n### {title} ({unit}; speed-up over {threads[0]} thread(s) in brackets)\n")
    print("| benchmark | " + " | ".join(f"{t}T" for t in threads) + " |")
    print("|---|" + "---:|" * len(threads))
    for name in sorted(rows):
        cells = []
        base = rows[name].get(threads[0])
        for t in threads:
            v = rows[name].get(t)
            if v is None:
                cells.append("")
            elif base:
                cells.append(f"{v:.4g} ({base / v:.2f}x)")
            else:
                cells.append(f"{v:.4g}")
        print(f"| {name} | " + " | ".join(cells) + " |")


def bench_rows(path, value):
    with open(path) as f:
        data = json.load(f)
    rows, threads = {}, set()
    for b in data.get("benchmarks", []):
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
            continue
        family, t = split_name(b["run_name"])
        if family is None:
            continue
        rows.setdefault(family, {})[t] = value(b)
        threads.add(t)
    return rows, sorted(threads)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "scaling-out"
    ctx = None
    main_rows, main_threads, hashes = {}, [], set()
    for path in glob.glob(os.path.join(out, "main_*.json")):
        with open(path) as f:
            m = json.load(f)
        t = m["threads"]
        main_threads.append(t)
        main_rows.setdefault("step (median)", {})[t] = m["ms_per_step"]["median"]
        for k, v in m["pass_ms_median"].items():
            if k != "total":
                main_rows.setdefault(k, {})[t] = v
        hashes.add(m["state_hash"])
    if main_rows:
        table(f"Main job (state hash {', '.join(sorted(hashes))})", "ms per step", main_rows, sorted(main_threads))
    for name, title, unit, value in (
        ("broad.json", "Broad phase", "ms per frame",
         lambda b: b["real_time"] * UNIT_TO_MS[b["time_unit"]]),
        ("narrow.json", "Narrow phase, NarrowPhase::collide", "ns per pair",
         lambda b: b.get("ns_per_pair", float("nan"))),
        ("ray.json", "Raycasts", "ms per batch",
         lambda b: b["real_time"] * UNIT_TO_MS[b["time_unit"]]),
    ):
        path = os.path.join(out, name)
        if not os.path.exists(path):
            continue
        with open(path) as f:
            ctx = json.load(f).get("context", ctx)
        rows, threads = bench_rows(path, value)
        if rows:
            table(title, unit, rows, threads)
    if ctx:
        print(f"\nhost: {ctx.get('host_name', '?')}, {ctx.get('num_cpus', '?')} CPUs at "
              f"{ctx.get('mhz_per_cpu', '?')} MHz, {ctx.get('date', '')}")


if __name__ == "__main__":
    main()
