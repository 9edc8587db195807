#!/usr/bin/python3
"""What export.nvdb.precision costs in the image (docs/notes/nvdb-precision.md, issue 46 item 2).

Per preset (generated at --resolution 128) and per precision (float, fp16, fp8, fp4, fpn at two
tolerances): the .nvdb file's size against the float file's, and the linear PSNR on the cloud's
pixels of its renders against the float file's, through the path tracer (`--backend pathtrace`)
and the viewer's default GL marcher. The quantity compared is the cloud's own linear radiance,
C = L - T * L_bg (as scripts/accuracy_linear.py): T the float file's transmittance (GL,
render.output=transmittance, 1024 steps), L_bg the view at density 0; the cloud pixels are those
with T < 0.98. PSNR = 10 log10(peak^2 / MSE) of the luminance of C over the cloud pixels, peak =
the float render's largest C there. The path tracer draws the same random numbers for every file
(its image is the same at any thread count), so the difference is the data's, plus the paths
whose scattering decisions a changed density flips; "pt noise" is the PSNR the float render's own
standard error (NAME.stderr.exr) would give, the level below which a difference is within noise.

Usage: scripts/nvdb_precision.py [--spp N] [--size WxH] [--work DIR] [--presets a,b]
Needs build/bin and Debian's blender (reads the EXRs, scripts/exr_to_npy.py). Prints a markdown
table; about 6 minutes on 2 cores at the defaults.
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("CLOUD_BIN", os.path.join(ROOT, "build/bin"))
GEN, VIEW = os.path.join(BIN, "cloudgen"), os.path.join(BIN, "cloudviewer")
LUM = np.array([0.2126, 0.7152, 0.0722])
PRECISIONS = [("float", []), ("fp16", []), ("fp8", []), ("fp4", []),
              ("fpn 0.01", ["export.nvdb.tolerance=0.01"]), ("fpn 0.002", ["export.nvdb.tolerance=0.002"])]


def sets(lst):
    return [a for s in lst for a in ("--set", s)]


def run(args):
    r = subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        raise SystemExit("nvdb_precision.py: %s failed (%d): %s" % (" ".join(args), r.returncode, r.stderr[-2000:]))


def tag(p):
    return p.replace(" ", "_")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--size", default="160x90")
    ap.add_argument("--resolution", type=int, default=128)
    ap.add_argument("--presets", default="cumulus,cumulonimbus")
    ap.add_argument("--work")
    a = ap.parse_args()
    work = a.work or tempfile.mkdtemp(prefix="nvdb_precision_")
    os.makedirs(work, exist_ok=True)
    presets = a.presets.split(",")
    exrs = []
    for s in presets:
        for p, extra in PRECISIONS:
            f = os.path.join(work, "%s_%s.nvdb" % (s, tag(p)))
            run([GEN, "generate", s, "-q", "--resolution", str(a.resolution), "-o", f] +
                sets(["export.nvdb.precision=" + p.split()[0]] + extra))
        base = [VIEW, None, "--headless", "--size", a.size] + sets(["render.bloom=0"])
        ref = os.path.join(work, "%s_float.nvdb" % s)
        jobs = [(ref, sets(["render.density=0"]), "%s.bg" % s),
                (ref, sets(["render.output=transmittance", "render.steps=1024"]), "%s.t" % s)]
        for p, _ in PRECISIONS:
            f = os.path.join(work, "%s_%s.nvdb" % (s, tag(p)))
            jobs.append((f, [], "%s_%s.gl" % (s, tag(p))))
            jobs.append((f, ["--backend", "pathtrace", "--spp", str(a.spp)], "%s_%s.pt" % (s, tag(p))))
        for f, extra, name in jobs:
            out = os.path.join(work, name + ".exr")
            if not os.path.exists(out):
                args = list(base)
                args[1] = f
                run(args + extra + ["--out", out])
            exrs.append(out)
            if name.endswith("float.pt"):
                exrs.append(os.path.join(work, name + ".stderr.exr"))
            print("rendered " + name, file=sys.stderr)
    lst = os.path.join(work, "exr_list.txt")
    open(lst, "w").write("\n".join(e for e in exrs if not os.path.exists(e[:-4] + ".npy")) + "\n")
    r = subprocess.run(["blender", "-b", "--python-exit-code", "1", "--python",
                        os.path.join(ROOT, "scripts/exr_to_npy.py"), "--", lst],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        raise SystemExit("nvdb_precision.py: blender could not convert the EXRs:\n" + r.stdout[-3000:])

    ld = lambda n: np.load(os.path.join(work, n + ".npy"))[..., :3].astype(np.float64)
    print("| preset | precision | file bytes | vs float | path tracer PSNR (dB) | GL PSNR (dB) |")
    print("|---|---|---:|---:|---:|---:|")
    for s in presets:
        t, bg = ld(s + ".t"), ld(s + ".bg")
        mask = t.mean(axis=2) < 0.98
        cloud = lambda img: ((img - t * bg) @ LUM)[mask]
        refs = {k: cloud(ld("%s_float.%s" % (s, k))) for k in ("pt", "gl")}
        se = (ld("%s_float.pt.stderr" % s) @ LUM)[mask]
        fsize = os.path.getsize(os.path.join(work, "%s_float.nvdb" % s))

        def psnr(k, c):
            mse = float(((c - refs[k]) ** 2).mean())
            return math.inf if mse == 0 else 10 * math.log10(refs[k].max() ** 2 / mse)

        for p, _ in PRECISIONS:
            size = os.path.getsize(os.path.join(work, "%s_%s.nvdb" % (s, tag(p))))
            if p == "float":
                print("| %s (%d cloud px; pt noise %.1f dB) | float | %d | 1.00 | reference | reference |" % (
                    s, int(mask.sum()), 10 * math.log10(refs["pt"].max() ** 2 / float((se ** 2).mean())), size))
                continue
            pt = psnr("pt", cloud(ld("%s_%s.pt" % (s, tag(p)))))
            gl = psnr("gl", cloud(ld("%s_%s.gl" % (s, tag(p)))))
            print("| %s | %s | %d | %.2f | %.1f | %.1f |" % (s, p, size, size / fsize, pt, gl))
    print("work folder: " + work, file=sys.stderr)


if __name__ == "__main__":
    main()
