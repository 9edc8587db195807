#!/usr/bin/python3
"""vdb_equal.py A.vdb B.vdb: exit 0 when two VDB files hold the same grids (names, classes,
transforms, half/float storage, metadata apart from OpenVDB's per-write file_* statistics), the
same active voxels and the same values; otherwise print the first differences and exit 1.
Read through OpenVDB (pyopenvdb), independently of cloudgen's own reader."""
import sys
import pyopenvdb as vdb


def load(path):
    grids, meta = vdb.readAll(path)
    return {g.name: g for g in grids}, meta


def voxels(grid):
    """{(i,j,k): value} of every active voxel, tiles expanded."""
    out = {}
    for it in grid.iterOnValues():
        lo, hi = it.min, it.max
        for i in range(lo[0], hi[0] + 1):
            for j in range(lo[1], hi[1] + 1):
                for k in range(lo[2], hi[2] + 1):
                    out[(i, j, k)] = it.value
    return out


def main(a, b):
    ga, ma = load(a)
    gb, mb = load(b)
    problems = []
    if sorted(ga) != sorted(gb):
        problems.append(f"grids differ: {sorted(ga)} vs {sorted(gb)}")
    if ma != mb:
        problems.append(f"file metadata differs: {ma} vs {mb}")
    for name in sorted(set(ga) & set(gb)):
        x, y = ga[name], gb[name]
        strip = lambda g: {k: v for k, v in g.metadata.items() if not k.startswith("file_")}
        if strip(x) != strip(y):
            problems.append(f"{name}: metadata differs: {strip(x)} vs {strip(y)}")
        if x.gridClass != y.gridClass or x.saveFloatAsHalf != y.saveFloatAsHalf:
            problems.append(f"{name}: class or storage differs")
        if x.transform.info() != y.transform.info():
            problems.append(f"{name}: transform differs:\n{x.transform.info()}\n{y.transform.info()}")
        if x.activeVoxelCount() != y.activeVoxelCount():
            problems.append(f"{name}: active voxels {x.activeVoxelCount()} vs {y.activeVoxelCount()}")
        va, vb = voxels(x), voxels(y)
        diff = [c for c in va.keys() | vb.keys() if va.get(c) != vb.get(c)]
        if diff:
            c = sorted(diff)[0]
            problems.append(f"{name}: {len(diff)} voxels differ, first {c}: {va.get(c)} vs {vb.get(c)}")
    for p in problems:
        print(f"{a} vs {b}: {p}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
