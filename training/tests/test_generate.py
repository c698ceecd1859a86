"""The dataset generator (data-gen/generate.py) and its texture library (data-gen/textures.py).

The library's images are PNGs that an independent decoder (Pillow) reads back, checksums
verified, as exactly the pixels the library computes; the repeating patterns have no seam larger
than their largest step inside; the library and the scenes regenerate byte for byte whatever
the interpreter's hash seed. The generated scenes name only library images, texture about three
rooms in four and never a sphere (it has no texture coordinates), texture Lambertian, glossy,
plastic and metal materials, and vary the texture scales.
That every generated scene compiles needs the scene-compile stage: pipelines/tests/test_generated_scenes.py.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "data-gen"))
import textures  # noqa: E402

SIDE = 64


def test_library_images_are_pngs_of_the_computed_pixels(tmp_path):
    paths = textures.write_library(tmp_path, SIDE, 3)
    assert [p.name for p in paths] == [f"{n}.png" for n in textures.NAMES]
    for name, path in zip(textures.NAMES, paths):
        with Image.open(path) as im:
            im.verify()  # chunk checksums and structure
        with Image.open(path) as im:
            assert im.format == "PNG" and im.size == (SIDE, SIDE), name
            assert im.mode == ("RGBA" if name in textures.CUT_OUTS else "RGB"), name
            decoded = np.asarray(im)
        computed = np.array(textures.image(name, SIDE, 3))
        assert computed.min() >= 0.0 and computed.max() <= 1.0, name
        assert np.array_equal(decoded, np.floor(computed * 255.0 + 0.5)), name
        # Not flat: every image has structure.
        assert decoded[..., :3].std() > 5.0, name
    # A second write changes no file (make sees them as up to date).
    times = [p.stat().st_mtime_ns for p in paths]
    textures.write_library(tmp_path, SIDE, 3)
    assert [p.stat().st_mtime_ns for p in paths] == times
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in paths)


def test_cut_outs_are_partly_transparent_and_patterns_repeat_without_seams():
    for name in textures.CUT_OUTS:
        alpha = np.array(textures.image(name, SIDE, 1))[..., 3]
        assert set(np.unique(alpha)) == {0.0, 1.0} and 0.1 < alpha.mean() < 0.9, name
    for name in textures.TILING:
        img = np.array(textures.image(name, SIDE, 1))
        for a in (img, img.transpose(1, 0, 2)):
            largest_step = np.abs(np.diff(a, axis=1)).mean(axis=(0, 2)).max()
            seam = np.abs(a[:, -1] - a[:, 0]).mean()
            assert seam <= largest_step, name


def _run(args, hash_seed):
    env = {**os.environ, "PYTHONHASHSEED": str(hash_seed)}
    return subprocess.run(args, cwd=ROOT, env=env, check=True, capture_output=True).stdout


def test_library_and_scenes_regenerate_byte_for_byte_whatever_the_hash_seed(tmp_path):
    library = (
        "import sys; sys.path.insert(0, 'data-gen'); import textures; "
        "sys.stdout.buffer.write(b''.join(textures.png_bytes(textures.image(n, 32, 5)) for n in textures.NAMES))"
    )
    runs = [_run(["python3", "-c", library], s) for s in (0, 4242)]
    assert runs[0] == runs[1] == b"".join(textures.png_bytes(textures.image(n, 32, 5)) for n in textures.NAMES)
    for s in (0, 4242):
        _run(
            ["python3", "data-gen/generate.py", "--scenes", "12", "--side", "16", "--only", "scenes"]
            + ["--out", str(tmp_path / str(s))],
            s,
        )
    first = sorted((tmp_path / "0").glob("*/*.ron"))
    assert len(first) == 12
    assert all(p.read_text() == (tmp_path / "4242" / p.relative_to(tmp_path / "0")).read_text() for p in first)


def test_generated_rooms_use_the_library(tmp_path):
    subprocess.run(
        [
            "python3",
            "data-gen/generate.py",
            "--preset",
            "full",
            "--side",
            "32",
            "--only",
            "scenes",
            "--out",
            str(tmp_path),
        ],
        cwd=ROOT,
        check=True,
        capture_output=True,
    )
    assert not (tmp_path / "textures").exists()
    listed = subprocess.run(
        ["python3", "data-gen/generate.py", "--list-textures"], cwd=ROOT, check=True, capture_output=True, text=True
    )
    assert listed.stdout.split() == [f"textures/{n}.png" for n in textures.NAMES]
    scenes = sorted(tmp_path.glob("*/*.ron"))
    assert len(scenes) == 240
    textured, used, scales, opacities, emitters, kinds = 0, set(), set(), 0, 0, set()
    for path in scenes:
        text = path.read_text()
        if "textures: {" not in text:
            assert "surfaces:" not in text and "Texture(" not in text, path
            continue
        textured += 1
        for image in re.findall(r'path: "([^"]*\.png)"', text):
            assert image.startswith("../textures/") and image[12:-4] in textures.NAMES, (path, image)
            used.add(image[12:-4])
        scales |= set(re.findall(r"uv_transform: \(\(([-\d.]+), ([-\d.]+)", text))
        surfaced = set(re.findall(r'^\s+"(m\d+)": \(color:', text, re.M))
        spheres = set(re.findall(r'shape: Sphere\(.*material: "(m\d+)"', text))
        assert surfaced and not surfaced & spheres, path
        for m in surfaced:
            kinds.add(re.search(rf'^\s+"{m}": (\w+)\(', text, re.M).group(1))
        opacities += "opacity:" in text
        emitters += "emission: Texture(" in text
    assert 0.65 * len(scenes) < textured < 0.85 * len(scenes)
    assert used == set(textures.NAMES)
    assert len(scales) > 200 and opacities > 20 and emitters > 20
    # Textures tint every kind of material that has a main colour.
    assert kinds == {"Lambertian", "Glossy", "Plastic", "Conductor"}
