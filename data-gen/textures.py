"""Procedural texture library of the scene generators (standard library only).

Every image is a function of (name, side, seed): integer hashing, no `random` state shared with
the scenes, no `hash()` (randomised per process), so a library regenerates byte for byte. The
images are 8-bit sRGB PNGs (RGB, or RGBA where the alpha is a cut-out), written with zlib and
struct. The tiling patterns (planks, tiles, fabric, marble, plaster, grille) repeat seamlessly,
so a `uv_transform` scale repeats them without seams; the paper and the photographs do not.

  wood-planks        staggered planks with grain, rings and dark joints
  tiles              square tiles with grout lines, near-neutral (a material colour tints them)
  fabric             2/2 twill weave of two thread tones
  paper-text         a page of glyph-like strokes on paper, in lines and paragraphs
  photo-landscape    a "photograph": sky gradient, sun, hills, lake, film grain
  photo-still-life   a "photograph": backdrop, table, shaded fruit and a vase, film grain
  marble             veins of turbulence on a light stone
  plaster            low-contrast mottled noise for walls
  leaves             RGBA: a spray of leaves, alpha 0 between them (a cut-out plant)
  grille             RGBA: a square metal grid, alpha 0 in the holes

An image is a list of rows of (r, g, b) or (r, g, b, a) tuples of sRGB-encoded values in [0, 1].
"""

import math
import os
import struct
import zlib

# The library, in the order it is written: (name, generator, tiles seamlessly).
NAMES = (
    "wood-planks",
    "tiles",
    "fabric",
    "paper-text",
    "photo-landscape",
    "photo-still-life",
    "marble",
    "plaster",
    "leaves",
    "grille",
)
# Patterns that repeat across their edges (the others are pictures: clamp them).
TILING = {"wood-planks", "tiles", "fabric", "marble", "plaster", "grille", "leaves"}
# Images with a cut-out alpha channel.
CUT_OUTS = {"leaves", "grille"}


# --- Hashing and noise ---------------------------------------------------------------------------


def unit_hash(seed, i, j=0, k=0):
    """A uniform number in [0, 1) from integers (a 32-bit integer mix, the same on every run)."""
    h = (seed * 0x27D4EB2D + i * 0x165667B1 + j * 0x61C88647 + k * 0x3C6EF372) & 0xFFFFFFFF
    h ^= h >> 15
    h = (h * 0x2C1B3C6D) & 0xFFFFFFFF
    h ^= h >> 12
    h = (h * 0x297A2D39) & 0xFFFFFFFF
    h ^= h >> 15
    return h / 4294967296.0


def _smooth(t):
    return t * t * (3.0 - 2.0 * t)


def value_noise(w, h, px, py, seed):
    """Smoothly interpolated lattice noise in [0, 1), px x py cells across the w x h image and
    periodic over it (the lattice wraps), as rows of floats."""
    lattice = [[unit_hash(seed, i, j) for i in range(px)] for j in range(py)]
    xs = [(x + 0.5) * px / w for x in range(w)]
    x0 = [int(t) % px for t in xs]
    x1 = [(int(t) + 1) % px for t in xs]
    fx = [_smooth(t - int(t)) for t in xs]
    along_x = [[r[a] + (r[b] - r[a]) * t for a, b, t in zip(x0, x1, fx)] for r in lattice]
    rows = []
    for y in range(h):
        t = (y + 0.5) * py / h
        s = _smooth(t - int(t))
        ra, rb = along_x[int(t) % py], along_x[(int(t) + 1) % py]
        rows.append([a + (b - a) * s for a, b in zip(ra, rb)])
    return rows


def fbm(w, h, px, py, octaves, seed):
    """Fractal sum of value noise (cells doubling, amplitude halving per octave) in [0, 1)."""
    total = [[0.0] * w for _ in range(h)]
    amp, norm = 1.0, 0.0
    for o in range(octaves):
        layer = value_noise(w, h, px << o, py << o, seed * 31 + o)
        total = [[t + amp * v for t, v in zip(tr, lr)] for tr, lr in zip(total, layer)]
        norm += amp
        amp *= 0.5
    return [[t / norm for t in row] for row in total]


def _mix(a, b, t):
    return tuple(x + (y - x) * t for x, y in zip(a, b))


def _clamp(x):
    return min(max(x, 0.0), 1.0)


# --- The patterns --------------------------------------------------------------------------------


def wood_planks(side, seed):
    rows_of_planks = 4
    plank_h = side // rows_of_planks
    grain = value_noise(side, side, 3, 48, seed)
    fine = fbm(side, side, 16, 64, 2, seed + 1)
    light, dark = (0.78, 0.56, 0.34), (0.45, 0.27, 0.14)
    # Joints: two per plank row, staggered; plank pieces have their own tone and ring phase.
    joints = [
        sorted(int(side * (unit_hash(seed, r, m, 7) * 0.5 + 0.5 * m)) for m in (0, 1)) for r in range(rows_of_planks)
    ]
    img = []
    for y in range(side):
        r = y // plank_h
        local = (y - r * plank_h) / plank_h
        row = []
        for x in range(side):
            piece = sum(1 for j in joints[r] if x >= j) % 2 + 2 * r
            tone = 0.85 + 0.3 * unit_hash(seed, piece, 1)
            phase = unit_hash(seed, piece, 2) * 10.0
            ring = 0.5 + 0.5 * math.sin((local * 3.0 + grain[y][x] * 2.5 + phase) * 2 * math.pi)
            t = _clamp(0.25 + 0.5 * ring * ring + 0.35 * (fine[y][x] - 0.5))
            c = tuple(_clamp(v * tone) for v in _mix(dark, light, t))
            # Dark gaps between plank rows and at the joints.
            edge = min(y - r * plank_h, (r + 1) * plank_h - 1 - y)
            if edge < 1 or any(abs(x - j) < 1 for j in joints[r]):
                c = tuple(v * 0.35 for v in c)
            elif edge < 2:
                c = tuple(v * 0.75 for v in c)
            row.append(c)
        img.append(row)
    return img


def tiles(side, seed):
    n, grout = 4, max(2, side // 64)
    cell = side // n
    speck = value_noise(side, side, 64, 64, seed)
    cloud = fbm(side, side, 4, 4, 3, seed + 1)
    img = []
    for y in range(side):
        ty, iy = divmod(y, cell)
        row = []
        for x in range(side):
            tx, ix = divmod(x, cell)
            # The grout line between two tiles is split between them.
            d = min(
                ix - grout // 2,
                iy - grout // 2,
                cell - 1 - ix - (grout - grout // 2),
                cell - 1 - iy - (grout - grout // 2),
            )
            if d < 0:
                g = 0.52 + 0.08 * speck[y][x]
                row.append((g, g * 0.98, g * 0.94))
                continue
            base = 0.78 + 0.12 * unit_hash(seed, tx % n, ty % n)
            v = base + 0.06 * (cloud[y][x] - 0.5) + 0.03 * (speck[y][x] - 0.5)
            # A slight bevel: darker towards the tile's edge.
            if d < 2:
                v *= 0.9 + 0.05 * d
            row.append((_clamp(v), _clamp(v * 0.99), _clamp(v * 0.97)))
        img.append(row)
    return img


def fabric(side, seed):
    thread = max(4, side // 32)
    mottle = fbm(side, side, 4, 4, 3, seed)
    slub = value_noise(side, side, 4, 128, seed + 2)
    warp, weft = (0.82, 0.8, 0.76), (0.5, 0.55, 0.66)
    img = []
    for y in range(side):
        j, fy = divmod(y, thread)
        row = []
        for x in range(side):
            i, fx = divmod(x, thread)
            # 2/2 twill: the warp (vertical thread) lies on top on a diagonal band.
            warp_on_top = (i + j) % 4 < 2
            across = (fx if warp_on_top else fy) + 0.5
            profile = math.sin(math.pi * across / thread)
            base = warp if warp_on_top else weft
            k = (0.55 + 0.45 * profile) * (0.85 + 0.3 * mottle[y][x]) * (0.93 + 0.14 * slub[y][x])
            row.append(tuple(_clamp(c * k) for c in base))
        img.append(row)
    return img


# Glyph strokes in a unit cell (x right, y down; the x-height band is y in [0.35, 1]).
_STROKES = (
    ((0.2, 0.35), (0.2, 1.0)),  # stem
    ((0.2, 0.0), (0.2, 1.0)),  # ascender stem
    ((0.2, 0.35), (0.8, 0.35)),  # top bar
    ((0.2, 1.0), (0.8, 1.0)),  # base bar
    ((0.2, 0.65), (0.8, 0.65)),  # middle bar
    ((0.8, 0.35), (0.8, 1.0)),  # right stem
    ((0.2, 1.0), (0.8, 0.35)),  # diagonal
    ((0.2, 0.35), (0.8, 1.0)),  # back diagonal
)


def _stamp_segment(cover, x0, y0, x1, y1, width):
    """Coverage of a round-capped segment of `width` pixels, max-combined into `cover`."""
    h, w = len(cover), len(cover[0])
    r = width / 2
    lo_x, hi_x = max(0, int(min(x0, x1) - r - 1)), min(w - 1, int(max(x0, x1) + r + 1))
    lo_y, hi_y = max(0, int(min(y0, y1) - r - 1)), min(h - 1, int(max(y0, y1) + r + 1))
    dx, dy = x1 - x0, y1 - y0
    ll = dx * dx + dy * dy or 1e-9
    for y in range(lo_y, hi_y + 1):
        py = y + 0.5
        row = cover[y]
        for x in range(lo_x, hi_x + 1):
            px = x + 0.5
            t = max(0.0, min(1.0, ((px - x0) * dx + (py - y0) * dy) / ll))
            d = math.hypot(px - x0 - t * dx, py - y0 - t * dy)
            row[x] = max(row[x], _clamp(r + 0.5 - d))


def _stamp_ring(cover, cx, cy, radius, width):
    steps = 10
    for s in range(steps):
        a0, a1 = 2 * math.pi * s / steps, 2 * math.pi * (s + 1) / steps
        _stamp_segment(
            cover,
            cx + radius * math.cos(a0),
            cy + radius * math.sin(a0),
            cx + radius * math.cos(a1),
            cy + radius * math.sin(a1),
            width,
        )


def paper_text(side, seed):
    fibres = fbm(side, side, 8, 32, 3, seed)
    cover = [[0.0] * side for _ in range(side)]
    line_h = max(8, side // 16)
    gw, gh = line_h * 0.42, line_h * 0.62
    pen = max(1.0, line_h / 12)
    margin = side // 10
    y_base = margin + gh
    line = 0
    while y_base < side - margin:
        x = margin + (line_h if unit_hash(seed, line, 3) < 0.2 else 0)
        # The last line of a paragraph stops short; a paragraph ends after 3-6 lines.
        ends_paragraph = unit_hash(seed, line, 4) < 0.22
        stop = side - margin - (side * 0.4 * unit_hash(seed, line, 5) if ends_paragraph else 0)
        word = 0
        while True:
            letters = 2 + int(7 * unit_hash(seed, line, word, 1))
            if x + letters * gw > stop:
                break
            for k in range(letters):
                g = unit_hash(seed, line, word, 10 + k)
                top = y_base - gh
                strokes = [_STROKES[int(g * 8) % 8]]
                if unit_hash(seed, line, word, 40 + k) < 0.6:
                    strokes.append(_STROKES[int(unit_hash(seed, line, word, 70 + k) * 8) % 8])
                for (ax, ay), (bx, by) in strokes:
                    _stamp_segment(cover, x + ax * gw, top + ay * gh, x + bx * gw, top + by * gh, pen)
                if g > 0.8:
                    _stamp_ring(cover, x + 0.5 * gw, top + 0.68 * gh, 0.3 * gw, pen)
                x += gw
            x += gw * 0.9
            word += 1
        y_base += line_h * (2 if ends_paragraph else 1)
        line += 1
    paper, ink = (0.93, 0.91, 0.85), (0.08, 0.08, 0.14)
    return [
        [_mix(tuple(c * (0.94 + 0.06 * f) for c in paper), ink, k) for f, k in zip(fr, cr)]
        for fr, cr in zip(fibres, cover)
    ]


def _grain(side, seed, img, amount=0.04):
    noise = value_noise(side, side, side // 2, side // 2, seed)
    return [[tuple(_clamp(c + amount * (n - 0.5)) for c in p) for p, n in zip(row, nr)] for row, nr in zip(img, noise)]


def photo_landscape(side, seed):
    ridge = [0.5 + 0.5 * v for v in value_noise(side, 1, 6, 1, seed)[0]]
    far = [0.5 + 0.5 * v for v in value_noise(side, 1, 3, 1, seed + 1)[0]]
    sun_x, sun_y, sun_r = side * (0.2 + 0.6 * unit_hash(seed, 1)), side * 0.22, side * 0.07
    lake = 0.8 * side
    img = []
    for y in range(side):
        v = y / side
        row = []
        for x in range(side):
            sky = _mix((0.25, 0.45, 0.8), (0.95, 0.8, 0.6), v / 0.7)
            d = math.hypot(x - sun_x, y - sun_y)
            c = _mix(sky, (1.0, 0.95, 0.75), _clamp(1.5 - d / sun_r) + 0.35 * math.exp(-d / (3 * sun_r)))
            hill_far = side * (0.45 + 0.12 * far[x])
            hill_near = side * (0.55 + 0.15 * ridge[x])
            if y > hill_far:
                c = _mix((0.45, 0.5, 0.62), (0.35, 0.42, 0.45), (y - hill_far) / side * 4)
            if y > hill_near:
                c = _mix((0.25, 0.42, 0.16), (0.14, 0.25, 0.08), _clamp((y - hill_near) / (side * 0.3)))
            if y > lake:
                # The lake mirrors the sky, darker.
                c = _mix((0.3, 0.45, 0.65), (0.15, 0.25, 0.4), (y - lake) / (side - lake))
            row.append(c)
        img.append(row)
    return _grain(side, seed + 5, img)


def photo_still_life(side, seed):
    table = 0.62 * side
    fruit = [
        (side * (0.3 + 0.12 * k), table - side * 0.06, side * (0.07 + 0.02 * unit_hash(seed, k)), col)
        for k, col in enumerate(((0.85, 0.25, 0.1), (0.9, 0.7, 0.15), (0.35, 0.6, 0.15)))
    ]
    vase_x, vase_w, vase_top = side * 0.72, side * 0.09, side * 0.3
    light = (-0.5, -0.7)
    img = []
    for y in range(side):
        row = []
        for x in range(side):
            if y < table:
                c = _mix(
                    (0.35, 0.3, 0.35), (0.6, 0.5, 0.45), _clamp(1.0 - math.hypot(x - side * 0.4, y - side * 0.3) / side)
                )
            else:
                c = _mix((0.5, 0.33, 0.2), (0.3, 0.18, 0.1), (y - table) / (side - table))
            if vase_top < y < table and abs(x - vase_x) < vase_w * (
                1.0 - 0.5 * math.sin(math.pi * (y - vase_top) / (table - vase_top))
            ):
                shade = 0.6 + 0.4 * _clamp(1.0 - (x - vase_x + vase_w * 0.5) / (2 * vase_w))
                c = tuple(v * shade for v in (0.3, 0.45, 0.7))
            for fx, fy, r, col in fruit:
                dx, dy = (x - fx) / r, (y - fy) / r
                if dx * dx + dy * dy < 1.0:
                    dz = math.sqrt(1.0 - dx * dx - dy * dy)
                    lam = max(0.0, dx * light[0] + dy * light[1] + dz * 0.5) / 1.1
                    c = tuple(_clamp(v * (0.25 + 0.75 * lam) + 0.3 * lam**12) for v in col)
            row.append(c)
        img.append(row)
    return _grain(side, seed + 6, img)


def marble(side, seed):
    turb = fbm(side, side, 4, 4, 5, seed)
    img = []
    for y in range(side):
        row = []
        for x in range(side):
            # An integer number of vein periods across the image keeps the pattern periodic.
            s = math.sin(2 * math.pi * (2 * x / side + 1 * y / side + 2.2 * turb[y][x]))
            vein = abs(s) ** 0.35
            row.append(_mix((0.42, 0.42, 0.45), (0.9, 0.89, 0.86), vein))
        img.append(row)
    return img


def plaster(side, seed):
    n = fbm(side, side, 8, 8, 4, seed)
    return [[(0.78 + 0.2 * (v - 0.5), 0.77 + 0.2 * (v - 0.5), 0.74 + 0.2 * (v - 0.5)) for v in row] for row in n]


def leaves(side, seed):
    """Leaves (ellipses along a direction, a midrib) on a transparent ground."""
    img = [[(0.0, 0.0, 0.0, 0.0)] * side for _ in range(side)]
    vary = value_noise(side, side, 8, 8, seed)
    for k in range(14):
        cx, cy = side * unit_hash(seed, k, 1), side * unit_hash(seed, k, 2)
        a = 2 * math.pi * unit_hash(seed, k, 3)
        length, width = side * (0.18 + 0.1 * unit_hash(seed, k, 4)), side * 0.05
        ux, uy = math.cos(a), math.sin(a)
        green = (0.15 + 0.15 * unit_hash(seed, k, 5), 0.45 + 0.2 * unit_hash(seed, k, 6), 0.1)
        reach = int(length) + 2
        for y in range(int(cy) - reach, int(cy) + reach):
            for x in range(int(cx) - reach, int(cx) + reach):
                # Wrapped, so the spray tiles.
                dx, dy = x + 0.5 - cx, y + 0.5 - cy
                s, t = (dx * ux + dy * uy) / length, (-dx * uy + dy * ux) / width
                # A leaf: |t| below a lens profile over s in [-1, 1].
                edge = math.sqrt(max(0.0, 1.0 - s * s)) * (1.0 - 0.3 * s)
                if abs(t) < edge:
                    rib = 0.75 if abs(t) < 0.08 else 1.0
                    v = vary[y % side][x % side]
                    img[y % side][x % side] = tuple(_clamp(c * (0.8 + 0.4 * v) * rib) for c in green) + (1.0,)
    return img


def grille(side, seed):
    bars = 8
    cell = side // bars
    bar = max(2, cell // 4)
    rust = value_noise(side, side, 16, 16, seed)
    img = []
    for y in range(side):
        row = []
        for x in range(side):
            on = x % cell < bar or y % cell < bar
            v = 0.55 + 0.2 * rust[y][x]
            row.append((v, v * 0.97, v * 0.92, 1.0 if on else 0.0))
        img.append(row)
    return img


GENERATORS = {
    "wood-planks": wood_planks,
    "tiles": tiles,
    "fabric": fabric,
    "paper-text": paper_text,
    "photo-landscape": photo_landscape,
    "photo-still-life": photo_still_life,
    "marble": marble,
    "plaster": plaster,
    "leaves": leaves,
    "grille": grille,
}


def image(name, side, seed):
    """The texture `name` of the library at side x side pixels, from `seed`."""
    return GENERATORS[name](side, seed * 101 + NAMES.index(name))


# --- PNG -----------------------------------------------------------------------------------------


def png_bytes(img):
    """An 8-bit RGB or RGBA PNG (by the pixels' tuple length) of `img`, each row with the Up
    filter (PNG 1.2, section 6), zlib level 9."""
    channels = len(img[0][0])
    colour_type = {3: 2, 4: 6}[channels]
    h, w = len(img), len(img[0])
    raw = bytearray()
    prev = bytes(w * channels)
    for row in img:
        line = bytes(int(c * 255.0 + 0.5) for p in row for c in p)
        raw.append(2)
        raw += bytes((a - b) & 0xFF for a, b in zip(line, prev))
        prev = line

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", w, h, 8, colour_type, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(bytes(raw), 9))
        + chunk(b"IEND", b"")
    )


def write_library(directory, side, seed, names=NAMES):
    """Writes <directory>/<name>.png for each name, rewriting only files whose bytes changed (so
    make sees unchanged textures as up to date); the paths."""
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in names:
        path = directory / f"{name}.png"
        data = png_bytes(image(name, side, seed))
        if not path.exists() or path.read_bytes() != data:
            tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")  # make -j may run two writers
            tmp.write_bytes(data)
            tmp.replace(path)
        paths.append(path)
    return paths
