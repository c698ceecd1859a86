//! Writing a film: the mean image as `<prefix>_<level>.hdr.exr` with its run metadata, and on
//! request the per-pixel standard error of Y (`.se.exr`, R = G = B) and a PNG preview.

use crate::film::Film;
use luxest_io::exr::write_rgb_to;
use luxest_io::header;
use luxest_io::image::RgbImage;
use luxest_io::meta::RunInfo;
use luxest_io::naming::{self, Kind};
use luxest_io::outputs::OutputPlan;
use luxest_io::png::write_preview_png_auto_to;
use luxest_io::{Error, Result};
use std::path::{Path, PathBuf};

/// The files [`write_image`] writes for `path`: the image and, with `stderr`, its `.se.exr`.
pub fn image_files(path: &Path, stderr: bool) -> Result<Vec<PathBuf>> {
    let mut files = vec![path.to_path_buf()];
    if stderr {
        files.push(se_path(path)?);
    }
    Ok(files)
}

/// The standard-error image beside `path`.
fn se_path(path: &Path) -> Result<PathBuf> {
    naming::sibling(path, Kind::StandardError).ok_or_else(|| {
        Error::input(
            path,
            "image name must end in .<kind>.exr to name its .se.exr",
        )
    })
}

/// Writes the film's mean image to `path` (an `<stem>.hdr.exr`), its standard error next to it
/// when `stderr`, and a preview to `preview`: planned outputs of `plan`.
pub fn write_image(
    plan: &mut OutputPlan,
    path: &Path,
    film: &Film,
    info: &RunInfo,
    stderr: bool,
    preview: Option<&Path>,
) -> Result<()> {
    let mut img = mean_image(path, film, info)?;
    write_rgb_to(plan, path, &img)?;
    if let Some(p) = preview {
        write_preview_png_auto_to(plan, p, &img)?;
    }
    if stderr {
        let se_path = se_path(path)?;
        img.pixels = film
            .standard_error()
            .iter()
            .map(|&v| [v as f32; 3])
            .collect();
        write_rgb_to(plan, &se_path, &img)?;
    }
    Ok(())
}

/// The film's mean as the image written to `path`, with its run metadata; a non-finite pixel
/// is an error naming `path`.
pub fn mean_image(path: &Path, film: &Film, info: &RunInfo) -> Result<RgbImage> {
    let mean = film.mean();
    if let Some(i) = mean.iter().position(|c| !c.is_finite()) {
        return Err(Error::input(path, format!("pixel {i} is not finite")));
    }
    let mut img = RgbImage::new(film.width, film.height);
    img.pixels = mean.iter().map(|c| c.0.map(|v| v as f32)).collect();
    img.attributes = info.to_attributes();
    img.set_attribute(header::PIXEL_FILTER, "box");
    Ok(img)
}
