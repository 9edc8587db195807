#!/usr/bin/python3
"""Quick look at a cloudgen raw texture: side and top views of exp(-optical depth) of channel R,
plus a mid-height slice. Usage: preview_raw.py VOLUME.raw OUT.png"""
import json, sys
import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

raw, out = sys.argv[1], sys.argv[2]
side = json.load(open(raw[:-4] + ".json"))
nx, ny, nz = side["size"]
dt = {"rgba8": np.uint8, "rgba16f": np.float16, "rgba32f": np.float32}[side["format"]]
v = np.fromfile(raw, dtype=dt).reshape(nz, ny, nx, 4).astype(np.float32)
if dt == np.uint8:
    v /= 255.0
d = v[..., 0]
fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
ax[0].imshow(1 - np.exp(-d.sum(axis=0) * 0.3), origin="lower", cmap="gray", vmin=0, vmax=1)
ax[0].set_title("side (x right, y up): 1 - exp(-tau)")
ax[1].imshow(1 - np.exp(-d.sum(axis=1) * 0.3), origin="lower", cmap="gray", vmin=0, vmax=1)
ax[1].set_title("top (x right, z up)")
ax[2].imshow(d[:, ny // 6, :], origin="lower", cmap="magma", vmin=0, vmax=1)
ax[2].set_title(f"slice y={ny // 6}")
fig.suptitle(f"{raw}: {nx}x{ny}x{nz}, active {np.mean(d > 0) * 100:.1f}%")
fig.tight_layout()
fig.savefig(out, dpi=60)
