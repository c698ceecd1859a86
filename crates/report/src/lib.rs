//! The `report` stage: what a lighting engineer signs, from the sensor results of `estimate
//! sensors` on a scene with calculation surfaces.
//!
//! For every calculation surface (a sensor set that carries its grid layout) it writes into the
//! output directory
//!
//! - `<surface>.csv` and `<surface>.ron`: one row per grid point (index k = j · nu + i, cell
//!   (i, j), position, illuminance E and its standard error, lx) — [`tables`];
//! - `<surface>.isolux.png`: the false-colour isolux plot with contours, a legend in lx, the room
//!   outline and the luminaires' positions (`luxest_photometry::isolux`) — [`plot`];
//!
//! and for the scene one `report.html` ([`html`]: a self-contained page a lighting designer
//! signs, CSS inline and images as PNG data URIs) and one `report.md` with the same tables, for
//! diffs ([`markdown`]): the luminaire schedule (file, the file's lumens, count, multiplier,
//! maintenance factor, flux per luminaire and in total, input power when the files state it,
//! read from the compiled scene's header — [`scene_info`]), per surface the grid (points,
//! spacing, margin) and Eavg, Emin, Emax, U0 = Emin/Eavg, Ud = Emin/Emax each with its standard
//! error, checked against the surface's requirements (EN 12464-1 Ē_m and U0, pass / fail —
//! [`checks`]); UGR per observer and line of sight against its limit when the results carry
//! glare ratings; daylight factors against the EN 17037 target when they carry a sky
//! ([`daylight`]); with `--luminance IMAGE.exr` a false-colour luminance image of the room with
//! its cd/m² scale (`luminance.png`, [`luminance`]); when a peer's results are given ([`peer`],
//! e.g. Radiance's `rtrace -I`), the point-by-point comparison with the check
//! |E_luxest − E_peer| ≤ 1 % · E_peer + 3 σ_combined; and the signature block (designer, date,
//! checked by).
//!
//! **Uncertainties.** When the results carry per-batch estimates (independent batches of light
//! paths), the figures' standard errors are the delete-one-batch jackknife of
//! `luxest_photometry::GridStats::from_batches`, which accounts for the correlation between
//! points that share light paths; otherwise they are propagated from the per-point standard
//! errors with the points assumed independent (`from_independent`), and the report says so.
//!
//! Modules: [`cli`] (arguments and the run), [`input`] (the sensor results it reads),
//! [`surface`] (a calculation surface's grid and values), [`tables`], [`plot`], [`checks`],
//! [`daylight`], [`luminance`], [`markdown`], [`html`], [`scene_info`], [`peer`]; [`ugr_table`]
//! is the `report ugr-table FILE` subcommand (the CIE 190 tabular UGR of a luminaire file).
//!
//! All outputs are planned before anything is written and committed together
//! (`luxest_io::outputs::OutputPlan`): a run that fails leaves no partial report.

pub mod checks;
pub mod cli;
pub mod daylight;
pub mod html;
pub mod input;
pub mod luminance;
pub mod markdown;
pub mod peer;
pub mod plot;
pub mod scene_info;
pub mod surface;
pub mod tables;
pub mod ugr_table;
