//! The `report` stage: figures, tables and plots of calculation surfaces from sensor
//! results, checked against numbers computed here independently — on constructed results with
//! known batches (jackknife standard errors by hand), on bad input (one-line errors, no partial
//! outputs), against a peer, and end to end on a cos³ luminaire over a black floor, where the
//! work plane's illuminance is the closed form of the tabulated distribution.

use crate::util::{compile_text, estimate, StageResult, TempDir};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::meta::RunInfo;
use luxest_io::sensors::{SensorGrid, SensorResults, SensorSetResult, SensorValue};
use report::tables;

/// Runs the report stage in-process as its binary would; the error as printed, with its code.
fn report(args: &[&str]) -> StageResult {
    let argv = std::iter::once("report").chain(args.iter().copied());
    match luxest_io::cli::parse::<report::cli::Args>(argv) {
        Err(e) => Err((e.exit_code(), e.to_string())),
        Ok(None) => Ok(()),
        Ok(Some(a)) => report::cli::run(a).map_err(|e| (e.exit_code(), e.to_string())),
    }
}

/// A 3 x 2 grid: rectangle 4 m x 3 m at y = 0.75 (origin (0, 0.75, 3), u = +x, v = -z), margin
/// 0.5 m, so the points sit on a 1 m lattice at x = 1, 2, 3 and z = 2, 1.
const NU: usize = 3;
const NV: usize = 2;

fn grid() -> SensorGrid {
    SensorGrid {
        nu: NU as u32,
        nv: NV as u32,
        origin: Vec3::new(0.0, 0.75, 3.0),
        u: Vec3::new(4.0, 0.0, 0.0),
        v: Vec3::new(0.0, 0.0, -3.0),
        margin_m: 0.5,
    }
}

fn position(k: usize) -> Vec3 {
    let (i, j) = (k % NU, k / NU);
    Vec3::new(1.0 + i as f64, 0.75, 2.0 - j as f64)
}

/// Four independent batches of the six points (lx).
fn batches() -> Vec<Vec<f64>> {
    vec![
        vec![300.0, 420.0, 310.0, 505.0, 610.0, 498.0],
        vec![296.0, 431.0, 318.0, 497.0, 602.0, 503.0],
        vec![305.0, 415.0, 301.0, 510.0, 620.0, 492.0],
        vec![299.0, 428.0, 305.0, 502.0, 598.0, 507.0],
    ]
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Results with one grid set carrying `batches` (values and errors derived from them as
/// `estimate sensors --batch-values` defines them: mean and standard deviation / √B).
fn results(batches: &[Vec<f64>]) -> SensorResults {
    let b = batches.len() as f64;
    let points = (0..NU * NV)
        .map(|k| {
            let xs: Vec<f64> = batches.iter().map(|x| x[k]).collect();
            let m = mean(&xs);
            let var = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (b - 1.0);
            SensorValue::new(
                position(k),
                Vec3::new(0.0, 1.0, 0.0),
                m,
                (var / b).sqrt(),
                Rgb([m, m, m]),
            )
        })
        .collect();
    SensorResults {
        scene: "room".into(),
        run: RunInfo::new("local-estimate", 4000, 1, 0.5, "00ff"),
        unit: "lx".into(),
        singularity: "none".into(),
        sets: vec![
            SensorSetResult {
                name: "work-plane".into(),
                grid: Some(grid()),
                kind: None,
                points,
                batches: batches.to_vec(),
            },
            // A plain point list: not a surface of the report.
            SensorSetResult {
                name: "probe".into(),
                grid: None,
                kind: None,
                points: vec![SensorValue::new(
                    Vec3::new(0.1, 0.1, 0.1),
                    Vec3::new(0.0, 1.0, 0.0),
                    1.0,
                    0.1,
                    Rgb([1.0, 1.0, 1.0]),
                )],
                batches: vec![],
            },
        ],
        glare: Vec::new(),
        sky: None,
    }
}

/// The delete-one-batch jackknife of `stat` over the batches, written out here (Efron & Stein
/// 1981): θ_(b) from the point means without batch b, SE = √((B−1)/B Σ (θ_(b) − θ̄)²).
fn jackknife(batches: &[Vec<f64>], stat: impl Fn(&[f64]) -> f64) -> (f64, f64) {
    let b = batches.len();
    let n = batches[0].len();
    let means: Vec<f64> = (0..n)
        .map(|k| mean(&batches.iter().map(|x| x[k]).collect::<Vec<_>>()))
        .collect();
    let reps: Vec<f64> = (0..b)
        .map(|drop| {
            let loo: Vec<f64> = (0..n)
                .map(|k| {
                    let xs: Vec<f64> = (0..b)
                        .filter(|&c| c != drop)
                        .map(|c| batches[c][k])
                        .collect();
                    mean(&xs)
                })
                .collect();
            stat(&loo)
        })
        .collect();
    let rm = mean(&reps);
    let bf = b as f64;
    let se = ((bf - 1.0) / bf * reps.iter().map(|r| (r - rm) * (r - rm)).sum::<f64>()).sqrt();
    (stat(&means), se)
}

fn min(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}
fn max(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
}

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-12 * b.abs().max(1.0),
        "{what}: report {a} vs independent {b}"
    );
}

#[test]
fn report_figures_equal_the_jackknife_computed_independently() {
    let dir = TempDir::new("report-figures");
    let res = dir.path().join("room.sensors.ron");
    results(&batches()).write_ron(&res).unwrap();
    let out = dir.path().join("out");
    report(&[res.to_str().unwrap(), "-o", out.to_str().unwrap()]).unwrap();

    let table = tables::read_ron(&out.join("work-plane.ron")).unwrap();
    let f = &table.figures;
    let b = batches();
    let (avg, avg_se) = jackknife(&b, mean);
    let (emin, emin_se) = jackknife(&b, min);
    let (emax, emax_se) = jackknife(&b, max);
    let (u0, u0_se) = jackknife(&b, |v| min(v) / mean(v));
    let (ud, ud_se) = jackknife(&b, |v| min(v) / max(v));
    // For the mean, the jackknife is the batch-means standard error: check that too.
    let grid_means: Vec<f64> = b.iter().map(|x| mean(x)).collect();
    let gm = mean(&grid_means);
    let batch_means_se =
        (grid_means.iter().map(|x| (x - gm) * (x - gm)).sum::<f64>() / (4.0 * 3.0)).sqrt();
    close(avg_se, batch_means_se, "SE(Eavg) two ways");
    close(f.e_avg_lx.value, avg, "Eavg");
    close(f.e_avg_lx.standard_error, avg_se, "SE(Eavg)");
    close(f.e_min_lx.value, emin, "Emin");
    close(f.e_min_lx.standard_error, emin_se, "SE(Emin)");
    close(f.e_max_lx.value, emax, "Emax");
    close(f.e_max_lx.standard_error, emax_se, "SE(Emax)");
    close(f.u0.value, u0, "U0");
    close(f.u0.standard_error, u0_se, "SE(U0)");
    close(f.ud.value, ud, "Ud");
    close(f.ud.standard_error, ud_se, "SE(Ud)");
    assert_eq!(f.uncertainty, "jackknife over 4 batches");
    assert_eq!((table.nu, table.nv), (3, 2));
    assert_eq!(table.spacing_m, (1.0, 1.0));

    // CSV and RON rows: the input's positions, values and errors, read back exactly.
    let csv = tables::read_csv(&out.join("work-plane.csv")).unwrap();
    assert_eq!(csv, table.points);
    let input = results(&b);
    for (k, row) in csv.iter().enumerate() {
        let p = &input.sets[0].points[k];
        assert_eq!((row.index, row.i, row.j), (k, k % NU, k / NU));
        assert_eq!(row.position, (p.position.x, p.position.y, p.position.z));
        assert_eq!(row.illuminance_lx, p.value);
        assert_eq!(row.standard_error_lx, p.standard_error);
    }

    // The plot is a PNG; the report states the figures as the table holds them.
    let png = std::fs::read(out.join("work-plane.isolux.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    let line = format!(
        "| Eavg | {} |",
        report::markdown::format_figure(avg, avg_se, "lx")
    );
    assert!(md.contains(&line), "{line} missing from\n{md}");
    assert!(md.contains("3 × 2 = 6 points"));
    assert!(!md.contains("probe"), "a point list is not a surface");
    // Exactly the planned outputs, nothing else (no temporaries).
    let mut names: Vec<String> = dir
        .files()
        .iter()
        .filter(|p| p.starts_with(&out))
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "report.html",
            "report.md",
            "work-plane.csv",
            "work-plane.isolux.png",
            "work-plane.ron"
        ]
    );
}

/// Runs the report on `res`, expects a one-line exit-1 error containing `needle` and naming
/// the results file, and no output at all.
fn refused(dir: &TempDir, res: &SensorResults, needle: &str) {
    let path = dir.path().join("bad.sensors.ron");
    res.write_ron(&path).unwrap();
    let out = dir.path().join("out");
    let (code, msg) = report(&[path.to_str().unwrap(), "-o", out.to_str().unwrap()]).unwrap_err();
    assert_eq!(code, 1, "{msg}");
    assert!(!msg.contains('\n'), "not one line: {msg}");
    assert!(
        msg.contains("bad.sensors.ron"),
        "does not name the file: {msg}"
    );
    assert!(msg.contains(needle), "{msg:?} lacks {needle:?}");
    assert!(!out.exists(), "partial output left in {}", out.display());
}

#[test]
fn bad_results_are_refused_in_one_line_without_outputs() {
    let dir = TempDir::new("report-bad");
    // No grid anywhere.
    let mut r = results(&batches());
    r.sets[0].grid = None;
    refused(&dir, &r, "no calculation grid");
    // A batch with one point missing.
    let mut r = results(&batches());
    r.sets[0].batches[2].pop();
    refused(&dir, &r, "batch 2");
    // A single batch: no uncertainty can be propagated.
    let mut r = results(&batches());
    r.sets[0].batches.truncate(1);
    refused(&dir, &r, "at least 2 batches");
    // NaN in a batch and in a value.
    let mut r = results(&batches());
    r.sets[0].batches[1][4] = f64::NAN;
    refused(&dir, &r, "point 4");
    let mut r = results(&batches());
    r.sets[0].points[3].value = f64::NAN;
    refused(&dir, &r, "point 3");
    // Fewer points than the grid has.
    let mut r = results(&batches());
    r.sets[0].points.pop();
    refused(&dir, &r, "3 x 2 = 6 points");
    // Points that are not where the grid puts them.
    let mut r = results(&batches());
    r.sets[0].points[1].position.x += 0.25;
    refused(&dir, &r, "not the grid's");
    // A value edited away from its batches' mean (it was shown beside figures from the
    // batches), and a negative illuminance (U0 came out negative).
    let mut r = results(&batches());
    r.sets[0].points[2].value = 1000.0;
    refused(
        &dir,
        &r,
        "point 2: value 1000 is not the mean of its 4 batch values",
    );
    let mut r = results(&batches());
    r.sets[0].batches.clear();
    r.sets[0].points[5].value = -5.0;
    refused(&dir, &r, "point 5: illuminance -5 lx is negative");
    // A results file that is not RON at all.
    let path = dir.write("bad.sensors.ron", "SensorResults(scene: ");
    let (code, msg) = report(&[
        path.to_str().unwrap(),
        "-o",
        dir.path().join("o").to_str().unwrap(),
    ])
    .unwrap_err();
    assert_eq!(code, 1);
    assert!(
        msg.contains("bad.sensors.ron") && !msg.contains('\n'),
        "{msg}"
    );
}

#[test]
fn peer_comparison_flags_points_outside_one_percent_plus_three_sigma() {
    let dir = TempDir::new("report-peer");
    let res = dir.path().join("room.sensors.ron");
    let r = results(&batches());
    r.write_ron(&res).unwrap();
    let write_peer = |shift_k: usize, factor: f64| {
        let mut text = String::from(
            "# name: Peer\n# cpu_seconds: 2.5\nset,index,x,y,z,illuminance_lx,standard_error_lx\n",
        );
        for (k, p) in r.sets[0].points.iter().enumerate() {
            let v = if k == shift_k {
                p.value * factor
            } else {
                p.value
            };
            text += &format!(
                "work-plane,{k},{},{},{},{v},0.5\n",
                p.position.x, p.position.y, p.position.z
            );
        }
        dir.write("peer.csv", text)
    };
    // Point 2 at 1.5 % + 3.5 σ above luxest's: outside 1 % + 3 σ (σ of the point computed here).
    let p2 = &r.sets[0].points[2];
    let sigma = (p2.standard_error.powi(2) + 0.25).sqrt();
    let factor = 1.0 + (0.015 * p2.value + 3.5 * sigma) / p2.value;
    let peer = write_peer(2, factor);
    let out = dir.path().join("out");
    let args = [
        res.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--peer",
        peer.to_str().unwrap(),
    ];
    report(&args).unwrap();
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("### work-plane: FAIL"), "{md}");
    assert!(md.contains("5 of 6 points agree"));
    assert!(md.contains("Peer 2.5 CPU s"));
    let mut strict = args.to_vec();
    strict.push("--require-peer-agreement");
    let (code, msg) = report(&strict).unwrap_err();
    assert_eq!(code, 1);
    assert!(
        msg.contains("peer.csv") && msg.contains("work-plane"),
        "{msg}"
    );
    // 0.9 % off, inside the 1 % alone: every point agrees.
    write_peer(2, 1.009);
    report(&strict).unwrap();
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("### work-plane: PASS") && md.contains("6 of 6 points agree"),
        "{md}"
    );
}

#[test]
fn malformed_peer_files_are_refused_in_one_line_naming_file_and_line_without_outputs() {
    let dir = TempDir::new("report-bad-peer");
    let res = dir.path().join("room.sensors.ron");
    let r = results(&batches());
    r.write_ron(&res).unwrap();
    let good: Vec<String> = r.sets[0]
        .points
        .iter()
        .enumerate()
        .map(|(k, p)| {
            format!(
                "work-plane,{k},{},{},{},{},0.5",
                p.position.x, p.position.y, p.position.z, p.value
            )
        })
        .collect();
    let head = "# name: Peer\nset,index,x,y,z,illuminance_lx,standard_error_lx\n";
    let with_row = |k: usize, row: &str| {
        let mut rows = good.clone();
        rows[k] = row.to_string();
        format!("{head}{}\n", rows.join("\n"))
    };
    let p1 = &r.sets[0].points[1];
    let cases = [
        // (file text, expected part of the message); line numbers count the comment line.
        (
            with_row(1, "work-plane,1,0.5,0.75,2.0,NaN,0.5"),
            "line 4: not a finite number",
        ),
        (
            with_row(2, "work-plane,2,0.5,0.75"),
            "line 5: 4 fields, expected 7",
        ),
        (
            format!("# name: Peer\nset,x,y\n{}\n", good.join("\n")),
            "line 2: expected the header",
        ),
        (
            with_row(
                1,
                &format!(
                    "work-plane,1,{},{},{},{},0.5",
                    p1.position.x + 0.2,
                    p1.position.y,
                    p1.position.z,
                    p1.value
                ),
            ),
            "differs from luxest's",
        ),
        // Well-formed, but of another scene's surface: nothing would be compared.
        (
            format!(
                "{head}{}\n",
                good.join("\n").replace("work-plane,", "desk,")
            ),
            "line 3: set \"desk\" is no surface of",
        ),
        // One point of a set that is no surface (misspelt): it would be left out.
        (
            with_row(
                3,
                &format!(
                    "Work-plane,3,{},{},{},{},0.5",
                    r.sets[0].points[3].position.x,
                    r.sets[0].points[3].position.y,
                    r.sets[0].points[3].position.z,
                    r.sets[0].points[3].value
                ),
            ),
            "line 6: set \"Work-plane\" is no surface of",
        ),
    ];
    for (i, (text, want)) in cases.iter().enumerate() {
        let peer = dir.write(&format!("peer{i}.csv"), text);
        let out = dir.path().join(format!("out{i}"));
        let (code, msg) = report(&[
            res.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--peer",
            peer.to_str().unwrap(),
        ])
        .unwrap_err();
        assert_eq!(code, 1, "{msg}");
        assert!(
            !msg.contains('\n') && msg.contains(&format!("peer{i}.csv")) && msg.contains(want),
            "case {i}: {msg}"
        );
        assert!(!out.exists(), "case {i}: {} was made", out.display());
    }
    // Agreement with no peer to agree with is a usage error, not a pass.
    let out = dir.path().join("out-nopeer");
    let (code, msg) = report(&[
        res.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--require-peer-agreement",
    ])
    .unwrap_err();
    assert_eq!(code, 2, "{msg}");
    assert!(msg.contains("--peer"), "{msg}");
    assert!(!out.exists());
}

/// An IES file of I(γ) = 1000 cd cos³γ (0 above the horizontal) at 5° steps, rotationally
/// symmetric, every value written in full precision.
fn cos3_ies() -> String {
    let gammas: Vec<f64> = (0..=18).map(|j| 5.0 * j as f64).collect();
    let cd: Vec<String> = gammas
        .iter()
        .map(|g| format!("{:e}", cos3_node(*g)))
        .collect();
    format!(
        "IESNA:LM-63-2002\n[TEST] luxest test\nTILT=NONE\n1 -1 1 19 1 1 2 0 0 0\n1 1 0\n{}\n0\n{}\n",
        gammas
            .iter()
            .map(|g| g.to_string())
            .collect::<Vec<_>>()
            .join(" "),
        cd.join(" ")
    )
}

fn cos3_node(gamma_deg: f64) -> f64 {
    1000.0 * gamma_deg.to_radians().cos().max(0.0).powi(3)
}

/// The distribution as the standards read the table: linear in γ between the 5° nodes.
fn cos3_table(gamma_deg: f64) -> f64 {
    let j = ((gamma_deg / 5.0).floor() as usize).min(17);
    let t = (gamma_deg - 5.0 * j as f64) / 5.0;
    (1.0 - t) * cos3_node(5.0 * j as f64) + t * cos3_node(5.0 * (j + 1) as f64)
}

#[test]
fn cos3_luminaire_over_a_black_floor_gives_the_closed_form_work_plane() {
    let dir = TempDir::new("report-cos3");
    dir.write("cos3.ies", cos3_ies());
    let (lx, ly, lz) = (1.7, 3.0, 1.2);
    // EN 12464-1 layout, computed here: area 3 m x 2 m, d = 3 m (not a corridor),
    // p = 0.2 · 5^log10(3) m, n = ⌈L/p⌉.
    let p = 0.2 * 5f64.powf(3f64.log10());
    let (nu, nv) = ((3.0 / p).ceil() as usize, (2.0 / p).ceil() as usize);
    let mut e = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let x = 0.5 + (i as f64 + 0.5) * 3.0 / nu as f64;
            let z = 3.0 - (0.5 + (j as f64 + 0.5) * 2.0 / nv as f64);
            let d = [lx - x, ly - 0.75, lz - z];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let cos = d[1] / r2.sqrt();
            // E = I(γ) cos γ / r² (inverse-square and cosine laws).
            e.push(cos3_table(cos.acos().to_degrees()) * cos / r2);
        }
    }
    // Requirements either side of the closed form: Ē passes, U0 fails.
    let em_req = 0.9 * mean(&e);
    let u0_req = (1.1 * min(&e) / mean(&e)).min(1.0);
    assert!(u0_req > min(&e) / mean(&e));
    // The multiplier 2 and the maintenance factor 0.5 multiply the intensities: the table's.
    let text = format!(
        r#"Scene(name: "cos3",
        materials: {{ "black": Lambertian(reflectance: (0.0, 0.0, 0.0)) }},
        objects: [(shape: Quad(corner: (-10.0, 0.0, -10.0), u: (0.0, 0.0, 20.0), v: (20.0, 0.0, 0.0)),
                   material: "black")],
        luminaires: [(name: "spot", file: "cos3.ies", position: ({lx}, {ly}, {lz}),
                      multiplier: 2.0, maintenance_factor: 0.5)],
        calculation_surfaces: [(name: "work-plane", area: Floor(min: (0.0, 0.0), max: (4.0, 3.0), y: 0.0),
                                offset: 0.75, margin: 0.5,
                                requirements: (em_lux: {em_req:?}, u0: {u0_req:?}))])"#
    );
    let lxs = compile_text(&dir, "cos3", &text);
    let res = dir.path().join("cos3.sensors.ron");
    estimate(&[
        "sensors",
        lxs.to_str().unwrap(),
        "-o",
        res.to_str().unwrap(),
        "--paths",
        "2000",
        "--batch-values",
    ])
    .unwrap();
    // The header as `scene-compile --info` prints it (the same function).
    let scene = luxest_render::compiled::CompiledScene::load(&lxs).unwrap();
    let info = dir.write("scene.info.ron", scene_compile::cli::info_text(&scene));
    let out = dir.path().join("report");
    report(&[
        res.to_str().unwrap(),
        "--scene-info",
        info.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ])
    .unwrap();
    let table = tables::read_ron(&out.join("work-plane.ron")).unwrap();

    assert_eq!((table.nu, table.nv), (nu, nv));
    let eavg = mean(&e);
    let f = &table.figures;
    // Direct light only, computed deterministically by the local estimate: exact to 1e-9.
    assert!(
        (f.e_avg_lx.value - eavg).abs() <= 1e-9 * eavg,
        "{} vs {eavg}",
        f.e_avg_lx.value
    );
    assert!((f.e_min_lx.value - min(&e)).abs() <= 1e-9 * min(&e));
    assert!((f.e_max_lx.value - max(&e)).abs() <= 1e-9 * max(&e));
    assert!((f.u0.value - min(&e) / eavg).abs() <= 1e-9);
    // Every batch gives the same direct term: the standard error is rounding only.
    assert!(f.e_avg_lx.standard_error <= 1e-12 * eavg);
    for (row, ek) in table.points.iter().zip(&e) {
        assert!(
            (row.illuminance_lx - ek).abs() <= 1e-9 * ek,
            "point {}",
            row.index
        );
    }
    // The luminaire list: the file, one luminaire, the table's flux. ∫ I dΩ of the γ-linear
    // table = 2π Σ over 5° intervals of ∫ I(γ) sin γ dγ, by Simpson's rule on a fine mesh here.
    let n = 18 * 200;
    let h = 90f64.to_radians() / n as f64;
    let flux: f64 = (0..=n)
        .map(|k| {
            let g = k as f64 * h;
            let w = if k == 0 || k == n {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * cos3_table(g.to_degrees()) * g.sin()
        })
        .sum::<f64>()
        * h
        / 3.0
        * 2.0
        * std::f64::consts::PI;
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    // The schedule: luminaire, file, lumens (the file states none: the table's), count 1,
    // multiplier 2, MF 0.5.
    let row = format!("| spot | `cos3.ies` | {flux:.0} (table) | 1 | 2 | 0.5 | ");
    assert!(md.contains(&row), "{row}\nnot in\n{md}");
    // The requirements, from the scene through the compiled header, checked.
    assert!(
        md.contains("| work-plane | Ē | ") && md.contains(&format!("| ≥ {em_req} lx | **PASS** |")),
        "{md}"
    );
    assert!(md.contains(&format!("| ≥ {u0_req} | **FAIL** |")), "{md}");
    assert!(md.contains("**FAIL**: 1 of 2 requirements met."), "{md}");
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert_eq!(
        html.matches("<span class=\"mark fail\">FAIL</span>")
            .count(),
        2
    );
    assert_eq!(
        html.matches("<span class=\"mark pass\">PASS</span>")
            .count(),
        1
    );
    assert!(
        md.contains(&format!("{flux:.1}")),
        "flux {flux:.1} lm not in\n{md}"
    );
}

/// A surface that receives no light at any point (facing away, below the floor) has no
/// uniformity: the report says so instead of "U0 0.000 ± 0.000".
#[test]
fn uniformity_of_an_unlit_surface_is_undefined() {
    let dir = TempDir::new("report-dark");
    let res = dir.path().join("room.sensors.ron");
    let zeros = vec![vec![0.0; NU * NV]; 4];
    results(&zeros).write_ron(&res).unwrap();
    let out = dir.path().join("out");
    report(&[res.to_str().unwrap(), "-o", out.to_str().unwrap()]).unwrap();
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    for figure in ["U0 = Emin/Eavg", "Ud = Emin/Emax"] {
        assert!(
            md.contains(&format!(
                "| {figure} | undefined: no point of the surface receives light |"
            )),
            "{md}"
        );
    }
    // A lit surface keeps its numbers.
    let lit = dir.path().join("lit.sensors.ron");
    results(&batches()).write_ron(&lit).unwrap();
    let out = dir.path().join("out-lit");
    report(&[lit.to_str().unwrap(), "-o", out.to_str().unwrap()]).unwrap();
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("| U0 = Emin/Eavg | 0.") && !md.contains("undefined"),
        "{md}"
    );
}
