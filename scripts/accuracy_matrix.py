#!/usr/bin/python3
"""Every lighting option of the marcher against the path tracer (docs/notes/accuracy.md, issue 10).

For the thesis, cumulus and cumulonimbus presets, each at its default view, back-lit (the sun
opposite its default azimuth, 20 degrees up) and at sunset (the sun to the side, 3 degrees up):
the path tracer (two seeds of SPP paths per pixel; their mean is the reference, half their RMSE its
noise) against the marcher's CPU reference with single scattering, + powder, 2-4 octaves, the diffusion volume and
without the sky ambient (reference: the path tracer with the default settings), and with each
phase function (reference: the path tracer with the Mie phase, the physical one). Scores: the mean display luminance of the
cloud pixels (transmittance below 0.95) relative to the path tracer's, the RMSE of the display
image, and the CPU reference's whole-process time. Bloom off, so pixels compare one to one.
Rewrites the block between the accuracy-matrix markers in docs/notes/accuracy.md and draws
docs/images/accuracy_views.png (default lighting beside the path tracer, per preset and view).

Usage: scripts/accuracy_matrix.py [SPP] [WxH]   (default 128, 160x90; after scripts/test.sh)
"""
import json, math, os, subprocess, sys, tempfile, time

import matplotlib
matplotlib.use("Agg")
import matplotlib.image as im
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GEN, VIEW = os.path.join(ROOT, "build/bin/cloudgen"), os.path.join(ROOT, "build/bin/cloudviewer")
SPP = sys.argv[1] if len(sys.argv) > 1 else "128"
SIZE = sys.argv[2] if len(sys.argv) > 2 else "160x90"
PRESETS = ["thesis", "cumulus", "cumulonimbus"]
# (label, --set list, reference): transport options against the path tracer with the default
# settings; phase functions against the path tracer with the Mie phase (the physical one).
OPTIONS = [
    ("single scattering", ["render.ms_octaves=1", "render.powder=0"], "default"),
    ("+ powder (0.3)", ["render.ms_octaves=1"], "default"),
    ("2 octaves", ["render.ms_octaves=2"], "default"),
    ("3 octaves", ["render.ms_octaves=3"], "default"),
    ("**4 octaves (default)**", [], "default"),
    ("diffusion volume (render.ms_volume), no powder", ["render.ms_volume=true", "render.powder=0"], "default"),
    ("diffusion volume, powder 0.3", ["render.ms_volume=true"], "default"),
    ("default without the sky ambient", ["render.ambient=0"], "default"),
    ("phase: HG g 0.3 (default)", [], "mie"),
    ("phase: HG g 0.864 (Mie's g)", ["render.g=0.864"], "mie"),
    ("phase: two-lobe HG 0.9 / -0.3 / 0.97", ["render.phase=two-lobe-hg", "render.g=0.9"], "mie"),
    ("phase: HG + Draine, 20 um", ["render.phase=draine-hg"], "mie"),
    ("phase: Mie table", ["render.phase=mie"], "mie"),
]
REFERENCES = {"default": [], "mie": ["render.phase=mie"]}


def run(args):
    t0 = time.monotonic()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.monotonic() - t0


def sets(lst):
    out = []
    for s in lst:
        out += ["--set", s]
    return out


def main():
    work = tempfile.mkdtemp()
    rows, pictures = [], []
    for p in PRESETS:
        raw = os.path.join(work, p + ".raw")
        run([GEN, "generate", p, "-q", "-o", raw])
        lj = os.path.join(work, p + ".json.light")
        run([VIEW, raw, "--lighting-json", lj])
        d = json.load(open(lj))["sun_direction"]
        az = math.degrees(math.atan2(d[0], -d[2]))
        views = [("default", []), ("back-lit", ["--sun", "%.3f,20" % (az + 180)]),
                 ("sunset", ["--sun", "%.3f,3" % (az + 90)])]
        for vname, vargs in views:
            base = [VIEW, raw, "--headless", "--size", SIZE] + vargs + ["--set", "render.bloom=0"]
            tag = os.path.join(work, "%s_%s" % (p, vname))
            read = lambda n: im.imread(n)[..., :3].astype(np.float64)
            run(base + ["--backend", "cpu", "--set", "render.output=transmittance", "--set", "render.tonemap=clamp",
                        "--set", "render.exposure=1", "--out", tag + ".t.png"])
            mask = read(tag + ".t.png").mean(axis=2) < 0.95
            lum = lambda x: float((x @ np.array([0.2126, 0.7152, 0.0722]))[mask].mean())
            refs = {}
            for name, rset in REFERENCES.items():
                secs = [run(base + ["--backend", "pathtrace", "--spp", SPP, "--set", "render.frame=%d" % s] + sets(rset) +
                            ["--out", tag + ".pt_%s%d.png" % (name, s)]) for s in (0, 1)]
                a, b = read(tag + ".pt_%s0.png" % name), read(tag + ".pt_%s1.png" % name)
                refs[name] = ((a + b) / 2, float(np.sqrt(((a - b) ** 2).mean())) / 2, secs[0])
            for k, (label, opt, rname) in enumerate(OPTIONS):
                ref = refs[rname][0]
                out = tag + ".%d.png" % k
                secs = run(base + ["--backend", "cpu"] + sets(opt) + ["--out", out])
                c = read(out)
                rmse = float(np.sqrt(((c - ref) ** 2).mean()))
                rows.append((p, vname, label, lum(c) / lum(ref), rmse, secs, int(mask.sum())))
                if not opt and rname == "default":
                    pictures.append((c, ref))
            for name, (ref, noise, secs) in refs.items():
                rows.append((p, vname, "path tracer, %s spp%s" % (SPP, ", Mie phase" if name == "mie" else ""), 1.0,
                             noise, secs, int(mask.sum())))
            print("%s %s done" % (p, vname), file=sys.stderr)

    table = ["| preset | view | lighting | cloud luminance / path tracer's | RMSE vs path tracer | CPU reference s |",
             "|---|---|---|---:|---:|---:|"]
    for p, v, label, rel, rmse, secs, n in rows:
        noise = label.startswith("path tracer")
        table.append("| %s | %s | %s | %s | %s%.4f | %.2f |" % (
            p, v, label, "1" if noise else "%.3f (%+.1f%%)" % (rel, 100 * (rel - 1)), "noise " if noise else "", rmse,
            secs))
    stamp = "Measured %s on %d cores with `scripts/accuracy_matrix.py %s %s` (load %s at the end)." % (
        time.strftime("%Y-%m-%d", time.gmtime()), os.cpu_count(), SPP, SIZE, open("/proc/loadavg").read().split()[0])
    block = "\n".join(table) + "\n\n" + stamp + "\n"
    doc = os.path.join(ROOT, "docs/notes/accuracy.md")
    text = open(doc).read()
    b0 = text.index("<!-- BEGIN accuracy-matrix")
    b0 = text.index("\n", b0) + 1
    b1 = text.index("<!-- END accuracy-matrix")
    tmp = doc + ".tmp"
    open(tmp, "w").write(text[:b0] + block + text[b1:])
    os.replace(tmp, doc)

    # The picture: per preset a row of (default lighting | path tracer) for the three views.
    h, w = pictures[0][0].shape[:2]
    gap_v, gap_h = np.ones((h, 4, 3)), None
    lines = []
    for i in range(0, len(pictures), 3):
        parts = []
        for c, ref in pictures[i:i + 3]:
            parts += [c, np.ones((h, 1, 3)), ref, gap_v]
        lines.append(np.concatenate(parts[:-1], axis=1))
    gap_h = np.ones((4, lines[0].shape[1], 3))
    grid = [lines[0]]
    for line in lines[1:]:
        grid += [gap_h, line]
    out = os.path.join(ROOT, "docs/images/accuracy_views.png")
    im.imsave(out + ".tmp.png", np.clip(np.concatenate(grid, axis=0), 0, 1))
    os.replace(out + ".tmp.png", out)
    print(block)


if __name__ == "__main__":
    main()
