//! The tabular UGR of a luminaire (CIE 190:2010, the tabular method of CIE 117-1995): the
//! standard table of room sizes × reflectance combinations, viewed crosswise and endwise.
//!
//! **The standard room.** A box X × Y × H: H is the height of the luminaire plane above the
//! eye plane (the "floor" of the table is the floor cavity at eye level), X the room dimension
//! across the line of sight, Y along it, both in units of H (2H … 12H: [`ROOMS`]). The observer
//! sits at the middle of the wall of length X, eyes in the eye plane, looking horizontally
//! along Y. The luminaires fill the ceiling plane on a square grid of spacing S = 0.25 H (cell
//! centres, 4X × 4Y luminaires), each at the file's flux. *Endwise*: the line of sight is
//! parallel to the luminaire's C0–C180 axis (the axis of a linear luminaire's `length`);
//! *crosswise*: perpendicular to it.
//!
//! **Background.** L_b = E_W,ind / π, the indirect illuminance on the walls (CIE 117's value
//! for the eye at the wall) from a three-surface inter-reflection: ceiling, walls and floor
//! with the reflectances of [`REFLECTANCES`] (ceiling / walls / floor cavity), form factors of
//! the box in closed form (parallel rectangles; the rest by reciprocity and summation), and the
//! direct flux each surface receives from every luminaire, integrated over its intensity table
//! on a 5° × 2.5° (C, γ) grid.
//!
//! **Glare sum.** Σ L² ω / p² over every luminaire in the field of view, with L = I / A_p and
//! the far-field ω = A_p / D² of the tabular method (so the table does not depend on H), and
//! p from [`crate::ugr::position_index`] (Guth above the line of sight, capped at 16).
//!
//! `pipelines/ugr_table_check.py` computes the same definition independently (its own parsers,
//! brute-force form factors and direct flux) and `tests` compares both.

use crate::frame::{direction_from_c_gamma, Frame};
use crate::photometry::Photometry;
use crate::ugr::{GlareLuminaire, GlareTerm, SolidAngle};
use std::f64::consts::PI;

/// The table's rooms (X, Y) in units of H, in the standard order.
pub const ROOMS: [(f64, f64); 19] = [
    (2.0, 2.0),
    (2.0, 3.0),
    (2.0, 4.0),
    (2.0, 6.0),
    (2.0, 8.0),
    (2.0, 12.0),
    (4.0, 2.0),
    (4.0, 3.0),
    (4.0, 4.0),
    (4.0, 6.0),
    (4.0, 8.0),
    (4.0, 12.0),
    (8.0, 4.0),
    (8.0, 6.0),
    (8.0, 8.0),
    (8.0, 12.0),
    (12.0, 4.0),
    (12.0, 6.0),
    (12.0, 8.0),
];

/// The reflectance combinations (ceiling, walls, floor cavity), in the standard order.
pub const REFLECTANCES: [[f64; 3]; 5] = [
    [0.7, 0.5, 0.2],
    [0.7, 0.3, 0.2],
    [0.5, 0.5, 0.2],
    [0.5, 0.3, 0.2],
    [0.3, 0.3, 0.2],
];

/// The reference room of the table: X = 4H, Y = 8H, reflectances 0.7 / 0.5 / 0.2.
pub const REFERENCE: (usize, usize) = (10, 0);

/// Luminaire spacing in units of H.
pub const SPACING_H: f64 = 0.25;

const DC_DEG: f64 = 5.0;
const DG_DEG: f64 = 2.5;

/// A luminaire's UGR table: `crosswise[room][reflectance]`, `endwise[room][reflectance]`.
#[derive(Clone, Debug, PartialEq)]
pub struct UgrTable {
    pub source: String,
    pub flux_lm: f64,
    pub crosswise: Vec<Vec<f64>>,
    pub endwise: Vec<Vec<f64>>,
}

/// The form factor between two directly opposed, parallel a × b rectangles at distance c.
pub fn parallel_rectangles_form_factor(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (x1, y1) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    2.0 / (PI * x * y)
        * (0.5 * ((1.0 + x * x) * (1.0 + y * y) / (1.0 + x * x + y * y)).ln()
            + x * y1 * (x / y1).atan()
            + y * x1 * (y / x1).atan()
            - x * x.atan()
            - y * y.atan())
}

/// The direct flux (lm) reaching the ceiling, the walls and the floor of an X × Y (units of H,
/// H = 1) room from all luminaires of the grid, oriented by `frame`.
fn direct_flux(p: &Photometry, frame: &Frame, x: f64, y: f64) -> [f64; 3] {
    // Per direction cell of the luminaire: its world direction and flux I dΩ.
    let (nc, ng) = ((360.0 / DC_DEG) as usize, (180.0 / DG_DEG) as usize);
    let mut up = 0.0;
    let mut down: Vec<([f64; 3], f64)> = Vec::with_capacity(nc * ng / 2);
    for i in 0..nc {
        let c = (i as f64 + 0.5) * DC_DEG;
        for j in 0..ng {
            let (g0, g1) = (j as f64 * DG_DEG, (j + 1) as f64 * DG_DEG);
            let g = 0.5 * (g0 + g1);
            let w = DC_DEG.to_radians() * (g0.to_radians().cos() - g1.to_radians().cos());
            let flux = p.intensity_cd(c, g) * w;
            let d = frame.to_world(direction_from_c_gamma(c, g));
            if d[2] >= 0.0 {
                up += flux;
            } else {
                down.push(([d[0] / -d[2], d[1] / -d[2], 0.0], flux));
            }
        }
    }
    let (nx, ny) = (
        (x / SPACING_H).round() as usize,
        (y / SPACING_H).round() as usize,
    );
    let (mut floor, mut walls) = (0.0, 0.0);
    for ix in 0..nx {
        let lx = (ix as f64 + 0.5) * SPACING_H;
        for iy in 0..ny {
            let ly = (iy as f64 + 0.5) * SPACING_H;
            for (t, flux) in &down {
                let (hx, hy) = (lx + t[0], ly + t[1]);
                if (0.0..=x).contains(&hx) && (0.0..=y).contains(&hy) {
                    floor += flux;
                } else {
                    walls += flux;
                }
            }
        }
    }
    [up * (nx * ny) as f64, walls, floor]
}

/// The background luminance (cd/m²) of the standard room: indirect wall illuminance / π,
/// from the direct flux on ceiling, walls and floor.
fn background(flux: [f64; 3], x: f64, y: f64, rho: [f64; 3]) -> f64 {
    let (ac, aw) = (x * y, 2.0 * (x + y));
    let fcf = parallel_rectangles_form_factor(x, y, 1.0);
    let fcw = 1.0 - fcf;
    let fwc = ac * fcw / aw;
    // Rows: ceiling, walls, floor; F[i][j] = form factor from i to j.
    let f = [
        [0.0, fcw, fcf],
        [fwc, 1.0 - 2.0 * fwc, fwc],
        [fcf, fcw, 0.0],
    ];
    let area = [ac, aw, ac];
    // (I − diag(ρ) F) M = ρ E_direct.
    let mut a = [[0.0; 4]; 3];
    for i in 0..3 {
        for j in 0..3 {
            a[i][j] = if i == j { 1.0 } else { 0.0 } - rho[i] * f[i][j];
        }
        a[i][3] = rho[i] * flux[i] / area[i];
    }
    let m = solve3(a);
    let e_walls_indirect: f64 = (0..3).map(|j| f[1][j] * m[j]).sum();
    e_walls_indirect / PI
}

/// Gaussian elimination of a 3 × 3 system with its right-hand side in column 3.
fn solve3(mut a: [[f64; 4]; 3]) -> [f64; 3] {
    for k in 0..3 {
        let piv = (k..3)
            .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
            .unwrap_or(k);
        a.swap(k, piv);
        for i in 0..3 {
            if i != k {
                let r = a[i][k] / a[k][k];
                let pivot_row = a[k];
                for (x, p) in a[i].iter_mut().zip(pivot_row).skip(k) {
                    *x -= r * p;
                }
            }
        }
    }
    [0, 1, 2].map(|i| a[i][3] / a[i][i])
}

/// One standard room seen one way: the direct flux on ceiling, walls and floor (lm) and the
/// glare sum Σ L² ω / p² (what does not depend on the reflectances).
struct Room {
    x: f64,
    y: f64,
    flux: [f64; 3],
    terms: Vec<GlareTerm>,
}

impl Room {
    fn new(p: &Photometry, x: f64, y: f64, endwise: bool) -> Result<Room, String> {
        // Endwise: the C0–C180 axis (local x) along the line of sight (world +y).
        let frame = if endwise {
            Frame {
                m: [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
            }
        } else {
            Frame::default()
        };
        let (eye, view, up) = ([0.5 * x, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        let (nx, ny) = (
            (x / SPACING_H).round() as usize,
            (y / SPACING_H).round() as usize,
        );
        let mut terms = Vec::with_capacity(nx * ny);
        for ix in 0..nx {
            for iy in 0..ny {
                let lum = GlareLuminaire {
                    photometry: p,
                    opening: p.opening,
                    frame: &frame,
                    multiplier: 1.0,
                    centre: [
                        (ix as f64 + 0.5) * SPACING_H,
                        (iy as f64 + 0.5) * SPACING_H,
                        1.0,
                    ],
                };
                terms.extend(lum.term(eye, view, up, 1.0, SolidAngle::FarField)?);
            }
        }
        Ok(Room {
            x,
            y,
            flux: direct_flux(p, &frame, x, y),
            terms,
        })
    }

    fn ugr(&self, p: &Photometry, rho: [f64; 3]) -> Result<f64, String> {
        let lb = background(self.flux, self.x, self.y, rho);
        let u = crate::ugr::ugr(lb, 0.0, &self.terms).map_err(|m| format!("{}: {m}", p.name))?;
        Ok(u.value)
    }
}

/// The tabular UGR of one room (X, Y in units of H), reflectances and viewing direction.
pub fn tabular_ugr(
    p: &Photometry,
    x: f64,
    y: f64,
    rho: [f64; 3],
    endwise: bool,
) -> Result<f64, String> {
    Room::new(p, x, y, endwise)?.ugr(p, rho)
}

/// The whole table of a luminaire (see the module docs).
pub fn ugr_table(p: &Photometry) -> Result<UgrTable, String> {
    let mut t = UgrTable {
        source: p.name.clone(),
        flux_lm: p.flux_from_table_lm(),
        crosswise: Vec::new(),
        endwise: Vec::new(),
    };
    for &(x, y) in &ROOMS {
        let row = |endwise| -> Result<Vec<f64>, String> {
            let room = Room::new(p, x, y, endwise)?;
            REFLECTANCES.iter().map(|&r| room.ugr(p, r)).collect()
        };
        t.crosswise.push(row(false)?);
        t.endwise.push(row(true)?);
    }
    Ok(t)
}

impl UgrTable {
    /// The reference values (4H × 8H, 0.7 / 0.5 / 0.2): (crosswise, endwise).
    pub fn reference(&self) -> (f64, f64) {
        let (r, k) = REFERENCE;
        (self.crosswise[r][k], self.endwise[r][k])
    }

    /// The table as plain text in the layout of CIE 190 / manufacturers' data sheets, the
    /// reference room's values in brackets.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "UGR table (CIE 190 tabular method, spacing {SPACING_H}H) of {}\nluminaire flux \
             {:.0} lm (the file's); rooms X (across the line of sight) × Y (along it) in units \
             of H, the luminaire plane's height above the eye\n\n",
            self.source, self.flux_lm
        );
        let head: Vec<String> = REFLECTANCES
            .iter()
            .map(|r| {
                format!(
                    "{:.0}/{:.0}/{:.0}",
                    100.0 * r[0],
                    100.0 * r[1],
                    100.0 * r[2]
                )
            })
            .collect();
        s += &format!(
            "{:>4} {:>4} | {:^44} | {:^44}\n",
            "X", "Y", "viewed crosswise", "viewed endwise"
        );
        s += &format!(
            "{:>4} {:>4} | {} | {}\n",
            "",
            "",
            head.iter()
                .map(|h| format!("{h:>8}"))
                .collect::<Vec<_>>()
                .join(" "),
            head.iter()
                .map(|h| format!("{h:>8}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
        for (r, &(x, y)) in ROOMS.iter().enumerate() {
            let cell = |v: f64, k: usize| {
                if (r, k) == REFERENCE {
                    format!("{:>8}", format!("[{v:.1}]"))
                } else {
                    format!("{v:>8.1}")
                }
            };
            let row = |vals: &[f64]| {
                vals.iter()
                    .enumerate()
                    .map(|(k, &v)| cell(v, k))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            s += &format!(
                "{:>3}H {:>3}H | {} | {}\n",
                x,
                y,
                row(&self.crosswise[r]),
                row(&self.endwise[r])
            );
        }
        let (c, e) = self.reference();
        s += &format!("\nreference (4H × 8H, 70/50/20): crosswise {c:.1}, endwise {e:.1}\n");
        s
    }

    /// The table as CSV: `x_h,y_h,ceiling,walls,floor,crosswise,endwise`.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("x_h,y_h,ceiling,walls,floor,crosswise,endwise\n");
        for (r, &(x, y)) in ROOMS.iter().enumerate() {
            for (k, rho) in REFLECTANCES.iter().enumerate() {
                s += &format!(
                    "{x},{y},{},{},{},{:.3},{:.3}\n",
                    rho[0], rho[1], rho[2], self.crosswise[r][k], self.endwise[r][k]
                );
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn form_factors_of_a_box() {
        // Unit cube faces: 0.19982 (Howell's catalogue, C-11).
        assert!((parallel_rectangles_form_factor(1.0, 1.0, 1.0) - 0.199825).abs() < 1e-5);
        // Large plates far apart → A / (π c²) · ...: close plates see each other almost fully.
        assert!(parallel_rectangles_form_factor(1000.0, 1000.0, 1.0) > 0.99);
    }

    /// The whole table of the three example luminaires against pipelines/ugr_table_check.py's
    /// independent evaluation of the same definition (committed CSVs), to ±0.5 UGR (the issue's
    /// tolerance; they agree to a few hundredths).
    #[test]
    fn tables_agree_with_the_independent_evaluation() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        for (file, check) in [
            ("troffer-600-led.ies", "troffer-600-led.check.csv"),
            ("pendant-linear-4000.ldt", "pendant-linear-4000.check.csv"),
            ("downlight-150-round.ies", "downlight-150-round.check.csv"),
        ] {
            let p = crate::load(&root.join("scenes/photometry").join(file)).unwrap();
            let t = ugr_table(&p).unwrap();
            let text = std::fs::read_to_string(root.join("reports/lighting/ugr-table").join(check))
                .unwrap();
            let rows: Vec<Vec<f64>> = text
                .lines()
                .filter(|l| !l.starts_with('#') && !l.starts_with('x'))
                .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
                .collect();
            assert_eq!(rows.len(), ROOMS.len() * REFLECTANCES.len());
            for (n, row) in rows.iter().enumerate() {
                let (r, k) = (n / REFLECTANCES.len(), n % REFLECTANCES.len());
                assert_eq!((row[0], row[1]), ROOMS[r]);
                assert_eq!([row[2], row[3], row[4]], REFLECTANCES[k]);
                for (ours, theirs) in [(t.crosswise[r][k], row[5]), (t.endwise[r][k], row[6])] {
                    assert!(
                        (ours - theirs).abs() <= 0.5,
                        "{file} room {r} refl {k}: {ours} vs {theirs}"
                    );
                }
            }
        }
    }

    #[test]
    fn direct_flux_is_conserved() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/photometry");
        let p = crate::load(&dir.join("troffer-600-led.ies")).unwrap();
        let f = direct_flux(&p, &Frame::default(), 2.0, 3.0);
        let total: f64 = f.iter().sum();
        let expected = p.flux_from_table_lm() * 4.0 * 2.0 * 4.0 * 3.0;
        assert!((total / expected - 1.0).abs() < 0.01, "{total} {expected}");
        // No upward light; a larger room's floor takes a larger share.
        assert!(f[0] == 0.0 && f[1] > 0.0 && f[2] > 0.0, "{f:?}");
        let g = direct_flux(&p, &Frame::default(), 8.0, 8.0);
        assert!(
            g[2] / (g[1] + g[2]) > f[2] / (f[1] + f[2]) && g[2] > g[1],
            "{g:?}"
        );
    }
}
