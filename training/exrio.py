"""EXR input/output for the training scripts, standard library + numpy only.

Reads the files luxest writes (scanline, ZIP16 or uncompressed, FLOAT R, G, B) and writes
uncompressed scanline FLOAT RGB files that OpenEXR (and luxest) read."""
import struct
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "pipelines"))
import exr as _exr  # noqa: E402


def read(path):
    """Float32 array of shape (H, W, 3)."""
    w, h, pixels = _exr.read_rgb(str(path))
    return np.asarray(pixels, dtype=np.float32).reshape(h, w, 3)


def _attr(name, typ, data):
    return name.encode() + b"\0" + typ.encode() + b"\0" + struct.pack("<i", len(data)) + data


def write(path, image):
    """Writes (H, W, 3) float32 as an uncompressed scanline EXR (atomically)."""
    image = np.ascontiguousarray(image, dtype=np.float32)
    h, w, _ = image.shape
    channels = b"".join(c + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in (b"B", b"G", b"R")) + b"\0"
    header = b"\x76\x2f\x31\x01" + struct.pack("<i", 2)
    header += _attr("channels", "chlist", channels)
    header += _attr("compression", "compression", b"\0")
    header += _attr("dataWindow", "box2i", struct.pack("<4i", 0, 0, w - 1, h - 1))
    header += _attr("displayWindow", "box2i", struct.pack("<4i", 0, 0, w - 1, h - 1))
    header += _attr("lineOrder", "lineOrder", b"\0")
    header += _attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
    header += _attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
    header += _attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
    header += b"\0"
    line_bytes = 8 + w * 4 * 3
    first = len(header) + 8 * h
    offsets = struct.pack(f"<{h}Q", *(first + y * line_bytes for y in range(h)))
    body = bytearray()
    for y in range(h):
        body += struct.pack("<ii", y, w * 12)
        for c in (2, 1, 0):  # B, G, R: channels in alphabetical order
            body += image[y, :, c].tobytes()
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(header + offsets + bytes(body))
    tmp.replace(path)
