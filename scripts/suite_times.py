#!/usr/bin/python3
"""The per-test timing table of docs/notes/testing.md, from one run of the suite.

Usage: bash scripts/test.sh 2>&1 | tee suite.log; /usr/bin/python3 scripts/suite_times.py suite.log [build]

Reads ctest's "Test #N: NAME ... Passed S sec" lines from the log, and the per-test times that each
ASan+UBSan shard leaves in BUILD/Testing/asan_*.json (gtest's JSON output), and prints Markdown:
the suite's parts with their summed test time, then the costliest tests of each run.
"""
import glob
import json
import os
import re
import sys


def ctest_times(log):
    rows = {}
    pat = re.compile(r"Test +#\d+: (\S+) \.+\**\s*(\w+)\s+([\d.]+) sec")
    with open(log, errors="replace") as f:
        for line in f:
            m = pat.search(line)
            if m:
                rows[m.group(1)] = (float(m.group(3)), m.group(2))
    return rows


def asan_times(build):
    rows = []
    for path in sorted(glob.glob(os.path.join(build, "Testing", "asan_*.json"))):
        shard = os.path.basename(path)[len("asan_"):-len(".json")]
        with open(path) as f:
            doc = json.load(f)
        for suite in doc["testsuites"]:
            for t in suite["testsuite"]:
                rows.append((float(t["time"].rstrip("s")), suite["name"] + "." + t["name"], shard))
    return rows


def part(name):
    if name.startswith("sanitizers_"):
        return "ASan+UBSan shards"
    if name.startswith("fuzz_"):
        return "libFuzzer runs"
    if name.startswith(("blender_", "cycles_")):
        return "Blender and Cycles"
    if name.startswith("scale_out"):
        return "scale-out scripts"
    return "unit tests (optimised build)"


def main():
    log = sys.argv[1]
    build = sys.argv[2] if len(sys.argv) > 2 else "build"
    ct = ctest_times(log)
    parts = {}
    for name, (sec, _) in ct.items():
        p = part(name)
        n, s, worst = parts.get(p, (0, 0.0, 0.0))
        parts[p] = (n + 1, s + sec, max(worst, sec))
    print("| part | ctest entries | summed time (s) | longest (s) |")
    print("|---|---:|---:|---:|")
    for p, (n, s, worst) in sorted(parts.items(), key=lambda kv: -kv[1][1]):
        print(f"| {p} | {n} | {s:.0f} | {worst:.0f} |")
    failed = [n for n, (_, st) in ct.items() if st != "Passed"]
    print(f"\n{len(ct)} ctest entries, {len(failed)} not passed{': ' + ', '.join(failed) if failed else ''}.\n")
    print("Costliest ctest entries:\n\n| test | s |\n|---|---:|")
    for name, (sec, _) in sorted(ct.items(), key=lambda kv: -kv[1][0])[:25]:
        print(f"| {name} | {sec:.1f} |")
    rows = asan_times(build)
    if rows:
        print(f"\nUnder ASan+UBSan ({len(rows)} tests, {sum(r[0] for r in rows):.0f} s summed), the costliest:\n")
        print("| test | shard | s |\n|---|---|---:|")
        for sec, name, shard in sorted(rows, reverse=True)[:25]:
            print(f"| {name} | {shard} | {sec:.1f} |")


if __name__ == "__main__":
    main()
