#!/usr/bin/python3
"""docs/phase.md's figure and table: each analytic phase function against the Lorenz-Mie result for
the default cloud (effective radius 10 um, variance 0.111, 550 nm).
Usage: scripts/plot_phase.py [build/bin]   (writes docs/images/phase_models.png, prints the table)"""
import os, subprocess, sys, tempfile
import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

cg = os.path.join(sys.argv[1] if len(sys.argv) > 1 else "build/bin", "cloudgen")
tmp = tempfile.mkdtemp()
def table(*args):
    path = os.path.join(tmp, "t.csv")
    subprocess.run([cg, "phase", "-q", "-o", path] + list(args), check=True)
    d = np.loadtxt(path, delimiter=",", skiprows=1)
    return d[:, 0], d[:, 2]  # green: 550 nm
ang, mie = table("--model", "mie", "--effective-radius", "10")
th = np.radians(ang)
w = np.sin(th)
def integ(v):
    return 2 * np.pi * np.trapz(v * w, th)
g_mie = integ(mie * np.cos(th))
models = {"HG (g = Mie's %.3f)" % g_mie: table("--model", "hg", "--g", "%.4f" % g_mie)[1],
          "two-lobe HG (0.9, -0.3, weight 0.97)": table("--model", "two-lobe-hg")[1],
          "HG + Draine (Jendersie & d'Eon 2023)": table("--model", "draine-hg", "--effective-radius", "10")[1]}
fig, ax = plt.subplots(figsize=(6, 3.4), dpi=80)
ax.semilogy(ang, mie, "k", lw=1.5, label="Lorenz-Mie, 10 um droplets")
for name, v in models.items():
    ax.semilogy(ang, v, lw=1, label=name)
ax.set_xlabel("scattering angle, degrees", fontsize=8)
ax.set_ylabel("phase, 1/sr", fontsize=8)
ax.set_xlim(0, 180)
ax.legend(fontsize=7)
ax.tick_params(labelsize=7)
fig.tight_layout()
os.makedirs("docs/images", exist_ok=True)
fig.savefig("docs/images/phase_models.png")
def at(v, a):
    return v[np.searchsorted(ang, a - 1e-9)]
print("| model | g | RMS of log10(model / Mie), solid-angle weighted | model / Mie at 0 deg | 90 deg | 140 deg (fogbow) | 180 deg (glory) |")
print("|---|---|---|---|---|---|---|")
print(f"| Lorenz-Mie (reference) | {g_mie:.4f} | 0 | 1 | 1 | 1 | 1 |")
for name, v in models.items():
    r = np.log10(v / mie)
    rms = np.sqrt(np.trapz(r * r * w, th) / np.trapz(w, th))
    print(f"| {name} | {integ(v * np.cos(th)):.4f} | {rms:.3f} | {at(v, 0) / at(mie, 0):.2f} | {at(v, 90) / at(mie, 90):.2f} | "
          f"{at(v, 140) / at(mie, 140):.2f} | {at(v, 180) / at(mie, 180):.2f} |")
