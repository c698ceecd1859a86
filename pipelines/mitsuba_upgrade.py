"""Upgrade a Mitsuba 0.6 scene file to one Mitsuba 3 loads, for `make bench-scenes`.

Mitsuba 3 reads version 0.x files itself (camelCase property names become snake_case, `uscale`
and friends a `to_uv` transform, `diffuseReflectance` of `diffuse` its `reflectance`), but it
rejects what 0.6 had and 3 has not. Bitterli's rendering resources are distributed for Mitsuba
0.6, so neither Mitsuba 3 nor luxest loads them as published; this script writes a copy beside
the original that both load, changing only what Mitsuba 3 cannot read, every change listed in a
comment at the top of the output and printed:

- `<integrator>` elements are removed (both renderers are given theirs on the command line);
- `extEta` of `conductor` / `roughconductor` (the exterior medium's index, which Mitsuba 3's
  conductors do not have) is folded into the conductor's own `eta` and `k` (both divided by it,
  exact: a conductor's Fresnel term depends on their ratios); 1 is simply dropped;
- bitmap `filterType` `trilinear` / `ewa` (mip-mapped filtering) becomes `bilinear`;
- film `gamma` (a display setting of 0.6's films) is dropped; bitmap `gamma` 1 (data stored
  linearly) becomes Mitsuba 3's `raw`, −1 (sRGB, the default) is dropped;
- `bumpmap` (not read by luxest yet) is replaced by the BSDF it wraps — an approximation,
  listed as such;
- `roughdiffuse` (Oren–Nayar, which Mitsuba 3 does not have) becomes `diffuse` with its
  reflectance — an approximation, listed as such.

Anything else Mitsuba 3 cannot read is left for it (and luxest) to reject with a message.
The output keeps `version="0.6.0"`, so Mitsuba 3's own upgrade still applies, and references the
same meshes and textures (it is written into the same directory).

Usage: python mitsuba_upgrade.py SCENE_0.6.xml -o SCENE.xml
Standard library only."""

import argparse
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

CONDUCTORS = ("conductor", "roughconductor")
MIP_FILTERS = ("trilinear", "ewa")


def prop(elem, name):
    """The direct child property element of `elem` called `name` (0.6 or 3 spelling)."""
    snake = "".join("_" + c.lower() if c.isupper() and i and name[i - 1].islower() else c for i, c in enumerate(name))
    for c in elem:
        if c.get("name") in (name, snake):
            return c
    return None


def scale_colour(elem, factor):
    """Divides an `<rgb>`/`<spectrum>`/`<float>` property's value by `factor`; False if the
    value is not a plain list of numbers."""
    try:
        values = [float(v) for v in elem.get("value", "").replace(",", " ").split()]
    except ValueError:
        return False
    if not values:
        return False
    elem.set("value", ", ".join(f"{v / factor:.9g}" for v in values))
    return True


def upgrade(root):
    """Changes the tree in place; returns the list of changes (one line each)."""
    changes = []
    parents = {c: p for p in root.iter() for c in p}
    for integ in [e for e in root.iter("integrator")]:
        parents[integ].remove(integ)
        changes.append(f'removed <integrator type="{integ.get("type")}"> (renderers get theirs on the command line)')
    for bsdf in root.iter("bsdf"):
        kind = bsdf.get("type")
        where = f'<bsdf type="{kind}"{" id=" + repr(bsdf.get("id")) if bsdf.get("id") else ""}>'
        if kind in CONDUCTORS:
            ext = prop(bsdf, "extEta")
            if ext is not None:
                factor = float(ext.get("value"))
                bsdf.remove(ext)
                if factor != 1.0:
                    eta, k = prop(bsdf, "eta"), prop(bsdf, "k")
                    if eta is None or k is None or not (scale_colour(eta, factor) and scale_colour(k, factor)):
                        sys.exit(f"error: {where}: extEta {factor} with a named or missing eta/k cannot be folded")
                    changes.append(f"{where}: extEta {factor} folded into eta and k")
                else:
                    changes.append(f"{where}: extEta 1 dropped")
        if kind == "roughdiffuse":
            bsdf.set("type", "diffuse")
            for name in ("alpha", "useFastApprox"):
                p = prop(bsdf, name)
                if p is not None:
                    bsdf.remove(p)
            changes.append(f"{where}: became diffuse with the same reflectance (APPROXIMATION: Oren-Nayar dropped)")
    for bump in [e for e in root.iter("bsdf") if e.get("type") == "bumpmap"]:
        inner = [c for c in bump if c.tag in ("bsdf", "ref")]
        if len(inner) != 1:
            sys.exit('error: <bsdf type="bumpmap"> without exactly one nested BSDF')
        parent = parents[bump]
        i = list(parent).index(bump)
        parent.remove(bump)
        parent.insert(i, inner[0])
        if bump.get("id") and inner[0].tag == "bsdf" and not inner[0].get("id"):
            inner[0].set("id", bump.get("id"))
        changes.append('<bsdf type="bumpmap">: replaced by its nested BSDF (APPROXIMATION: bump mapping dropped)')
    for tex in root.iter("texture"):
        if tex.get("type") != "bitmap":
            continue
        g = prop(tex, "gamma")
        if g is not None:
            value = float(g.get("value"))
            tex.remove(g)
            if value == 1.0:
                ET.SubElement(tex, "boolean", name="raw", value="true")
            elif value != -1.0:
                sys.exit(f"error: bitmap gamma {value}: only 1 (linear) and -1 (sRGB) have a Mitsuba 3 equivalent")
            changes.append(
                f"bitmap {prop(tex, 'filename').get('value')!r}: gamma {g.get('value')} -> {'raw' if value == 1.0 else 'sRGB (default)'}"
            )
        f = prop(tex, "filterType")
        if f is not None and f.get("value") in MIP_FILTERS:
            changes.append(f"bitmap {prop(tex, 'filename').get('value')!r}: filterType {f.get('value')} -> bilinear")
            f.set("value", "bilinear")
    for film in root.iter("film"):
        g = prop(film, "gamma")
        if g is not None:
            film.remove(g)
            changes.append(f"<film>: gamma {g.get('value')} dropped")
    return changes


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", type=Path)
    ap.add_argument("-o", "--out", type=Path, required=True)
    a = ap.parse_args(argv)
    if a.out.resolve() == a.scene.resolve():
        sys.exit(f"error: {a.out}: the output would overwrite its input")
    if a.out.resolve().parent != a.scene.resolve().parent:
        sys.exit(f"error: {a.out}: must be written beside {a.scene} (it references the same files)")
    try:
        tree = ET.parse(a.scene)
    except (ET.ParseError, OSError) as e:
        sys.exit(f"error: {a.scene}: {e}")
    root = tree.getroot()
    version = root.get("version", "")
    if not version.startswith("0."):
        sys.exit(f"error: {a.scene}: version {version!r} is not a Mitsuba 0.x scene")
    changes = upgrade(root)
    note = "\n".join(
        [f" Upgraded for Mitsuba 3 from {a.scene.name} by pipelines/mitsuba_upgrade.py:"]
        + [f"  - {c}" for c in changes]
    )
    root.insert(0, ET.Comment(note.replace("--", "-") + "\n"))
    tmp = a.out.with_name(a.out.name + ".tmp")
    tree.write(tmp, encoding="unicode", xml_declaration=False)
    tmp.replace(a.out)
    for c in changes:
        print(c)


if __name__ == "__main__":
    main()
