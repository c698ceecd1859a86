//! The denoise stage: inference parity with Python onnxruntime, a dim image included (fixtures from
//! tests/fixtures/denoise/generate.py), tiling, and its errors on bad input.

use crate::util::{denoise, repo_root, StageResult, TempDir};
use luxest_io::exr::{read_rgb, write_rgb};
use luxest_io::header;
use luxest_io::image::RgbImage;
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    repo_root().join("tests/fixtures/denoise").join(name)
}

/// Copies the three features of fixture `img` into `dir`, returning the hdr path.
fn copy_features(dir: &TempDir, img: &str, features: &[&str]) -> PathBuf {
    for f in features {
        let name = format!("{img}.{f}.exr");
        std::fs::copy(fixture(&name), dir.path().join(&name)).unwrap();
    }
    dir.path().join(format!("{img}.hdr.exr"))
}

/// Largest |a - b| relative to max(1, |b|).
fn max_relative_difference(a: &RgbImage, b: &RgbImage) -> f64 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.pixels
        .iter()
        .flatten()
        .zip(b.pixels.iter().flatten())
        .map(|(&x, &y)| (x as f64 - y as f64).abs() / (y as f64).abs().max(1.0))
        .fold(0.0, f64::max)
}

fn run(args: &[&str]) -> StageResult {
    denoise(args)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The fixture models (both output heads of training/model.py, and the kernel-predicting one
/// with the emission feature, with the antialiased emission too, and with detail gates), the suffix of their expected outputs
/// (tests/fixtures/denoise/generate.py) and the features they take.
const MODELS: [(&str, &str, &[&str]); 5] = [
    ("tiny.onnx", "expected", &["hdr", "alb", "nrm"]),
    ("tiny_kpn.onnx", "kpn.expected", &["hdr", "alb", "nrm"]),
    (
        "tiny_emi.onnx",
        "emi.expected",
        &["hdr", "alb", "nrm", "emi"],
    ),
    (
        "tiny_ema.onnx",
        "ema.expected",
        &["hdr", "alb", "nrm", "emi", "ema"],
    ),
    (
        "tiny_gate.onnx",
        "gate.expected",
        &["hdr", "alb", "nrm", "emi", "ema"],
    ),
];

#[test]
fn output_equals_python_onnxruntime_to_1e_5() {
    for (model_name, suffix, features) in MODELS {
        let dir = TempDir::new("dn-parity");
        let model = fixture(model_name);
        for img in ["odd_000004spp", "tiles_000001spp", "dim_000004spp"] {
            let hdr = copy_features(&dir, img, features);
            run(&[s(&hdr), "--model", s(&model), "--threads", "2"]).unwrap();
            let out = read_rgb(&dir.path().join(format!("{img}.dn.exr"))).unwrap();
            let expected = read_rgb(&fixture(&format!("{img}.{suffix}.exr"))).unwrap();
            let d = max_relative_difference(&out, &expected);
            assert!(
                d <= 1e-5,
                "{model_name} {img}: max relative difference {d:e}"
            );
            // The input's run metadata travels with the result.
            assert_eq!(out.attribute(header::DENOISER), Some(model_name));
            let t: f64 = out
                .attribute(header::DENOISE_SECONDS)
                .unwrap()
                .parse()
                .unwrap();
            assert!(t > 0.0);
            // Its CPU seconds (the process's: the other tests of this binary count too, so only
            // that some were spent; the clock itself is tested in denoise's cli module).
            let cpu: f64 = out
                .attribute(header::DENOISE_CPU_SECONDS)
                .unwrap()
                .parse()
                .unwrap();
            assert!(cpu > 0.0 && cpu.is_finite(), "{cpu} CPU-s");
        }
    }
}

#[test]
fn tiles_with_enough_context_equal_the_whole_image() {
    for (model_name, _, features) in MODELS {
        let dir = TempDir::new("dn-tiles");
        let model = fixture(model_name);
        let hdr = copy_features(&dir, "tiles_000001spp", features);
        let whole = dir.path().join("whole.exr");
        run(&[s(&hdr), "--model", s(&model), "-o", s(&whole)]).unwrap();
        let whole = read_rgb(&whole).unwrap();
        // 160 x 96 in 32-pixel cores: 15 tiles, most of them interior. The U-Net's receptive
        // field radius (with the kernels of the coarsest scale, about 82 pixels) is below 96
        // pixels, so 96 pixels of context reproduce the whole image.
        let tiled = dir.path().join("tiled.exr");
        run(&[
            s(&hdr),
            "--model",
            s(&model),
            "-o",
            s(&tiled),
            "--tile",
            "32",
            "--overlap",
            "96",
        ])
        .unwrap();
        let d = max_relative_difference(&read_rgb(&tiled).unwrap(), &whole);
        assert!(d <= 1e-5, "{model_name}: tiled vs whole: {d:e}");
        // Without context the tiles visibly disagree: the test can fail.
        let bare = dir.path().join("bare.exr");
        run(&[
            s(&hdr),
            "--model",
            s(&model),
            "-o",
            s(&bare),
            "--tile",
            "32",
            "--overlap",
            "0",
        ])
        .unwrap();
        let d = max_relative_difference(&read_rgb(&bare).unwrap(), &whole);
        assert!(
            d > 1e-3,
            "{model_name}: tiles without context should differ, got {d:e}"
        );
    }
}

#[test]
fn bad_input_gives_one_line_errors_and_no_output() {
    let dir = TempDir::new("dn-errors");
    let model = fixture("tiny.onnx");
    let check = |args: &[&str], code: u8, needles: &[&str]| {
        let (c, msg) = run(args).expect_err("must fail");
        assert_eq!(c, code, "{msg}");
        assert!(!msg.trim().contains('\n'), "one line: {msg}");
        for n in needles {
            assert!(msg.contains(n), "{msg:?} should mention {n:?}");
        }
    };

    // A missing feature image.
    let hdr = copy_features(&dir, "odd_000004spp", &["hdr", "alb"]);
    // -o and --out-dir are alternatives: giving both is a usage error, not -o silently winning.
    let both = dir.path().join("both.dn.exr");
    let (c, msg) = run(&[
        s(&hdr),
        "--model",
        s(&model),
        "-o",
        s(&both),
        "--out-dir",
        s(dir.path()),
    ])
    .expect_err("-o with --out-dir");
    assert!(c == 2 && msg.contains("--out-dir"), "{c}: {msg}");
    assert!(!both.exists());
    // An input not named <img>.hdr.exr has no features next to it: the message says why.
    let odd = dir.path().join("odd.exr");
    std::fs::copy(&hdr, &odd).unwrap();
    check(
        &[s(&odd), "--model", s(&model), "-o", s(&both)],
        1,
        &["odd.exr", "<img>.hdr.exr", "--alb"],
    );
    check(
        &[s(&hdr), "--model", s(&model)],
        1,
        &["odd_000004spp.nrm.exr", "missing nrm feature"],
    );
    // A model that takes the emission needs its image.
    check(
        &[
            s(&hdr),
            "--model",
            s(&fixture("tiny_emi.onnx")),
            "--nrm",
            s(&fixture("odd_000004spp.nrm.exr")),
        ],
        1,
        &["odd_000004spp.emi.exr", "missing emi feature"],
    );
    // And one that adds back the antialiased emission, that one too.
    check(
        &[
            s(&hdr),
            "--model",
            s(&fixture("tiny_ema.onnx")),
            "--nrm",
            s(&fixture("odd_000004spp.nrm.exr")),
            "--emi",
            s(&fixture("odd_000004spp.emi.exr")),
        ],
        1,
        &["odd_000004spp.ema.exr", "missing ema feature"],
    );
    // A feature of another size.
    let nrm = dir.path().join("odd_000004spp.nrm.exr");
    write_rgb(&nrm, &RgbImage::new(20, 10)).unwrap();
    check(
        &[s(&hdr), "--model", s(&model)],
        1,
        &["odd_000004spp.nrm.exr", "20x10", "70x45"],
    );
    // NaN in the noisy image.
    std::fs::copy(fixture("odd_000004spp.nrm.exr"), &nrm).unwrap();
    let mut bad = read_rgb(&hdr).unwrap();
    bad.pixels[3 * 70 + 5][1] = f32::NAN;
    let nan = dir.path().join("nan_000004spp.hdr.exr");
    write_rgb(&nan, &bad).unwrap();
    check(
        &[
            s(&nan),
            "--model",
            s(&model),
            "--alb",
            s(&hdr),
            "--nrm",
            s(&nrm),
        ],
        1,
        &["nan_000004spp.hdr.exr", "pixel (5, 3)"],
    );
    // An EXR without R, G, B.
    let text = dir.write("x_000001spp.hdr.exr", "not an exr");
    check(
        &[
            s(&text),
            "--model",
            s(&model),
            "--alb",
            s(&hdr),
            "--nrm",
            s(&nrm),
        ],
        1,
        &["x_000001spp.hdr.exr", "OpenEXR"],
    );
    // Models that do not honour the contract.
    check(
        &[s(&hdr), "--model", s(&fixture("bad_inputs.onnx"))],
        1,
        &["bad_inputs.onnx", "input named `input`"],
    );
    check(
        &[s(&hdr), "--model", s(&fixture("bad_channels.onnx"))],
        1,
        &["bad_channels.onnx", "9 channels", "hdr, alb need 6"],
    );
    let junk = dir.write("junk.onnx", "not a model");
    check(
        &[s(&hdr), "--model", s(&junk)],
        1,
        &["junk.onnx", "not a loadable ONNX model"],
    );
    check(
        &[s(&hdr), "--model", "/nonexistent/m.onnx"],
        1,
        &["/nonexistent/m.onnx"],
    );
    // Usage errors.
    check(
        &[s(&hdr), "--model", s(&model), "--tile", "100"],
        2,
        &["multiple of 16"],
    );
    check(
        &[s(&hdr), s(&hdr), "--model", s(&model), "-o", "x.exr"],
        2,
        &["exactly one input"],
    );
    // A feature the model does not take would be ignored: refused, naming what it takes.
    check(
        &[s(&hdr), "--model", s(&model), "--emi", s(&hdr)],
        2,
        &["--emi: the model", "tiny.onnx", "(it takes hdr, alb, nrm)"],
    );

    // Nothing but the inputs was written.
    let outputs: Vec<_> = dir
        .files()
        .into_iter()
        .filter(|p| p.to_string_lossy().contains(".dn."))
        .collect();
    assert!(outputs.is_empty(), "{outputs:?}");
}

/// A model with the emission feature passes the emitters around its network: where the noisy
/// image is nothing but emission (hdr = emi), whatever the (untrained) weights, the result is
/// the emission exactly, inside the emitter, at its edge and outside it — also for radiance near
/// the f32 limit, where denoise scales hdr and emi alike by a power of two.
#[test]
fn the_emission_model_returns_the_emitters_unfiltered() {
    for peak in [300.0f32, 1e36] {
        let dir = TempDir::new("dn-emi");
        let (w, h) = (70, 45);
        let mut emi = RgbImage::new(w, h);
        let mut alb = RgbImage::new(w, h);
        let mut nrm = RgbImage::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if (10..30).contains(&x) && (5..20).contains(&y) {
                    emi.pixels[i] = [peak, peak / 3.0, peak / 7.0];
                }
                alb.pixels[i] = [0.5, 0.4, 0.3];
                nrm.pixels[i] = [0.0, 0.0, 1.0];
            }
        }
        let hdr = dir.path().join("e_000001spp.hdr.exr");
        write_rgb(&hdr, &emi).unwrap();
        write_rgb(&dir.path().join("e_000001spp.emi.exr"), &emi).unwrap();
        write_rgb(&dir.path().join("e_000001spp.alb.exr"), &alb).unwrap();
        write_rgb(&dir.path().join("e_000001spp.nrm.exr"), &nrm).unwrap();
        run(&[s(&hdr), "--model", s(&fixture("tiny_emi.onnx"))]).unwrap();
        let out = read_rgb(&dir.path().join("e_000001spp.dn.exr")).unwrap();
        for (i, (o, e)) in out.pixels.iter().zip(&emi.pixels).enumerate() {
            for c in 0..3 {
                assert!(
                    (o[c] - e[c]).abs() <= 1e-5 * e[c].abs(),
                    "peak {peak:e}: {o:?} vs the emission {e:?} at ({}, {})",
                    i % w,
                    i / w
                );
            }
        }
        // The model without the feature filters the emitter with the rest: the test can fail.
        let plain = dir.path().join("plain.exr");
        run(&[
            s(&hdr),
            "--model",
            s(&fixture("tiny_kpn.onnx")),
            "-o",
            s(&plain),
        ])
        .unwrap();
        let plain = read_rgb(&plain).unwrap();
        assert!(max_relative_difference(&plain, &emi) > 1e-3);
    }
}

/// `--features-of IMG.hdr.exr` takes the features a model needs from beside another image
/// name (how make eval denoises a local-estimate image with a path-traced level's features):
/// the same result as naming each of them, for a model that takes three features as for one
/// that takes five, with all five images there (a model does not read what it does not take).
#[test]
fn features_of_another_image_are_the_ones_the_model_takes() {
    let dir = TempDir::new("dn-features-of");
    let all = ["hdr", "alb", "nrm", "emi", "ema"];
    let features_of = copy_features(&dir, "odd_000004spp", &all);
    // The image to denoise, named as a local-estimate image, with no features beside it.
    let le = dir.path().join("odd_000300le.hdr.exr");
    std::fs::copy(&features_of, &le).unwrap();
    for (model_name, _, features) in [MODELS[0], MODELS[4]] {
        let model = fixture(model_name);
        let via = dir.path().join(format!("{model_name}.via.exr"));
        let named = dir.path().join(format!("{model_name}.named.exr"));
        run(&[
            s(&le),
            "--model",
            s(&model),
            "--features-of",
            s(&features_of),
            "-o",
            s(&via),
        ])
        .unwrap();
        let mut args = vec![s(&le), "--model", s(&model), "-o", s(&named)];
        let paths: Vec<String> = features[1..]
            .iter()
            .map(|f| format!("{}/odd_000004spp.{f}.exr", dir.path().display()))
            .collect();
        let flags: Vec<String> = features[1..].iter().map(|f| format!("--{f}")).collect();
        for (flag, path) in flags.iter().zip(&paths) {
            args.extend([flag.as_str(), path.as_str()]);
        }
        run(&args).unwrap();
        let (via_image, named_image) = (read_rgb(&via).unwrap(), read_rgb(&named).unwrap());
        assert_eq!(via_image.pixels, named_image.pixels, "{model_name}");
        // Without them the local-estimate image has no features: the option is what finds them.
        let (code, msg) = run(&[s(&le), "--model", s(&model), "-o", s(&named)]).unwrap_err();
        assert_eq!(code, 1, "{msg}");
        assert!(msg.contains("missing alb feature image"), "{msg}");
    }
    let model = fixture("tiny.onnx");
    for (args, want) in [
        (
            vec![
                s(&le),
                "--model",
                s(&model),
                "--features-of",
                s(&le),
                "--alb",
                s(&le),
            ],
            "cannot be used with",
        ),
        (
            vec![
                s(&le),
                s(&le),
                "--model",
                s(&model),
                "--features-of",
                s(&features_of),
            ],
            "exactly one input image",
        ),
        (
            vec![s(&le), "--model", s(&model), "--features-of", "x.exr"],
            "--features-of x.exr: name an image <img>.hdr.exr",
        ),
    ] {
        let (code, msg) = run(&args).unwrap_err();
        assert_eq!(code, 2, "{args:?}: {msg}");
        assert!(msg.contains(want), "{args:?}: {msg}");
    }
}
