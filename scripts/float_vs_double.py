#!/usr/bin/python3
"""Worst difference between the float paths and the double paths where both exist:
  - libnoise3d float vs double evaluation (`cloudgen noise` vs `cloudgen noise --double`), per kind;
  - the viewer's GL renderer (float, GPU or llvmpipe) vs its CPU reference (double), per preset view.
Prints a markdown table (docs/robustness.md). Usage: scripts/float_vs_double.py [build/bin]"""
import os, subprocess, sys, tempfile
import numpy as np
import matplotlib.image as mpimg

bin_dir = sys.argv[1] if len(sys.argv) > 1 else "build/bin"
tmp = tempfile.mkdtemp()
rows = []

def run(args):
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

for kind in ["perlin", "worley", "perlin-worley"]:
    out = {}
    for prec in ["float", "double"]:
        path = os.path.join(tmp, f"{kind}-{prec}.raw")
        run([f"{bin_dir}/cloudgen", "noise", "--kind", kind, "--period", "4", "--octaves", "5", "--size", "64",
             "--seed", "3", "-o", path] + (["--double"] if prec == "double" else []))
        out[prec] = np.fromfile(path, dtype=np.float32).astype(np.float64)
    d = np.abs(out["float"] - out["double"])
    rows.append((f"noise {kind}, 5 octaves, 64^3 (`cloudgen noise` vs `--double`)", f"{d.max():.2e}",
                 f"{d.mean():.2e}", "value units (range 1 or 2)"))

viewer = f"{bin_dir}/cloudviewer"
if os.path.exists(viewer):
    for preset in ["thesis", "cumulus"]:
        imgs = {}
        for backend in ["gl", "cpu"]:
            path = os.path.join(tmp, f"{preset}-{backend}.png")
            run([viewer, f"presets/{preset}.json", "--headless", "--size", "160x90", "--backend", backend,
                 "--set", "render.jitter=false", "--out", path])
            imgs[backend] = mpimg.imread(path)[..., :3].astype(np.float64) * 255
        d = np.abs(imgs["gl"] - imgs["cpu"])
        mse = ((imgs["gl"] - imgs["cpu"]) ** 2).mean()
        psnr = 10 * np.log10(255 ** 2 / mse) if mse > 0 else float("inf")
        rows.append((f"viewer GL vs CPU reference, {preset} default view, 160x90", f"{d.max():.0f} levels",
                     f"{d.mean():.3f} levels", f"8-bit sRGB display, PSNR {psnr:.1f} dB"))

print("| path | worst difference | mean difference | unit |")
print("|---|---|---|---|")
for r in rows:
    print("| " + " | ".join(r) + " |")
