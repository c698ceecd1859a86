"""Tests of the training toolkit: shapes, the transfer, learning, export parity, config."""

import json
import re
import sys
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import config  # noqa: E402
import grow  # noqa: E402
import loss as losses  # noqa: E402
import luxest_contract as contract  # noqa: E402
import model  # noqa: E402
import transfer  # noqa: E402
from conftest import tiny_split  # noqa: E402
from model import Denoiser, UNet  # noqa: E402


@pytest.mark.parametrize("head", model.HEADS)
def test_shapes_any_size(head):
    torch.manual_seed(0)
    net = Denoiser(width=8, head=head).eval()
    for h, w in [(37, 53), (16, 16), (1, 5)]:
        out = net(torch.rand(2, 9, h, w))
        assert out.shape == (2, 3, h, w)
    assert UNet(width=8)(torch.rand(1, 9, 64, 32)).shape == (1, 3, 64, 32)


def _uniform_irradiance(h=48, w=64, seed=3):
    """A noiseless image of uniform irradiance (2.5, 1.0, 0.4) under a random albedo texture
    with black patches (below the demodulation floor), and random normals: (N=1, 9, H, W)."""
    g = torch.Generator().manual_seed(seed)
    alb = torch.rand(1, 3, h, w, generator=g)
    alb[:, :, 5:12, 7:30] = 0.0
    hdr = alb.clamp(min=model.ALBEDO_FLOOR) * torch.tensor([2.5, 1.0, 0.4]).view(1, 3, 1, 1)
    nrm = torch.nn.functional.normalize(torch.randn(1, 3, h, w, generator=g), dim=1)
    return torch.cat([hdr, alb, nrm], 1)


def test_kernel_head_returns_a_noiseless_uniform_irradiance_image_unchanged():
    # Whatever the (random, untrained) weights: every scale's kernels average equal irradiance
    # and the blends add U(o) - U(D(f)) = 0 (with detail gates also beta f + (1 - beta) U(D(f))
    # = f); the albedo texture is remodulated exactly. The
    # direct head, untrained, does not (so the check can fail).
    x = _uniform_irradiance()
    for seed in range(4):
        torch.manual_seed(seed)
        net = Denoiser(width=8, head="kpn", detail_gate=seed % 2 == 1).eval()
        with torch.no_grad():
            out = net(x)
        assert torch.allclose(out, x[:, 0:3], rtol=1e-5, atol=1e-7), float((out - x[:, 0:3]).abs().max())
    with torch.no_grad():
        direct = Denoiser(width=8, head="direct").eval()(x)
    assert not torch.allclose(direct, x[:, 0:3], rtol=1e-2)


def test_emission_model_passes_the_emitters_around_the_network():
    # Whatever the (random, untrained) weights: the irradiance the emitter does not emit is
    # filtered as without it (uniform here, so returned exactly) and the emission is added back
    # unfiltered, so the light's radiance, colour and edge cannot shift. The model without the
    # feature blurs the emitter into its surroundings (the test can fail).
    x = _uniform_irradiance()
    emi = torch.zeros(1, 3, 48, 64)
    emi[:, :, 20:30, 10:40] = torch.tensor([170.0, 120.0, 40.0]).view(1, 3, 1, 1)
    x[:, 0:3] += emi
    x12 = torch.cat([x, emi], 1)
    expected = _uniform_irradiance()[:, 0:3] + emi
    for seed in range(3):
        torch.manual_seed(seed)
        net = Denoiser(width=8, head="kpn", features=model.FEATURE_SETS[1]).eval()
        with torch.no_grad():
            out = net(x12)
        assert torch.allclose(out, expected, rtol=1e-5, atol=1e-6), float((out - expected).abs().max())
    torch.manual_seed(0)
    with torch.no_grad():
        plain = Denoiser(width=8, head="kpn").eval()(x)
    assert not torch.allclose(plain, expected, rtol=1e-2)
    with pytest.raises(ValueError, match="kpn"):
        Denoiser(head="direct", features=model.FEATURE_SETS[1])
    with pytest.raises(ValueError, match="features"):
        Denoiser(features=("hdr", "emi"))


def test_antialiased_emission_is_added_back_in_place_of_the_images_own():
    # At 1 spp an edge pixel of the emitter holds all of its radiance (hdr and emi) or none; ema
    # holds the fraction it covers. A model with ema subtracts emi and adds back ema: same
    # weights as without it (the network does not see ema), and whatever they are, the output
    # differs from the emi model's by exactly ema - emi.
    x = _uniform_irradiance()
    emi = torch.zeros(1, 3, 48, 64)
    light = torch.tensor([170.0, 120.0, 40.0]).view(1, 3, 1, 1)
    emi[:, :, 20:30, 10:40] = light
    emi[:, :, 30, 10:40:2] = light[..., 0]  # the edge row: every other pixel's sample hit the light
    ema = emi.clone()
    ema[:, :, 30, 10:40] = 0.5 * light[..., 0]
    x[:, 0:3] += emi
    for seed in range(2):
        torch.manual_seed(seed)
        net4 = Denoiser(width=8, head="kpn", features=model.FEATURE_SETS[1]).eval()
        net5 = Denoiser(width=8, head="kpn", features=model.FEATURE_SETS[2]).eval()
        net5.load_state_dict(net4.state_dict())  # the same parameters
        with torch.no_grad():
            a = net4(torch.cat([x, emi], 1))
            b = net5(torch.cat([x, emi, ema], 1))
        assert net5.in_channels == 15
        assert torch.allclose(b - a, ema - emi, rtol=1e-5, atol=1e-4), float((b - a - (ema - emi)).abs().max())
        assert torch.allclose(
            b[:, :, 30, 10:40], _uniform_irradiance()[:, 0:3, 30, 10:40] + 0.5 * light[:, :, 0], rtol=1e-5
        )


@pytest.mark.parametrize("gate", [False, True])
def test_kernel_head_with_identity_kernels_returns_any_input(gate):
    # Centre weight ~1, blend 0 (and detail kept whole) at every scale: a clean input is left
    # alone exactly.
    torch.manual_seed(4)
    x = torch.rand(2, 9, 32, 48) * torch.tensor([20.0] * 3 + [1.0] * 6).view(1, 9, 1, 1)
    k2 = model.KERNEL * model.KERNEL
    heads = []
    for s in range(model.SCALES):
        n, h, w = x.shape[0], x.shape[2] >> s, x.shape[3] >> s
        logits = torch.full((n, k2 + ((2 if gate else 1) if s < model.SCALES - 1 else 0), h, w), -60.0)
        logits[:, k2 // 2] = 60.0
        if gate and s < model.SCALES - 1:
            logits[:, k2 + 1] = 60.0
        heads.append(logits)
    out = model.reconstruct(x[:, 0:3], x[:, 3:6], heads, detail_gate=gate)
    assert torch.allclose(out, x[:, 0:3], rtol=1e-5, atol=1e-6)
    if gate:  # the gates closed: the finer scales' detail is gone (the check can fail)
        for logits in heads[:-1]:
            logits[:, k2 + 1] = -60.0
        out = model.reconstruct(x[:, 0:3], x[:, 3:6], heads, detail_gate=gate)
        assert not torch.allclose(out, x[:, 0:3], rtol=1e-2)


def test_kernel_gathers_agree():
    # Training gathers the neighbours with unfold, the exported graph with slices.
    torch.manual_seed(6)
    img = torch.rand(2, 3, 20, 28) * 5
    logits = torch.randn(2, model.KERNEL**2, 20, 28) * 4
    a = model.apply_kernels(img, logits, "unfold")
    b = model.apply_kernels(img, logits, "slices")
    assert torch.allclose(a, b, rtol=1e-5, atol=1e-6)
    # A softmax-weighted mean: the explicit form.
    w = torch.softmax(logits, 1)
    k = model.KERNEL
    p = torch.nn.functional.pad(img, (k // 2,) * 4, mode="replicate")
    y, x = 7, 11
    want = sum(w[:, i, y, x, None] * p[:, :, y + i // k, x + i % k] for i in range(k * k))
    assert torch.allclose(a[:, :, y, x], want, rtol=1e-5)


@pytest.mark.parametrize("gate", [False, True])
def test_multi_scale_blend_against_a_hand_written_pyramid(gate):
    # Random kernels and blends, 4 scales: o_3 = f_3, o_s = f_s + a_s (U(o_{s+1}) - U(D(f_s))),
    # with the detail gate o_s = U(D(f_s)) + b_s (f_s - U(D(f_s))) + a_s (U(o_{s+1}) - U(D(f_s))),
    # written out with explicit neighbour loops, 2x2 block means and bilinear up-sampling.
    torch.manual_seed(7)
    n, h, w, k = 1, 16, 24, model.KERNEL
    hdr = torch.rand(n, 3, h, w) * 4
    alb = torch.rand(n, 3, h, w)
    extra = 2 if gate else 1
    heads = [
        torch.randn(n, k * k + (extra if s < model.SCALES - 1 else 0), h >> s, w >> s) * 2 for s in range(model.SCALES)
    ]
    got = model.reconstruct(hdr, alb, heads, detail_gate=gate)

    def filt(img, logits):
        wgt = torch.softmax(logits[:, : k * k], 1)
        p = torch.nn.functional.pad(img, (k // 2,) * 4, mode="replicate")
        out = torch.zeros_like(img)
        for y in range(img.shape[2]):
            for x in range(img.shape[3]):
                for i in range(k * k):
                    out[:, :, y, x] += wgt[:, i, y, x, None] * p[:, :, y + i // k, x + i % k]
        return out

    def down(t):
        return t.reshape(t.shape[0], t.shape[1], t.shape[2] // 2, 2, t.shape[3] // 2, 2).mean((3, 5))

    def up(t):
        return torch.nn.functional.interpolate(t, scale_factor=2.0, mode="bilinear", align_corners=False)

    a = alb.clamp(min=model.ALBEDO_FLOOR)
    irr = [hdr / a]
    for _ in range(model.SCALES - 1):
        irr.append(down(irr[-1]))
    o = filt(irr[-1], heads[-1])
    for s in range(model.SCALES - 2, -1, -1):
        f = filt(irr[s], heads[s])
        alpha = torch.sigmoid(heads[s][:, k * k : k * k + 1])
        beta = torch.sigmoid(heads[s][:, k * k + 1 : k * k + 2]) if gate else 1.0
        o = up(down(f)) + beta * (f - up(down(f))) + alpha * (up(o) - up(down(f)))
    want = (o * a).clamp(min=0)
    assert torch.allclose(got, want, rtol=1e-4, atol=1e-5)
    # The blend matters: without it (alpha = 0) the result differs.
    assert not torch.allclose(got, (filt(irr[0], heads[0]) * a).clamp(min=0), rtol=1e-2)


@pytest.mark.parametrize("head", model.HEADS)
def test_scale_equivariance(head):
    # Scaling the radiance and the exposure input inversely scales the result (as denoise's
    # power-of-two rescaling near the f32 limit relies on).
    torch.manual_seed(5)
    net = Denoiser(width=8, head=head).eval()
    x = torch.rand(1, 9, 32, 32)
    y = x.clone()
    y[:, 0:3] *= 1e6
    e = transfer.exposure_of(x[:, 0:3])
    with torch.no_grad():
        a, b = net(x, e), net(y, e / 1e6)
    assert float((b - a * 1e6).abs().max()) <= 1e-4 * float((a * 1e6).abs().max())


def test_transfer_round_trip_and_exposure():
    x = torch.rand(3, 3, 20, 30) * torch.tensor([1e-3, 1.0, 1e5]).view(3, 1, 1, 1)
    e = transfer.exposure_of(x).view(-1, 1, 1, 1)
    back = transfer.inverse(transfer.forward(x, e), e)
    assert torch.allclose(back, x, rtol=1e-5, atol=1e-9)
    # Exposure normalises brightness: scaling the image by k scales the exposure by 1/k
    # (up to the 1e-4 floor inside the log).
    assert torch.allclose(transfer.exposure_of(x[2:] * 10.0), e[2:].view(-1) / 10.0, rtol=1e-3)


DEVICES = ["cpu"] + (["cuda"] if torch.cuda.is_available() else [])


@pytest.mark.parametrize("device", DEVICES)
@pytest.mark.parametrize("head", model.HEADS)
def test_one_training_step_lowers_the_loss(head, device):
    # On a GPU too, where present (the MS-SSIM window was once made on the CPU whatever the
    # device: the first CUDA training stopped at its first step).
    torch.manual_seed(1)
    net = Denoiser(width=8, head=head).to(device)
    ref = torch.rand(4, 3, 32, 32, device=device)
    noisy = ref * (1 + 0.5 * torch.randn_like(ref)).clamp(min=0)
    inp = torch.cat([noisy, torch.rand(4, 3, 32, 32, device=device), torch.rand(4, 3, 32, 32, device=device)], 1)
    opt = torch.optim.Adam(net.parameters(), lr=1e-3)

    def current():
        pred, exp = net.transferred(inp, transfer.exposure_of(noisy))
        return losses.loss(net.loss_domain(pred, exp), transfer.forward(ref, exp), 0.2)

    before = current()
    opt.zero_grad()
    before.backward()
    opt.step()
    with torch.no_grad():
        after = current()
    assert float(after) < float(before.detach())


ROOT = Path(__file__).resolve().parents[2]


def test_display_is_the_evaluations_tonemap():
    # loss.display against the evaluation tonemap Rust computes (tests/contract.rs writes it,
    # evaluate::metrics::tonemap of a row of values at a fixed image's exposure).
    fixture = ROOT / "tests" / "fixtures" / "contract" / "exposure.json"
    expected = json.loads(fixture.read_text())["tonemap"]
    x = torch.tensor(expected["input"], dtype=torch.float64).view(1, 1, 1, -1).expand(1, 3, 1, -1)
    got = losses.display(x, torch.tensor([expected["exposure"]], dtype=torch.float64))
    for c in range(3):
        assert np.allclose(got[0, c, 0].numpy(), expected["output"], rtol=1e-12, atol=1e-15)


def test_psnr_loss_is_minus_the_evaluations_psnr():
    # The metrics fixture (tests/fixtures/metrics: numpy and scikit-image transcriptions that
    # Rust's evaluate is checked against): a linear pair, the reference's autoexposure, and the
    # PSNR of the pair after the tonemap. One crop of the whole image: the loss is minus that
    # PSNR, up to the floor added to the squared error.
    import luxest_contract as contract

    d = ROOT / "tests" / "fixtures" / "metrics"
    values = dict(
        line.split(" ", 1)
        for line in (d / "expected.txt").read_text().splitlines()
        if line and not line.startswith("#")
    )
    to = lambda a: torch.from_numpy(np.asarray(a, dtype=np.float64)).permute(2, 0, 1)[None]
    ref = contract.read(d / "hdr_ref.exr").pixels[..., :3]
    test = contract.read(d / "hdr_test.exr").pixels[..., :3]
    k = contract.exposure(ref)
    assert k == pytest.approx(float(values["hdr.autoexposure"]), rel=1e-9)
    psnr = float(values["hdr.tm.psnr"])
    got = float(losses.psnr_loss(to(test), to(ref), torch.tensor([k], dtype=torch.float64)))
    assert got == pytest.approx(10 * np.log10(10 ** (-psnr / 10) + losses.PSNR_FLOOR), abs=1e-9)

    # Per crop with its own exposure, then averaged: a batch of the pair and of the pair halved
    # in error at another exposure, against a numpy transcription of the tonemap's definition.
    def tonemap(v, e):
        x = np.maximum(np.asarray(v, dtype=np.float64), 0) * e
        t = x / (1 + x)
        return np.clip(
            np.where(t <= 0.0031308, 12.92 * t, 1.055 * np.power(np.maximum(t, 0.0031308), 1 / 2.4) - 0.055), 0, 1
        )

    half = ref + 0.5 * (test - ref)
    mse_half = float(((tonemap(half, 3 * k) - tonemap(ref, 3 * k)) ** 2).mean())
    both = float(
        losses.psnr_loss(
            torch.cat([to(test), to(half)]),
            torch.cat([to(ref), to(ref)]),
            torch.tensor([k, 3 * k], dtype=torch.float64),
        )
    )
    assert both == pytest.approx((got + 10 * np.log10(mse_half + losses.PSNR_FLOOR)) / 2, abs=1e-9)
    # Overflowing radiance tonemaps to white, not NaN.
    assert float(
        losses.display(torch.full((1, 3, 1, 1), float("inf")), torch.tensor([1.0]))[0, 0, 0, 0]
    ) == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("head", model.HEADS)
def test_one_psnr_step_raises_the_psnr(head):
    torch.manual_seed(2)
    net = Denoiser(width=8, head=head)
    ref = torch.rand(4, 3, 32, 32)
    noisy = ref * (1 + 0.5 * torch.randn_like(ref)).clamp(min=0)
    inp = torch.cat([noisy, torch.rand(4, 3, 32, 32), torch.rand(4, 3, 32, 32)], 1)
    opt = torch.optim.Adam(net.parameters(), lr=1e-3)
    cfg = config.parse(["--loss", "psnr"])
    import train

    def current():
        pred, exp = net.transferred(inp, transfer.exposure_of(noisy))
        return train.objective(net, pred, exp, ref, transfer.exposure_of(ref), cfg)

    before = current()
    opt.zero_grad()
    before.backward()
    opt.step()
    with torch.no_grad():
        assert float(current()) < float(before.detach())
        # An output equal to the reference (as each head expresses it) scores the floor: the
        # objective reads a direct head's output through the inverse transfer.
        _, exp = net.transferred(inp, transfer.exposure_of(noisy))  # as the network shapes it
        perfect = ref if head == "kpn" else transfer.forward(ref, exp)
        floor = 10 * np.log10(losses.PSNR_FLOOR)
        assert float(train.objective(net, perfect, exp, ref, transfer.exposure_of(ref), cfg)) == pytest.approx(
            floor, abs=1e-3
        )


def test_ms_ssim_is_one_for_identical_images_and_less_otherwise():
    a = torch.rand(2, 3, 64, 64)
    assert abs(float(losses.ms_ssim(a, a)) - 1.0) < 1e-5
    assert float(losses.ms_ssim(a, a + 0.2 * torch.randn_like(a))) < 0.9


def test_split_joins_compute_the_same_decoder():
    # Export takes each decoder block's first convolution over [upsampled, skip] as the sum of
    # one convolution per part (no Concat node); the decoder's outputs must not change.
    torch.manual_seed(9)
    net = model.UNet(in_channels=9, width=8, out_channels=0).eval()
    x = torch.rand(2, 9, 48, 32)
    with torch.no_grad():
        a = net.decoder(x)
        net.split_joins()
        b = net.decoder(x)
    for s, (u, v) in enumerate(zip(a, b)):
        assert u.shape == v.shape
        assert torch.allclose(u, v, rtol=1e-5, atol=1e-6), s
    assert float(a[0].abs().max()) > 0


# The network of each shared model (conftest.MODELS): head, features, detail gate, scales. `ema`
# is the `emi` run exported to add back the antialiased emission: the same weights, all five
# features; `five` the `gated` run grown to five scales.
EXPORTED = {
    "kpn": ("kpn", model.FEATURE_SETS[0], False, 4),
    "direct": ("direct", model.FEATURE_SETS[0], False, 4),
    "emi": ("kpn", model.FEATURE_SETS[1], False, 4),
    "ema": ("kpn", model.FEATURE_SETS[2], False, 4),
    "gated": ("kpn", model.FEATURE_SETS[2], True, 4),
    "five": ("kpn", model.FEATURE_SETS[2], True, 5),
}


def exported_network(models, name):
    """(the torch network of shared model `name` with its run's weights, in eval mode; its ONNX path)."""
    head, features, gate, scales = EXPORTED[name]
    net = Denoiser(width=8, head=head, features=features, detail_gate=gate, scales=scales)
    net.load_state_dict(torch.load(models[name]["run"] / "checkpoint.pt", weights_only=False)["model"])
    return net.eval(), models[name]["onnx"]


@pytest.mark.parametrize("name", list(EXPORTED))
def test_export_matches_onnxruntime(models, name):
    # Every network shape the exporter writes: each head, feature set, with and without detail
    # gates, 4 and 5 scales (shared exports: conftest.py).
    ort = pytest.importorskip("onnxruntime")
    import export

    head, features, gate, scales = EXPORTED[name]
    net, onnx_path = exported_network(models, name)
    session = ort.InferenceSession(str(onnx_path), providers=["CPUExecutionProvider"])
    assert [i.name for i in session.get_inputs()] + [o.name for o in session.get_outputs()] == list(contract.TENSORS)
    c = 3 * len(features)
    torch.manual_seed(2)
    for h, w in [(40, 56), (33, 17)]:
        x = torch.rand(1, c, h, w) * torch.tensor([5.0] * 3 + [1.0] * 6 + [2.0] * (c - 9)).view(1, c, 1, 1)
        if c >= 12:
            x[:, 9:c, : h // 2] = 0.0  # emission in the lower half only
        with torch.no_grad():
            a = net(x).numpy()
        e = transfer.exposure_np(x[0, 0:3].permute(1, 2, 0).numpy())
        assert abs(float(e[0]) - float(transfer.exposure_of(x[:, 0:3])[0])) <= 1e-6 * float(e[0])
        b = session.run([contract.OUTPUT_TENSOR], {contract.INPUT_TENSOR: x.numpy(), contract.EXPOSURE_TENSOR: e})[0]
        assert a.shape == b.shape
        assert np.max(np.abs(a - b)) <= 1e-4 * max(1.0, float(np.abs(a).max()))
    graph = __import__("onnx").load(str(onnx_path)).graph
    # The decoder joins are exported without Concat (model.UNet.split_joins): no Concat takes
    # an upsampled map.
    producer = {o: n.op_type for n in graph.node for o in n.output}
    joins = [
        n.name
        for n in graph.node
        if n.op_type == "Concat" and any(producer.get(i) in ("Resize", "Upsample") for i in n.input)
    ]
    assert not joins and any(n.op_type == "Resize" for n in graph.node)
    meta = {p.key: p.value for p in __import__("onnx").load(str(onnx_path)).metadata_props}
    assert meta[contract.CHANNELS] == ",".join(features)
    assert (export.EMISSION in meta[contract.MODEL_TRANSFER]) == ("emi" in features)
    assert (export.EMISSION_AA in meta[contract.MODEL_TRANSFER]) == ("ema" in features)
    assert json.loads(meta[contract.MODEL_CONFIG])["base_width"] == 8
    assert json.loads(meta[contract.MODEL_CONFIG])["head"] == head
    assert export.outputs(head, scales) in meta[contract.MODEL_TRANSFER]
    assert (export.DETAIL_GATE in meta[contract.MODEL_TRANSFER]) == gate
    back, state = export.load_onnx(onnx_path)
    # The test runs train with config's defaults: both feature sets, the input scaled to 1/16.
    assert back.own_features and meta[contract.FEATURE_SAMPLES] == "1"
    assert float(meta[contract.MEAN_LUMINANCE]) == back.mean_luminance == 0.0625
    assert back.detail_gate == gate and back.scales == scales
    assert all(torch.equal(state[k], v) for k, v in net.state_dict().items())


@pytest.mark.models("emi", "ema", "kpn")
def test_a_run_with_the_emission_exports_adding_back_the_antialiased_one(models, tmp_path):
    # The shared `ema` model: the `emi` run (hdr, alb, nrm, emi) exported with
    # antialiased_emission: it takes ema too and adds it back in place of emi.
    ort = pytest.importorskip("onnxruntime")
    import export

    net4 = Denoiser(width=8, head="kpn", features=model.FEATURE_SETS[1]).eval()
    net4.load_state_dict(torch.load(models["emi"]["run"] / "checkpoint.pt", weights_only=False)["model"])
    assert json.loads((models["emi"]["run"] / "config.json").read_text())["features"] == list(model.FEATURE_SETS[1])
    session = ort.InferenceSession(str(models["ema"]["onnx"]), providers=["CPUExecutionProvider"])
    meta = {p.key: p.value for p in __import__("onnx").load(str(models["ema"]["onnx"])).metadata_props}
    assert meta[contract.CHANNELS] == "hdr,alb,nrm,emi,ema" and export.EMISSION_AA in meta[contract.MODEL_TRANSFER]
    torch.manual_seed(5)
    x = torch.rand(1, 12, 32, 48) * 3.0
    ema = torch.rand(1, 3, 32, 48) * 7.0
    e = transfer.exposure_np(x[0, 0:3].permute(1, 2, 0).numpy())
    b = session.run(None, {contract.INPUT_TENSOR: torch.cat([x, ema], 1).numpy(), contract.EXPOSURE_TENSOR: e})[0]
    with torch.no_grad():
        a = net4(x, torch.from_numpy(e)).numpy()
    added = (ema - x[:, 9:12]).numpy()
    assert np.max(np.abs(b - a - added)) <= 1e-4 * max(1.0, float(np.abs(b).max()))
    # A run without the emission cannot (refused before anything is exported).
    with pytest.raises(ValueError, match="emi"):
        export.export(models["kpn"]["run"], tmp_path / "n.onnx", antialiased_emission=True)
    assert not (tmp_path / "n.onnx").exists()


def test_config_round_trip(tmp_path):
    cfg = config.parse(["--minutes", "3", "--noisy-spp", "1", "4", "--extra-seeds", "2", "3"])
    assert cfg.minutes == 3.0 and cfg.noisy_spp == [1, 4] and cfg.extra_seeds == [2, 3]
    assert config.parse([]).extra_seeds == [] and config.parse(["--extra-seeds"]).extra_seeds == []
    cfg.save(tmp_path / "c.json")
    assert asdict(config.Config.load(tmp_path / "c.json")) == asdict(cfg)
    # A run saved before the head option was a direct one.
    old = asdict(cfg)
    del old["head"]
    (tmp_path / "old.json").write_text(json.dumps(old))
    assert config.Config.load(tmp_path / "old.json").head == "direct"
    # ... and one saved before extra noise realizations had none.
    del old["extra_seeds"], old["extra_spp"]
    (tmp_path / "old.json").write_text(json.dumps(old))
    assert (
        config.Config.load(tmp_path / "old.json").extra_seeds,
        config.Config.load(tmp_path / "old.json").extra_spp,
    ) == ([], [1, 2, 4, 8, 16, 32])
    # ... and one saved before the detail gate (on by default since) had none; a key of no
    # current option (a model's metadata written by a later version) is dropped; a flag turns
    # the detail gate on and off.
    del old["detail_gate"]
    (tmp_path / "old.json").write_text(json.dumps(old))
    assert config.Config.load(tmp_path / "old.json").detail_gate is False
    assert config.Config().detail_gate is True
    (tmp_path / "later.json").write_text(json.dumps({**asdict(cfg), "no_such_option": 3}))
    assert asdict(config.Config.load(tmp_path / "later.json")) == asdict(cfg)
    assert config.parse([]).detail_gate is True
    assert config.parse(["--no-detail-gate"]).detail_gate is False


def test_training_runs_its_steps_and_resumes(tmp_path):
    # A tiny preprocessed split; a run stopped by its time budget, then resumed to its 5 steps:
    # the run record counts them and where it was resumed.
    import preprocess
    import train

    rng = np.random.default_rng(3)
    for split in ("train", "valid"):
        tiny_split(tmp_path / "data" / split, 32, rng)
    (tmp_path / "data" / "test").mkdir()
    args = [
        "--data-dir",
        str(tmp_path / "data"),
        "--prep-dir",
        str(tmp_path / "prep"),
        "--run-dir",
        str(tmp_path / "run"),
        "--noisy-spp",
        "4",
        "--dle-paths",
        "--crop",
        "32",
        "--batch",
        "2",
        "--base-width",
        "8",
        "--threads",
        "1",
    ]
    preprocess.main(args)
    train.main(args + ["--steps", "5", "--minutes", "0"])  # out of time at once: a checkpoint at step 0
    first = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert first["steps"] == 0
    train.main(args + ["--steps", "5", "--minutes", "5", "--resume"])
    record = json.loads((tmp_path / "run" / "run.json").read_text())
    assert record["run"]["steps"] == 5 and record["run"]["resumed_at"] == [first["steps"]]
    assert record["run"]["seconds"] >= first["seconds"] and record["head"] == "kpn"
    expected = "bf16" if train.autocast_dtype(torch.device("cpu"), "auto") is not None else "fp32"
    assert record["precision"] == "auto" and record["run"]["autocast"] == expected
    # The other loss trains and is recorded; an unknown one is refused in one line.
    train.main(args + ["--steps", "2", "--loss", "psnr", "--run-dir", str(tmp_path / "psnr")])
    record = json.loads((tmp_path / "psnr" / "run.json").read_text())
    assert record["loss"] == "psnr" and record["run"]["steps"] == 2 and record["run"]["valid_loss"] < 0
    with pytest.raises(SystemExit, match="--loss 'l2'"):
        train.main(args + ["--steps", "2", "--loss", "l2", "--run-dir", str(tmp_path / "l2")])
    # A run is resumed with its own loss only.
    with pytest.raises(SystemExit, match="the run's loss is 'psnr', not 'l1'"):
        train.main(args + ["--steps", "4", "--run-dir", str(tmp_path / "psnr"), "--resume"])


def test_autocast_follows_the_precision_and_the_cpu():
    # auto: bf16 where PyTorch has native bf16 kernels (CUDA, AVX-512/AMX CPUs), float32 on
    # AVX2-only CPUs, where emulated bf16 made a step 8x slower; explicit choices are kept.
    import train

    cpu, cuda = torch.device("cpu"), torch.device("cuda")
    assert train.autocast_dtype(cpu, "auto", "AVX2") is None
    assert train.autocast_dtype(cpu, "auto", "DEFAULT") is None
    assert train.autocast_dtype(cpu, "auto", "AVX512") is torch.bfloat16
    assert train.autocast_dtype(cuda, "auto") is torch.bfloat16
    assert train.autocast_dtype(cpu, "bf16", "AVX2") is torch.bfloat16
    assert train.autocast_dtype(cpu, "fp32", "AVX512") is None
    with pytest.raises(SystemExit, match="--precision 'fp16'"):
        train.autocast_dtype(cpu, "fp16", "AVX2")


def test_loader_workers_cut_the_same_crops(tmp_path):
    # Worker processes (automatic on a GPU) cut exactly the crops one process cuts: a crop
    # depends only on (seed, index), so a run is reproducible whatever the loader.
    import preprocess
    import train
    import dataset

    d = tiny_split(tmp_path / "data" / "train", 40, np.random.default_rng(5))
    preprocess.preprocess_split(d, tmp_path / "prep" / "train", [4])
    data = dataset.Crops(tmp_path / "prep" / "train", 16, seed=7, length=12)
    batches = [list(torch.utils.data.DataLoader(data, batch_size=4, num_workers=w)) for w in (0, 2)]
    assert len(batches[0]) == len(batches[1]) == 3
    for one, two in zip(*batches):
        for x, y in zip(one, two):
            assert torch.equal(x, y)
    cpu, cuda = torch.device("cpu"), torch.device("cuda")
    assert train.loader_workers(-1, cpu) == 0 and train.loader_workers(-1, cuda) == 8
    assert train.loader_workers(3, cpu) == 3
    with pytest.raises(SystemExit, match="--workers -2"):
        train.loader_workers(-2, cpu)


def test_crops_cut_on_the_device_are_the_loaders(tmp_path, capsys, monkeypatch):
    # dataset.DeviceCrops (the split in the training device's memory, automatic on a GPU) cuts
    # bit for bit the batches the DataLoader cuts: two scenes of different shapes, two levels
    # each and an extra noise realization of one, sharing their scene's reference, every flip,
    # transpose and channel order.
    import luxest_contract as contract
    import preprocess
    import train
    import dataset

    rng = np.random.default_rng(11)
    d = tmp_path / "data" / "train"
    d.mkdir(parents=True)
    for name, (h, w) in (("g", (40, 56)), ("k", (48, 36))):
        contract.write(
            d / contract.image_name(name, "hdr"), rng.random((h, w, 3)) * 4, {contract.SAMPLES: 64, contract.SEED: 2}
        )
        for spp in (4, 16):
            for kind in contract.FEATURES:
                contract.write(
                    d / contract.image_name(name, kind, spp),
                    rng.random((h, w, 3)),
                    {contract.SAMPLES: spp, contract.SEED: 1},
                )
    (d / contract.REALIZATION_DIR.format(seed=5)).mkdir()
    for kind in contract.FEATURES:
        contract.write(
            d / contract.REALIZATION_DIR.format(seed=5) / contract.image_name("k", kind, 4),
            rng.random((48, 36, 3)),
            {contract.SAMPLES: 4, contract.SEED: 5},
        )
    preprocess.preprocess_split(d, tmp_path / "prep" / "train", [4, 16], extra_seeds=[5])
    data = dataset.Crops(tmp_path / "prep" / "train", 32, seed=3, length=96, extra_seeds=[5])
    assert len(data.pairs) == 5 and len({id(r) for _, r, *_ in data.pairs}) == 2 and len(data.groups) == 4
    draws = [data.draw(i) for i in range(96)]
    assert {d[3:6] for d in draws} == {(a, b, c) for a in (False, True) for b in (False, True) for c in (False, True)}
    assert {d[6] for d in draws} == set(range(len(dataset.PERMUTATIONS)))
    cfg = config.parse(["--batch", "8", "--cropper", "device"])
    cpu = torch.device("cpu")
    ours = list(train.batches(data, cfg, cpu))
    theirs = list(torch.utils.data.DataLoader(data, batch_size=8))
    assert len(ours) == len(theirs) == 12
    for one, two in zip(ours, theirs):
        assert len(one) == len(two) == 4  # inputs, references, their exposures
        for x, y in zip(one, two):
            assert x.shape == y.shape and torch.equal(x, y)
        assert one[0].is_contiguous(memory_format=torch.channels_last)
    # With a mean luminance (each input's radiance and its reference scaled by a power of two,
    # with the exposures of the scaled images) both cut the same batches too.
    scaled = dataset.Crops(tmp_path / "prep" / "train", 32, seed=3, length=16, extra_seeds=[5], mean_luminance=0.0625)
    # hdr and emi uniform on [0, 1): mean of max(hdr - emi, 0) about 1/6, halved into [1/16, 1/8).
    assert set(scaled.scales) == {0.5}
    pairs = list(zip(train.batches(scaled, cfg, cpu), torch.utils.data.DataLoader(scaled, batch_size=8)))
    assert len(pairs) == 2
    for one, two in pairs:
        for x, y in zip(one, two):
            assert torch.equal(x, y)
    # A length that is not a multiple of the batch ends in a partial batch, as the DataLoader's.
    short = dataset.Crops(tmp_path / "prep" / "train", 32, seed=3, length=10)
    ours = list(train.batches(short, config.parse(["--batch", "4", "--cropper", "device"]), cpu))
    theirs = list(torch.utils.data.DataLoader(short, batch_size=4))
    assert [len(b[0]) for b in ours] == [len(b[0]) for b in theirs] == [4, 4, 2]
    assert all(torch.equal(x, y) for one, two in zip(ours, theirs) for x, y in zip(one, two))
    assert train.cropper("auto", cpu) == "loader" and train.cropper("auto", torch.device("cuda")) == "device"
    assert train.cropper("loader", torch.device("cuda")) == "loader"
    with pytest.raises(SystemExit, match="--cropper 'gpu'"):
        train.cropper("gpu", cpu)
    # What the split takes on the device: the bytes of DeviceCrops' own tensors of arrays.
    cut = dataset.DeviceCrops(data, cpu)
    assert dataset.DeviceCrops.bytes_held(data) == cut.inputs.nbytes + cut.refs.nbytes
    # A split that does not fit 3/4 of the free memory: device refuses in one line, auto cuts
    # with the loader and says so, loader never asks; a split that fits stays on the device.
    need, gpu = cut.inputs.nbytes + cut.refs.nbytes, torch.device("cuda")
    assert train.cropper("auto", gpu, need, need / 0.75) == "device"
    assert train.cropper("auto", gpu, need + 1, need / 0.75, "prep/train") == "loader"
    assert "prep/train: its arrays take" in capsys.readouterr().err
    assert train.cropper("loader", gpu, need + 1, 0) == "loader" and train.cropper("auto", cpu, need, 0) == "loader"
    with pytest.raises(
        SystemExit, match=r"^train: --cropper device: .*prep[/\\]train: its arrays take .* GiB free on cpu"
    ):
        monkeypatch.setattr(train, "free_memory", lambda device: need)
        next(train.batches(data, cfg, cpu))


@pytest.mark.models("emi", "ema", "gated")
def test_a_run_starts_from_an_exported_models_weights(models, tiny_prep, tmp_path):
    # --init-from: a fine-tuning starts from the weights of an exported model (or a checkpoint)
    # with its own schedule; a network of another width is refused in one line. The model: the
    # shared `ema` export (all five features, no detail gates) of the `emi` run's weights.
    import train

    args = tiny_prep + ["--steps", "2", "--no-detail-gate"]
    first_onnx, first_pt = models["ema"]["onnx"], models["emi"]["run"] / "checkpoint.pt"
    train.main(
        args
        + ["--run-dir", str(tmp_path / "second"), "--base-width", "8", "--minutes", "0", "--init-from", str(first_onnx)]
    )
    first = torch.load(first_pt, weights_only=False)["model"]
    second = torch.load(tmp_path / "second" / "checkpoint.pt", weights_only=False)["model"]
    assert first.keys() == second.keys() and all(torch.equal(first[k], second[k]) for k in first)
    # Not the initialisation it would have had otherwise.
    train.main(args + ["--run-dir", str(tmp_path / "fresh"), "--base-width", "8", "--minutes", "0", "--seed", "9"])
    fresh = torch.load(tmp_path / "fresh" / "checkpoint.pt", weights_only=False)["model"]
    assert not all(torch.equal(first[k], fresh[k]) for k in first)
    with pytest.raises(SystemExit, match="a width-8 kpn model .* this run trains width 4"):
        train.main(
            args
            + [
                "--base-width",
                "4",
                "--minutes",
                "0",
                "--run-dir",
                str(tmp_path / "third"),
                "--init-from",
                str(first_onnx),
            ]
        )
    with pytest.raises(SystemExit, match="weights of another network"):
        train.main(
            args
            + [
                "--base-width",
                "16",
                "--minutes",
                "0",
                "--run-dir",
                str(tmp_path / "fourth"),
                "--init-from",
                str(first_pt),
            ]
        )
    # A run with detail gates from a model without them: its weights, and gates that keep 0.993
    # of the detail, so the output starts within that fraction of the detail band of the model's.
    k2 = model.KERNEL**2
    a = model.denoiser(config.Config(base_width=8, detail_gate=False)).eval()
    a.load_state_dict(first)
    x = torch.rand(1, a.in_channels, 32, 32) * 2
    x[:, 9:] = 0.0  # no emission
    for src in (first_onnx, first_pt):
        gated_dir = tmp_path / f"gated-{src.suffix[1:]}"
        train.main(
            args
            + [
                "--run-dir",
                str(gated_dir),
                "--base-width",
                "8",
                "--minutes",
                "0",
                "--detail-gate",
                "--init-from",
                str(src),
            ]
        )
        gated = torch.load(gated_dir / "checkpoint.pt", weights_only=False)["model"]
        assert grow.has_detail_gates(gated) and not grow.has_detail_gates(first)
        assert all(torch.equal(first[k], gated[k]) for k in first if not k.startswith("heads."))
        for s in range(model.SCALES):
            w, b = gated[f"heads.{s}.weight"], gated[f"heads.{s}.bias"]
            assert torch.equal(w[: k2 + 1], first[f"heads.{s}.weight"]) and torch.equal(
                b[: k2 + 1], first[f"heads.{s}.bias"]
            )
            if s < model.SCALES - 1:  # a gate of weights 0 and bias DETAIL_GATE_INIT
                assert w.shape[0] == k2 + 2 and not w[k2 + 1].any() and float(b[k2 + 1]) == grow.DETAIL_GATE_INIT
            else:
                assert w.shape[0] == k2
        # The same network with those gate logits written out: beta = sigmoid(5) everywhere.
        b = model.denoiser(config.Config(base_width=8, detail_gate=True)).eval()
        b.load_state_dict(gated)
        with torch.no_grad():
            yb = b(x)
            feats = a.unet.decoder(
                torch.cat(
                    [
                        transfer.forward(x[:, 0:3], transfer.exposure_of(x[:, 0:3]).view(-1, 1, 1, 1)),
                        x[:, 3:9],
                        transfer.forward(x[:, 9:12], transfer.exposure_of(x[:, 0:3]).view(-1, 1, 1, 1)),
                    ],
                    1,
                )
            )
            heads = [h(f) for h, f in zip(a.heads, feats)]
            heads = [
                torch.cat([h, torch.full_like(h[:, :1], grow.DETAIL_GATE_INIT)], 1) if s < model.SCALES - 1 else h
                for s, h in enumerate(heads)
            ]
            want = model.reconstruct(x[:, 0:3], x[:, 3:6], heads, detail_gate=True) + x[:, 12:15]
            ya = a(x)
        assert torch.allclose(yb, want, rtol=1e-4, atol=1e-5), float((yb - want).abs().max())
        assert float((ya - yb).abs().max()) > 0  # the gates start a little below 1
    # A gated checkpoint, and a gated model's export (the shared `gated` one), for a run without.
    for src in (gated_dir / "checkpoint.pt", models["gated"]["onnx"]):
        with pytest.raises(SystemExit, match="a model with detail gates"):
            train.main(
                args
                + ["--base-width", "8", "--minutes", "0", "--run-dir", str(tmp_path / "fifth"), "--init-from", str(src)]
            )
    # Resuming a run with another network (here: without its gates) is refused in one line.
    with pytest.raises(SystemExit, match="the run trains .*detail_gate True, scales 4; this one .*detail_gate False"):
        train.main(args + ["--run-dir", str(gated_dir), "--base-width", "8", "--steps", "3", "--resume"])
    with pytest.raises(SystemExit, match="the detail gate needs the kpn head"):
        train.main(
            args
            + [
                "--run-dir",
                str(tmp_path / "sixth"),
                "--base-width",
                "8",
                "--head",
                "direct",
                "--detail-gate",
                "--features",
                "hdr",
                "alb",
                "nrm",
            ]
        )


@pytest.mark.models("gated")
def test_a_wider_run_starts_from_a_narrower_model_computing_its_function(models, tiny_prep, tmp_path):
    # --init-from a narrower kpn model widens it (grow.widen): the same outputs, old weights in
    # place, new channels feeding nothing, the same new channels whatever the run's seed (so
    # that fine-tunings of one widened model can be souped), and a step moves the zeros. The
    # narrow model: the shared `gated` one (width 8, trained 3 steps).
    import train

    args = tiny_prep + ["--detail-gate"]
    runs = {}
    for name, extra in (
        ("a", ["--seed", "1", "--minutes", "0"]),
        ("b", ["--seed", "7", "--minutes", "0"]),
        ("stepped", ["--seed", "1", "--steps", "2", "--lr", "1e-2"]),
    ):
        train.main(
            args
            + extra
            + ["--run-dir", str(tmp_path / name), "--base-width", "16", "--init-from", str(models["gated"]["onnx"])]
        )
        runs[name] = torch.load(tmp_path / name / "checkpoint.pt", weights_only=False)["model"]
    narrow = torch.load(models["gated"]["run"] / "checkpoint.pt", weights_only=False)["model"]
    wide = runs["a"]
    assert all(torch.equal(wide[k], runs["b"][k]) for k in wide)
    assert wide["unet.enc1.0.weight"].shape == (24, 16, 3, 3) and narrow["unet.enc1.0.weight"].shape == (12, 8, 3, 3)
    assert torch.equal(wide["unet.enc1.0.weight"][:12, :8], narrow["unet.enc1.0.weight"])
    assert not wide["unet.enc1.0.weight"][:12, 8:].any() and wide["unet.enc1.0.weight"][12:].abs().sum() > 0
    # dec0's first convolution takes [upsampled dec1 (12 -> 24), enc0 (8 -> 16)]: the skip's
    # old weights move to after the coarse level's new channels.
    w, v = wide["unet.dec0.0.0.weight"], narrow["unet.dec0.0.0.weight"]
    assert torch.equal(w[:8, :12], v[:, :12]) and torch.equal(w[:8, 24:32], v[:, 12:20])
    assert not w[:8, 12:24].any() and not w[:8, 32:].any()
    for s in range(model.SCALES):
        assert not wide[f"heads.{s}.weight"][:, narrow[f"heads.{s}.weight"].shape[1] :].any()
    cfg8, cfg16 = (config.Config(base_width=b, detail_gate=True) for b in (8, 16))
    a, b = model.denoiser(cfg8).eval(), model.denoiser(cfg16).eval()
    a.load_state_dict(narrow)
    b.load_state_dict(wide)
    x = torch.rand(2, a.in_channels, 48, 32) * 3
    x[:, 3:6] = x[:, 3:6].clamp(0.05, 1)
    with torch.no_grad():
        ya, yb = a(x), b(x)
    assert torch.allclose(ya, yb, rtol=1e-5, atol=1e-5), float((ya - yb).abs().max())
    moved = runs["stepped"]["unet.enc1.0.weight"][:12, 8:]
    assert moved.abs().sum() > 0  # the new channels' fan-out learns
    with pytest.raises(ValueError, match="cannot narrow"):
        grow.widen(wide, cfg16, 8)


@pytest.mark.models("gated", "five")
def test_a_fifth_scale_starts_near_the_four_scale_model_and_learns(models, tiny_prep, tmp_path):
    # --scales 5 --init-from a 4-scale model (grow.add_coarsest_scale): the weights in place, a
    # blend logit of bias -5 at 1/8 (alpha 0.0067) and a zero 1/16 head, so the output moves
    # from the 4-scale model's by 0.0067 of the 1/8 scale's coarse band at most; hand-computed.
    # The 4-scale model: the shared `gated` one (trained 3 steps).
    import export
    import train

    args = tiny_prep + ["--detail-gate", "--base-width", "8"]
    four_onnx = models["gated"]["onnx"]
    train.main(
        args + ["--run-dir", str(tmp_path / "five"), "--scales", "5", "--minutes", "0", "--init-from", str(four_onnx)]
    )
    four = torch.load(models["gated"]["run"] / "checkpoint.pt", weights_only=False)["model"]
    five = torch.load(tmp_path / "five" / "checkpoint.pt", weights_only=False)["model"]
    k2 = model.KERNEL**2
    assert all(torch.equal(four[k], five[k]) for k in four if k not in ("heads.3.weight", "heads.3.bias"))
    assert torch.equal(five["heads.3.weight"][:k2], four["heads.3.weight"])
    assert not five["heads.3.weight"][k2:].any() and five["heads.3.bias"][k2:].tolist() == [-5.0, 5.0]
    assert not five["heads.4.weight"].any() and not five["heads.4.bias"].any()
    a = model.denoiser(config.Config(base_width=8, detail_gate=True)).eval()
    b = model.denoiser(config.Config(base_width=8, detail_gate=True, scales=5)).eval()
    a.load_state_dict(four)
    b.load_state_dict(five)
    x = torch.rand(1, a.in_channels, 64, 48) * 2
    x[:, 3:6] = x[:, 3:6].clamp(0.05, 1)
    x[:, 9:] = 0.0
    with torch.no_grad():
        ya, yb = a(x), b(x)
        # By hand: the 4-scale result at 1/8 is f3; the 5-scale one is
        # beta f3 + (1 - beta) low3 + alpha (up(out4) - low3), out4 a uniform 5x5 mean at 1/16.
        exp = transfer.exposure_of(x[:, 0:3]).view(-1, 1, 1, 1)
        inp = torch.cat([transfer.forward(x[:, 0:3], exp), x[:, 3:9], transfer.forward(x[:, 9:12], exp)], 1)
        heads = [h(f) for h, f in zip(b.heads, b.unet.decoder(inp))]
        assert torch.allclose(heads[4], torch.zeros_like(heads[4]))
        want = model.reconstruct(x[:, 0:3], x[:, 3:6], heads, detail_gate=True)
    assert torch.allclose(yb, want, rtol=1e-4, atol=1e-5)
    rel = float((ya - yb).abs().mean() / ya.abs().mean())
    assert 0 < rel < 0.01, rel
    train.main(
        args
        + [
            "--run-dir",
            str(tmp_path / "stepped"),
            "--scales",
            "5",
            "--steps",
            "2",
            "--lr",
            "1e-2",
            "--init-from",
            str(four_onnx),
        ]
    )
    stepped = torch.load(tmp_path / "stepped" / "checkpoint.pt", weights_only=False)["model"]
    assert stepped["heads.4.weight"].abs().sum() > 0 and stepped["heads.3.weight"][k2:].abs().sum() > 0
    # Exported and read back whole, the zero bias of the 1/16 head included (the exporter's
    # optimiser may drop a Conv's zero bias; export.load_onnx restores it): the shared `five`
    # model, this grown model with random weights in its 1/16 head.
    grown = torch.load(models["five"]["run"] / "checkpoint.pt", weights_only=False)["model"]
    assert (
        all(torch.equal(grown[k], five[k]) for k in five if k != "heads.4.weight") and not grown["heads.4.bias"].any()
    )
    back, state = export.load_onnx(models["five"]["onnx"])
    assert back.scales == 5 and state.keys() == grown.keys() and all(torch.equal(state[k], grown[k]) for k in grown)
    with pytest.raises(SystemExit, match="of 5 scales .* this run trains width 8 kpn of 4 scales"):
        train.main(
            args + ["--run-dir", str(tmp_path / "back"), "--minutes", "0", "--init-from", str(models["five"]["onnx"])]
        )


@pytest.mark.models()  # the tiny dataset only
def test_time_schedule_is_torchs_one_cycle_over_the_budget(tiny_prep, tmp_path):
    # --schedule time: the rates of torch's OneCycleLR at the same fraction of the cycle,
    # the fraction being the larger of steps / cap and seconds / budget; a run ends its cycle
    # at the cap (or the budget) and a resumed one goes on from its step.
    import train

    n = 100001
    net = torch.nn.Linear(2, 2)
    ref_opt = torch.optim.Adam(net.parameters(), lr=1e-3)
    ref = torch.optim.lr_scheduler.OneCycleLR(ref_opt, max_lr=1e-3, total_steps=n, pct_start=0.15)
    expected = {}
    for k in range(n):
        if k in (0, 5000, 15000, 40000, 90000, 100000):
            expected[k] = (ref.get_last_lr()[0], ref_opt.param_groups[0]["betas"][0])
        if k < n - 1:
            ref_opt.step()
            ref.step()
    opt = torch.optim.Adam(net.parameters(), lr=1e-3)
    sched = train.TimeOneCycle(opt, 1e-3, steps=n - 1, seconds=600.0)
    for k, (lr, beta) in expected.items():
        sched.at(k, 0.0)
        assert abs(sched.get_last_lr()[0] - lr) < 1e-3 * 1e-3 and abs(opt.param_groups[0]["betas"][0] - beta) < 1e-4
        sched.at(0, 600.0 * k / (n - 1))  # the same point of the cycle reached by time
        assert abs(opt.param_groups[0]["lr"] - lr) < 1e-6
    assert sched.done(0, 600.0) and sched.done(n - 1, 0.0) and not sched.done(10, 10.0)

    args = tiny_prep + ["--run-dir", str(tmp_path / "run"), "--base-width", "8", "--schedule", "time"]
    train.main(args + ["--steps", "3", "--minutes", "5"])
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["steps"] == 3
    train.main(args + ["--steps", "5", "--minutes", "5", "--resume"])
    record = json.loads((tmp_path / "run" / "run.json").read_text())
    assert record["run"]["steps"] == 5 and record["run"]["resumed_at"] == [3] and record["schedule"] == "time"
    with pytest.raises(SystemExit, match="--schedule 'epochs'"):
        train.main(args + ["--schedule", "epochs"])
    steps_args = [a for a in args if a not in ("--schedule", "time")] + ["--schedule", "steps"]
    with pytest.raises(SystemExit, match="the run's schedule is 'time', not 'steps'"):
        train.main(steps_args + ["--steps", "8", "--resume"])


@pytest.mark.parametrize("name", ["default", "wide"])
def test_committed_models_keep_the_contract(name):
    # Each committed model: its record (models/<name>.config.json) describes the network in its
    # metadata, and run by onnxruntime as denoise feeds it (infer.denoise: the whole image's
    # exposure), it returns a noiseless image of uniform irradiance unchanged (the kernel head's
    # property, whatever the weights), emitters added back as they are (emi subtracted, ema added).
    import export
    import infer
    import onnxruntime as ort

    root = Path(__file__).resolve().parents[2]
    cfg, _ = export.load_onnx(root / "models" / f"{name}.onnx")
    record = json.loads((root / "models" / f"{name}.config.json").read_text())
    recorded = config.Config.from_values(record)
    assert [getattr(cfg, k) for k in config.NETWORK] == [getattr(recorded, k) for k in config.NETWORK]
    # The features it takes and the scaling of its input, as its recipe trained it.
    meta = {p.key: p.value for p in __import__("onnx").load(str(root / "models" / f"{name}.onnx")).metadata_props}
    assert meta[contract.FEATURE_SAMPLES] == str(config.feature_samples(recorded))
    assert contract.model_mean_luminance(meta) == config.scale_luminance(recorded)
    if name == "default":
        # aov-write's default --min-samples writes features the default model takes.
        cli = (root / "crates" / "aov-write" / "src" / "cli.rs").read_text()
        default_min = int(re.search(r"pub const DEFAULT_MIN_SAMPLES: u32 = (\d+);", cli).group(1))
        assert default_min >= int(meta[contract.FEATURE_SAMPLES])
    x = _uniform_irradiance(h=40, w=56)[0].permute(1, 2, 0).numpy()
    hdr, alb, nrm = x[..., 0:3].copy(), x[..., 3:6], x[..., 6:9]
    emission = np.zeros_like(hdr)
    emission[30:34, 10:20] = [40.0, 35.0, 30.0]
    session = ort.InferenceSession(str(root / "models" / f"{name}.onnx"), providers=["CPUExecutionProvider"])
    kinds = infer.channels(session)
    assert kinds == list(cfg.features) and kinds[:3] == ["hdr", "alb", "nrm"]
    feats = {"alb": alb, "nrm": nrm, "emi": emission, "ema": emission}
    out = infer.denoise(session, hdr + emission, *[feats[k] for k in kinds[1:]])
    expected = hdr + emission
    assert np.allclose(out, expected, rtol=2e-4, atol=1e-6), float(np.abs(out - expected).max())
