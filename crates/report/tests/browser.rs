//! The HTML report in a real browser: `report` writes report.html for constructed results (a
//! work plane that fails its Ē_m and meets its U0, two glare views on either side of their
//! limit, a daylight factor that meets its target, a luminance image), headless Chromium
//! renders it to a PNG screenshot, and the screenshot is checked: the page is not blank and
//! ends inside the window after the signature block; the isolux plot and the false-colour
//! luminance image are drawn pixel for pixel as the report wrote them, in the order the layout
//! puts them; the pass / fail marks appear in their colours, in the order of the checks.
//!
//! The browser is `$LUXEST_CHROMIUM`, or `chromium-headless-shell` or `chromium` on the PATH
//! (scripts/setup.sh installs Debian's chromium-headless-shell); without one the test fails
//! and says so.

use luxest_io::color::Rgb;
use luxest_io::image::RgbImage;
use luxest_io::math::Vec3;
use luxest_io::meta::RunInfo;
use luxest_io::sensors::{
    GlareResult, GlareSource, Part, SensorGrid, SensorResults, SensorSetResult, SensorValue,
    SkyInfo,
};
use luxest_io::texture_image::{decode_png, Samples};
use report::html::{FAIL_RGB, PASS_RGB};
use std::path::{Path, PathBuf};
use std::process::Command;

const WINDOW: (usize, usize) = (1000, 4000);

/// A scratch directory removed on drop.
struct Scratch(PathBuf);
impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn browser() -> PathBuf {
    if let Some(p) = std::env::var_os("LUXEST_CHROMIUM") {
        return PathBuf::from(p);
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    for name in ["chromium-headless-shell", "chromium"] {
        for dir in std::env::split_paths(&path) {
            if dir.join(name).is_file() {
                return dir.join(name);
            }
        }
    }
    panic!(
        "headless Chromium not found (neither chromium-headless-shell nor chromium on the PATH, \
         LUXEST_CHROMIUM unset): run scripts/setup.sh, which installs Debian's \
         chromium-headless-shell, or set LUXEST_CHROMIUM to a Chromium binary"
    );
}

/// A 6 x 4 work plane at 0.75 m over a 7 m x 5 m floor, E = 150 + 60 i + 20 j lx.
fn results() -> SensorResults {
    let (nu, nv) = (6usize, 4usize);
    let points = (0..nu * nv)
        .map(|k| {
            let (i, j) = (k % nu, k / nu);
            let p = Vec3::new(1.0 + i as f64, 0.75, 4.0 - j as f64);
            let e = 150.0 + 60.0 * i as f64 + 20.0 * j as f64;
            SensorValue::new(p, Vec3::new(0.0, 1.0, 0.0), e, 1.5, Rgb([e; 3]))
        })
        .collect();
    let glare = |view: Vec3, ugr: f64| GlareResult {
        observer: "desk".into(),
        position: Vec3::new(2.0, 1.2, 2.5),
        view,
        ugr,
        standard_error: 0.1,
        background_luminance: Part {
            value: 40.0,
            standard_error: 0.2,
        },
        limit: Some(19.0),
        sources: vec![GlareSource {
            luminaire: "L1".into(),
            luminance: 5000.0,
            solid_angle_sr: 0.01,
            position_index: 2.0,
        }],
        note: None,
    };
    SensorResults {
        scene: "room".into(),
        run: RunInfo::new("local-estimate", 100_000, 1, 0.5, "00ff"),
        unit: "lx".into(),
        singularity: "none".into(),
        sets: vec![SensorSetResult {
            name: "work-plane".into(),
            grid: Some(SensorGrid {
                nu: nu as u32,
                nv: nv as u32,
                origin: Vec3::new(0.0, 0.75, 5.0),
                u: Vec3::new(7.0, 0.0, 0.0),
                v: Vec3::new(0.0, 0.0, -5.0),
                margin_m: 0.5,
            }),
            kind: None,
            points,
            batches: Vec::new(),
        }],
        glare: vec![
            glare(Vec3::new(1.0, 0.0, 0.0), 16.2),
            glare(Vec3::new(0.0, 0.0, -1.0), 21.0),
        ],
        sky: Some(SkyInfo {
            description: "CIE overcast sky (gensky -c)".into(),
            horizontal_illuminance_lux: 10_000.0,
            sky_horizontal_illuminance_lux: 10_000.0,
            sun: None,
        }),
    }
}

const SCENE_INFO: &str = r#"(name: "room",
 emitters: [Luminaire(name: "L1", position: (3.5, 2.8, 2.5), photometry: 0, multiplier: 0.8,
                      maintenance_factor: 0.8, flux_rgb: (2880.0, 2880.0, 2880.0)),
            Luminaire(name: "downlight-with-a-long-name", position: (1.5, 2.8, 1.5),
                      photometry: 1, multiplier: 1.0, flux_rgb: (1500.0, 1500.0, 1500.0))],
 photometries: [(source: "photometry/troffer-600-led.ies", table_flux_lm: 3600.0,
                 file_flux_lm: 3600.0, input_watts: 30.0),
                (source: "photometry/a-downlight-from-a-manufacturer-catalogue.ies",
                 table_flux_lm: 1500.0)],
 sensors: [(name: "work-plane",
            requirements: (em_lux: 500.0, u0: 0.6,
                           daylight_factor: (median_percent: 2.0, min_percent: 0.7)))])
// content hash 00ff
"#;

/// An sRGB screenshot, 3 bytes a pixel.
struct Shot {
    w: usize,
    h: usize,
    rgb: Vec<u8>,
}

impl Shot {
    fn read(path: &Path) -> Shot {
        let bytes = std::fs::read(path).unwrap();
        let t = decode_png(path, &bytes).unwrap();
        let Samples::U8(s) = t.samples else {
            panic!("{}: not an 8-bit PNG", path.display())
        };
        let rgb = s
            .chunks(t.channels)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        Shot {
            w: t.width,
            h: t.height,
            rgb,
        }
    }
    fn at(&self, x: usize, y: usize) -> [u8; 3] {
        let k = 3 * (y * self.w + x);
        [self.rgb[k], self.rgb[k + 1], self.rgb[k + 2]]
    }
}

fn near(a: [u8; 3], b: [u8; 3]) -> bool {
    (0..3).all(|c| a[c].abs_diff(b[c]) <= 3)
}

/// Where `img` is drawn in `shot` (top-left), matched pixel for pixel at 400 spread samples.
fn find(shot: &Shot, img: &Shot, what: &str) -> (usize, usize) {
    // The anchor: the first strongly coloured pixel along the image's middle row.
    let ay = img.h / 2;
    let ax = (0..img.w)
        .find(|&x| {
            let p = img.at(x, ay);
            p.iter().max().unwrap() - p.iter().min().unwrap() > 60
        })
        .unwrap_or_else(|| panic!("{what}: no coloured pixel on its middle row"));
    let anchor = img.at(ax, ay);
    let samples: Vec<(usize, usize)> = (0..400)
        .map(|k| ((k * 7919) % img.w, (k * 104_729 / 7) % img.h))
        .collect();
    for y in ay..shot.h.saturating_sub(img.h - ay) {
        for x in ax..shot.w.saturating_sub(img.w - ax) {
            if !near(shot.at(x, y), anchor) {
                continue;
            }
            let (ox, oy) = (x - ax, y - ay);
            let hits = samples
                .iter()
                .filter(|&&(sx, sy)| near(shot.at(ox + sx, oy + sy), img.at(sx, sy)))
                .count();
            if hits >= 396 {
                return (ox, oy);
            }
        }
    }
    panic!(
        "{what} ({} x {} px) is not drawn in the screenshot",
        img.w, img.h
    );
}

/// The runs of rows holding a mark colour, top to bottom: (is pass, first row).
fn marks(shot: &Shot) -> Vec<(bool, usize)> {
    let mut out: Vec<(bool, usize)> = Vec::new();
    let mut last: Option<(bool, usize)> = None;
    for y in 0..shot.h {
        let has = |c: [u8; 3]| (0..shot.w).filter(|&x| shot.at(x, y) == c).count() >= 20;
        let row = if has(PASS_RGB) {
            Some(true)
        } else if has(FAIL_RGB) {
            Some(false)
        } else {
            None
        };
        if let Some(p) = row {
            match last {
                Some((q, y1)) if q == p && y1 + 1 == y => {}
                _ => out.push((p, y)),
            }
            last = Some((p, y));
        }
    }
    out
}

#[test]
fn report_html_renders_in_headless_chromium_with_its_images_and_marks() {
    let chromium = browser();
    let dir = std::env::temp_dir().join(format!("luxest-browser-{}", std::process::id()));
    let _scratch = Scratch(dir.clone());
    std::fs::create_dir_all(&dir).unwrap();
    let res = dir.join("room.sensors.ron");
    results().write_ron(&res).unwrap();
    let info = dir.join("scene.info.ron");
    std::fs::write(&info, SCENE_INFO).unwrap();
    // 64 x 48 px: left half 1 cd/m², right half 100 cd/m² (grey, so Y is the value).
    let mut img = RgbImage::new(64, 48);
    for (k, p) in img.pixels.iter_mut().enumerate() {
        *p = [if k % 64 < 32 { 1.0 } else { 100.0 }; 3];
    }
    img.set_attribute(luxest_io::header::SCENE_HASH, "00ff");
    let exr = dir.join("room.exr");
    luxest_io::exr::write_rgb(&exr, &img).unwrap();
    let out = dir.join("report");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let argv = [
        "report".to_string(),
        s(&res),
        "--scene-info".into(),
        s(&info),
        "--luminance".into(),
        s(&exr),
        "-o".into(),
        s(&out),
        "--quiet".into(),
    ];
    let args = luxest_io::cli::parse::<report::cli::Args>(argv.iter().map(String::as_str))
        .unwrap()
        .unwrap();
    report::cli::run(args).unwrap();
    let html = out.join("report.html");
    let text = std::fs::read_to_string(&html).unwrap();
    // Self-contained: no script, no file or network reference besides the data URIs.
    assert!(!text.contains("<script") && !text.contains("src=\"http"));
    assert_eq!(text.matches("src=\"data:image/png;base64,").count(), 2);
    // The Markdown report has the same tables and verdicts.
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    for row in [
        "| work-plane | Ē | 330.00 ± 0.31 lx (0.09 %) | ≥ 500 lx | **FAIL** |",
        "| desk | (2.00, 1.20, 2.50) | (1.00, 0.00, 0.00) | 16.20 ± 0.10 | 40.00 ± 0.20 | 1 | 19 | **PASS** |",
        "| desk | (2.00, 1.20, 2.50) | (0.00, 0.00, -1.00) | 21.00 ± 0.10 | 40.00 ± 0.20 | 1 | 19 | **FAIL** |",
        "| work-plane | DF min | 1.500 ± 0.015 % (1.00 %) | ≥ 0.7 % | **PASS** |",
        "| L1 | `photometry/troffer-600-led.ies` | 3600 | 1 | 1 | 0.8 | 2880.0 | 2880 | 30 |",
        "**FAIL**: 3 of 6 requirements met.",
        "| downlight-with-a-long-name | `photometry/a-downlight-from-a-manufacturer-catalogue.ies` | 1500 (table) | 1 | 1 | 1 | 1500.0 | 1500 | not stated |",
    ] {
        assert!(md.contains(row), "{row}\nnot in\n{md}");
    }

    let shot_path = dir.join("shot.png");
    let run = Command::new(&chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--force-color-profile=srgb",
            "--force-device-scale-factor=1",
            &format!("--user-data-dir={}", dir.join("profile").display()),
            &format!("--window-size={},{}", WINDOW.0, WINDOW.1),
            &format!("--screenshot={}", shot_path.display()),
            &format!("file://{}", html.display()),
        ])
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}", chromium.display()));
    assert!(
        run.status.success() && shot_path.is_file(),
        "{} failed: {}",
        chromium.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    let shot = Shot::read(&shot_path);
    assert_eq!((shot.w, shot.h), WINDOW);

    // Not blank, and the page ends inside the window.
    let inked = |y: usize| (0..shot.w).any(|x| shot.at(x, y) != [255, 255, 255]);
    let first = (0..shot.h).find(|&y| inked(y)).expect("the page is blank");
    let last = (0..shot.h).rev().find(|&y| inked(y)).unwrap();
    assert!(first < 60, "content starts at row {first}");
    assert!(
        last + 20 < shot.h,
        "the page is cut off at the window's {} px",
        shot.h
    );
    // Nothing reaches into the right margin (a table wider than the page would).
    let overflow = (0..shot.h).find(|&y| (shot.w - 12..shot.w).any(|x| shot.at(x, y) != [255; 3]));
    assert_eq!(
        overflow, None,
        "content in the right margin at row {overflow:?}"
    );

    // The marks, in document order: the summary (3 of 6 requirements fail), Ē (330 < 500 lx)
    // and U0 (150/330 < 0.6) on the work plane, the two views (16.2 and 21.0 against 19), the
    // daylight factor's median and minimum (3.3 % and 1.5 % against 2 % and 0.7 %).
    let m = marks(&shot);
    let kinds: Vec<bool> = m.iter().map(|k| k.0).collect();
    assert_eq!(
        kinds,
        [false, false, false, true, false, true, true],
        "marks (pass?, row) top to bottom: {m:?}"
    );

    // The images, drawn as the report wrote them: the isolux plot between the work plane's
    // marks and the glare table's, the luminance image after the daylight marks, the
    // signature block after it.
    let isolux = Shot::read(&out.join("work-plane.isolux.png"));
    let (_, iy) = find(&shot, &isolux, "the isolux plot");
    assert!(
        m[2].1 < iy && iy + isolux.h < m[3].1,
        "isolux at row {iy}, marks {m:?}"
    );
    let lum = Shot::read(&out.join("luminance.png"));
    let (lx, ly) = find(&shot, &lum, "the false-colour luminance image");
    assert!(m[6].1 < ly, "luminance image at row {ly}, marks {m:?}");
    assert!(
        last > ly + lum.h + 100,
        "no signature block below the image"
    );
    // Its halves in the scale's end colours: 1 cd/m² the lowest, 100 the highest.
    let fc = luxest_photometry::isolux::colour;
    let (x0, y0) = (lx + 16, ly + 44);
    assert!(near(shot.at(x0 + 160, y0 + 240), fc(0.0)));
    assert!(near(shot.at(x0 + 480, y0 + 240), fc(1.0)));
}
