//! The goniometric intensity distribution both parsers produce.
//!
//! A [`Photometry`] holds a table of luminous intensity I (cd, for the real luminaire: the file's
//! values times its multipliers) on a grid of C planes and γ angles (degrees, type C, see
//! [`crate::frame`]). Symmetric files are expanded to the full 0°–360° range when parsed, by the
//! same reflections the standards define, so every lookup and every integral works on one form:
//!
//! | symmetry            | given C range       | reflections generating the full range |
//! |---------------------|---------------------|---------------------------------------|
//! | rotational          | one plane           | I(C) = I(0)                           |
//! | quadrant            | 0–90                | C, 180 − C, 180 + C, 360 − C          |
//! | bilateral 0–180     | 0–180               | C, 360 − C                            |
//! | bilateral 90–270    | 90–270 (or 270–90)  | C, 180 − C                            |
//! | none                | 0 – (≤ 360)         | C                                     |
//!
//! The expanded C list starts at 0° and is closed by a copy of the 0° plane at 360°; a file's own
//! 360° plane (IES "none" symmetry) must duplicate its 0° plane and is dropped. When the
//! reflections leave no 0° plane (90–270 symmetry without a 180° plane), one is inserted by
//! interpolating across 360° between the last and first planes, which leaves the interpolated
//! distribution unchanged.
//!
//! **Interpolation** (IES LM-63-2002 §5, CIE 102, EULUMDAT practice): bilinear in (C, γ) between
//! the four surrounding table values. For γ outside the table's range [γ₀, γ_last] (a downlight
//! table stopping at 90°, an uplight table starting at 90°) the intensity is 0; angles within
//! 1e-9° of an end are clamped onto it.
//!
//! **Flux.** [`Photometry::flux_from_table_lm`] is Φ = ∫ I dΩ = ∫∫ I(C, γ) sin γ dγ dC over the
//! bilinear surface, evaluated *exactly* cell by cell: with u = (C − C₀)/ΔC and
//! v = (γ − γ₀)/Δγ, ∫(1 − u) dC = ∫u dC = ΔC/2, and
//! ∫ v sin γ dγ = −cos γ₁ + (sin γ₁ − sin γ₀)/Δγ, ∫(1 − v) sin γ dγ = cos γ₀ − (sin γ₁ − sin γ₀)/Δγ.
//! So the only difference between this flux and that of the smooth distribution the table samples
//! is the interpolation error, bounded by 2π·(Δγ²/8)·max|∂²I/∂γ²| + the same in C.
//!
//! **Which flux the luminaire emits.** The luminaire emits the integral of its table:
//! that is what the intensities it radiates add up to, and the Monte Carlo estimators must
//! conserve it. The file's lamp lumens are metadata; [`Photometry::flux_check`] compares the
//! table integral against the flux the file declares (EULUMDAT: lamp flux × LORL; IES: none is
//! declared, so only the implied light output ratio LOR = Φ_table / Φ_lamps is reported).

use crate::frame::c_gamma_from_direction;

/// Which file format and version a photometry came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SourceFormat {
    /// IES LM-63 without a version line (1986) or tagged `IESNA91`.
    Ies1986,
    Ies1991,
    Ies1995,
    Ies2002,
    Ies2019,
    Eulumdat,
}

/// The horizontal (C-plane) symmetry the file declared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Symmetry {
    /// One C plane: the same in every plane.
    Rotational,
    /// C 0–90 given; symmetric about the 0–180 and 90–270 planes.
    Quadrant,
    /// C 0–180 given; symmetric about the 0–180 plane.
    Bilateral0To180,
    /// C 90–270 (IES) or 270–90 (EULUMDAT Isym 3) given; symmetric about the 90–270 plane.
    Bilateral90To270,
    /// No symmetry: the full range given.
    None,
}

/// The lamp flux the file states.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LampFlux {
    /// Relative photometry: `lamps` lamps of total flux `total_lm` (IES: lamps × lumens per lamp;
    /// EULUMDAT: the first lamp set's total flux).
    Relative { lamps: u32, total_lm: f64 },
    /// Absolute photometry (IES lumens per lamp = −1; EULUMDAT negative number of lamps): the
    /// intensities are those of the luminaire. `luminaire_lm` is EULUMDAT's stated luminaire flux.
    Absolute { luminaire_lm: Option<f64> },
}

/// The shape of the luminous opening (IES LM-63-2002 Table 1 sign convention; EULUMDAT: width 0
/// means circular).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OpeningShape {
    Point,
    Rectangular,
    /// A box with luminous sides (height > 0).
    RectangularWithSides,
    Circular,
    Elliptical,
    Sphere,
    Ellipsoid,
    VerticalCylinder,
    /// Any other sign combination LM-63-2002 lists (horizontal cylinders, ...).
    Other,
}

/// Size of the luminous opening in metres: `length` along the C0–C180 axis (local x), `width`
/// along C90–C270 (local y), `height` along z; all non-negative (diameters for round shapes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LuminousOpening {
    pub shape: OpeningShape,
    pub length_m: f64,
    pub width_m: f64,
    pub height_m: f64,
}

impl LuminousOpening {
    /// From IES signed dimensions (already in metres): negative values mean round shapes.
    pub fn from_ies(width: f64, length: f64, height: f64) -> Self {
        let shape = match (sign(width), sign(length), sign(height)) {
            (0, 0, 0) => OpeningShape::Point,
            (1, 1, 0) => OpeningShape::Rectangular,
            (1, 1, 1) => OpeningShape::RectangularWithSides,
            (-1, -1, 0) if width == length => OpeningShape::Circular,
            (-1, -1, 0) => OpeningShape::Elliptical,
            (-1, -1, -1) if width == length && length == height => OpeningShape::Sphere,
            (-1, -1, -1) => OpeningShape::Ellipsoid,
            (-1, -1, 1) => OpeningShape::VerticalCylinder,
            _ => OpeningShape::Other,
        };
        LuminousOpening {
            shape,
            length_m: length.abs(),
            width_m: width.abs(),
            height_m: height.abs(),
        }
    }
}

impl LuminousOpening {
    /// The IES LM-63 signed dimensions (width, length, height) of this opening, m: what
    /// [`LuminousOpening::from_ies`] reads back into the same shape (zeros for a point and for
    /// [`OpeningShape::Other`]).
    pub fn ies_signed(&self) -> [f64; 3] {
        let (l, w, h) = (self.length_m, self.width_m, self.height_m);
        match self.shape {
            OpeningShape::Point | OpeningShape::Other => [0.0; 3],
            OpeningShape::Rectangular => [w, l, 0.0],
            OpeningShape::RectangularWithSides => [w, l, h],
            OpeningShape::Circular | OpeningShape::Elliptical => [-w, -l, 0.0],
            OpeningShape::Sphere | OpeningShape::Ellipsoid => [-w, -l, -h],
            OpeningShape::VerticalCylinder => [-w, -l, h],
        }
    }

    /// Projected (silhouette) area in m² seen from the unit direction `d` of the luminaire frame:
    /// flat rectangle l·w·|d_z|, flat circle or ellipse π l w/4 · |d_z|, box with luminous sides
    /// l w |d_z| + w h |d_x| + l h |d_y|, vertical cylinder π l w/4 · |d_z| + l h √(1 − d_z²),
    /// ellipsoid (semi-axes a, b, c = l/2, w/2, h/2) π √(b²c² d_x² + a²c² d_y² + a²b² d_z²),
    /// sphere π l²/4. `None` for a point and for shapes not modelled ([`OpeningShape::Other`]).
    ///
    /// An area-like luminaire emitting the file's intensity from its opening has the uniform
    /// luminance L(ω) = I(ω) / A_proj(ω) (cd/m²); a flat opening has A_proj = 0 sideways and
    /// cannot emit upwards, so its table must have I = 0 for γ ≥ 90°.
    pub fn projected_area_m2(&self, d: [f64; 3]) -> Option<f64> {
        let (l, w, h) = (self.length_m, self.width_m, self.height_m);
        let (dx, dy, dz) = (d[0].abs(), d[1].abs(), d[2].abs());
        let q = std::f64::consts::FRAC_PI_4;
        Some(match self.shape {
            OpeningShape::Point | OpeningShape::Other => return None,
            OpeningShape::Rectangular => l * w * dz,
            OpeningShape::Circular | OpeningShape::Elliptical => q * l * w * dz,
            OpeningShape::RectangularWithSides => l * w * dz + w * h * dx + l * h * dy,
            OpeningShape::VerticalCylinder => {
                q * l * w * dz + l * h * (1.0 - dz * dz).max(0.0).sqrt()
            }
            OpeningShape::Sphere | OpeningShape::Ellipsoid => {
                let (a, b, c) = (l / 2.0, w / 2.0, h / 2.0);
                std::f64::consts::PI
                    * ((b * c * dx).powi(2) + (a * c * dy).powi(2) + (a * b * dz).powi(2)).sqrt()
            }
        })
    }

    /// A point (m, luminaire frame, photometric centre at the origin) uniformly distributed on a
    /// flat opening (rectangle, circle or ellipse in the plane z = 0) from two uniform numbers;
    /// `None` for other shapes.
    pub fn sample_flat_point(&self, u1: f64, u2: f64) -> Option<[f64; 3]> {
        match self.shape {
            OpeningShape::Rectangular => {
                Some([(u1 - 0.5) * self.length_m, (u2 - 0.5) * self.width_m, 0.0])
            }
            OpeningShape::Circular | OpeningShape::Elliptical => {
                let r = u1.clamp(0.0, 1.0).sqrt();
                let t = std::f64::consts::TAU * u2;
                Some([
                    0.5 * self.length_m * r * t.cos(),
                    0.5 * self.width_m * r * t.sin(),
                    0.0,
                ])
            }
            _ => None,
        }
    }

    /// Area (m²) of a flat opening, `None` for other shapes.
    pub fn flat_area_m2(&self) -> Option<f64> {
        match self.shape {
            OpeningShape::Rectangular => Some(self.length_m * self.width_m),
            OpeningShape::Circular | OpeningShape::Elliptical => {
                Some(std::f64::consts::FRAC_PI_4 * self.length_m * self.width_m)
            }
            _ => None,
        }
    }
}

fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// The table integral against the flux the file declares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluxCheck {
    /// ∫ I dΩ over the bilinear table (lm): the flux the luminaire emits.
    pub table_lm: f64,
    /// The luminaire flux the file declares, if it declares one (EULUMDAT: lamp flux × LORL/100).
    pub declared_lm: Option<f64>,
    /// (table − declared) / declared.
    pub rel_diff: Option<f64>,
    /// Implied light output ratio Φ_table / Φ_lamps for relative photometry.
    pub lor: Option<f64>,
}

/// A goniometric intensity distribution over the full sphere, in candela.
#[derive(Debug, Clone, PartialEq)]
pub struct Photometry {
    /// The file it came from, as named to the parser.
    pub name: String,
    pub format: SourceFormat,
    /// The symmetry the file declared (the table is always expanded).
    pub symmetry: Symmetry,
    /// IES keywords (`[KEY]`, value) in file order; EULUMDAT text fields under descriptive keys.
    pub keywords: Vec<(String, String)>,
    pub lamp_flux: LampFlux,
    pub opening: LuminousOpening,
    /// Input power (W) if the file states it (IES input watts; EULUMDAT first lamp set wattage).
    pub input_watts: Option<f64>,
    /// The factor already applied to the file's values to get candela (IES multiplier × ballast
    /// factor [× ballast-lamp factor]; EULUMDAT lamp flux/1000 × conversion factor).
    pub applied_factor: f64,
    /// EULUMDAT's declared light output ratio (%), downward flux fraction (%).
    pub ldt_lor_percent: Option<f64>,
    pub ldt_dff_percent: Option<f64>,
    c_deg: Vec<f64>,
    gamma_deg: Vec<f64>,
    /// Row-major: `cd[i * gamma_deg.len() + j]` is I(C_i, γ_j).
    cd: Vec<f64>,
}

/// What the parsers hand over before expansion: the given C planes (angles in the file's order,
/// possibly 270..360..90 for EULUMDAT Isym 3) with one row of intensities (cd) each.
pub(crate) struct RawTable {
    pub symmetry: Symmetry,
    pub c_deg: Vec<f64>,
    pub gamma_deg: Vec<f64>,
    pub rows: Vec<Vec<f64>>,
}

const ANGLE_EPS: f64 = 1e-9;

/// (C angles 0..=360, γ angles, row-major candela).
pub(crate) type ExpandedTable = (Vec<f64>, Vec<f64>, Vec<f64>);

fn norm360(a: f64) -> f64 {
    let mut x = a % 360.0;
    if x < 0.0 {
        x += 360.0;
    }
    if x >= 360.0 - ANGLE_EPS || x.abs() < ANGLE_EPS {
        0.0
    } else {
        x
    }
}

impl RawTable {
    /// Expands to the full 0–360° range (see the module table). Errors are plain messages; the
    /// parser adds file and line.
    pub(crate) fn expand(self) -> Result<ExpandedTable, String> {
        let ops: &[fn(f64) -> f64] = match self.symmetry {
            Symmetry::Rotational | Symmetry::None => &[|c| c],
            Symmetry::Quadrant => &[|c| c, |c| 180.0 - c, |c| 180.0 + c, |c| 360.0 - c],
            Symmetry::Bilateral0To180 => &[|c| c, |c| 360.0 - c],
            Symmetry::Bilateral90To270 => &[|c| c, |c| 180.0 - c],
        };
        let mut planes: Vec<(f64, usize)> = Vec::new();
        if self.symmetry == Symmetry::Rotational {
            planes.push((0.0, 0));
        } else {
            for op in ops {
                for (k, &c) in self.c_deg.iter().enumerate() {
                    planes.push((norm360(op(c)), k));
                }
            }
        }
        // Stable sort keeps the file's own plane first among duplicates (mirror images of a
        // boundary plane, or a 360° plane folded onto 0°).
        planes.sort_by(|a, b| a.0.total_cmp(&b.0));
        planes.dedup_by(|b, a| (b.0 - a.0).abs() < 1e-6);
        let ng = self.gamma_deg.len();
        let mut angles: Vec<f64> = planes.iter().map(|p| p.0).collect();
        let mut rows: Vec<&[f64]> = planes.iter().map(|p| self.rows[p.1].as_slice()).collect();
        // Without a 0° plane (e.g. 90–270 symmetry with planes 135 and 225 only), insert the
        // plane the wrap-around interpolation between the last and the first plane gives at 0°:
        // a node on a linear segment leaves the bilinear interpolant unchanged.
        let zero_row: Vec<f64>;
        if angles[0] != 0.0 {
            let (a_first, a_last) = (angles[0], angles[angles.len() - 1]);
            let f = (360.0 - a_last) / (360.0 - a_last + a_first);
            let (first, last) = (rows[0], rows[rows.len() - 1]);
            zero_row = (0..ng)
                .map(|j| last[j] * (1.0 - f) + first[j] * f)
                .collect();
            angles.insert(0, 0.0);
            rows.insert(0, &zero_row);
        }
        angles.push(360.0);
        rows.push(rows[0]);
        let mut cd = Vec::with_capacity(rows.len() * ng);
        for r in &rows {
            cd.extend_from_slice(r);
        }
        Ok((angles, self.gamma_deg, cd))
    }
}

impl Photometry {
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn from_parts(
        name: &str,
        format: SourceFormat,
        keywords: Vec<(String, String)>,
        lamp_flux: LampFlux,
        opening: LuminousOpening,
        input_watts: Option<f64>,
        applied_factor: f64,
        table: RawTable,
    ) -> Result<Photometry, String> {
        let symmetry = table.symmetry;
        let (c_deg, gamma_deg, cd) = table.expand()?;
        Ok(Photometry {
            name: name.to_string(),
            format,
            symmetry,
            keywords,
            lamp_flux,
            opening,
            input_watts,
            applied_factor,
            ldt_lor_percent: None,
            ldt_dff_percent: None,
            c_deg,
            gamma_deg,
            cd,
        })
    }

    /// A distribution from a full table, for programs and tests that compute one: `c_deg` must
    /// start at 0, increase strictly and stay below 360 (the 360° plane is added); `gamma_deg`
    /// increase strictly within [0, 180]; `cd[i][j]` = I(C_i, γ_j) ≥ 0, finite.
    pub fn from_table(
        name: &str,
        c_deg: &[f64],
        gamma_deg: &[f64],
        cd: &[Vec<f64>],
    ) -> Result<Photometry, String> {
        check_angles(c_deg, 0.0, 360.0, "C").map_err(|e| e.1)?;
        check_angles(gamma_deg, 0.0, 180.0, "γ").map_err(|e| e.1)?;
        if c_deg.first() != Some(&0.0) || c_deg.last().is_some_and(|&c| c >= 360.0) {
            return Err("C angles must start at 0 and stay below 360".into());
        }
        if gamma_deg.len() < 2 {
            return Err("at least two γ angles are needed".into());
        }
        if cd.len() != c_deg.len() || cd.iter().any(|r| r.len() != gamma_deg.len()) {
            return Err("intensity table shape does not match the angles".into());
        }
        if cd.iter().flatten().any(|&v| !(v >= 0.0 && v.is_finite())) {
            return Err("intensities must be finite and non-negative".into());
        }
        let table = RawTable {
            symmetry: if c_deg.len() == 1 {
                Symmetry::Rotational
            } else {
                Symmetry::None
            },
            c_deg: c_deg.to_vec(),
            gamma_deg: gamma_deg.to_vec(),
            rows: cd.to_vec(),
        };
        let opening = LuminousOpening::from_ies(0.0, 0.0, 0.0);
        Photometry::from_parts(
            name,
            SourceFormat::Ies2002,
            Vec::new(),
            LampFlux::Absolute { luminaire_lm: None },
            opening,
            None,
            1.0,
            table,
        )
    }

    /// C angles of the expanded table (degrees): 0 first, 360 last (a copy of 0).
    pub fn c_angles_deg(&self) -> &[f64] {
        &self.c_deg
    }
    /// γ angles of the table (degrees), increasing within [0, 180].
    pub fn gamma_angles_deg(&self) -> &[f64] {
        &self.gamma_deg
    }
    /// Table value I(C_i, γ_j) in cd.
    pub fn table_cd(&self, i: usize, j: usize) -> f64 {
        self.cd[i * self.gamma_deg.len() + j]
    }
    /// The expanded table in the form [`Photometry::from_table`] takes (C angles without the
    /// closing 360° plane, γ angles, rows of candela), so a compiled scene can store it and
    /// rebuild a distribution with identical intensities everywhere.
    pub fn to_table(&self) -> (Vec<f64>, Vec<f64>, Vec<Vec<f64>>) {
        let ng = self.gamma_deg.len();
        let nc = self.c_deg.len() - 1;
        let rows = (0..nc)
            .map(|i| self.cd[i * ng..(i + 1) * ng].to_vec())
            .collect();
        (self.c_deg[..nc].to_vec(), self.gamma_deg.clone(), rows)
    }

    /// The value of a keyword (`[KEY]` in IES; MANUFAC, LUMINAIRE, LUMCAT, LAMP, TEST, FILENAME,
    /// DATE, COLOUR, CRI for EULUMDAT), case-insensitive.
    pub fn keyword(&self, key: &str) -> Option<&str> {
        self.keywords
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
    }

    /// Largest table value (cd).
    pub fn max_cd(&self) -> f64 {
        self.cd.iter().copied().fold(0.0, f64::max)
    }

    /// The intensity (cd) at (C, γ) in degrees, bilinearly interpolated; C any real (taken mod
    /// 360), γ in [0, 180]; 0 outside the table's γ range or for non-finite angles.
    pub fn intensity_cd(&self, c_deg: f64, gamma_deg: f64) -> f64 {
        if !c_deg.is_finite() || !gamma_deg.is_finite() {
            return 0.0;
        }
        let Some((j, v)) = locate_gamma(&self.gamma_deg, gamma_deg) else {
            return 0.0;
        };
        let (i, u) = locate_c(&self.c_deg, c_deg);
        let ng = self.gamma_deg.len();
        let at = |ii: usize, jj: usize| self.cd[ii * ng + jj];
        let j1 = (j + 1).min(ng - 1);
        let i1 = (i + 1).min(self.c_deg.len() - 1);
        let a = at(i, j) * (1.0 - v) + at(i, j1) * v;
        let b = at(i1, j) * (1.0 - v) + at(i1, j1) * v;
        a * (1.0 - u) + b * u
    }

    /// The intensity (cd) towards a direction in the luminaire frame (need not be normalised).
    pub fn intensity_dir_cd(&self, dir_local: [f64; 3]) -> f64 {
        let (c, g) = c_gamma_from_direction(dir_local);
        self.intensity_cd(c, g)
    }

    /// Φ = ∫ I dΩ (lm), exact over the bilinear surface (see the module docs).
    pub fn flux_from_table_lm(&self) -> f64 {
        let ng = self.gamma_deg.len();
        let mut total = 0.0;
        for i in 0..self.c_deg.len() - 1 {
            for j in 0..ng - 1 {
                total += self.cell_integral(i, j);
            }
        }
        total
    }

    /// ∫∫ over table cell (i, j) of I sin γ dγ dC (lm).
    pub(crate) fn cell_integral(&self, i: usize, j: usize) -> f64 {
        let ng = self.gamma_deg.len();
        let dc = (self.c_deg[i + 1] - self.c_deg[i]).to_radians();
        let (g0, g1) = (
            self.gamma_deg[j].to_radians(),
            self.gamma_deg[j + 1].to_radians(),
        );
        let dg = g1 - g0;
        let ds = (g1.sin() - g0.sin()) / dg;
        let w1 = -g1.cos() + ds; // ∫ v sin γ dγ
        let w0 = g0.cos() - g1.cos() - w1; // ∫ (1 − v) sin γ dγ
        let at = |ii: usize, jj: usize| self.cd[ii * ng + jj];
        let lo = at(i, j) + at(i + 1, j);
        let hi = at(i, j + 1) + at(i + 1, j + 1);
        0.5 * dc * (lo * w0 + hi * w1)
    }

    /// The table integral against the file's declared flux (see the module docs).
    pub fn flux_check(&self) -> FluxCheck {
        let table_lm = self.flux_from_table_lm();
        let lamp_lm = match self.lamp_flux {
            LampFlux::Relative { total_lm, .. } => Some(total_lm),
            LampFlux::Absolute { luminaire_lm } => luminaire_lm,
        };
        let declared_lm = match (self.ldt_lor_percent, lamp_lm) {
            (Some(lor), Some(lm)) => Some(lm * lor / 100.0),
            _ => None,
        };
        let lor = match self.lamp_flux {
            LampFlux::Relative { total_lm, .. } if total_lm > 0.0 => Some(table_lm / total_lm),
            _ => None,
        };
        FluxCheck {
            table_lm,
            declared_lm,
            rel_diff: declared_lm.filter(|&d| d > 0.0).map(|d| (table_lm - d) / d),
            lor,
        }
    }

    /// The file's flux: lamp lumens for relative photometry, the stated luminaire flux for
    /// absolute EULUMDAT, `None` for absolute IES (−1 lumens per lamp).
    pub fn file_flux_lm(&self) -> Option<f64> {
        match self.lamp_flux {
            LampFlux::Relative { total_lm, .. } => Some(total_lm),
            LampFlux::Absolute { luminaire_lm } => luminaire_lm,
        }
    }

    /// A copy with every intensity multiplied by `factor` (≥ 0), e.g. a maintenance factor.
    pub fn scaled(&self, factor: f64) -> Photometry {
        let mut p = self.clone();
        for v in &mut p.cd {
            *v *= factor;
        }
        p.applied_factor *= factor;
        p
    }
}

/// Checks angles lie in [lo, hi] and increase strictly; the error gives the offending index.
pub(crate) fn check_angles(a: &[f64], lo: f64, hi: f64, what: &str) -> Result<(), (usize, String)> {
    if a.is_empty() {
        return Err((0, format!("no {what} angles")));
    }
    for (k, &x) in a.iter().enumerate() {
        if !(lo..=hi).contains(&x) {
            return Err((k, format!("{what} angle {x} outside [{lo}, {hi}]")));
        }
        if k > 0 && x <= a[k - 1] {
            return Err((
                k,
                format!(
                    "{what} angles not strictly increasing ({} then {x}); check the angle counts",
                    a[k - 1]
                ),
            ));
        }
    }
    Ok(())
}

/// Cell index j and fraction v in [0, 1] with γ = γ_j + v (γ_{j+1} − γ_j); None outside.
pub(crate) fn locate_gamma(g: &[f64], gamma: f64) -> Option<(usize, f64)> {
    let n = g.len();
    let (lo, hi) = (g[0], g[n - 1]);
    if gamma < lo - ANGLE_EPS || gamma > hi + ANGLE_EPS {
        return None;
    }
    let x = gamma.clamp(lo, hi);
    // Last j with g[j] <= x, limited to n - 2 so the cell exists.
    let j = g.partition_point(|&a| a <= x).saturating_sub(1).min(n - 2);
    let v = ((x - g[j]) / (g[j + 1] - g[j])).clamp(0.0, 1.0);
    Some((j, v))
}

/// Cell index i and fraction u for a C angle in the closed list 0..=360.
pub(crate) fn locate_c(c: &[f64], c_deg: f64) -> (usize, f64) {
    let mut x = c_deg % 360.0;
    if x < 0.0 {
        x += 360.0;
    }
    let n = c.len();
    let i = c.partition_point(|&a| a <= x).saturating_sub(1).min(n - 2);
    let u = ((x - c[i]) / (c[i + 1] - c[i])).clamp(0.0, 1.0);
    (i, u)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flux_of_isotropic_table_is_4pi_i() {
        let g: Vec<f64> = (0..=18).map(|k| k as f64 * 10.0).collect();
        let p = Photometry::from_table("iso", &[0.0], &g, &[vec![100.0; 19]]).unwrap();
        let want = 4.0 * std::f64::consts::PI * 100.0;
        assert!((p.flux_from_table_lm() - want).abs() < 1e-9 * want);
        assert_eq!(p.intensity_cd(123.0, 77.0), 100.0);
    }

    #[test]
    fn bilinear_between_nodes_and_zero_beyond_table() {
        let g = [0.0, 45.0, 90.0];
        let c = [0.0, 90.0, 180.0, 270.0];
        let rows: Vec<Vec<f64>> = (0..4)
            .map(|i| vec![10.0 * i as f64, 20.0 + i as f64, 5.0])
            .collect();
        let p = Photometry::from_table("t", &c, &g, &rows).unwrap();
        // Midway in C between planes 1 and 2, a quarter of the way from 0° to 45° in γ.
        let want = {
            let a = 10.0 * 0.75 + 21.0 * 0.25;
            let b = 20.0 * 0.75 + 22.0 * 0.25;
            0.5 * (a + b)
        };
        assert!((p.intensity_cd(135.0, 11.25) - want).abs() < 1e-12);
        // Between 270° and the closing 360° (= plane 0).
        assert!((p.intensity_cd(315.0, 45.0) - 0.5 * (23.0 + 20.0)).abs() < 1e-12);
        assert!((p.intensity_cd(-45.0, 45.0) - 0.5 * (23.0 + 20.0)).abs() < 1e-12);
        assert_eq!(p.intensity_cd(0.0, 90.5), 0.0);
        assert_eq!(p.intensity_cd(0.0, 90.0), 5.0);
    }
}
