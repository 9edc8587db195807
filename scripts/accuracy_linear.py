#!/usr/bin/python3
"""The real-time lighting against the path tracer in linear light (docs/notes/accuracy.md, issue 42).

The quantity scored is the cloud's own linear radiance, C = L - T * L_bg: the image minus what the
background contributes through the cloud, on the pixels whose opacity 1 - T exceeds 0.02. T is the
transmittance the GL marcher writes with render.output=transmittance at 1024 steps, L_bg the same
view rendered with density 0. Per case, against the path tracer (`--backend pathtrace`):

  mean    mean luminance of C over the cloud pixels / the path tracer's
  relRMSE RMS of the per-pixel luminance difference / the path tracer's mean, with the path
          tracer's own noise removed (sqrt(raw^2 - floor^2), floor = RMS standard error / mean,
          from its NAME.stderr.exr; the floor is printed beside it)
  dark    the same ratio as `mean` over the darkest quarter of the cloud pixels (by the path
          tracer's luminance): the shadowed side, where the multiple scattering matters most
  se      standard error of the path tracer's mean, from its NAME.stderr.exr, relative

Cases (the issue's matrix, as three crossed blocks so that it runs in about an hour on 2 cores):
  A: 4 scenes x extinction 0.02, 0.06, 0.15 /m x front, side, back light; HG g 0.3; sun only
  B: 4 scenes x 3 lights x phase HG 0.6, HG 0.85, Mie table; extinction 0.06; sun only
  C: 4 scenes x 3 lights; extinction 0.06; HG 0.3; with the sky ambient (precomputed sky, ground)
Scenes: the cumulus, thesis and cumulonimbus presets at 96 voxels (their `view`), and a dense
synthetic cloud (a flattened ellipsoid of density 1, 1200 x 800 x 1200 m, 20 m voxels). Light
directions are relative to the camera: front = the sun 30 degrees off the camera's back, 35 up;
side = 90 degrees to the right, 25 up; back = ahead of the camera, behind the cloud, 25 up.
"Sun only" is the analytic sky's sun, no sky light, no ground (as the Cycles cross-check).
Each case scores the default (GL) and `render.ms_volume=true render.powder=0`, albedo 1, bloom off.

Usage: scripts/accuracy_linear.py [--spp N] [--size WxH] [--quick] [--work DIR] [--no-doc]
  --quick: one scene, front and back, extinction 0.06 (a minute: to try a change)
  --work DIR: keep the renders there and reuse those already made (resume)
Needs build/bin (scripts/test.sh) and Debian's blender (reads the EXRs, scripts/exr_to_npy.py).
Rewrites the block between the accuracy-linear markers in docs/notes/accuracy.md, unless --no-doc,
and draws docs/images/accuracy_linear.png (the default beside the path tracer, extinction 0.06,
per scene: front, side, back).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("CLOUD_BIN", os.path.join(ROOT, "build/bin"))
GEN, VIEW = os.path.join(BIN, "cloudgen"), os.path.join(BIN, "cloudviewer")
LUM = np.array([0.2126, 0.7152, 0.0722])
SCENES = ["cumulus", "thesis", "cumulonimbus", "dense"]
LIGHTS = {"front": (210.0, 35.0), "side": (90.0, 25.0), "back": (0.0, 25.0)}  # azimuth from the view, elevation
PHASES = {"hg0.3": ["render.phase=hg", "render.g=0.3"], "hg0.6": ["render.phase=hg", "render.g=0.6"],
          "hg0.85": ["render.phase=hg", "render.g=0.85"], "mie": ["render.phase=mie"]}
SUN_ONLY = ["render.sky=analytic", "render.ambient=0", "render.ground=false"]
METHODS = {"default": [], "ms_volume": ["render.ms_volume=true", "render.powder=0"]}


def cases(quick):
    out = []
    if quick:
        return [("cumulus", 0.06, l, "hg0.3", "sun") for l in ("front", "back")]
    for s in SCENES:
        for l in LIGHTS:
            out += [(s, e, l, "hg0.3", "sun") for e in (0.02, 0.06, 0.15)]
            out += [(s, 0.06, l, p, "sun") for p in ("hg0.6", "hg0.85", "mie")]
            out.append((s, 0.06, l, "hg0.3", "sky"))
    return out


def sets(lst):
    return [a for s in lst for a in ("--set", s)]


def run(args, out):
    """Runs one render unless `out` exists already; returns its seconds (0 when reused)."""
    if os.path.exists(out):
        return 0.0
    t0 = time.monotonic()
    r = subprocess.run(args + ["--out", out], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        raise SystemExit("accuracy_linear.py: %s failed (%d): %s" % (" ".join(args), r.returncode, r.stderr[-2000:]))
    return time.monotonic() - t0


def dense_cloud(path):
    """The synthetic scene: a flattened ellipsoid of density 1 with a two-voxel edge, y up."""
    import pyopenvdb as vdb
    vs, radii = 20.0, np.array([600.0, 400.0, 600.0])
    n = (2 * radii / vs + 4).astype(int)
    idx = np.indices(n).astype(np.float64)
    c = (n - 1) / 2.0
    r = np.sqrt(sum(((idx[i] - c[i]) * vs / radii[i]) ** 2 for i in range(3)))
    dens = np.clip(0.5 - (r - 1.0) * radii.min() / (2 * vs), 0, 1).astype(np.float32)
    g = vdb.FloatGrid()
    g.copyFromArray(dens, ijk=(0, 0, 0))
    g.transform = vdb.createLinearTransform(voxelSize=vs)
    g.name = "density"
    g.gridClass = vdb.GridClass.FOG_VOLUME
    vdb.write(path + ".tmp.vdb", grids=[g])
    os.replace(path + ".tmp.vdb", path)


def view_azimuth(path):
    """Azimuth (degrees clockwise from -z, the --sun convention) the camera of the file's view looks toward."""
    import pyopenvdb as vdb
    meta = vdb.readAllGridMetadata(path)[0]
    if "view" not in meta:
        return 180.0  # the viewer's automatic view looks along +z
    v = json.loads(meta["view"])
    d = np.array(v["target"]) - np.array(v["eye"])
    return math.degrees(math.atan2(d[0], -d[2]))


def render_all(work, spp, size, todo):
    """Makes every image the cases need; returns {case: path tracer seconds}."""
    vols, secs = {}, {}
    for s in sorted({c[0] for c in todo}):
        vols[s] = os.path.join(work, s + ".vdb")
        if not os.path.exists(vols[s]):
            if s == "dense":
                dense_cloud(vols[s])
            else:
                subprocess.run([GEN, "generate", s, "-q", "--resolution", "96", "-o", vols[s]], check=True)
    tpath = os.path.join(work, "pathtrace_seconds.json")  # kept so that a resumed run states the full cost
    times = json.load(open(tpath)) if os.path.exists(tpath) else {}
    for n, (s, ext, light, phase, amb) in enumerate(todo):
        tag = os.path.basename("%s_%g_%s_%s_%s" % todo[n])
        az = (view_azimuth(vols[s]) + LIGHTS[light][0] + 180.0) % 360.0 - 180.0
        base = [VIEW, vols[s], "--headless", "--size", size, "--sun", "%.3f,%.1f" % (az, LIGHTS[light][1])]
        base += sets(["render.bloom=0", "render.albedo=1"] + (SUN_ONLY if amb == "sun" else []))
        run(base + sets(["render.density=0"]), os.path.join(work, "%s_%s_%s.bg.exr" % (s, light, amb)))
        run(base + sets(["render.sigma_t=%g" % ext, "render.output=transmittance", "render.steps=1024"]),
            os.path.join(work, "%s_%g.t.exr" % (s, ext)))
        look = base + sets(["render.sigma_t=%g" % ext] + PHASES[phase])
        out = os.path.join(work, tag)
        secs[todo[n]] = run(look + ["--backend", "pathtrace", "--spp", str(spp)], out + ".pt.exr") or times.get(tag, 0.0)
        times[tag] = secs[todo[n]]
        with open(tpath + ".tmp", "w") as f:
            json.dump(times, f)
        os.replace(tpath + ".tmp", tpath)
        for m, extra in METHODS.items():
            run(look + sets(extra), out + "." + m + ".exr")
        print("[%d/%d] %s %g %s %s %s: path tracer %.1f s" % (n + 1, len(todo), s, ext, light, phase, amb,
                                                             secs[todo[n]]), file=sys.stderr)
    return secs


def to_npy(work):
    exrs = [os.path.join(work, f) for f in sorted(os.listdir(work))
            if f.endswith(".exr") and not os.path.exists(os.path.join(work, f[:-4] + ".npy"))]
    if not exrs:
        return
    lst = os.path.join(work, "exr_list.txt")
    open(lst, "w").write("\n".join(exrs) + "\n")
    r = subprocess.run(["blender", "-b", "--python-exit-code", "1", "--python",
                        os.path.join(ROOT, "scripts/exr_to_npy.py"), "--", lst],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        raise SystemExit("accuracy_linear.py: blender could not convert the EXRs:\n" + r.stdout[-3000:])


def score(work, case):
    s, ext, light, phase, amb = case
    ld = lambda n: np.load(os.path.join(work, n + ".npy"))[..., :3].astype(np.float64)
    tag = "%s_%g_%s_%s_%s" % case
    t = ld("%s_%g.t" % (s, ext))
    bg = ld("%s_%s_%s.bg" % (s, light, amb))
    mask = t.mean(axis=2) < 0.98
    cloud = lambda img: ((img - t * bg) @ LUM)[mask]
    ref = cloud(ld(tag + ".pt"))
    se = (ld(tag + ".pt.stderr") @ LUM)[mask]
    m = ref.mean()
    dark = ref <= np.percentile(ref, 25)
    row = {"n": int(mask.sum()), "se": float(np.sqrt((se ** 2).sum()) / len(se) / m),
           "floor": float(np.sqrt((se ** 2).mean()) / m)}
    for meth in METHODS:
        c = cloud(ld(tag + "." + meth))
        raw = float(np.sqrt(((c - ref) ** 2).mean()) / m)
        rel = math.sqrt(max(raw ** 2 - row["floor"] ** 2, 0.0))
        row[meth] = (float(c.mean() / m), rel, float(c[dark].mean() / ref[dark].mean()))
    return row


NOISY = 0.25  # a path-tracer noise floor above the relRMSE bound: the relRMSE is not measurable
LABEL = {"hg0.3": "HG 0.3", "hg0.6": "HG 0.6", "hg0.85": "HG 0.85", "mie": "Mie table"}


def table(rows):
    out = ["| scene | extinction /m | light | phase | sky light | cloud px | path tracer se | "
           "default: mean, relRMSE, dark | ms_volume: mean, relRMSE, dark | path tracer noise floor of relRMSE |",
           "|---|---:|---|---|---|---:|---:|---|---|---:|"]
    for (s, ext, light, phase, amb), r in rows:
        noisy = r["floor"] > NOISY
        good = lambda v: abs(v[0] - 1) <= 0.10 and (noisy or v[1] <= 0.25)
        f = lambda v: ("%.2fx, %s, %.2fx" if good(v) else "**%.2fx, %s**, %.2fx") % (
            v[0], "noise" if noisy else "%.2f" % v[1], v[2])
        out.append("| %s | %g | %s | %s | %s | %d | %.2f%% | %s | %s | %.3f |" % (
            s, ext, light, LABEL[phase], "sun only" if amb == "sun" else "sky + ground", r["n"], 100 * r["se"],
            f(r["default"]), f(r["ms_volume"]), r["floor"]))
    return out


def summary(rows):
    out = []
    clean = np.array([r["floor"] <= NOISY for _, r in rows])
    for meth in METHODS:
        v = np.array([r[meth] for _, r in rows])
        ok = int(((np.abs(v[:, 0] - 1) <= 0.10) & ((v[:, 1] <= 0.25) | ~clean)).sum())
        out.append("- **%s**: mean ratio %.2f-%.2fx (median %.2fx), darkest quarter %.2f-%.2fx; relRMSE %.2f-%.2f "
                   "(median %.2f) where the reference is clean enough to tell; within 10%% and relRMSE <= 0.25 in "
                   "%d of %d cases." % (meth, v[:, 0].min(), v[:, 0].max(), np.median(v[:, 0]), v[:, 2].min(),
                                        v[:, 2].max(), v[clean, 1].min(), v[clean, 1].max(), np.median(v[clean, 1]),
                                        ok, len(v)))
    if not clean.all():
        out.append("- \"noise\": %d cases (%s) whose path-tracer noise floor exceeds %.2f, so their relRMSE cannot be "
                   "told from the reference's own noise at this spp; their mean still can (se column)." % (
                       int((~clean).sum()), ", ".join(sorted({LABEL[c[3]] for c, r in rows if r["floor"] > NOISY})),
                       NOISY))
    return out


def picture(work, todo, out):
    """Per scene a row of (default | path tracer) for front, side and back light at the first
    0.06 /m; linear radiance through exposure 1.5 and Reinhard, sRGB (display only)."""
    disp = lambda x: np.clip(np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 1e-9), 1 / 2.4) - 0.055),
                             0, 1)
    tone = lambda n: disp(1.5 * np.load(os.path.join(work, n + ".npy"))[..., :3] / (1 + 1.5 * np.load(os.path.join(
        work, n + ".npy"))[..., :3]))
    lines = []
    for s in SCENES:
        tags = ["%s_%g_%s_hg0.3_sun" % (s, 0.06, l) for l in LIGHTS]
        if not all(os.path.exists(os.path.join(work, t + ".pt.npy")) for t in tags):
            continue
        parts = []
        for t in tags:
            a, b = tone(t + ".default"), tone(t + ".pt")
            parts += [a, np.ones((a.shape[0], 1, 3)), b, np.ones((a.shape[0], 4, 3))]
        lines += [np.concatenate(parts[:-1], axis=1), np.ones((4, sum(p.shape[1] for p in parts[:-1]), 3))]
    if lines:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.image as im
        im.imsave(out + ".tmp.png", np.concatenate(lines[:-1], axis=0))
        os.replace(out + ".tmp.png", out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spp", type=int, default=128)
    ap.add_argument("--size", default="160x90")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--work")
    ap.add_argument("--no-doc", action="store_true")
    a = ap.parse_args()
    for b in (GEN, VIEW):
        if not os.access(b, os.X_OK):
            raise SystemExit("accuracy_linear.py: %s is missing; run scripts/test.sh first" % b)
    work = a.work or tempfile.mkdtemp(prefix="accuracy_linear.")
    os.makedirs(work, exist_ok=True)
    todo = cases(a.quick)
    secs = render_all(work, a.spp, a.size, todo)
    to_npy(work)
    rows = [(c, score(work, c)) for c in todo]
    lines = table(rows) + [""] + summary(rows) + [""]
    lines.append("Measured %s on %d cores with `scripts/accuracy.sh --spp %d --size %s%s` (the path tracer: %.0f min in "
                 "all, %.0f-%.0f s a case). Bold: outside 10%% in mean or relRMSE > 0.25." % (
                     time.strftime("%Y-%m-%d", time.gmtime()), os.cpu_count(), a.spp, a.size,
                     " --quick" if a.quick else "", sum(secs.values()) / 60, min(secs.values()), max(secs.values())))
    block = "\n".join(lines) + "\n"
    print(block)
    if not a.no_doc and not a.quick:
        doc = os.path.join(ROOT, "docs/notes/accuracy.md")
        text = open(doc).read()
        b0 = text.index("\n", text.index("<!-- BEGIN accuracy-linear")) + 1
        b1 = text.index("<!-- END accuracy-linear")
        open(doc + ".tmp", "w").write(text[:b0] + block + text[b1:])
        os.replace(doc + ".tmp", doc)
    if not a.quick:
        picture(work, todo, os.path.join(ROOT, "docs/images/accuracy_linear.png"))
    if not a.work:
        print("renders kept in %s" % work, file=sys.stderr)


if __name__ == "__main__":
    main()
