//! `make bench` for the estimate stage (reads the scenes compiled by `make scenes`).
//!
//! 1. Throughput of the local estimate: sensor points × light paths per second, shadow rays/s.
//! 2. Time to a 1 % standard error on every sensor of `sobolev`, for the local estimate and
//!    for direct simulation (counting disks of radius 0.1 m), and their ratio: the speedup at
//!    equal (statistical) error.
//! 3. The double local estimate image of `cornell-box` at 256²: shadow rays/s.

use estimate::direct_simulation::{self, DirectSimulationConfig};
use estimate::local_estimate::{self as local, LocalConfig, Singularity};
use estimate::sensor_batches::{Batches, SensorEstimates};
use luxest_io::cli::Console;
use luxest_io::progress::Progress;
use luxest_render::compiled::CompiledScene;
use luxest_render::scene::SensorPoint;
use luxest_render::world::World;
use std::path::PathBuf;

fn world(name: &str) -> World {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../build/{name}/scene.lxs"));
    let scene =
        CompiledScene::load(&path).unwrap_or_else(|e| panic!("{e} (run `make scenes` first)"));
    World::new(scene).unwrap()
}

fn sensors(w: &World) -> Vec<SensorPoint> {
    w.scene
        .header
        .sensors
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .collect()
}

fn batches(paths: u64) -> Batches {
    Batches {
        paths,
        batches: 32,
        seed: 1,
        threads: luxest_io::cli::thread_count(None),
    }
}

/// The forward estimators compared: the local estimate with a kernel treatment, or direct
/// simulation with a counting-disk radius.
#[derive(Clone, Copy)]
enum Method {
    LocalEstimate(Singularity),
    DirectSimulation { radius: f64 },
}

fn run(w: &World, s: &[SensorPoint], method: Method, paths: u64) -> SensorEstimates {
    match method {
        Method::LocalEstimate(singularity) => {
            let cfg = LocalConfig {
                batches: batches(paths),
                singularity,
                max_depth: 100_000,
                near_field: None,
                environment_samples: 0,
            };
            local::estimate(w, s, &vec![0.0; s.len()], &cfg, &Progress::off())
        }
        Method::DirectSimulation { radius } => {
            let cfg = DirectSimulationConfig {
                batches: batches(paths),
                radius,
                max_depth: 100_000,
            };
            direct_simulation::estimate(w, s, &cfg, &Progress::off())
        }
    }
}

/// Paths and seconds needed for a relative standard error of `target` on every sensor,
/// extrapolated from a pilot run (SE ∝ 1/sqrt(paths), time ∝ paths).
fn time_to_error(
    w: &World,
    s: &[SensorPoint],
    method: Method,
    pilot: u64,
    target: f64,
) -> (u64, f64, f64) {
    let r = run(w, s, method, pilot);
    let worst = (0..s.len())
        .map(|i| r.standard_error[i] / r.value[i])
        .fold(0.0, f64::max);
    let factor = (worst / target).powi(2);
    let paths = (pilot as f64 * factor).ceil() as u64;
    (paths, r.seconds * factor, worst)
}

fn main() {
    let le = Method::LocalEstimate(Singularity::Ball { eps: 1e-3 });
    println!(
        "estimate benchmark ({} threads)",
        luxest_io::cli::thread_count(None)
    );

    for (name, paths) in [("sobolev", 1_000_000u64), ("cie171-5.8", 50_000)] {
        let w = world(name);
        let s = sensors(&w);
        let r = run(&w, &s, le, paths);
        println!(
            "local estimate, {name}: {} sensors x {paths} paths in {:.2} s = {:.3e} sensor-paths/s, {:.1} M shadow rays/s, {:.2} collisions/path",
            s.len(),
            r.seconds,
            s.len() as f64 * paths as f64 / r.seconds,
            r.shadow_rays as f64 / r.seconds / 1e6,
            r.collisions as f64 / paths as f64
        );
    }

    let w = world("sobolev");
    let s = sensors(&w);
    let (n_le, t_le, _) = time_to_error(&w, &s, le, 200_000, 0.01);
    // Check the extrapolation with a real run.
    let check = run(&w, &s, le, n_le);
    let achieved = (0..s.len())
        .map(|i| check.standard_error[i] / check.value[i])
        .fold(0.0, f64::max);
    println!(
        "time to 1% standard error on every sobolev sensor: local estimate {n_le} paths, {:.2} s predicted, {:.2} s measured (max relative SE {:.4})",
        t_le, check.seconds, achieved
    );
    let (n_d, t_d, _) = time_to_error(
        &w,
        &s,
        Method::DirectSimulation { radius: 0.1 },
        2_000_000,
        0.01,
    );
    println!(
        "time to 1% standard error on every sobolev sensor: direct simulation (bins r = 0.1 m) {n_d} paths, {t_d:.1} s (extrapolated)"
    );
    println!(
        "speedup of the local estimate at equal statistical error: {:.0}x",
        t_d / check.seconds
    );

    let w = world("cornell-box");
    let mut camera = w.scene.header.camera.clone().unwrap();
    camera.resolution = (256, 256);
    let cam = luxest_render::camera::PinholeCamera::new(&camera).unwrap();
    let icfg = estimate::double_local_estimate::ImageConfig {
        paths: 300,
        pixel_samples: 1,
        seed: 1,
        threads: luxest_io::cli::thread_count(None),
        singularity: Singularity::Clamp {
            eps: 1e-2 * w.room_scale,
        },
        max_depth: 100_000,
        mis_paths: estimate::cli::DEFAULT_MIS_PATHS,
    };
    let r = estimate::double_local_estimate::render(&w, &cam, &icfg, &Console::QUIET);
    println!(
        "double local estimate, cornell-box 256x256, {} paths + {} light-tracing paths each: {:.2} s, {} collisions, {} shadow rays (connections and light tracing), {:.1} M shadow rays/s",
        icfg.paths,
        icfg.mis_paths,
        r.seconds,
        r.collisions,
        r.shadow_rays,
        r.shadow_rays as f64 / r.seconds / 1e6,
    );
}
