#!/usr/bin/python3
"""How cloud-like a volume is, in the two measures of issue 43 (docs/shaping.md#realism).

  realism.py [--check] FILE.vdb [FILE.vdb ...]     (VDBs written with --up y, so the grid's y is up)

--check exits 1 unless each file's spectrum is a falling power law in both bands (fit R^2 >= 0.95,
slope <= -2): issue 43's "a power law over both bands, not a flat floor".

For each file, from its `density` grid:
- the 3D power spectrum: |FFT|^2 of the density (mean removed), averaged over shells of wave number
  k (cycles per voxel), and the slopes of log P against log k over wavelengths of 32-8 voxels and
  8-3 voxels (Disney's cloud: -3.78 and -2.97; Kolmogorov's turbulent scalar: -11/3);
- the area-perimeter dimension D of the top-down silhouettes: columns with a vertical optical depth
  of at least 1 (extinction 0.5 / voxel at density 1, the viewer's default) are cloud; each
  4-connected cloud's area A and perimeter P (pixel edges) give D as twice the slope of log P
  against log A, over clouds of at least 8 pixels (real fields: D = 1.35, Lovejoy 1982). Needs
  several clouds: printed when there are at least 10.
Prints one line per file. numpy and python3-openvdb only (Debian's /usr/bin/python3).
"""
import sys

import numpy as np
import pyopenvdb as vdb


def density(path):
    g = vdb.read(path, "density")
    (x0, y0, z0), (x1, y1, z1) = g.evalActiveVoxelBoundingBox()
    lo = (min(x0, 0), min(y0, 0), min(z0, 0))
    a = np.zeros((x1 - lo[0] + 1, y1 - lo[1] + 1, z1 - lo[2] + 1), dtype=np.float32)
    g.copyToArray(a, ijk=lo)
    return a


def spectrum_slopes(d):
    f = np.fft.fftn(d - d.mean())
    p = (f.real ** 2 + f.imag ** 2).astype(np.float64)
    k = np.sqrt(sum(np.meshgrid(*[np.fft.fftfreq(n) ** 2 for n in d.shape], indexing="ij", sparse=False)))
    edges = np.geomspace(1 / 48, 0.5, 40)
    idx = np.digitize(k.ravel(), edges)
    pk, kk = [], []
    flat = p.ravel()
    kr = k.ravel()
    for i in range(1, len(edges)):
        m = idx == i
        if m.sum() >= 8:
            pk.append(flat[m].mean())
            kk.append(kr[m].mean())
    kk, pk = np.array(kk), np.array(pk)

    def slope(lam_hi, lam_lo):
        """The slope of log P against log k over the band, and the fit's R^2 (1: a power law)."""
        m = (kk >= 1 / lam_hi) & (kk <= 1 / lam_lo) & (pk > 0)
        if m.sum() < 3:
            return float("nan"), float("nan")
        x, y = np.log(kk[m]), np.log(pk[m])
        fit = np.polyfit(x, y, 1)
        resid = y - np.polyval(fit, x)
        r2 = 1 - (resid ** 2).sum() / max(((y - y.mean()) ** 2).sum(), 1e-300)
        return fit[0], r2

    return slope(32, 8), slope(8, 3)


def label(mask):
    """4-connected components of a 2D boolean mask (no scipy): a list of index arrays."""
    h, w = mask.shape
    seen = np.zeros_like(mask, dtype=bool)
    comps = []
    for sy, sx in zip(*np.nonzero(mask)):
        if seen[sy, sx]:
            continue
        stack, pix = [(sy, sx)], []
        seen[sy, sx] = True
        while stack:
            y, x = stack.pop()
            pix.append((y, x))
            for ny, nx in ((y + 1, x), (y - 1, x), (y, x + 1), (y, x - 1)):
                if 0 <= ny < h and 0 <= nx < w and mask[ny, nx] and not seen[ny, nx]:
                    seen[ny, nx] = True
                    stack.append((ny, nx))
        comps.append(pix)
    return comps


def silhouette_dimension(d):
    tau = 0.5 * d.sum(axis=1)  # along y, the up axis
    mask = tau >= 1.0
    padded = np.pad(mask, 1)
    areas, perims = [], []
    for pix in label(mask):
        if len(pix) < 8:
            continue
        ys, xs = np.array(pix).T + 1
        # Pixel edges between this cloud and the clear sky (4 neighbours).
        p = sum(int((~padded[ys + dy, xs + dx]).sum()) for dy, dx in ((1, 0), (-1, 0), (0, 1), (0, -1)))
        areas.append(len(pix))
        perims.append(p)
    if len(areas) < 10:
        return float("nan"), len(areas)
    return 2 * np.polyfit(np.log(areas), np.log(perims), 1)[0], len(areas)


def main():
    args = sys.argv[1:]
    check = "--check" in args
    args = [a for a in args if a != "--check"]
    if not args:
        sys.exit(__doc__)
    failed = False
    for path in args:
        d = density(path)
        (s1, r1), (s2, r2) = spectrum_slopes(d)
        dim, n = silhouette_dimension(d)
        dtext = f"D {dim:.2f} over {n} clouds" if n >= 10 else f"D: {n} clouds (too few)"
        print(f"{path}: {d.shape[0]}x{d.shape[1]}x{d.shape[2]}, spectrum slope {s1:.2f} (32-8 voxels, R^2 {r1:.3f}), "
              f"{s2:.2f} (8-3 voxels, R^2 {r2:.3f}); {dtext}")
        # --check: each band a power law (R^2 >= 0.95) that falls (slope <= -2), not a flat floor
        # of white noise (slope about 0) or a spectrum that bends inside a band.
        for band, s, r in (("32-8", s1, r1), ("8-3", s2, r2)):
            if check and not (r >= 0.95 and s <= -2):
                print(f"  not a falling power law over {band} voxels: slope {s:.2f}, R^2 {r:.3f}")
                failed = True
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
