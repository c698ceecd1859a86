//! `make bench` for trace: samples/s and rays/s of the path tracer on `cornell-box` at 512²
//! and on a 1M-triangle scene (`build/bench-1m`, from pipelines/bench_scene.py), and, on the
//! very same rays (recorded during one pass), the raw Embree rate: closest-hit queries for the
//! path rays and occlusion queries for the shadow rays, on the same threads. The ratio is the
//! share of the raw ray rate the full path tracer sustains (target: at least 60 % on
//! cornell-box). The same rays sorted into wavefront order (by bounce) are also timed as single
//! rays, as packets of 8 (`rtcIntersect8`) and as streams of 256 (`rtcIntersect1M`): what a
//! wavefront formulation of the tracer could gain in Embree.

use luxest_io::cli::thread_count;
use luxest_io::progress::Progress;
use luxest_render::parallel::run_batches;
use luxest_render::rt::Ray;
use std::path::PathBuf;
use std::time::Instant;
use trace::{Film, Renderer};

/// How the raw rate queries Embree.
#[derive(Clone, Copy, Debug)]
enum Query {
    /// `rtcIntersect1` / `rtcOccluded1`, one ray at a time (what `trace` does).
    Single,
    /// `rtcIntersect8` / `rtcOccluded8` on packets of 8 rays of the same bounce from
    /// neighbouring pixels (what a wavefront tracer would submit).
    Packet8,
    /// `rtcIntersect16` / `rtcOccluded16` on packets of 16 such rays (AVX-512).
    Packet16,
    /// `rtcIntersect1M` / `rtcOccluded1M` on streams of 256 such rays.
    Stream256,
}

/// The rays in wavefront order: by bounce, and within a bounce in the order recorded (tile by
/// tile, pixel by pixel).
fn wavefront(rays: &[Ray], depths: &[u32]) -> Vec<Ray> {
    let mut idx: Vec<usize> = (0..rays.len()).collect();
    idx.sort_by_key(|&i| depths[i]);
    idx.into_iter().map(|i| rays[i]).collect()
}

/// Hits and blocked segments counted over packets of width N (`intersect` and `occluded`: the
/// tracer's queries of that width).
fn packets<const N: usize>(
    closest: &[Ray],
    shadow: &[Ray],
    intersect: impl Fn(&[Ray], &mut [Option<luxest_render::rt::Hit>; N]),
    occluded: impl Fn(&[Ray], &mut [bool; N]),
) -> usize {
    let (mut h, mut o) = ([None; N], [false; N]);
    let mut n = 0;
    for p in closest.chunks(N) {
        intersect(p, &mut h);
        n += h.iter().filter(|x| x.is_some()).count();
    }
    for p in shadow.chunks(N) {
        occluded(p, &mut o);
        n += o.iter().filter(|&&x| x).count();
    }
    n
}

/// Raw Embree time for the recorded rays, split over `threads`.
fn raw_seconds(
    world: &luxest_render::world::World,
    closest: &[Ray],
    shadow: &[Ray],
    threads: usize,
    query: Query,
) -> f64 {
    let chunks = 64;
    let slice = |v: &[Ray], c: usize| -> std::ops::Range<usize> {
        // Chunk bounds on multiples of 256, so that packets and streams are whole.
        let len = v.len().div_ceil(chunks).next_multiple_of(256);
        (c * len).min(v.len())..((c + 1) * len).min(v.len())
    };
    let tracer = &world.tracer;
    let start = Instant::now();
    let hits: Vec<usize> = run_batches(chunks, threads, |c| {
        let (closest, shadow) = (&closest[slice(closest, c)], &shadow[slice(shadow, c)]);
        let mut n = 0;
        match query {
            Query::Single => {
                for r in closest {
                    let hit = tracer.intersect(r.origin, r.direction, r.tnear, r.tfar);
                    n += usize::from(hit.is_some());
                }
                for r in shadow {
                    n += usize::from(tracer.occluded(r.origin, r.direction, r.tnear, r.tfar));
                }
            }
            Query::Packet8 => {
                n += packets::<8>(
                    closest,
                    shadow,
                    |c, h| tracer.intersect8(c, h),
                    |c, o| tracer.occluded8(c, o),
                )
            }
            Query::Packet16 => {
                n += packets::<16>(
                    closest,
                    shadow,
                    |c, h| tracer.intersect16(c, h),
                    |c, o| tracer.occluded16(c, o),
                )
            }
            Query::Stream256 => {
                let (mut h, mut o) = (Vec::new(), Vec::new());
                for s in closest.chunks(256) {
                    tracer.intersect_many(s, &mut h);
                    n += h.iter().filter(|x| x.is_some()).count();
                }
                for s in shadow.chunks(256) {
                    tracer.occluded_many(s, &mut o);
                    n += o.iter().filter(|&&x| x).count();
                }
            }
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
    renderer.advance(&mut film, 1, false, &Progress::off());
    let (mut t, mut log) = (f64::INFINITY, None);
    for _ in 0..3 {
        let mut f = Film::new(cam.width as usize, cam.height as usize);
        let start = Instant::now();
        let l = renderer.advance(&mut f, spp, false, &Progress::off());
        t = t.min(start.elapsed().as_secs_f64());
        log = Some(l);
    }
    let log = log.unwrap();
    let samples = (cam.width * cam.height) as f64 * spp as f64;
    let rays = (log.closest + log.shadow) as f64;
    // One recorded pass for the raw rate on identical rays (the same pixels and samples'
    // distribution as the timed passes), best of 3.
    let mut rec_film = Film::new(cam.width as usize, cam.height as usize);
    let rec = renderer.advance(&mut rec_film, 1, true, &Progress::off());
    let best = |closest: &[Ray], shadow: &[Ray], q: Query| {
        (0..3)
            .map(|_| raw_seconds(&world, closest, shadow, threads, q))
            .fold(f64::INFINITY, f64::min)
    };
    let t_raw = best(&rec.closest_rays, &rec.shadow_rays, Query::Single);
    let (wc, ws) = (
        wavefront(&rec.closest_rays, &rec.closest_depths),
        wavefront(&rec.shadow_rays, &rec.shadow_depths),
    );
    let t_wave = [
        Query::Single,
        Query::Packet8,
        Query::Packet16,
        Query::Stream256,
    ]
    .map(|q| (q, best(&wc, &ws, q)));
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
    for (q, tq) in t_wave {
        println!(
            "  raw Embree on the same rays in wavefront order (by bounce), {q:?}: {:.2} M rays/s \
             ({:.2}x single rays in path order)",
            rec_rays / tq / 1e6,
            t_raw / tq
        );
    }
}

fn main() {
    println!("trace benchmark ({} threads)", thread_count(None));
    bench("cornell-box", "512x512", 8);
    bench("bench-1m", "512x512", 4);
}
