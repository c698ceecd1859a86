//! `make bench` for trace: samples/s and rays/s of the path tracer on `cornell-box` at 512²
//! and on a 1M-triangle scene (`build/bench-1m`, from pipelines/bench_scene.py), and, on the
//! very same rays (recorded during one pass), the raw Embree rate: closest-hit queries for the
//! path rays and occlusion queries for the shadow rays, on the same threads. The ratio is the
//! share of the raw ray rate the full path tracer sustains (target: at least 60 % on
//! cornell-box).

use luxest_io::cli::thread_count;
use luxest_render::parallel::run_batches;
use luxest_render::rt::Ray;
use std::path::PathBuf;
use std::time::Instant;
use trace::{Film, Renderer};

/// Raw Embree time for the recorded rays, split over `threads`.
fn raw_seconds(
    world: &luxest_render::world::World,
    closest: &[Ray],
    shadow: &[Ray],
    threads: usize,
) -> f64 {
    let chunks = 64;
    let slice = |v: &[Ray], c: usize| -> std::ops::Range<usize> {
        let len = v.len().div_ceil(chunks);
        (c * len).min(v.len())..((c + 1) * len).min(v.len())
    };
    let start = Instant::now();
    let hits: Vec<usize> = run_batches(chunks, threads, "raw", |c| {
        let mut n = 0;
        for r in &closest[slice(closest, c)] {
            n += usize::from(
                world
                    .tracer
                    .intersect(r.origin, r.direction, r.tnear, r.tfar)
                    .is_some(),
            );
        }
        for r in &shadow[slice(shadow, c)] {
            n += usize::from(
                world
                    .tracer
                    .occluded(r.origin, r.direction, r.tnear, r.tfar),
            );
        }
        n
    });
    std::hint::black_box(hits);
    start.elapsed().as_secs_f64()
}

fn bench(name: &str, resolution: &str, spp: u32) {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../build/{name}/scene.lxs"));
    let (world, cam) = trace::load(&path, Some(resolution))
        .unwrap_or_else(|e| panic!("{e} (run `make bench`, which builds it)"));
    let threads = thread_count(None);
    let renderer = Renderer::new(&world, cam, 1, threads, 1024);
    let mut film = Film::new(cam.width as usize, cam.height as usize);
    // Warm-up pass, then the timed passes (best of 3: the machine is shared).
    renderer.advance(&mut film, 1, false);
    let (mut t, mut log) = (f64::INFINITY, None);
    for _ in 0..3 {
        let mut f = Film::new(cam.width as usize, cam.height as usize);
        let start = Instant::now();
        let l = renderer.advance(&mut f, spp, false);
        t = t.min(start.elapsed().as_secs_f64());
        log = Some(l);
    }
    let log = log.unwrap();
    let samples = (cam.width * cam.height) as f64 * spp as f64;
    let rays = (log.closest + log.shadow) as f64;
    // One recorded pass for the raw rate on identical rays (the same pixels and samples'
    // distribution as the timed passes), best of 3.
    let mut rec_film = Film::new(cam.width as usize, cam.height as usize);
    let rec = renderer.advance(&mut rec_film, 1, true);
    let t_raw = (0..3)
        .map(|_| raw_seconds(&world, &rec.closest_rays, &rec.shadow_rays, threads))
        .fold(f64::INFINITY, f64::min);
    let rec_rays = (rec.closest_rays.len() + rec.shadow_rays.len()) as f64;
    println!(
        "trace {name} {resolution}, {spp} spp, {} triangles: {:.2} s (best of 3), {:.3} M samples/s, {:.2} M rays/s ({:.2} rays/sample); \
         raw Embree on the same rays: {:.2} M rays/s; path tracer / raw = {:.0}%",
        world.scene.triangle_count(),
        t,
        samples / t / 1e6,
        rays / t / 1e6,
        rays / samples,
        rec_rays / t_raw / 1e6,
        100.0 * (rays / t) / (rec_rays / t_raw)
    );
}

fn main() {
    println!("trace benchmark ({} threads)", thread_count(None));
    bench("cornell-box", "512x512", 8);
    bench("bench-1m", "512x512", 4);
}
