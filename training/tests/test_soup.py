"""Tests of soup.py: the weighted mean of the ingredients' weights, from runs and exported models
alike; other networks and overwriting an ingredient refused in one line."""

import hashlib
import json
import sys
from pathlib import Path

import pytest
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import config  # noqa: E402
import export  # noqa: E402
import luxest_contract as contract  # noqa: E402
import model  # noqa: E402
import soup  # noqa: E402
import transfer  # noqa: E402


# Soups of the small direct-head network: soup.py averages whatever weights its ingredients
# share, whatever the head, and a direct-head network exports in seconds (conftest.py).
NETWORK = {"head": "direct", "features": ["hdr", "alb", "nrm"], "detail_gate": False}


def run_dir(path, seed, width=8):
    """A run directory holding a randomly initialised network (config.json, checkpoint.pt)."""
    torch.manual_seed(seed)
    cfg = config.Config(base_width=width, **NETWORK)
    net = model.denoiser(cfg)
    path.mkdir(parents=True)
    cfg.save(path / "config.json")
    torch.save({"model": net.state_dict(), "step": 0}, path / "checkpoint.pt")
    return net.state_dict()


@pytest.fixture(scope="module")
def runs(models, tmp_path_factory):
    """Two runs of one network, the second also exported: the shared `direct` model."""
    tmp = tmp_path_factory.mktemp("runs")
    b_run, b_onnx = models["direct"]["run"], models["direct"]["onnx"]
    assert {k: v for k, v in json.loads((b_run / "config.json").read_text()).items() if k in NETWORK} == NETWORK
    a = run_dir(tmp / "a", 1)
    b = torch.load(b_run / "checkpoint.pt", weights_only=False)["model"]
    return {"a": tmp / "a", "b": b_run, "b.onnx": b_onnx}, a, b


@pytest.mark.models("direct")
def test_soup_is_the_weighted_mean_of_the_ingredients(runs):
    src, a, b = runs
    # A run directory, a checkpoint and an exported model are the same kind of ingredient.
    for ingredients in ([src["a"], src["b"]], [src["a"] / "checkpoint.pt", src["b.onnx"]]):
        _, mean, _, _ = soup.soup(ingredients)
        assert mean.keys() == a.keys()
        for k in a:
            want = (a[k].double() + b[k].double()) / 2
            assert torch.allclose(mean[k].double(), want, rtol=0, atol=1e-7), k
        assert any(not torch.equal(mean[k], a[k]) for k in a)
    _, mean, _, weights = soup.soup([src["a"], src["b"]], [3, 1])
    assert weights == [0.75, 0.25]
    k = "unet.out.weight"
    assert torch.allclose(mean[k].double(), 0.75 * a[k].double() + 0.25 * b[k].double(), rtol=0, atol=1e-7)


@pytest.mark.models("direct")
def test_a_soup_of_one_model_is_that_model_and_exports(runs, tmp_path):
    ort = pytest.importorskip("onnxruntime")
    src, _, a = runs
    soup.main([str(src["b.onnx"]), str(src["b"]), "--run-dir", str(tmp_path / "s"), "--out", str(tmp_path / "s.onnx")])
    _, state = export.load_onnx(tmp_path / "s.onnx")
    assert all(torch.equal(state[k], a[k]) for k in a)
    assert config.Config.load(tmp_path / "s" / "config.json").run_dir == str(tmp_path / "s")
    record = json.loads((tmp_path / "s" / "soup.json").read_text())
    assert [i["weight"] for i in record["ingredients"]] == [0.5, 0.5]
    assert record["ingredients"][0]["sha256"] == hashlib.sha256(src["b.onnx"].read_bytes()).hexdigest()
    x = torch.rand(1, 9, 24, 40)
    e = transfer.exposure_np(x[0, 0:3].permute(1, 2, 0).numpy())
    feed = {contract.INPUT_TENSOR: x.numpy(), contract.EXPOSURE_TENSOR: e}
    outs = [
        ort.InferenceSession(str(p), providers=["CPUExecutionProvider"]).run(None, feed)[0]
        for p in (src["b.onnx"], tmp_path / "s.onnx")
    ]
    assert (outs[0] == outs[1]).all()


def test_soup_refuses_other_networks_and_overwriting_an_ingredient(tmp_path):
    run_dir(tmp_path / "a", 1)
    run_dir(tmp_path / "w", 2, width=16)
    with pytest.raises(SystemExit, match=r"w/checkpoint.pt: another network \(base_width 16.*than .*base_width 8"):
        soup.soup([tmp_path / "a", tmp_path / "w"])
    with pytest.raises(SystemExit, match="no such file"):
        soup.soup([tmp_path / "a", tmp_path / "missing.onnx"])
    (tmp_path / "junk.onnx").write_bytes(b"not a model")
    with pytest.raises(SystemExit, match="junk.onnx: not a model exported by export.py"):
        soup.soup([tmp_path / "junk.onnx"])
    (tmp_path / "odd").mkdir()
    (tmp_path / "odd" / "config.json").write_text("{")
    torch.save({"model": {}}, tmp_path / "odd" / "checkpoint.pt")
    with pytest.raises(SystemExit, match="odd/config.json: not a run configuration"):
        soup.soup([tmp_path / "odd"])
    with pytest.raises(SystemExit, match="2 weights for 1 ingredients"):
        soup.soup([tmp_path / "a"], [1, 2])
    with pytest.raises(SystemExit, match="must be finite, non-negative"):
        soup.soup([tmp_path / "a", tmp_path / "a"], [float("nan"), 1])
    # Nothing is written when an output would overwrite an ingredient's file, a file of the soup's
    # own run, or a run that is not a soup.
    before = {p: p.read_bytes() for p in (tmp_path / "a").iterdir()}
    for args, message in [
        (["--run-dir", str(tmp_path / "a")], "--run-dir .*a/config.json: is an ingredient's file"),
        (
            ["--run-dir", str(tmp_path / "s"), "--out", str(tmp_path / "a" / "checkpoint.pt")],
            "--out .*: is an ingredient's file",
        ),
        (["--run-dir", str(tmp_path / "s"), "--out", str(tmp_path / "s" / "soup.json")], "is one of --run-dir's files"),
        (
            ["--run-dir", str(tmp_path / "s"), "--out", str(tmp_path / "nowhere" / "s.onnx")],
            "not a file in an existing directory",
        ),
        (["--run-dir", str(tmp_path / "w")], "--run-dir .*w: holds something other than a soup"),
    ]:
        with pytest.raises(SystemExit, match=message):
            soup.main([str(tmp_path / "a" / "checkpoint.pt"), str(tmp_path / "a")] + args)
    assert {p: p.read_bytes() for p in (tmp_path / "a").iterdir()} == before
    assert not (tmp_path / "s").exists() and not (tmp_path / "w" / "soup.json").exists()
