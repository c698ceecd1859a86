"""Reference data for luxest's bitmap textures (crates/render/src/texture.rs), made with Mitsuba 3.

Writes, next to this script:
- bitmap.png: a 5x3 8-bit sRGB RGB image, texel (i, j) = (40 i + 7 j + 20, 250 - 23 i - 31 j, 60 j + 13 i + 5);
- mitsuba_bitmap.csv: Mitsuba 3's `bitmap` texture of bitmap.png evaluated at fixed UVs, for every
  wrap mode, filter, raw (linear) or sRGB decoding and two `to_uv` transforms (columns wrap,
  filter, raw, transform, u, v, r, g, b; transform 0 the identity, 1 the matrix AFFINE below);
- pattern.jpg: a 48x32 JPEG (quality 100) of 3x2 flat 16x16 blocks with the colours BLOCKS,
  pattern_grey.jpg: a 32x16 grey JPEG of two flat blocks (GREY_BLOCKS);
  jpeg_mitsuba.csv: Mitsuba's 8-bit decoding of each block's centre pixel (file, x, y, r, g, b);
- rgba_half.exr: a 4x3 RGBA half-float EXR (PIZ) with texel (i, j) = (i / 4, j / 8, -(i + j), 1 - i / 8);
  luminance.exr: a 3x2 single-channel (Y) float EXR with texel (i, j) = i + 10 j.

Run: .venv-peers/bin/python crates/render/tests/data/texture/mitsuba_bitmap.py
"""

import csv
import os

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
HERE = os.path.dirname(os.path.abspath(__file__))

AFFINE = [[2.0, 0.5, 0.1], [-0.3, 1.5, 0.25]]
BLOCKS = [[(200, 30, 40), (20, 180, 60), (30, 50, 220)], [(250, 250, 250), (128, 128, 128), (240, 200, 10)]]
GREY_BLOCKS = [40, 210]


def bitmap_png():
    w, h = 5, 3
    data = np.zeros((h, w, 3), dtype=np.uint8)
    for j in range(h):
        for i in range(w):
            data[j, i] = (40 * i + 7 * j + 20, 250 - 23 * i - 31 * j, 60 * j + 13 * i + 5)
    bitmap = mi.Bitmap(data, mi.Bitmap.PixelFormat.RGB)
    bitmap.set_srgb_gamma(True)
    bitmap.write(os.path.join(HERE, "bitmap.png"))


def uvs():
    """Fixed points: corners, edges, texel centres, outside the unit square on every side."""
    points = [
        (0.0, 0.0),
        (0.5, 0.5),
        (0.1, 0.9),
        (1.0, 1.0),
        (0.999, 0.001),
        (-0.05, 1.02),
        (0.3, 1.0 / 6.0),
        (0.55, 0.49),
        (1.37, -0.21),
        (-1.3, 2.7),
        (2.05, 0.8),
        (-0.6, -0.45),
    ]
    state = 12345
    for _ in range(24):
        pair = []
        for _ in range(2):
            state = (1103515245 * state + 12345) % 2**31
            pair.append(-1.5 + 4.0 * state / 2**31)
        points.append(tuple(pair))
    return points


def lookups():
    rows = []
    for wrap in ["repeat", "mirror", "clamp"]:
        for filt in ["bilinear", "nearest"]:
            for raw in [False, True]:
                for t, m in enumerate([[[1, 0, 0], [0, 1, 0]], AFFINE]):
                    # A 4x4 `to_uv` maps (u, v, 0, 1): the translation is its fourth column.
                    to_uv = mi.ScalarTransform4f(
                        [[m[0][0], m[0][1], 0, m[0][2]], [m[1][0], m[1][1], 0, m[1][2]], [0, 0, 1, 0], [0, 0, 0, 1]]
                    )
                    tex = mi.load_dict(
                        {
                            "type": "bitmap",
                            "filename": os.path.join(HERE, "bitmap.png"),
                            "wrap_mode": wrap,
                            "filter_type": filt,
                            "raw": raw,
                            "to_uv": to_uv,
                        }
                    )
                    for u, v in uvs():
                        si = mi.SurfaceInteraction3f()
                        si.uv = mi.Point2f(u, v)
                        c = tex.eval(si)
                        rows.append(
                            [
                                wrap,
                                filt,
                                int(raw),
                                t,
                                repr(u),
                                repr(v),
                                repr(float(c[0])),
                                repr(float(c[1])),
                                repr(float(c[2])),
                            ]
                        )
    with open(os.path.join(HERE, "mitsuba_bitmap.csv"), "w", newline="") as f:
        out = csv.writer(f, lineterminator="\n")
        out.writerow(["wrap", "filter", "raw", "transform", "u", "v", "r", "g", "b"])
        out.writerows(rows)


def jpegs():
    rgb = np.zeros((32, 48, 3), dtype=np.uint8)
    for by in range(2):
        for bx in range(3):
            rgb[16 * by : 16 * by + 16, 16 * bx : 16 * bx + 16] = BLOCKS[by][bx]
    grey = np.zeros((16, 32, 1), dtype=np.uint8)
    for bx in range(2):
        grey[:, 16 * bx : 16 * bx + 16] = GREY_BLOCKS[bx]
    rows = []
    for name, data, fmt in [
        ("pattern.jpg", rgb, mi.Bitmap.PixelFormat.RGB),
        ("pattern_grey.jpg", grey, mi.Bitmap.PixelFormat.Y),
    ]:
        bitmap = mi.Bitmap(data, fmt)
        bitmap.set_srgb_gamma(True)
        path = os.path.join(HERE, name)
        bitmap.write(path, quality=100)
        back = np.array(mi.Bitmap(path))
        back = back.reshape(back.shape[0], back.shape[1], -1)
        for y in range(8, data.shape[0], 16):
            for x in range(8, data.shape[1], 16):
                p = [int(c) for c in back[y, x]]
                rows.append([name, x, y] + (p * 3 if len(p) == 1 else p))
    with open(os.path.join(HERE, "jpeg_mitsuba.csv"), "w", newline="") as f:
        out = csv.writer(f, lineterminator="\n")
        out.writerow(["file", "x", "y", "r", "g", "b"])
        out.writerows(rows)


def exrs():
    data = np.zeros((3, 4, 4), dtype=np.float16)
    for j in range(3):
        for i in range(4):
            data[j, i] = (i / 4, j / 8, -(i + j), 1 - i / 8)
    mi.Bitmap(data, mi.Bitmap.PixelFormat.RGBA).write(os.path.join(HERE, "rgba_half.exr"))
    y = np.zeros((2, 3, 1), dtype=np.float32)
    for j in range(2):
        for i in range(3):
            y[j, i] = i + 10 * j
    mi.Bitmap(y, mi.Bitmap.PixelFormat.Y).write(os.path.join(HERE, "luminance.exr"))


if __name__ == "__main__":
    bitmap_png()
    lookups()
    jpegs()
    exrs()
