//! Next-event estimation's light choice: the light BVH and the power-proportional choice give
//! the same images and the same direct light in expectation (each compared with the other
//! within their own standard errors), in a room with small bright, large dim, point, spot and
//! back-facing emitters.

use crate::util::{compile_text, TempDir};
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::light_bvh::LightSampler;
use luxest_render::sampling::Rng;
use luxest_render::world::World;
use trace::{Film, Renderer};

/// A 4 m x 3 m x 2.5 m room: a large dim luminous wall, small bright ceiling patches (one facing
/// up into the ceiling: it lights nothing directly below it), a medium panel on a side wall, an
/// isotropic point and a spot; a box on the floor shadows part of it.
const ROOM: &str = r#"Scene(
    camera: Camera(position: (0.3, 1.4, 0.3), look_at: (3.0, 0.6, 2.5), vfov_deg: 70.0, resolution: (24, 18)),
    materials: {
        "white": Lambertian(reflectance: (0.7, 0.7, 0.7)),
        "grey": Lambertian(reflectance: (0.4, 0.45, 0.5)),
    },
    objects: [
        (shape: Quad(corner: (0, 0, 0), u: (0, 0, 3), v: (4, 0, 0)), material: "white"),
        (shape: Quad(corner: (0, 2.5, 0), u: (4, 0, 0), v: (0, 0, 3)), material: "white"),
        (shape: Quad(corner: (0, 0, 0), u: (4, 0, 0), v: (0, 2.5, 0)), material: "white"),
        (shape: Quad(corner: (0, 0, 3), u: (0, 2.5, 0), v: (4, 0, 0)), material: "white"),
        (shape: Quad(corner: (0, 0, 0), u: (0, 2.5, 0), v: (0, 0, 3)), material: "white"),
        (shape: Quad(corner: (4, 0, 0), u: (0, 0, 3), v: (0, 2.5, 0)), material: "white"),
        (shape: Quad(corner: (0.2, 0.2, 2.999), u: (0, 2.0, 0), v: (3.6, 0, 0)), material: "white",
            emission: Radiance((2.0, 2.0, 2.0))),
        (shape: Quad(corner: (1.0, 2.499, 1.0), u: (0.05, 0, 0), v: (0, 0, 0.05)), material: "white",
            emission: Radiance((4e4, 3e4, 2e4))),
        (shape: Quad(corner: (2.5, 2.499, 2.0), u: (0.05, 0, 0), v: (0, 0, 0.05)), material: "white",
            emission: Radiance((3e4, 3e4, 3e4))),
        (shape: Quad(corner: (3.0, 2.4, 0.5), u: (0, 0, 0.05), v: (0.05, 0, 0)), material: "white",
            emission: Radiance((5e4, 5e4, 5e4))),
        (shape: Quad(corner: (3.999, 0.8, 1.0), u: (0, 0, 0.6), v: (0, 0.6, 0)), material: "white",
            emission: Radiance((60.0, 60.0, 60.0))),
        (shape: Box(size: (0.8, 0.6, 0.8)), transform: (translate: (2.0, 0.3, 1.5)), material: "grey"),
    ],
    point_lights: [
        (position: (0.5, 2.0, 2.5), power: Intensity(30.0)),
        (position: (3.5, 2.3, 2.5), power: Intensity(200.0),
         spot: (direction: (0.0, -1.0, 0.0), cutoff_deg: 35.0, beam_width_deg: 20.0)),
    ],
)"#;

fn room(sampler: LightSampler) -> (World, luxest_render::camera::PinholeCamera) {
    let dir = TempDir::new("light-sampling");
    let (mut world, cam) = trace::load(&compile_text(&dir, "room", ROOM), None).unwrap();
    world.set_light_sampler(sampler);
    (world, cam)
}

/// (mean luminance, its standard error) of the pixels in `xs` x `ys` of a film.
fn region(film: &Film, xs: std::ops::Range<usize>, ys: std::ops::Range<usize>) -> (f64, f64) {
    let (mean, se) = (film.mean(), film.standard_error());
    let (mut m, mut v, mut n) = (0.0, 0.0, 0.0);
    for y in ys {
        for x in xs.clone() {
            let i = y * film.width + x;
            m += mean[i].luminance();
            v += se[i] * se[i];
            n += 1.0;
        }
    }
    (m / n, v.sqrt() / n)
}

#[test]
fn trace_images_are_the_same_with_the_bvh_and_the_power_choice() {
    // The image and its quadrants: each within 4 joint standard errors (5 regions).
    let films: Vec<Film> = [(LightSampler::Bvh, 1), (LightSampler::Power, 2)]
        .into_iter()
        .map(|(sampler, seed)| {
            let (world, cam) = room(sampler);
            let mut film = Film::new(cam.width as usize, cam.height as usize);
            Renderer::new(&world, cam, seed, 2, 64).advance(&mut film, 96, false, &Progress::off());
            film
        })
        .collect();
    let (w, h) = (films[0].width, films[0].height);
    let regions = [
        (0..w, 0..h),
        (0..w / 2, 0..h / 2),
        (w / 2..w, 0..h / 2),
        (0..w / 2, h / 2..h),
        (w / 2..w, h / 2..h),
    ];
    for (xs, ys) in regions {
        let (a, sa) = region(&films[0], xs.clone(), ys.clone());
        let (b, sb) = region(&films[1], xs.clone(), ys.clone());
        assert!(a.is_finite() && a > 0.0);
        let z = (a - b) / (sa * sa + sb * sb).sqrt();
        assert!(
            z.abs() < 4.0,
            "{xs:?} x {ys:?}: bvh {a} ± {sa}, power {b} ± {sb}"
        );
    }
}

/// Unoccluded direct illuminance at `x` (normal `n`, which the light choice is given) by
/// next-event estimation: (mean, standard error) over `samples` light points.
fn direct_illuminance(world: &World, x: Vec3, n: Vec3, samples: usize, seed: u64) -> (f64, f64) {
    let mut rng = Rng::new(seed, 7);
    let (mut s, mut s2) = (0.0, 0.0);
    for _ in 0..samples {
        let l = world.sample_light_point_facing(&mut rng, x, Some(n));
        let v = l.position - x;
        let d2 = v.length_squared();
        let mut e = 0.0;
        if d2 > 0.0 {
            let w = v * (1.0 / d2.sqrt());
            let cos_x = n.dot(w).max(0.0);
            let cos_l = l.normal.map_or(1.0, |nl| (-nl.dot(w)).max(0.0));
            e = (l.emitted * (cos_x * cos_l / (d2 * l.pdf))).luminance();
            assert!(e.is_finite());
        }
        s += e;
        s2 += e * e;
    }
    let m = s / samples as f64;
    (
        m,
        ((s2 / samples as f64 - m * m) / (samples as f64 - 1.0)).sqrt(),
    )
}

#[test]
fn next_event_estimates_agree_and_the_pdf_is_the_sampled_one() {
    let (mut world, _) = room(LightSampler::Bvh);
    let receivers = [
        (Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 0.0)),
        (Vec3::new(3.5, 0.0, 2.5), Vec3::new(0.0, 1.0, 0.0)),
        (Vec3::new(2.0, 2.5, 1.5), Vec3::new(0.0, -1.0, 0.0)),
        (Vec3::new(0.0, 1.2, 1.5), Vec3::new(1.0, 0.0, 0.0)),
    ];
    for (k, &(x, n)) in receivers.iter().enumerate() {
        world.set_light_sampler(LightSampler::Bvh);
        let (a, sa) = direct_illuminance(&world, x, n, 20_000, k as u64);
        // The area density of every sampled area point is light_point_pdf of one of the area
        // emitters at this receiver (MIS weighs emitter hits with it).
        let pdfs: Vec<f64> = (0..world.scene.header.emitters.len() as u32)
            .map(|e| world.light_point_pdf_facing(e, x, Some(n)))
            .collect();
        let mut rng = Rng::new(9, k as u64);
        for _ in 0..200 {
            let l = world.sample_light_point_facing(&mut rng, x, Some(n));
            if l.normal.is_some() {
                assert!(
                    pdfs.iter().any(|p| (p - l.pdf).abs() <= 1e-12 * l.pdf),
                    "{} not in {pdfs:?}",
                    l.pdf
                );
            }
        }
        world.set_light_sampler(LightSampler::Power);
        let (b, sb) = direct_illuminance(&world, x, n, 20_000, 100 + k as u64);
        let z = (a - b) / (sa * sa + sb * sb).sqrt();
        assert!(
            z.abs() < 4.0,
            "receiver {k}: bvh {a} ± {sa}, power {b} ± {sb}"
        );
        assert!(a > 0.0);
    }
}
