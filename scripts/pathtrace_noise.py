#!/usr/bin/python3
"""The path tracer's noise per phase function (docs/notes/phase.md, issue 10).

Renders the cumulus preset at its default view with `--backend pathtrace` twice (two seeds) per
phase function and per viewer binary given, and prints each one's noise: the RMS difference of the
two display images over sqrt(2) (the noise of one image), their mean value (the two binaries must
agree within the noise) and the seconds per image. Give two binaries to compare a change against
the build before it.

Usage: scripts/pathtrace_noise.py [SPP] [VIEWER ...]   (default 32 and build/bin/cloudviewer)
"""
import os, subprocess, sys, tempfile, time

import matplotlib
matplotlib.use("Agg")
import matplotlib.image as im
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SPP = sys.argv[1] if len(sys.argv) > 1 else "32"
VIEWERS = sys.argv[2:] or [os.path.join(ROOT, "build/bin/cloudviewer")]
PHASES = ["hg", "two-lobe-hg", "draine-hg", "mie"]


def main():
    work = tempfile.mkdtemp()
    raw = os.path.join(work, "cumulus.raw")
    subprocess.run([os.path.join(ROOT, "build/bin/cloudgen"), "generate", "cumulus", "-q", "-o", raw], check=True)
    print("| viewer | phase | noise (display, one image) | mean | s per image |\n|---|---|---:|---:|---:|")
    for v in VIEWERS:
        for ph in PHASES:
            imgs, secs = [], []
            for seed in (0, 1):
                out = os.path.join(work, "%s_%d.png" % (ph, seed))
                t = time.monotonic()
                subprocess.run([v, raw, "--headless", "--size", "128x72", "--backend", "pathtrace", "--spp", SPP,
                                "--set", "render.bloom=0", "--set", "render.phase=" + ph, "--set",
                                "render.frame=%d" % seed, "--out", out],
                               check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                secs.append(time.monotonic() - t)
                imgs.append(im.imread(out)[..., :3].astype(np.float64))
            noise = float(np.sqrt(((imgs[0] - imgs[1]) ** 2).mean() / 2))
            print("| %s | %s | %.5f | %.4f | %.2f |" % (v, ph, noise, imgs[0].mean(), np.mean(secs)), flush=True)


if __name__ == "__main__":
    main()
