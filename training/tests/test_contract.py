"""The Python side of the stage contracts (python/luxest_contract.py) against Rust.

The fixtures in tests/fixtures/contract/ are written by Rust (luxest-io's naming and header
modules, `RgbImage::autoexposure`, crates/denoise's model tensor names); here Python must compose
and parse the same names, read the ZIP-compressed EXR Rust wrote to the header values Rust
recorded, use the same estimator and tensor names, and compute the same exposure.
The Makefile's naming function (pipelines/naming.mk) is checked against the same names."""

import json
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

import luxest_contract as contract

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "tests" / "fixtures" / "contract"


def fixture(name):
    path = FIXTURES / name
    if not path.exists():
        pytest.fail(f"{path}: missing (written by the Rust contract tests: cargo test)")
    return path


# --- Independent checks (no fixture) -----------------------------------------------------------


def test_names_compose_and_parse():
    assert contract.image_name("gen0001", "hdr", 4) == "gen0001_000004spp.hdr.exr"
    assert contract.image_name("cornell_box", "nrm") == "cornell_box_ref.nrm.exr"
    assert contract.image_name("cb", "hdr", 1000, unit="le") == "cb_001000le.hdr.exr"
    assert contract.image_name("a", "dn", 1234567) == "a_1234567spp.dn.exr"
    assert contract.parse_image_name("gen0001_000004spp.hdr.exr") == contract.ImageName("gen0001", 4, False, "hdr")
    assert contract.parse_image_name("data/x/cornell_box_ref.nrm.exr") == contract.ImageName(
        "cornell_box", None, True, "nrm"
    )
    assert contract.parse_image_name("cb_001000le.dn.exr") == contract.ImageName("cb", 1000, False, "dn", "le")
    assert contract.parse_image_name("x_000001spp.z.exr") == contract.ImageName("x", 1, False, "z")
    for bad in (
        "notes.txt",
        "a_ref.exr",
        "a_4spp.hdr.exr",
        "a_000004spp.foo.exr",
        "a_000004spp.hdr.png",
        "_ref.hdr.exr",
        "aref.hdr.exr",
        "a_00000xspp.hdr.exr",
    ):
        assert contract.parse_image_name(bad) is None, bad
    with pytest.raises(ValueError):
        contract.image_name("a", "hdr", 2.5)


def test_exr_round_trip_is_zip_and_keeps_header(tmp_path):
    import OpenEXR

    img = (np.random.default_rng(3).random((7, 11, 3)) * 1e5).astype(np.float32)
    img[0, 0] = [1e-30, 3.4e38, -2.0]  # beyond f16 range: must stay f32
    path = tmp_path / contract.image_name("x", "hdr", 16)
    contract.write(path, img, {contract.SAMPLES: 16, contract.SEED: 7, contract.SECONDS: 0.125})
    back = contract.read(path)
    assert np.array_equal(back.pixels, img)
    assert back.value(contract.SAMPLES) == 16 and back.value(contract.SEED) == 7
    assert back.value(contract.SECONDS) == 0.125 and back.value(contract.ESTIMATOR) is None
    with OpenEXR.File(str(path)) as f:
        assert f.header()["compression"] == OpenEXR.ZIP_COMPRESSION


def test_bad_input_is_one_line_naming_the_file(tmp_path):
    garbage = tmp_path / "g.exr"
    garbage.write_bytes(b"not an exr")
    with pytest.raises(contract.ContractError) as e:
        contract.read(garbage)
    assert str(garbage) in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(contract.ContractError, match="missing header attribute luxest.seed"):
        contract.seed({}, "f.exr")
    with pytest.raises(contract.ContractError, match=f"{contract.SAMPLES} = `x` is not a valid int"):
        contract.samples({contract.SAMPLES: "x"}, "f.exr")


def test_exposure_against_closed_forms():
    # A uniform image of luminance Y has exposure 0.18 / (Y + 1e-4).
    grey = np.full((4, 6, 3), 2.0, dtype=np.float32)
    assert math.isclose(contract.exposure(grey), 0.18 / (2.0 + 1e-4), rel_tol=1e-12)
    # Half the pixels pure red 1, half black: Y = 0.2126 or 0; the log-mean is the mean of logs.
    img = np.zeros((2, 2, 3), dtype=np.float32)
    img[0, :, 0] = 1.0
    expect = 0.18 / math.exp(0.5 * (math.log(0.2126 + 1e-4) + math.log(1e-4)))
    assert math.isclose(contract.exposure(img), expect, rel_tol=1e-12)
    # Negative luminance counts as zero.
    assert math.isclose(contract.exposure(-grey), 0.18 / 1e-4, rel_tol=1e-12)


def test_sensor_run_metadata(tmp_path):
    # The layout luxest-io's write_ron gives SensorResults (pretty RON, struct names).
    path = contract.sensors_name(tmp_path, "sobolev")
    path.write_text(
        'SensorResults(\n    scene: "sobolev",\n    run: RunInfo(\n        samples: 8000,\n        seed: 1,\n'
        '        seconds: 0.061184665,\n        estimator: "local-estimate",\n        scene_hash: "ea59",\n'
        '        program_version: "0.1.0",\n    ),\n    unit: "lx",\n    sets: [],\n)\n'
    )
    assert path.name == "sobolev.sensors.ron"
    run = contract.read_sensor_run(path)
    assert run == {
        "samples": 8000,
        "seed": 1,
        "seconds": 0.061184665,
        "estimator": "local-estimate",
        "scene_hash": "ea59",
        "program_version": "0.1.0",
    }
    path.write_text('SensorResults(scene: "x")')
    with pytest.raises(contract.ContractError, match="no run metadata"):
        contract.read_sensor_run(path)


def test_report_csvs_read_as_written(tmp_path):
    # Headers as luxest-io (SensorResults::write_csv) and evaluate write them.
    sensors = tmp_path / "x.sensors.csv"
    sensors.write_text(
        "set,index,x,y,z,nx,ny,nz,value_lx,standard_error_lx,r,g,b\nfloor,0,0,0,0,0,1,0,1.5e2,2.5e0,1.5e2,1.5e2,1.5e2\n"
    )
    rows, unit = contract.read_sensors_csv(sensors)
    assert unit == "lx" and (rows[0]["set"], rows[0]["value"], rows[0]["standard_error"]) == ("floor", 150.0, 2.5)
    report = tmp_path / "s.csv"
    report.write_text(
        "results,case,point,exact_lx,estimate_lx,standard_error_lx,z,relative_error\n"
        'r.sensors.ron,"sphere:I=100","wall (0, 1, 0)",2e2,2.02e2,1e0,2,1e-2\n'
    )
    rows, unit = contract.read_sensor_report(report)
    assert unit == "lx" and rows[0]["point"] == "wall (0, 1, 0)" and rows[0]["case"] == "sphere:I=100"
    assert (rows[0]["exact"], rows[0]["estimate"], rows[0]["z"], rows[0]["relative_error"]) == (200.0, 202.0, 2.0, 0.01)
    images = tmp_path / "i.csv"
    images.write_text(
        "image,reference,estimator,samples,render_seconds,feature_seconds,denoise_seconds,total_seconds,"
        "psnr_db,ssim,ms_ssim,flip,rel_mse,smape\n"
        "a_000004spp.dn.exr,a_ref.hdr.exr,path-tracing+denoise,4,1e-1,0e0,5e-2,1.5e-1,3e1,9e-1,,1e-1,1e-3,2e-2\n"
    )
    [row] = contract.read_image_report(images)
    assert row["samples"] == 4.0 and row["psnr_db"] == 30.0 and math.isnan(row["ms_ssim"])
    images.write_text("image,psnr_db\nx,abc\n")
    with pytest.raises(contract.ContractError, match="column psnr_db = `abc` is not a number"):
        contract.read_image_report(images)


# --- Rust-written fixtures ---------------------------------------------------------------------


def naming_cases():
    return json.loads(fixture("naming.json").read_text())


def test_every_rust_name_composes_and_parses_alike():
    cases = naming_cases()
    assert len(cases) >= 4
    for c in cases:
        unit = c.get("unit", "spp")
        spp = None if c["reference"] else c["spp"]
        assert contract.image_name(c["name"], c["kind"], spp, unit=unit) == c["file"], c
        parsed = contract.parse_image_name(c["file"])
        assert parsed is not None, c
        assert (parsed.name, parsed.spp, parsed.reference, parsed.kind) == (
            c["name"],
            spp,
            c["reference"],
            c["kind"],
        ), c


def test_make_composes_the_same_names():
    """pipelines/naming.mk's functions give Rust's names (the Makefile composes dataset targets)."""
    cases = [c for c in naming_cases() if c.get("unit", "spp") == "spp"]
    calls = " ".join(
        f"$(info $(call {'lx_ref' if c['reference'] else 'lx_image'},{c['name']},"
        + (f"{c['kind']}" if c["reference"] else f"{c['spp']},{c['kind']}")
        + "))"
        for c in cases
    )
    out = subprocess.run(
        ["make", "--no-print-directory", "-f", str(ROOT / "pipelines/naming.mk"), "-f", "-", "all"],
        input=f"{calls}\nall: ;@:\n",
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert out.split() == [c["file"] for c in cases]


def test_make_lists_the_same_features():
    """pipelines/naming.mk's LX_FEATURES (the feature images make's rules depend on) are the
    contract's features beside hdr, in the same order; lx_features names each image."""
    calls = "$(info $(LX_FEATURES))$(info $(call lx_features,p,4))"
    out = subprocess.run(
        ["make", "--no-print-directory", "-f", str(ROOT / "pipelines/naming.mk"), "-f", "-", "all"],
        input=f"{calls}\nall: ;@:\n",
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    features, flags = out.splitlines()
    assert ["hdr"] + features.split() == list(contract.FEATURES)
    assert flags.split() == [contract.image_name("p", f, 4) for f in contract.FEATURES[1:]]


def test_rust_header_reads_to_the_recorded_values():
    expected = json.loads(fixture("header.json").read_text())
    img = contract.read(fixture("header.exr"))
    import OpenEXR

    with OpenEXR.File(str(fixture("header.exr"))) as f:
        assert f.header()["compression"] == OpenEXR.ZIP_COMPRESSION  # what Rust writes
    assert img.pixels.shape[:2] == (3, 5) and img.pixels.dtype == np.float32
    assert set(contract.KEYS) - {contract.CHANNELS} <= set(expected), "the fixture sets every image key"
    for key, value in expected.items():
        assert key in contract.KEYS, f"Rust key {key} is not in luxest_contract.KEYS"
        got = img.value(key, required=True)
        if isinstance(value, float) or contract.TYPES.get(key) is float:
            assert got == float(value), key
        else:
            assert got == value, key


def test_python_exposure_equals_rusts():
    expected = json.loads(fixture("exposure.json").read_text())
    hdr = contract.read_rgb(fixture("exposure_input.exr"))
    assert math.isclose(contract.exposure(hdr), expected["exposure"], rel_tol=1e-6)


def test_python_dim_exponent_equals_rusts():
    # The brightening of dim images (the same power of two and exposure as crates/denoise).
    expected = json.loads(fixture("exposure.json").read_text())
    assert contract.DIM_LUMINANCE == expected["dim_luminance"]
    hdr = contract.read_rgb(fixture("exposure_input.exr"))
    exponents = set()
    for case in expected["dim"]:
        scaled = hdr * np.float32(case["factor"])
        emi = scaled * np.float32(0.5) if case["emission"] == "half" else None
        e = contract.dim_exponent(scaled, emi)
        assert e == case["exponent"], case
        assert math.isclose(contract.exposure(scaled, 2.0**e), case["exposure"], rel_tol=1e-12), case
        assert math.isclose(contract.evaluation_exposure(scaled), case["evaluation_exposure"], rel_tol=1e-12), case
        exponents.add(e)
    assert 0 in exponents and max(exponents) > 60  # the fixture covers the bright and the very dim


def test_python_range_exponent_equals_rusts():
    # The scaling into a model's octave of mean luminance (the same power of two and exposure
    # as crates/denoise for a model with MEAN_LUMINANCE).
    expected = json.loads(fixture("exposure.json").read_text())
    low = expected["range_luminance"]
    hdr = contract.read_rgb(fixture("exposure_input.exr"))
    exponents = set()
    for case in expected["range"]:
        scaled = hdr * np.float32(case["factor"])
        emi = scaled * np.float32(0.5) if case["emission"] == "half" else None
        e = contract.range_exponent(scaled, emi, low)
        assert e == case["exponent"], case
        assert math.isclose(contract.exposure(scaled, 2.0**e), case["exposure"], rel_tol=1e-12), case
        mean = contract.filtered_luminance(scaled, emi) * 2.0**e
        assert low <= mean < 2 * low, case
        exponents.add(e)
    assert min(exponents) < -30 and max(exponents) > 10  # bright and dim both covered


def test_model_metadata_keys_match_rust():
    # The metadata keys export.py writes are those crates/denoise reads (luxest-io header).
    expected = json.loads(fixture("model_meta.json").read_text())
    assert list(expected) == ["CHANNELS", "FEATURE_SAMPLES", "MEAN_LUMINANCE"]
    for name, value in expected.items():
        assert getattr(contract, name) == value, name


def test_dim_exponent_against_closed_forms():
    # A uniform image of luminance Y < 1/32 is brightened by the least 2^e with 2^e Y >= 1/32.
    grey = np.full((4, 5, 3), 1e-3)
    assert contract.dim_exponent(grey) == 5  # 1e-3 * 32 = 0.032 >= 0.03125 > 1e-3 * 16
    assert contract.dim_exponent(np.full((2, 2, 3), 1 / 32)) == 0
    assert contract.dim_exponent(np.full((2, 2, 3), 1 / 64)) == 1
    assert contract.dim_exponent(np.zeros((3, 3, 3))) == 0  # black: nothing to brighten
    assert contract.dim_exponent(-grey) == 0  # negative radiance counts as 0
    # Emission is not what a model denoises: an emitter beside a dim wall does not hide the wall.
    hdr = np.full((2, 2, 3), 1e-6)
    hdr[0, 0] = 100.0
    emi = np.zeros_like(hdr)
    emi[0, 0] = 100.0
    assert contract.dim_exponent(hdr) == 0
    assert contract.dim_exponent(hdr, emi) == math.ceil(math.log2((1 / 32) / (0.75e-6)))
    # The exposure of the brightened image is that of the image times 2^e.
    assert math.isclose(contract.exposure(grey, 32.0), contract.exposure(grey * 32.0), rel_tol=1e-15)


def test_oidn_denoiser_name_and_labels_match_rust():
    # How `luxest.denoiser` names OIDN (written by pipelines/oidn_denoise.py) is the prefix Rust's
    # evaluate reads to label an image `<estimator>+oidn`.
    expected = json.loads(fixture("denoiser.json").read_text())
    assert contract.OIDN_DENOISER_PREFIX == expected["oidn_prefix"]
    labels = {(c["estimator"], c["denoiser"]): c["label"] for c in expected["labels"]}
    assert labels[("double-local-estimate", contract.OIDN_DENOISER_PREFIX + "1.4.3")] == "double-local-estimate+oidn"
    assert labels[("path-tracing", "default.onnx")] == "path-tracing+denoise"
    # luxest_contract.estimator_label (pipelines/eval.py's labels) gives every one of Rust's.
    for (estimator, denoiser), label in labels.items():
        assert contract.estimator_label(estimator, denoiser) == label


def test_estimator_names_match_rust():
    # Every value of `luxest.estimator` the stages write (luxest-io's header::estimator), by the
    # name of its constant: the same names and order as luxest_contract.ESTIMATORS.
    expected = json.loads(fixture("estimators.json").read_text())
    assert len(expected) >= 7
    for name, value in expected.items():
        assert getattr(contract, name) == value, name
    assert contract.ESTIMATORS == tuple(expected.values())


def test_model_tensor_names_match_rust():
    # The names crates/denoise looks up in a model's graph (model::tensor) are those export.py
    # gives it and infer.py feeds (luxest_contract.TENSORS); test_training's export tests check
    # an exported graph has exactly these.
    expected = json.loads(fixture("tensors.json").read_text())
    assert list(expected) == ["INPUT", "EXPOSURE", "OUTPUT"]
    for role, value in expected.items():
        assert getattr(contract, f"{role}_TENSOR") == value, role
    assert contract.TENSORS == tuple(expected.values())
