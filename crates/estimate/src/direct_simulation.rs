//! Direct simulation: the analog Monte Carlo baseline the local estimate is measured against.
//!
//! Light paths are traced from the emitters exactly as for the local estimate
//! ([`crate::transport::walk_photon`]: the same walk and random numbers), but nothing is
//! connected: a sensor counts the flux weight Q of every photon that lands on its surface
//! within `radius` of it (the same plane, arriving from the sensor's front), divided by the
//! disk's area π radius². The estimate is biased by the averaging over the disk and has no
//! exact direct term; its variance falls only as the disk grows. Planar sensors only.

use crate::sensor_batches::{self, BatchSums, Batches, SensorEstimates};
use crate::transport::walk_photon;
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::sampling::Rng;
use luxest_render::scene::SensorPoint;
use luxest_render::world::World;

#[derive(Clone, Debug)]
pub struct DirectSimulationConfig {
    pub batches: Batches,
    /// Radius of the disk a sensor counts photons in, m.
    pub radius: f64,
    /// Bound on path length.
    pub max_depth: u32,
}

/// The photon arriving at `x` (travelling along `dir`) on a surface with normal `ng` deposits
/// its flux `q` into every disk it lands in.
fn deposit(
    sensors: &[SensorPoint],
    radius: f64,
    (x, ng, dir): (Vec3, Vec3, Vec3),
    q: Rgb,
    out: &mut BatchSums,
) {
    let inv_area = 1.0 / (std::f64::consts::PI * radius * radius);
    for (i, s) in sensors.iter().enumerate() {
        let v = x - s.position;
        if v.length_squared() < radius * radius
            && ng.dot(s.normal).abs() > 0.999
            && v.dot(s.normal).abs() < 1e-3 * radius
            && dir.dot(s.normal) < 0.0
        {
            out.add(i, q * inv_area, false);
        }
    }
}

fn run_batch(
    world: &World,
    sensors: &[SensorPoint],
    cfg: &DirectSimulationConfig,
    (batch, paths): (usize, u64),
    progress: &Progress,
) -> BatchSums {
    let mut rng = Rng::new(cfg.batches.seed, batch as u64 + 1);
    let mut out = BatchSums::new(sensors.len());
    let mut tally = progress.tally();
    for _ in 0..paths {
        let end = walk_photon(world, &mut rng, cfg.max_depth, |sp, dir, q| {
            deposit(sensors, cfg.radius, (sp.position, sp.ng, dir), q, &mut out)
        });
        out.collisions += end.collisions;
        out.truncated += u64::from(end.truncated);
        tally.add(1);
    }
    out
}

/// Runs direct simulation for `sensors`, counting its light paths on `progress`.
pub fn estimate(
    world: &World,
    sensors: &[SensorPoint],
    cfg: &DirectSimulationConfig,
    progress: &Progress,
) -> SensorEstimates {
    sensor_batches::run(
        &cfg.batches,
        sensors.len(),
        &vec![Rgb::BLACK; sensors.len()],
        false,
        |b, paths| run_batch(world, sensors, cfg, (b, paths), progress),
    )
}
