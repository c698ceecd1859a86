"""Every scene data-gen/generate.py writes compiles with the texture library it writes, and the
compiled scenes carry the textures they name (the scene-compile stage of LUXEST_BIN_DIR, as in
test_slurm.py: make test-slurm builds it first). The generator's own checks, which need no stage,
are training/tests/test_generate.py."""

import os
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def scene_compile():
    path = Path(os.environ.get("LUXEST_BIN_DIR", ROOT / "target" / "debug")) / "scene-compile"
    if not path.exists():
        pytest.fail(f"{path}: missing (build it first: cargo build -p scene-compile, or set LUXEST_BIN_DIR)")
    return str(path)


def test_generated_scenes_compile_with_their_textures(tmp_path):
    compiler = scene_compile()
    out = tmp_path / "scenes"
    subprocess.run(
        ["python3", "data-gen/generate.py", "--scenes", "24", "--side", "16", "--out", str(out)],
        cwd=ROOT,
        check=True,
        capture_output=True,
    )
    scenes = sorted(out.glob("*/*.ron"))
    assert len(scenes) == 24
    textured = 0
    for ron in scenes:
        lxs = tmp_path / "compiled" / f"{ron.stem}.lxs"
        r = subprocess.run([compiler, "-q", str(ron), "-o", str(lxs)], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        assert r.stderr == "", r.stderr  # no warning: every texture and material is used
        info = subprocess.run([compiler, "--info", str(lxs)], capture_output=True, text=True, check=True).stdout
        declared = re.findall(r'^\s+"(t\d+)": \(path: "([^"]+)"', ron.read_text(), re.M)
        textured += bool(declared)
        # Each texture the scene declares is in the compiled file: its name, its image, the
        # library's side.
        compiled = re.findall(r'name: "(t\d+)",\s+source: "([^"]+)",\s+width: (\d+),\s+height: (\d+)', info)
        assert sorted(compiled) == sorted((n, p, "256", "256") for n, p in declared), ron
    assert 12 <= textured <= 22
