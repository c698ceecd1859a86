//! The environment emitter of a scene: a constant sky or an equirectangular OpenEXR map read
//! into the compiled scene (see `luxest_render::environment` for the mapping and sampling),
//! with its flux through the scene's bounding disk; or a daylight sky (`luxest_render::sky`)
//! tabulated into a map, with its sun disk and its unobstructed horizontal illuminance.

use luxest_io::color::Rgb;
use luxest_io::sensors::{SkyInfo, SunInfo};
use luxest_io::{Error, Result};
use luxest_render::compiled::{Emitter, EnvironmentMap, SceneHeader};
use luxest_render::environment::EnvironmentLight;
use luxest_render::scene::Environment;
use std::path::Path;

/// The compiled emitter of `env` for the scene `header` (its bounding sphere sets the flux)
/// and the map's texels (empty for a constant environment). `scene_path` resolves the map's
/// path and names the scene in errors; a sky's warnings (the sun below the horizon or capped
/// at 87°) go to `warnings`.
pub fn compile(
    scene_path: &Path,
    env: &Environment,
    header: &SceneHeader,
    warnings: &mut Vec<String>,
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
                    sun: None,
                    sky: None,
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
                    sun: None,
                    sky: None,
                },
                image.pixels,
            ))
        }
        Environment::Sky(sky) => {
            let fail = |m: String| Error::at(scene_path, "environment.Sky", m);
            let model = sky.model().map_err(fail)?;
            for w in &model.warnings {
                warnings.push(format!("environment.Sky: {w}"));
            }
            let (to_world, w, h, texels) = model.tabulate();
            let mut light = EnvironmentLight::map((w, h, texels.clone()), 1.0, to_world, sphere)
                .map_err(fail)?;
            let sun = model.sun_disk();
            if let Some(s) = &sun {
                light = light.with_sun(s).map_err(fail)?;
            }
            let flux_rgb = light.flux_rgb();
            if !(flux_rgb.is_finite() && flux_rgb.luminance() > 0.0) {
                return Err(fail("the sky's flux is not finite and positive".into()));
            }
            let up = model.frame[2];
            // What the estimators see: the tabulated map (without the sun) on the
            // unobstructed horizontal plane, plus the sun's direct part.
            let sky_only = EnvironmentLight::map((w, h, texels.clone()), 1.0, to_world, sphere)
                .map_err(fail)?;
            let e_sky = luxest_render::sky::horizontal_illuminance_of(
                |d| sky_only.radiance(d).luminance(),
                up,
                720,
            );
            let sun_info = sun.as_ref().map(|s| SunInfo {
                altitude_deg: model.altitude.to_degrees(),
                azimuth_deg: model.azimuth.to_degrees(),
                direct_normal_illuminance_lux: s.direct_normal_illuminance(),
                direct_horizontal_illuminance_lux: model.sun_horizontal_illuminance(),
            });
            let e_sun = sun_info
                .as_ref()
                .map_or(0.0, |s| s.direct_horizontal_illuminance_lux);
            Ok((
                Emitter::Environment {
                    name: "sky".into(),
                    radiance_rgb: Rgb::splat(1.0),
                    map: Some(EnvironmentMap {
                        source: model.gensky.clone(),
                        width: w as u32,
                        height: h as u32,
                        to_world,
                    }),
                    flux_rgb,
                    sun,
                    sky: Some(SkyInfo {
                        description: model.description(),
                        horizontal_illuminance_lux: e_sky + e_sun,
                        sky_horizontal_illuminance_lux: e_sky,
                        sun: sun_info,
                    }),
                },
                texels,
            ))
        }
    }
}
