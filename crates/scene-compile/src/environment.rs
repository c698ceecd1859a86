//! The environment emitter of a scene: a constant sky or an equirectangular OpenEXR map read
//! into the compiled scene (see `luxest_render::environment` for the mapping and sampling),
//! with its flux through the scene's bounding disk.

use luxest_io::color::Rgb;
use luxest_io::{Error, Result};
use luxest_render::compiled::{Emitter, EnvironmentMap, SceneHeader};
use luxest_render::environment::EnvironmentLight;
use luxest_render::scene::Environment;
use std::path::Path;

/// The compiled emitter of `env` for the scene `header` (its bounding sphere sets the flux)
/// and the map's texels (empty for a constant environment). `scene_path` resolves the map's
/// path and names the scene in errors.
pub fn compile(
    scene_path: &Path,
    env: &Environment,
    header: &SceneHeader,
) -> Result<(Emitter, Vec<[f32; 3]>)> {
    let sphere = header.bounding_sphere();
    match env {
        Environment::Constant(l) => {
            let light = EnvironmentLight::constant(*l, sphere);
            Ok((
                Emitter::Environment {
                    name: "environment".into(),
                    radiance_rgb: *l,
                    map: None,
                    flux_rgb: light.flux_rgb(),
                },
                Vec::new(),
            ))
        }
        Environment::Map {
            path,
            scale,
            to_world,
        } => {
            let file = scene_path.parent().unwrap_or(Path::new(".")).join(path);
            if !file.is_file() {
                return Err(Error::at(
                    scene_path,
                    "environment.path",
                    format!("environment map {} not found", file.display()),
                ));
            }
            let image = luxest_io::exr::read_rgb_finite(&file)?;
            let (w, h) = (image.width, image.height);
            if u32::try_from(w).is_err() || u32::try_from(h).is_err() {
                return Err(Error::input(&file, format!("{w}x{h} texels is too large")));
            }
            let light =
                EnvironmentLight::map((w, h, image.pixels.clone()), *scale, *to_world, sphere)
                    .map_err(|m| Error::input(&file, m))?;
            let flux_rgb = light.flux_rgb();
            if !(flux_rgb.is_finite() && flux_rgb.luminance() > 0.0) {
                return Err(Error::input(
                    &file,
                    "the environment map's flux is not finite and positive",
                ));
            }
            Ok((
                Emitter::Environment {
                    name: "environment".into(),
                    radiance_rgb: Rgb::splat(*scale),
                    map: Some(EnvironmentMap {
                        source: path.clone(),
                        width: w as u32,
                        height: h as u32,
                        to_world: *to_world,
                    }),
                    flux_rgb,
                },
                image.pixels,
            ))
        }
    }
}
