//! Parity of `evaluate::metrics` with the reference implementations (scikit-image, pytorch_msssim,
//! NVIDIA's flip_evaluator, numpy), on the fixtures of `tests/fixtures/metrics`. Regenerate them
//! with `.venv/bin/python tests/fixtures/metrics/generate.py`.

use crate::util::repo_root;
use evaluate::metrics::{
    autoexposure, flip, ms_ssim, ms_ssim_levels, psnr, rel_mse, smape, ssim, tonemap, Display,
    FLIP_PIXELS_PER_DEGREE,
};
use luxest_io::exr::read_rgb;
use luxest_io::image::RgbImage;
use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;

const TOLERANCE: f64 = 1e-4;

fn fixtures() -> PathBuf {
    repo_root().join("tests/fixtures/metrics")
}

/// `key value` lines; `#` starts a comment.
fn expected() -> HashMap<String, String> {
    let path = fixtures().join("expected.txt");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| {
            let (k, v) = l
                .split_once(' ')
                .unwrap_or_else(|| panic!("bad line {l:?}"));
            (k.to_string(), v.trim().to_string())
        })
        .collect()
}

fn load(name: &str) -> RgbImage {
    let path = fixtures().join(name);
    read_rgb(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

struct Checker {
    expected: HashMap<String, String>,
    /// Metric name -> (max |difference|, count).
    max_diff: BTreeMap<String, (f64, usize)>,
    failures: Vec<String>,
}

impl Checker {
    fn raw(&self, key: &str) -> &str {
        self.expected
            .get(key)
            .unwrap_or_else(|| panic!("expected.txt has no {key}"))
    }

    fn value(&self, key: &str) -> Option<f64> {
        match self.raw(key) {
            "none" => None,
            v => Some(v.parse().unwrap_or_else(|e| panic!("{key}: {v:?}: {e}"))),
        }
    }

    fn number(&self, key: &str) -> f64 {
        self.value(key)
            .unwrap_or_else(|| panic!("{key} is none in expected.txt"))
    }

    /// Compares `got` with the expected value of `key`, recording the difference under `metric`.
    fn check(&mut self, metric: &str, key: &str, got: Option<f64>) {
        let want = self.value(key);
        let diff = match (got, want) {
            (None, None) => 0.0,
            (Some(g), Some(w)) if g == w => 0.0, // includes inf == inf
            (Some(g), Some(w)) if g.is_finite() && w.is_finite() => (g - w).abs(),
            _ => f64::INFINITY,
        };
        println!("{key:<40} rust {got:>24?} reference {want:>24?} |diff| {diff:.3e}");
        let entry = self.max_diff.entry(metric.to_string()).or_insert((0.0, 0));
        entry.0 = entry.0.max(diff);
        entry.1 += 1;
        if diff.is_nan() || diff > TOLERANCE {
            self.failures
                .push(format!("{key}: rust {got:?}, reference {want:?}"));
        }
    }

    fn display_metrics(&mut self, case: &str, reference: &Display, test: &Display) {
        let (w, h) = (reference.width, reference.height);
        assert_eq!(w as f64, self.number(&format!("{case}.width")), "{case}");
        assert_eq!(h as f64, self.number(&format!("{case}.height")), "{case}");
        self.check("psnr", &format!("{case}.psnr"), Some(psnr(reference, test)));
        if self.value(&format!("{case}.ssim")).is_some() {
            self.check("ssim", &format!("{case}.ssim"), Some(ssim(reference, test)));
        }
        let levels = ms_ssim_levels(w.min(h));
        assert_eq!(
            levels as f64,
            self.number(&format!("{case}.ms_ssim_levels")),
            "{case}: MS-SSIM levels"
        );
        self.check(
            "ms_ssim",
            &format!("{case}.ms_ssim"),
            ms_ssim(reference, test),
        );
        assert!(
            (self.number(&format!("{case}.flip_ppd")) - FLIP_PIXELS_PER_DEGREE).abs() < 1e-9,
            "{case}: pixels per degree"
        );
        let f = flip(reference, test);
        assert_eq!(f.map.len(), w * h);
        self.check("flip", &format!("{case}.flip"), Some(f.mean));
        let map_max = f.map.iter().fold(0.0f32, |m, v| m.max(*v)) as f64;
        self.check("flip_map", &format!("{case}.flip_map_max"), Some(map_max));
        let map_mean = f.map.iter().map(|v| *v as f64).sum::<f64>() / f.map.len() as f64;
        self.check("flip_map", &format!("{case}.flip_map_mean"), Some(map_mean));
        let prefix = format!("{case}.flip_map.");
        let mut probes: Vec<(usize, usize)> = self
            .expected
            .keys()
            .filter_map(|k| k.strip_prefix(&prefix))
            .map(|xy| {
                let (x, y) = xy.split_once('.').unwrap();
                (x.parse().unwrap(), y.parse().unwrap())
            })
            .collect();
        probes.sort_unstable();
        assert!(!probes.is_empty(), "{case}: no FLIP map probes");
        for (x, y) in probes {
            let got = f.map[y * w + x] as f64;
            self.check("flip_map", &format!("{prefix}{x}.{y}"), Some(got));
        }
    }
}

#[test]
fn metrics_match_reference_implementations() {
    let mut c = Checker {
        expected: expected(),
        max_diff: BTreeMap::new(),
        failures: Vec::new(),
    };

    let cases = [
        "blur_low",
        "noise_mid",
        "odd_high",
        "color_shift",
        "tiny",
        "identical",
    ];
    for case in cases {
        let reference = Display::from_rgb(&load(c.raw(&format!("{case}.reference"))));
        let test = Display::from_rgb(&load(c.raw(&format!("{case}.test"))));
        c.display_metrics(case, &reference, &test);
    }

    // The identical pair: exact values, not just within the tolerance.
    let ident = Display::from_rgb(&load(c.raw("identical.reference")));
    assert_eq!(psnr(&ident, &ident), f64::INFINITY);
    assert_eq!(flip(&ident, &ident).mean, 0.0);
    assert!((ssim(&ident, &ident) - 1.0).abs() < 1e-12);
    // Too small for MS-SSIM.
    let tiny = Display::from_rgb(&load(c.raw("tiny.reference")));
    assert_eq!(ms_ssim(&tiny, &tiny), None);

    // Linear HDR pair.
    let hdr_ref = load(c.raw("hdr.reference"));
    let hdr_test = load(c.raw("hdr.test"));
    assert!(hdr_test.pixels.iter().any(|p| p.iter().any(|v| *v < 0.0)));
    c.check("rel_mse", "hdr.rel_mse", Some(rel_mse(&hdr_ref, &hdr_test)));
    c.check("smape", "hdr.smape", Some(smape(&hdr_ref, &hdr_test)));
    c.check(
        "rel_mse",
        "hdr.rel_mse_self",
        Some(rel_mse(&hdr_ref, &hdr_ref)),
    );
    let exposure = autoexposure(&hdr_ref);
    c.check("autoexposure", "hdr.autoexposure", Some(exposure));
    let tm_ref = tonemap(&hdr_ref, exposure);
    let tm_test = tonemap(&hdr_test, exposure);
    let w = tm_test.width;
    let prefix = "hdr.tonemap_test.";
    let mut probes: Vec<String> = c
        .expected
        .keys()
        .filter(|k| k.starts_with(prefix))
        .cloned()
        .collect();
    probes.sort();
    assert!(!probes.is_empty());
    for key in probes {
        let parts: Vec<usize> = key[prefix.len()..]
            .split('.')
            .map(|p| p.parse().unwrap())
            .collect();
        let got = tm_test.pixels[parts[1] * w + parts[0]][parts[2]];
        c.check("tonemap", &key, Some(got));
    }
    c.check(
        "tonemap",
        "hdr.tonemap1_psnr",
        Some(psnr(&tonemap(&hdr_ref, 1.0), &tonemap(&hdr_test, 1.0))),
    );
    c.display_metrics("hdr.tm", &tm_ref, &tm_test);

    println!("\nmax |difference| per metric (tolerance {TOLERANCE:e}):");
    for (metric, (diff, n)) in &c.max_diff {
        println!("  {metric:<14} {diff:.3e} over {n} values");
    }
    assert!(
        c.failures.is_empty(),
        "{} values differ by more than {TOLERANCE:e}:\n{}",
        c.failures.len(),
        c.failures.join("\n")
    );
}
