#!/usr/bin/env python3
"""Writes the small example meshes checked in under scenes/meshes/ (standard library only).

- torus.obj: a torus (R = 0.3 m, r = 0.1 m) as 48 x 24 quads with vertex normals and texture
  coordinates, the way modelling tools export it (polygons are triangulated on load): u once
  around the ring, v once around the tube, on a (48 + 1) x (24 + 1) grid so that the seams
  get u = 1 on one side and 0 on the other (faces index positions and coordinates separately).
- trefoil.glb: a tube around a trefoil knot, binary glTF 2.0 with indexed triangles, normals,
  texture coordinates (TEXCOORD_0: u once along the knot, v once around the tube; the seam
  vertices doubled) and a node transform (scale 0.1, translation), exercising the glTF node
  hierarchy.

Re-running reproduces the files byte for byte.
"""

import json
import math
import struct
from pathlib import Path

OUT = Path(__file__).resolve().parent.parent / "scenes" / "meshes"


def torus_obj(R=0.3, r=0.1, nu=48, nv=24):
    lines = ["# torus R=0.3 r=0.1, 48x24 quads, written by data-gen/example_meshes.py", "o torus"]
    for i in range(nu):
        u = 2 * math.pi * i / nu
        for j in range(nv):
            v = 2 * math.pi * j / nv
            x = (R + r * math.cos(v)) * math.cos(u)
            z = (R + r * math.cos(v)) * math.sin(u)
            y = r * math.sin(v)
            lines.append(f"v {x:.6f} {y:.6f} {z:.6f}")
    for i in range(nu + 1):
        for j in range(nv + 1):
            lines.append(f"vt {i / nu:.6f} {j / nv:.6f}")
    for i in range(nu):
        u = 2 * math.pi * i / nu
        for j in range(nv):
            v = 2 * math.pi * j / nv
            lines.append(f"vn {math.cos(v) * math.cos(u):.6f} {math.sin(v):.6f} {math.cos(v) * math.sin(u):.6f}")
    idx = lambda i, j: (i % nu) * nv + (j % nv) + 1
    uv = lambda i, j: i * (nv + 1) + j + 1
    for i in range(nu):
        for j in range(nv):
            corners = ((i, j), (i, j + 1), (i + 1, j + 1), (i + 1, j))
            lines.append("f " + " ".join(f"{idx(*c)}/{uv(*c)}/{idx(*c)}" for c in corners))
    return "\n".join(lines) + "\n"


def trefoil_glb(nu=256, nv=12, tube=0.35):
    def curve(t):
        return (math.sin(t) + 2 * math.sin(2 * t), math.cos(t) - 2 * math.cos(2 * t), -math.sin(3 * t))

    pos, nrm, tex, idx = [], [], [], []
    for i in range(nu):
        t = 2 * math.pi * i / nu
        p = curve(t)
        q = curve(t + 1e-4)
        tng = [q[k] - p[k] for k in range(3)]
        ln = math.sqrt(sum(c * c for c in tng))
        tng = [c / ln for c in tng]
        # A normal frame from a fixed helper axis (the knot never runs parallel to z for long).
        a = (0.0, 0.0, 1.0)
        n1 = [tng[1] * a[2] - tng[2] * a[1], tng[2] * a[0] - tng[0] * a[2], tng[0] * a[1] - tng[1] * a[0]]
        ln = math.sqrt(sum(c * c for c in n1))
        n1 = [c / ln for c in n1]
        n2 = [tng[1] * n1[2] - tng[2] * n1[1], tng[2] * n1[0] - tng[0] * n1[2], tng[0] * n1[1] - tng[1] * n1[0]]
        ring = []
        for j in range(nv):
            v = 2 * math.pi * j / nv
            n = [math.cos(v) * n1[k] + math.sin(v) * n2[k] for k in range(3)]
            ring.append(([p[k] + tube * n[k] for k in range(3)], n))
        # The seam around the tube: its first vertex again, with v = 1.
        for j, (q, n) in enumerate(ring + ring[:1]):
            pos.append(q)
            nrm.append(n)
            tex.append((i / nu, j / nv))
    # The seam along the knot: the first ring again, with u = 1.
    first = nv + 1
    pos += pos[:first]
    nrm += nrm[:first]
    tex += [(1.0, t[1]) for t in tex[:first]]
    for i in range(nu):
        for j in range(nv):
            a = i * first + j
            b = i * first + j + 1
            c = (i + 1) * first + j + 1
            d = (i + 1) * first + j
            # Counter-clockwise seen from outside: (b - a) x (c - a) ~ dn/dv x T points along n.
            idx += [a, b, c, a, c, d]
    pbytes = b"".join(struct.pack("<3f", *p) for p in pos)
    nbytes = b"".join(struct.pack("<3f", *n) for n in nrm)
    tbytes = b"".join(struct.pack("<2f", *t) for t in tex)
    ibytes = b"".join(struct.pack("<I", i) for i in idx)
    binary = ibytes + pbytes + nbytes + tbytes
    mins = [min(p[k] for p in pos) for k in range(3)]
    maxs = [max(p[k] for p in pos) for k in range(3)]
    doc = {
        "asset": {"version": "2.0", "generator": "luxest data-gen/example_meshes.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "trefoil", "children": [1], "scale": [0.1, 0.1, 0.1]},
            {"name": "tube", "mesh": 0, "translation": [0.0, 0.0, 0.0]},
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 1, "NORMAL": 2, "TEXCOORD_0": 3}, "indices": 0, "mode": 4}]}
        ],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(ibytes), "target": 34963},
            {"buffer": 0, "byteOffset": len(ibytes), "byteLength": len(pbytes), "target": 34962},
            {"buffer": 0, "byteOffset": len(ibytes) + len(pbytes), "byteLength": len(nbytes), "target": 34962},
            {
                "buffer": 0,
                "byteOffset": len(ibytes) + len(pbytes) + len(nbytes),
                "byteLength": len(tbytes),
                "target": 34962,
            },
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
            {"bufferView": 1, "componentType": 5126, "count": len(pos), "type": "VEC3", "min": mins, "max": maxs},
            {"bufferView": 2, "componentType": 5126, "count": len(nrm), "type": "VEC3"},
            {"bufferView": 3, "componentType": 5126, "count": len(tex), "type": "VEC2"},
        ],
    }
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * ((4 - len(js) % 4) % 4)
    binary += b"\0" * ((4 - len(binary) % 4) % 4)
    chunks = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks


if __name__ == "__main__":
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "torus.obj").write_text(torus_obj())
    (OUT / "trefoil.glb").write_bytes(trefoil_glb())
    print(f"wrote {OUT / 'torus.obj'} and {OUT / 'trefoil.glb'}")
