//! Sensors on edges and in corners.
//!
//! A sensor lying on an edge also lies in the plane of the adjacent surface, which it then sees
//! exactly edge-on: every estimator is ill-posed there (the local-estimate kernel has cos_j = 0
//! on that surface, a gathering ray starts inside it). The physically meaningful value is the
//! limit from the open side. We evaluate it at the sensor moved `delta` away from every nearby
//! surface other than its own: short probe rays in the 17 directions of the sensor's closed
//! hemisphere find surfaces closer than `2 delta`, and the point is pushed out along their
//! normals (twice, for corners). The bias this adds is of the order of the illuminance
//! gradient times delta; the estimators use delta = their regularisation radius eps.

use luxest_io::math::Vec3;
use luxest_render::scene::SensorPoint;
use luxest_render::world::World;

/// Sensors as evaluated.
pub struct Placement {
    pub points: Vec<SensorPoint>,
    /// Per sensor, its near-field radius (m): the radius asked for when a surface other than
    /// its own lies within it, else 0 (no split).
    pub near_radius: Vec<f64>,
    pub moved: usize,
}

/// The 17 probe directions of the closed hemisphere about `n`.
fn probe_directions(n: Vec3) -> Vec<Vec3> {
    let (t, b) = n.orthonormal_basis();
    let mut v = Vec::with_capacity(17);
    for i in -1i32..=1 {
        for j in -1i32..=1 {
            for k in 0i32..=1 {
                if i != 0 || j != 0 || k != 0 {
                    v.push(
                        (t * i as f64 + b * j as f64 + n * k as f64)
                            .try_normalize()
                            .unwrap(),
                    );
                }
            }
        }
    }
    v
}

/// Whether the sensor's own surface (normal ±`n`) lies under the point `delta` from `p` along
/// `m`: a short ray down from just above that point hits a surface parallel to the sensor's.
fn own_surface_continues(world: &World, p: Vec3, n: Vec3, m: Vec3, delta: f64, lift: f64) -> bool {
    let q = p + m * delta + n * lift;
    world
        .tracer
        .intersect(q, -n, 0.0, 2.0 * lift)
        .is_some_and(|h| world.surface(&h).ng.dot(n).abs() > 0.999)
}

/// Moves edge/corner sensors `delta` off the adjacent surfaces and gives the near-field radius
/// `near_radius` to each sensor with a surface other than its own closer than that.
pub fn place(world: &World, sensors: &[SensorPoint], delta: f64, near_radius: f64) -> Placement {
    let (points, moved) = separate_from_adjacent_surfaces(world, sensors, delta);
    let radii = points
        .iter()
        .map(|s| {
            let origin = s.position + s.normal * world.margin(s.position, s.position);
            let near = emitter_within(world, s, near_radius)
                || probe_directions(s.normal).into_iter().any(|d| {
                    world
                        .tracer
                        .intersect(origin, d, 0.0, near_radius)
                        .is_some_and(|h| {
                            let sp = world.surface(&h);
                            sp.ng.dot(s.normal).abs() < 0.999
                                || (sp.position - s.position).dot(s.normal).abs() > delta * 1e-3
                        })
                });
            if near {
                near_radius
            } else {
                0.0
            }
        })
        .collect();
    Placement {
        points,
        near_radius: radii,
        moved,
    }
}

/// Whether a triangle of an area emitter has a point closer than `radius` to the sensor, on the
/// side its normal faces: the 17 probe rays miss an emitter small against its distance (a 4 cm
/// lamp 5 cm away), whose light the near field's emitter sampling then never estimated.
fn emitter_within(world: &World, s: &SensorPoint, radius: f64) -> bool {
    use luxest_render::compiled::Emitter;
    world.scene.header.emitters.iter().any(|e| match e {
        Emitter::Area {
            first_triangle,
            triangle_count,
            ..
        } => (*first_triangle..first_triangle + triangle_count).any(|t| {
            let tri = world.scene.triangle(t as usize);
            tri.iter().any(|&v| (v - s.position).dot(s.normal) > 0.0)
                && (closest_point_on_triangle(s.position, tri) - s.position).length_squared()
                    < radius * radius
        }),
        _ => false,
    })
}

/// The point of triangle `[a, b, c]` closest to `p` (Ericson, *Real-Time Collision Detection*,
/// 5.1.5: by the Voronoi region of `p`).
pub fn closest_point_on_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Returns the evaluation points and how many sensors were moved.
pub fn separate_from_adjacent_surfaces(
    world: &World,
    sensors: &[SensorPoint],
    delta: f64,
) -> (Vec<SensorPoint>, usize) {
    let mut moved = 0;
    let out = sensors
        .iter()
        .map(|s| {
            let mut p = s.position;
            let n = s.normal;
            let mut changed = false;
            for _ in 0..2 {
                let lift = world.margin(p, p);
                let origin = p + n * lift;
                let mut push = Vec3::ZERO;
                for d in probe_directions(n) {
                    if let Some(h) = world.tracer.intersect(origin, d, 0.0, 2.0 * delta) {
                        let sp = world.surface(&h);
                        // Normal of the hit surface, facing the sensor.
                        let mut m = if sp.ng.dot(d) < 0.0 { sp.ng } else { -sp.ng };
                        if (p - sp.position).dot(m).abs() < lift {
                            // The surface passes through the sensor (an edge): the ray's side
                            // is rounding's choice (a probe heading into the room can be hit
                            // at t = 0 and then "faces" the outside; on two walls of a Box
                            // room that pushed edge sensors out, where they read 0). The
                            // open side is the one where the sensor's own surface goes on.
                            match (
                                own_surface_continues(world, p, n, m, delta, lift),
                                own_surface_continues(world, p, n, -m, delta, lift),
                            ) {
                                (false, true) => m = -m,
                                (true, false) => {}
                                // A free edge, or no own surface: no side is better.
                                _ => continue,
                            }
                        }
                        let dist = (p - sp.position).dot(m);
                        if dist < delta && m.dot(n) < 0.999 {
                            let need = (delta - dist) * m;
                            // Combine pushes per axis without double counting.
                            push = Vec3::new(
                                if need.x.abs() > push.x.abs() {
                                    need.x
                                } else {
                                    push.x
                                },
                                if need.y.abs() > push.y.abs() {
                                    need.y
                                } else {
                                    push.y
                                },
                                if need.z.abs() > push.z.abs() {
                                    need.z
                                } else {
                                    push.z
                                },
                            );
                        }
                    }
                }
                if push.length_squared() == 0.0 {
                    break;
                }
                // Stay in the sensor's own plane.
                p = p + push - n * push.dot(n);
                changed = true;
            }
            moved += usize::from(changed);
            SensorPoint { position: p, ..*s }
        })
        .collect();
    (out, moved)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closest point equals the minimum over a fine grid of the triangle's points, for
    /// points in every Voronoi region (vertices, edges, face, both sides).
    #[test]
    fn closest_point_matches_a_search_over_the_triangle() {
        let tri = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.2, 0.0),
            Vec3::new(0.3, 1.0, 0.4),
        ];
        let n = 400;
        let mut grid = Vec::new();
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                grid.push(tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v);
            }
        }
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 1.5
        };
        for _ in 0..200 {
            let p = Vec3::new(next(), next(), next());
            let q = closest_point_on_triangle(p, tri);
            let best = grid
                .iter()
                .map(|g| (*g - p).length())
                .fold(f64::INFINITY, f64::min);
            let d = (q - p).length();
            assert!(d <= best + 1e-12, "{p:?}: {d} above the search's {best}");
            assert!(best - d < 5e-3, "{p:?}: {d} far below the search's {best}");
        }
    }
}
