//! The isolux plot of a direct-only office work plane: the picture's colours and contours agree
//! with the values, and the PNG round-trips.

use luxest_photometry::isolux::{render_isolux, IsoluxOptions};
use luxest_photometry::{load, CalcGrid, GridSpec, GridStats, Luminaire, Orientation};
use std::path::Path;
use std::sync::Arc;

fn office() -> (CalcGrid, Vec<f64>, Vec<(f64, f64)>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/photometry");
    let troffer = Arc::new(load(&root.join("troffer-600-led.ies")).unwrap());
    let pendant = Arc::new(load(&root.join("pendant-linear-4000.ldt")).unwrap());
    let frame = Orientation::default().frame().unwrap();
    let mut lums: Vec<Luminaire> = [(1.5, 1.0), (4.5, 1.0), (1.5, 3.0), (4.5, 3.0)]
        .iter()
        .map(|&(x, y)| Luminaire {
            photometry: troffer.clone(),
            position: [x, y, 3.0],
            frame,
            multiplier: 1.0,
        })
        .collect();
    lums.push(Luminaire {
        photometry: pendant,
        position: [3.0, 2.0, 2.2],
        frame,
        multiplier: 1.0,
    });
    let grid = CalcGrid::new(GridSpec::work_plane(0.0, 0.0, 6.0, 4.0, 0.75, 0.5)).unwrap();
    let values: Vec<f64> = grid
        .points()
        .iter()
        .map(|&p| {
            lums.iter()
                .map(|l| l.direct_illuminance_lx(p, grid.normal))
                .sum()
        })
        .collect();
    let pos = lums
        .iter()
        .map(|l| (l.position[0], l.position[1]))
        .collect();
    (grid, values, pos)
}

#[test]
fn office_isolux_plot() {
    let (grid, values, pos) = office();
    let sigma: Vec<f64> = values.iter().map(|v| 0.005 * v).collect();
    let stats = GridStats::from_independent(&values, &sigma).unwrap();
    let opts = IsoluxOptions {
        title: "Office work plane 0.75 m: direct illuminance".into(),
        luminaires_st: pos,
        ..Default::default()
    };
    let img = render_isolux(&grid, &values, Some(&stats), &opts).unwrap();
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("office-isolux.png");
    std::fs::write(&out, img.encode_png().unwrap()).unwrap();
    eprintln!(
        "wrote {} ({} x {}); Eavg {:.1} Emin {:.1} U0 {:.3}",
        out.display(),
        img.width,
        img.height,
        stats.e_avg.value,
        stats.e_min.value,
        stats.u0.value
    );
    // Round trip through the PNG decoder.
    let mut decoder =
        png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&out).unwrap()))
            .read_info()
            .unwrap();
    let mut back = vec![0; decoder.output_buffer_size().unwrap()];
    let frame = decoder.next_frame(&mut back).unwrap();
    assert_eq!((frame.width, frame.height), (img.width, img.height));
    assert_eq!(frame.color_type, png::ColorType::Rgb);
    assert_eq!(&back[..frame.buffer_size()], &img.data[..]);
    // The plot is 640 px wide for 6 m: scale 106.67 px/m, origin at (56, 48 + 427).
    let scale = 640.0 / 6.0;
    let px = |s: f64, t: f64| {
        (
            (56.0 + s * scale) as u32,
            (48.0 + 4.0 * scale - t * scale) as u32,
        )
    };
    // The margin is grey, the calculation area coloured.
    assert_eq!(img.pixel(px(0.2, 2.0).0, px(0.2, 2.0).1), [205, 205, 205]);
    let (x, y) = px(grid.local(4, 2).0 + 0.13, grid.local(4, 2).1 + 0.11);
    assert_ne!(img.pixel(x, y), [205, 205, 205]);
    // Ink exists (contours, text) and the legend bar runs from blue at the bottom to red at the top.
    let dark = img
        .data
        .chunks(3)
        .filter(|c| c.iter().all(|&v| v < 60))
        .count();
    assert!(dark > 2000, "{dark}");
    let bar_x = 56 + 640 + 34;
    let top = img.pixel(bar_x, 50);
    let bottom = img.pixel(bar_x, 48 + 427 - 3);
    assert!(top[0] > 180 && top[2] < 100, "{top:?}");
    assert!(bottom[2] > 120 && bottom[0] < 60, "{bottom:?}");
}

#[test]
fn degenerate_grids_render_without_panicking() {
    use luxest_photometry::Spacing;
    for (nu, nv) in [(1, 1), (1, 5), (7, 1)] {
        let mut spec = GridSpec::work_plane(0.0, 0.0, 3.0, 2.0, 0.0, 0.0);
        spec.spacing = Spacing::Counts(nu, nv);
        let g = CalcGrid::new(spec).unwrap();
        for values in [
            vec![100.0; nu * nv],
            (0..nu * nv).map(|k| 50.0 + k as f64).collect(),
        ] {
            let img = render_isolux(&g, &values, None, &IsoluxOptions::default()).unwrap();
            assert!(img.width > 640 && img.height > 220);
        }
    }
    let g = CalcGrid::new(GridSpec::work_plane(0.0, 0.0, 3.0, 2.0, 0.0, 0.0)).unwrap();
    assert!(render_isolux(&g, &[1.0], None, &IsoluxOptions::default()).is_err());
    let mut v = vec![1.0; g.len()];
    v[0] = f64::NAN;
    assert!(render_isolux(&g, &v, None, &IsoluxOptions::default()).is_err());
}

/// Contours in the right place: for a linear ramp E = 100 s (lx, s in m along u) the isolux lines
/// are the verticals s = level/100; the ink must sit there and not 8 px to either side.
#[test]
fn contours_of_a_ramp_are_where_the_values_say() {
    use luxest_photometry::Spacing;
    let mut spec = GridSpec::work_plane(0.0, 0.0, 6.0, 3.0, 0.0, 0.0);
    spec.spacing = Spacing::Counts(12, 6);
    let g = CalcGrid::new(spec).unwrap();
    let values: Vec<f64> = (0..g.nv)
        .flat_map(|j| (0..g.nu).map(move |i| (i, j)))
        .map(|(i, j)| 100.0 * g.local(i, j).0)
        .collect();
    let opts = IsoluxOptions {
        levels_lx: Some(vec![100.0, 250.0, 420.0]),
        ..Default::default()
    };
    let img = render_isolux(&g, &values, None, &opts).unwrap();
    let scale = 640.0 / 6.0;
    let is_ink = |p: [u8; 3]| p.iter().all(|&v| v < 80);
    for level in [100.0, 250.0, 420.0] {
        let x = 56.0 + level / 100.0 * scale;
        // Rows near the top quarter, away from labels placed around mid-segments.
        for y in [60u32, 70, 80] {
            let near = (-1..=1).any(|dx| is_ink(img.pixel((x as i64 + dx) as u32, y)));
            assert!(near, "no contour at level {level} (x = {x}), row {y}");
            for off in [-8.0, 8.0] {
                assert!(
                    !is_ink(img.pixel((x + off) as u32, y)),
                    "ink off the contour at {level}{off:+}"
                );
            }
        }
    }
}

#[test]
fn load_errors_name_the_file() {
    let e = load(Path::new("/nonexistent/lamp.ies"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("/nonexistent/lamp.ies: cannot read"), "{e}");
    let e = load(&crate::common::fixture("../parsers.rs"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown photometric file type"), "{e}");
}
