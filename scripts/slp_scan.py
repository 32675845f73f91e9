#!/usr/bin/env python3
"""Lists every vector narrowing to float that is widened straight back to double in
GCC's vectoriser dumps (slp2 for basic blocks, vect for loops) of each translation
unit in a build's compile_commands.json: the pair GCC 12 folds into a plain copy,
dropping the float rounding (docs/narrowphase.md "Testing"). Prints one line per
pair found and exits 1 if there is any.

Usage: scripts/slp_scan.py BUILD_DIR [-jN] [FILTER]   (FILTER: substring of paths)
"""
import json, os, re, subprocess, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

NARROW = re.compile(r'^\s*(\S+) = (?:\(vector\(\d+\) float\) \S+|VEC_PACK_TRUNC_EXPR <.*>);')
WIDEN = re.compile(r'^\s*\S+ = (?:\(vector\(\d+\) double\) (\S+)|VEC_UNPACK_(?:FLOAT_)?[LH][OI]_EXPR <(\S+)>);')


def scan(path):
    found, fn, narrowed = [], None, set()
    for line in open(path, errors='replace'):
        if line.startswith(';; Function'):
            fn, narrowed = line.split()[2], set()
        m = NARROW.match(line)
        if m:
            narrowed.add(m.group(1))
        m = WIDEN.match(line)
        if m and (m.group(1) or m.group(2)) in narrowed:
            found.append(f'{fn}: {line.strip()}')
    return found


def main():
    args = sys.argv[1:]
    jobs = 2
    for a in [a for a in args if a.startswith('-j')]:
        jobs = int(a[2:])
        args.remove(a)
    build, filt = args[0], (args[1] if len(args) > 1 else '')
    entries = [e for e in json.load(open(os.path.join(build, 'compile_commands.json')))
               if filt in e['file'] and not e['file'].endswith('.hxx.cxx')]  # not the PCH
    out = tempfile.mkdtemp(prefix='impact_slp_scan_')

    def one(e):
        cmd = e['command'].split(' -o ')[0]
        tag = os.path.join(out, e['file'].replace('/', '_'))
        r = subprocess.run(f'{cmd} -fdump-tree-slp2 -fdump-tree-vect -dumpbase {tag} -S -o /dev/null {e["file"]}',
                           shell=True, cwd=e['directory'], capture_output=True, text=True)
        if r.returncode != 0:
            return e['file'], [f'compile failed: {r.stderr[-300:]}']
        hits = []
        for d in os.listdir(out):
            if d.startswith(os.path.basename(tag)) and (d.endswith('.slp2') or d.endswith('.vect')):
                hits += scan(os.path.join(out, d))
                os.remove(os.path.join(out, d))
        return e['file'], hits

    bad = 0
    with ThreadPoolExecutor(jobs) as ex:
        for f, hits in ex.map(one, entries):
            for h in hits:
                print(f'{f}: {h}')
                bad += 1
    print(f'{len(entries)} translation units, {bad} narrowing/widening pairs')
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main())
