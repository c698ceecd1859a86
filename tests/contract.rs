//! The cross-language contract fixtures of `tests/fixtures/contract/`, written here from
//! `luxest-io` (the one Rust place for file names, header keys, EXR writing and the
//! autoexposure) and read by Python's `training/tests/test_contract.py`:
//!
//! - `naming.json`: image file names with their parts (`name`, `spp`, `reference`, `unit`
//!   `spp`|`le`, `kind`, `file`), composed by [`luxest_io::naming`];
//! - `header.exr` + `header.json`: a 5×3 RGB f32 ZIP-compressed EXR from
//!   [`luxest_io::exr::write_rgb`] with every image header key of [`luxest_io::header`] set,
//!   and those values by key (numbers as JSON numbers);
//! - `denoiser.json`: how `luxest.denoiser` names Intel Open Image Denoise, and the estimator
//!   labels `evaluate` gives denoised images ([`evaluate::images::estimator_label`]);
//! - `estimators.json`: every value of `luxest.estimator` ([`luxest_io::header::estimator`]) by
//!   the name of its constant;
//! - `tensors.json`: the names of the denoiser model graph's tensors
//!   ([`denoise::model::tensor`]), which `training/export.py` gives the graph;
//! - `model_meta.json`: the model metadata keys `denoise` reads ([`header::CHANNELS`],
//!   [`header::model`]), which `training/export.py` writes;
//! - `exposure_input.exr` + `exposure.json`: a fixed image and its
//!   [`RgbImage::autoexposure`], the denoiser's brightening of it scaled dim
//!   ([`luxest_io::exposure::dim_exponent`], with and without emission, the exposure the model then
//!   gets, and the evaluation's, `evaluate::metrics::autoexposure`), its scaling into a model's
//!   octave of mean luminance ([`luxest_io::exposure::range_exponent`]), and
//!   the evaluation tonemap of a few values (`evaluate::metrics::tonemap`) at its exposure.
//!
//! The test regenerates every file in a temporary directory and asserts that the committed copy
//! is byte-for-byte the same, so a change to either side's contract shows up as a failing test
//! on the Rust side and then on the Python side. `LUXEST_BLESS=1 cargo test contract` rewrites
//! the committed copies (after an intended change, or an `exr` crate upgrade that changes the
//! compressed bytes).

use crate::util::{repo_root, TempDir};
use denoise::model::tensor;
use luxest_io::exposure::{dim_exponent, range_exponent, DIM_LUMINANCE};

/// The mean luminance of the fixture's range cases (what training/config.py's default records).
const RANGE_LUMINANCE: f64 = 1.0 / 16.0;
use luxest_io::exr::write_rgb;
use luxest_io::header;
use luxest_io::header::estimator;
use luxest_io::image::RgbImage;
use luxest_io::meta::RunInfo;
use luxest_io::naming::{ImageName, Kind, Level};
use std::path::Path;

/// A JSON string literal (the names and values here are ASCII without control characters).
fn json_str(s: &str) -> String {
    assert!(s.chars().all(|c| c.is_ascii() && !c.is_ascii_control()));
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

/// A JSON number that reads back as the same f64 (`{:?}` keeps the `.0` of integral values).
fn json_f64(v: f64) -> String {
    assert!(v.is_finite());
    format!("{v:?}")
}

fn naming_json() -> String {
    let cases = [
        ("gen0001", Level::Spp(1), Kind::Hdr),
        ("gen0001", Level::Spp(4), Kind::Alb),
        ("gen0001", Level::Spp(64), Kind::Nrm),
        ("gen0001", Level::Spp(1_234_567), Kind::Denoised),
        ("cornell-box", Level::Reference, Kind::Hdr),
        ("cornell-box", Level::Reference, Kind::Alb),
        ("cornell-box", Level::Reference, Kind::Nrm),
        ("room_with_underscores", Level::Spp(16), Kind::StandardError),
        ("room_with_underscores", Level::Spp(16), Kind::Depth),
        ("gen0001", Level::Spp(4), Kind::Emission),
        ("cornell-box", Level::Reference, Kind::Emission),
        ("gen0001", Level::Spp(1), Kind::EmissionAntialiased),
        ("cornell-box", Level::LightPaths(1000), Kind::Hdr),
        ("sobolev", Level::LightPaths(4000), Kind::Denoised),
    ];
    let rows: Vec<String> = cases
        .iter()
        .map(|&(name, level, kind)| {
            let image = ImageName::new(name, level, kind);
            let file = image.file_name();
            // The composed name must parse back to its parts.
            assert_eq!(ImageName::parse(&file).as_ref(), Some(&image), "{file}");
            let (spp, unit) = match level {
                Level::Spp(n) => (n.to_string(), "spp"),
                Level::Reference => ("null".to_string(), "spp"),
                Level::LightPaths(n) => (n.to_string(), "le"),
            };
            format!(
                "  {{\"name\": {}, \"spp\": {spp}, \"reference\": {}, \"unit\": {}, \"kind\": {}, \"file\": {}}}",
                json_str(name),
                level == Level::Reference,
                json_str(unit),
                json_str(kind.tag()),
                json_str(&file)
            )
        })
        .collect();
    format!("[\n{}\n]\n", rows.join(",\n"))
}

/// `denoiser.json`: the OIDN prefix of `luxest.denoiser` and the labels of a few cases.
fn denoiser_json() -> String {
    let oidn = format!("{}1.4.3", header::OIDN_DENOISER_PREFIX);
    let oidn2 = format!("{}2.5.1", header::OIDN_DENOISER_PREFIX);
    let cases = [
        ("path-tracing", None),
        ("path-tracing", Some("default.onnx")),
        ("double-local-estimate", Some(oidn.as_str())),
        ("path-tracing", Some(oidn2.as_str())),
    ];
    let rows: Vec<String> = cases
        .iter()
        .map(|&(estimator, denoiser)| {
            format!(
                "    {{\"estimator\": {}, \"denoiser\": {}, \"label\": {}}}",
                json_str(estimator),
                denoiser.map_or("null".to_string(), json_str),
                json_str(&evaluate::images::estimator_label(estimator, denoiser))
            )
        })
        .collect();
    format!(
        "{{\n  \"oidn_prefix\": {},\n  \"labels\": [\n{}\n  ]\n}}\n",
        json_str(header::OIDN_DENOISER_PREFIX),
        rows.join(",\n")
    )
}

/// A JSON object of (key, string value) pairs, one per line, in the order given.
fn json_names(pairs: &[(&str, &str)]) -> String {
    let rows: Vec<String> = pairs
        .iter()
        .map(|&(k, v)| format!("  {}: {}", json_str(k), json_str(v)))
        .collect();
    format!("{{\n{}\n}}\n", rows.join(",\n"))
}

/// `estimators.json`: every estimator name by its constant's name, in `estimator::ALL`'s order.
fn estimators_json() -> String {
    let names = [
        ("PATH_TRACING", estimator::PATH_TRACING),
        ("FIRST_HIT_FEATURES", estimator::FIRST_HIT_FEATURES),
        ("LOCAL_ESTIMATE", estimator::LOCAL_ESTIMATE),
        ("DIRECT_SIMULATION", estimator::DIRECT_SIMULATION),
        ("GATHER", estimator::GATHER),
        ("DOUBLE_LOCAL_ESTIMATE", estimator::DOUBLE_LOCAL_ESTIMATE),
        ("LIGHT_TRACING", estimator::LIGHT_TRACING),
    ];
    // Every name once: an estimator added to ALL must be added here too.
    assert_eq!(names.map(|(_, v)| v), estimator::ALL);
    json_names(&names)
}

/// `tensors.json`: the model graph's tensor names by their constant's name, in `tensor::ALL`'s
/// order.
fn tensors_json() -> String {
    let names = [
        ("INPUT", tensor::INPUT),
        ("EXPOSURE", tensor::EXPOSURE),
        ("OUTPUT", tensor::OUTPUT),
    ];
    assert_eq!(names.map(|(_, v)| v), tensor::ALL);
    json_names(&names)
}

/// `model_meta.json`: the ONNX metadata keys of a model that `denoise` reads, by their
/// constant's name (`header::CHANNELS`, `header::model`).
fn model_meta_json() -> String {
    json_names(&[
        ("CHANNELS", header::CHANNELS),
        ("FEATURE_SAMPLES", header::model::FEATURE_SAMPLES),
        ("MEAN_LUMINANCE", header::model::MEAN_LUMINANCE),
    ])
}

/// Writes `header.exr` and returns `header.json`'s text.
fn write_header_fixture(dir: &Path) -> String {
    let mut image = RgbImage::new(5, 3);
    for (i, p) in image.pixels.iter_mut().enumerate() {
        let v = i as f32 * 0.125;
        *p = [v, 1.0 - v, 1.0e5 * v];
    }
    let run = RunInfo {
        program_version: "0.1.0".into(),
        ..RunInfo::new(
            "path-tracing",
            64,
            7,
            1.25,
            "0123456789abcdef0123456789abcdef",
        )
    };
    run.write_attributes(&mut image.attributes);
    image.set_attribute(header::PIXEL_FILTER, "box");
    image.set_attribute(header::SINGULARITY, "clamp(eps=1e-2 m)");
    image.set_attribute(header::PIXEL_SAMPLES, 4);
    image.set_attribute(header::DENOISER, "default.onnx");
    image.set_attribute(header::DENOISE_SECONDS, 0.5);
    image.set_attribute(header::DENOISE_CPU_SECONDS, 0.875);
    image.set_attribute(header::FEATURE_SECONDS, 0.375);
    write_rgb(&dir.join("header.exr"), &image).unwrap();

    let numbers = [
        (header::SAMPLES, run.samples.to_string()),
        (header::SEED, run.seed.to_string()),
        (header::SECONDS, json_f64(run.seconds)),
        (header::PIXEL_SAMPLES, "4".to_string()),
        (header::DENOISE_SECONDS, json_f64(0.5)),
        (header::DENOISE_CPU_SECONDS, json_f64(0.875)),
        (header::FEATURE_SECONDS, json_f64(0.375)),
    ];
    let mut rows = Vec::new();
    // Every image key, in the header module's order (CHANNELS is ONNX model metadata).
    for key in header::ALL.iter().filter(|&&k| k != header::CHANNELS) {
        let value = match numbers.iter().find(|(k, _)| k == key) {
            Some((_, v)) => v.clone(),
            None => json_str(image.attribute(key).unwrap()),
        };
        // What was written is what the number says.
        assert_eq!(
            image.attribute(key).unwrap().parse::<f64>().ok(),
            value.parse::<f64>().ok(),
            "{key}"
        );
        rows.push(format!("  {}: {value}", json_str(key)));
    }
    format!("{{\n{}\n}}\n", rows.join(",\n"))
}

/// Writes `exposure_input.exr` and returns `exposure.json`'s text.
fn write_exposure_fixture(dir: &Path) -> String {
    let (w, h) = (7, 4);
    let mut image = RgbImage::new(w, h);
    for (i, p) in image.pixels.iter_mut().enumerate() {
        let (x, y) = ((i % w) as f32, (i / w) as f32);
        // Dark, bright, zero and negative values, so every branch of the formula counts.
        *p = [
            0.01 * (1.0 + x) * (1.0 + y),
            if ((x + y) as usize).is_multiple_of(3) {
                0.0
            } else {
                20.0 * x
            },
            if i == 5 { -1.0 } else { 0.5 + 0.25 * y },
        ];
    }
    write_rgb(&dir.join("exposure_input.exr"), &image).unwrap();
    let exposure = image.autoexposure();
    // Independent check of the formula: 0.18 / exp(mean ln(max(Y, 0) + 1e-4)), Rec. 709 Y.
    let mean_log = image
        .pixels
        .iter()
        .map(|p| {
            let y = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            (y.max(0.0) + 1e-4).ln()
        })
        .sum::<f64>()
        / (w * h) as f64;
    assert!((exposure - 0.18 / mean_log.exp()).abs() <= 1e-15 * exposure);

    // The denoiser's brightening of dim images: the image times a factor (f32 products), alone
    // or with half of it as emission, its dim_exponent and the exposure the model then gets.
    let mut dim = Vec::new();
    for factor in [1.0f32, 1e-3, 3e-7, 1e-30] {
        let mut scaled = image.clone();
        for p in &mut scaled.pixels {
            *p = p.map(|c| c * factor);
        }
        let mut half = scaled.clone();
        for p in &mut half.pixels {
            *p = p.map(|c| 0.5 * c);
        }
        for (label, emission) in [("none", None), ("half", Some(&half))] {
            let e = dim_exponent(&scaled, emission);
            let k = scaled.autoexposure_scaled(2f64.powi(e));
            dim.push(format!(
                "    {{\"factor\": {}, \"emission\": {}, \"exponent\": {e}, \"exposure\": {}, \"evaluation_exposure\": {}}}",
                json_f64(factor as f64),
                json_str(label),
                json_f64(k),
                json_f64(evaluate::metrics::autoexposure(&scaled))
            ));
        }
    }

    // The scaling into a model's octave of mean luminance (range_exponent, 1/16 as the models
    // record it): bright images dimmed, dim ones brightened, with and without the emission.
    let mut range = Vec::new();
    for factor in [1.0f32, 1e-3, 3e-7, 1e4, 1e12] {
        let mut scaled = image.clone();
        for p in &mut scaled.pixels {
            *p = p.map(|c| c * factor);
        }
        let mut half = scaled.clone();
        for p in &mut half.pixels {
            *p = p.map(|c| 0.5 * c);
        }
        for (label, emission) in [("none", None), ("half", Some(&half))] {
            let e = range_exponent(&scaled, emission, RANGE_LUMINANCE);
            range.push(format!(
                "    {{\"factor\": {}, \"emission\": {}, \"exponent\": {e}, \"exposure\": {}}}",
                json_f64(factor as f64),
                json_str(label),
                json_f64(scaled.autoexposure_scaled(2f64.powi(e)))
            ));
        }
    }

    let inputs = [0.0f32, 1e-3, 0.05, 0.18, 1.0, 4.0, 100.0, -0.5];
    let mut row = RgbImage::new(inputs.len(), 1);
    row.pixels = inputs.iter().map(|&v| [v; 3]).collect();
    let display = evaluate::metrics::tonemap(&row, exposure);
    let list = |v: Vec<String>| format!("[{}]", v.join(", "));
    format!(
        "{{\n  \"exposure\": {},\n  \"dim_luminance\": {},\n  \"dim\": [\n{}\n  ],\n  \"range_luminance\": {},\n  \"range\": [\n{}\n  ],\n  \"tonemap\": {{\n    \"definition\": {},\n    \"exposure\": {},\n    \"input\": {},\n    \"output\": {}\n  }}\n}}\n",
        json_f64(exposure),
        json_f64(DIM_LUMINANCE),
        dim.join(",\n"),
        json_f64(RANGE_LUMINANCE),
        range.join(",\n"),
        json_str(evaluate::images::TONEMAP),
        json_f64(exposure),
        list(inputs.iter().map(|&v| json_f64(v as f64)).collect()),
        list(display.pixels.iter().map(|p| json_f64(p[0])).collect()),
    )
}

#[test]
fn contract_fixtures_are_what_luxest_io_writes() {
    let tmp = TempDir::new("contract");
    std::fs::write(tmp.path().join("naming.json"), naming_json()).unwrap();
    let header_json = write_header_fixture(tmp.path());
    std::fs::write(tmp.path().join("header.json"), header_json).unwrap();
    std::fs::write(tmp.path().join("denoiser.json"), denoiser_json()).unwrap();
    std::fs::write(tmp.path().join("estimators.json"), estimators_json()).unwrap();
    std::fs::write(tmp.path().join("tensors.json"), tensors_json()).unwrap();
    std::fs::write(tmp.path().join("model_meta.json"), model_meta_json()).unwrap();
    let exposure_json = write_exposure_fixture(tmp.path());
    std::fs::write(tmp.path().join("exposure.json"), exposure_json).unwrap();

    let committed = repo_root().join("tests/fixtures/contract");
    let bless = std::env::var_os("LUXEST_BLESS").is_some_and(|v| v == "1");
    let mut stale = Vec::new();
    for name in [
        "naming.json",
        "header.exr",
        "header.json",
        "denoiser.json",
        "estimators.json",
        "tensors.json",
        "model_meta.json",
        "exposure_input.exr",
        "exposure.json",
    ] {
        let fresh = std::fs::read(tmp.path().join(name)).unwrap();
        let path = committed.join(name);
        if bless {
            std::fs::create_dir_all(&committed).unwrap();
            std::fs::write(&path, &fresh).unwrap();
        } else if std::fs::read(&path).ok().as_deref() != Some(&fresh[..]) {
            stale.push(name);
        }
    }
    assert!(
        stale.is_empty(),
        "tests/fixtures/contract/{stale:?} differ from what luxest-io writes now; if the change \
         is intended, rerun with LUXEST_BLESS=1 and make the Python side (python/luxest_contract.py) \
         agree"
    );
}
