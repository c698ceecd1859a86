"""Tests of the training toolkit: shapes, the transfer, learning, export parity, config."""
import json
import sys
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import config  # noqa: E402
import loss as losses  # noqa: E402
import transfer  # noqa: E402
from model import Denoiser, UNet  # noqa: E402


def test_shapes_any_size():
    torch.manual_seed(0)
    net = Denoiser(width=8).eval()
    for h, w in [(37, 53), (16, 16), (1, 5)]:
        out = net(torch.rand(2, 9, h, w))
        assert out.shape == (2, 3, h, w)
    assert UNet(width=8)(torch.rand(1, 9, 64, 32)).shape == (1, 3, 64, 32)


def test_transfer_round_trip_and_exposure():
    x = torch.rand(3, 3, 20, 30) * torch.tensor([1e-3, 1.0, 1e5]).view(3, 1, 1, 1)
    e = transfer.exposure_of(x).view(-1, 1, 1, 1)
    back = transfer.inverse(transfer.forward(x, e), e)
    assert torch.allclose(back, x, rtol=1e-5, atol=1e-9)
    # Exposure normalises brightness: scaling the image by k scales the exposure by 1/k
    # (up to the 1e-4 floor inside the log).
    assert torch.allclose(transfer.exposure_of(x[2:] * 10.0), e[2:].view(-1) / 10.0, rtol=1e-3)


def test_one_training_step_lowers_the_loss():
    torch.manual_seed(1)
    net = Denoiser(width=8)
    ref = torch.rand(4, 3, 32, 32)
    noisy = ref * (1 + 0.5 * torch.randn_like(ref)).clamp(min=0)
    inp = torch.cat([noisy, torch.rand(4, 3, 32, 32), torch.rand(4, 3, 32, 32)], 1)
    opt = torch.optim.Adam(net.parameters(), lr=1e-3)

    def current():
        pred, exp = net.transferred(inp, transfer.exposure_of(noisy))
        return losses.loss(pred, transfer.forward(ref, exp), 0.2)

    before = current()
    opt.zero_grad()
    before.backward()
    opt.step()
    with torch.no_grad():
        after = current()
    assert float(after) < float(before.detach())


def test_ms_ssim_is_one_for_identical_images_and_less_otherwise():
    a = torch.rand(2, 3, 64, 64)
    assert abs(float(losses.ms_ssim(a, a)) - 1.0) < 1e-5
    assert float(losses.ms_ssim(a, a + 0.2 * torch.randn_like(a))) < 0.9


def test_export_matches_onnxruntime(tmp_path):
    ort = pytest.importorskip("onnxruntime")
    import export

    torch.manual_seed(2)
    cfg = config.Config(base_width=8)
    cfg.save(tmp_path / "config.json")
    net = Denoiser(width=8)
    torch.save({"model": net.state_dict(), "step": 0}, tmp_path / "checkpoint.pt")
    model = tmp_path / "m.onnx"
    export.export(tmp_path, model)
    session = ort.InferenceSession(str(model), providers=["CPUExecutionProvider"])
    net.eval()
    for h, w in [(40, 56), (33, 17)]:
        x = torch.rand(1, 9, h, w) * torch.tensor([5.0] * 3 + [1.0] * 6).view(1, 9, 1, 1)
        a = net(x).detach().numpy()
        e = transfer.exposure_np(x[0, 0:3].permute(1, 2, 0).numpy())
        assert abs(float(e[0]) - float(transfer.exposure_of(x[:, 0:3])[0])) <= 1e-6 * float(e[0])
        b = session.run(None, {"input": x.numpy(), "exposure": e})[0]
        assert a.shape == b.shape
        assert np.max(np.abs(a - b)) <= 1e-4 * max(1.0, float(np.abs(a).max()))
    meta = {p.key: p.value for p in __import__("onnx").load(str(model)).metadata_props}
    assert meta["luxest.channels"] == "hdr,alb,nrm"
    assert json.loads(meta["luxest.config"])["base_width"] == 8


def test_config_round_trip(tmp_path):
    cfg = config.parse(["--minutes", "3", "--noisy-spp", "1", "4"])
    assert cfg.minutes == 3.0 and cfg.noisy_spp == [1, 4]
    cfg.save(tmp_path / "c.json")
    assert asdict(config.Config.load(tmp_path / "c.json")) == asdict(cfg)
