"""Minimal reader for the EXR files luxest writes (scanline, ZIP16 or no compression, FLOAT
R, G, B channels), standard library only, for the pipeline scripts. Not a general OpenEXR
reader: other layouts raise ValueError."""
import struct
import zlib


def read_rgb(path):
    """Returns (width, height, pixels) with pixels a row-major list of (r, g, b) floats."""
    d = open(path, "rb").read()
    if d[:4] != b"\x76\x2f\x31\x01":
        raise ValueError(f"{path}: not an OpenEXR file")
    pos, attrs = 8, {}
    while d[pos] != 0:
        e = d.index(b"\0", pos)
        name = d[pos:e].decode()
        pos = e + 1
        e = d.index(b"\0", pos)
        pos = e + 1
        size = struct.unpack("<i", d[pos:pos + 4])[0]
        pos += 4
        attrs[name] = d[pos:pos + size]
        pos += size
    pos += 1
    compression = attrs["compression"][0]
    if compression not in (0, 3):
        raise ValueError(f"{path}: compression {compression} is not supported here (only none and ZIP16)")
    channels, cpos, cl = [], 0, attrs["channels"]
    while cl[cpos] != 0:
        e = cl.index(b"\0", cpos)
        name = cl[cpos:e].decode()
        ptype = struct.unpack("<i", cl[e + 1:e + 5])[0]
        if ptype != 2:
            raise ValueError(f"{path}: channel {name} is not FLOAT")
        channels.append(name)
        cpos = e + 1 + 16
    if sorted(channels) != ["B", "G", "R"]:
        raise ValueError(f"{path}: expected channels R, G, B; found {', '.join(channels)}")
    xmin, ymin, xmax, ymax = struct.unpack("<4i", attrs["dataWindow"])
    w, h = xmax - xmin + 1, ymax - ymin + 1
    lines_per_block = 16 if compression == 3 else 1
    nblocks = (h + lines_per_block - 1) // lines_per_block
    offsets = struct.unpack(f"<{nblocks}Q", d[pos:pos + 8 * nblocks])
    pixels = [None] * (w * h)
    for o in offsets:
        y, size = struct.unpack("<ii", d[o:o + 8])
        raw = d[o + 8:o + 8 + size]
        lines = min(lines_per_block, h - (y - ymin))
        if compression == 3 and size < w * 4 * len(channels) * lines:
            t = bytearray(zlib.decompress(raw))
            for i in range(1, len(t)):
                t[i] = (t[i - 1] + t[i] - 128) & 255
            half = (len(t) + 1) // 2
            raw = bytearray(len(t))
            raw[0::2] = t[:half]
            raw[1::2] = t[half:]
        per = w * 4
        for l in range(lines):
            base = l * len(channels) * per
            vals = {c: struct.unpack(f"<{w}f", raw[base + k * per:base + (k + 1) * per]) for k, c in enumerate(channels)}
            row = (y - ymin + l) * w
            for i in range(w):
                pixels[row + i] = (vals["R"][i], vals["G"][i], vals["B"][i])
    return w, h, pixels
