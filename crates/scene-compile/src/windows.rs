//! Windows (`Scene.windows`): openings cut from the wall `Quad` objects they lie in.
//!
//! A window is a parallelogram `corner + s u + t v` in world space. It must lie in the plane of
//! one `Quad` object (after that object's transform) and inside it, with its edges along the
//! quad's edges, so that in the quad's own coordinates (s, t) ∈ [0, 1]² it is a rectangle. Every
//! quad holding windows is replaced by the quads of the grid its windows' edges draw (cells
//! inside a window dropped, the others merged along s into strips), in world space with the
//! quad's material, sidedness and orientation; a window with `glazing` gets a quad of that
//! material filling the opening. The pieces get texture coordinates of their own (each [0, 1]²).
//! Errors (one line, naming `windows[k]`): a window of zero area, one lying in no quad, edges not
//! along the quad's, windows overlapping, a window in an emitting quad, unknown glazing.

use luxest_io::math::Vec3;
use luxest_io::{Error, Result};
use luxest_render::scene::{Object, Scene, Shape, Transform};
use std::path::Path;

/// A quad's world corner and edges.
#[derive(Clone, Copy)]
struct WorldQuad {
    corner: Vec3,
    u: Vec3,
    v: Vec3,
}

impl WorldQuad {
    /// (s, t) of the point `p` projected into the quad's plane, and its distance to the plane.
    fn coords(&self, p: Vec3) -> (f64, f64, f64) {
        let d = p - self.corner;
        let (uu, uv, vv) = (self.u.dot(self.u), self.u.dot(self.v), self.v.dot(self.v));
        let det = uu * vv - uv * uv;
        let (du, dv) = (d.dot(self.u), d.dot(self.v));
        let s = (du * vv - dv * uv) / det;
        let t = (dv * uu - du * uv) / det;
        let off = d - self.u * s - self.v * t;
        (s, t, off.length())
    }

    fn point(&self, s: f64, t: f64) -> Vec3 {
        self.corner + self.u * s + self.v * t
    }
}

/// An opening in a quad: s0, s1, t0, t1 and the window's index.
type Hole = (f64, f64, f64, f64, usize);

/// The scene with its windows cut (`None` when it has none).
pub fn cut(scene: &Scene, path: &Path) -> Result<Option<Scene>> {
    if scene.windows.is_empty() {
        return Ok(None);
    }
    let quads: Vec<Option<WorldQuad>> = scene
        .objects
        .iter()
        .map(|o| match &o.shape {
            Shape::Quad { corner, u, v } => {
                let a = o.transform.to_affine();
                Some(WorldQuad {
                    corner: a.apply_point(*corner),
                    u: a.apply_vector(*u),
                    v: a.apply_vector(*v),
                })
            }
            _ => None,
        })
        .collect();
    // Per object: its holes as (s0, s1, t0, t1, window index).
    let mut holes: Vec<Vec<Hole>> = vec![Vec::new(); scene.objects.len()];
    let mut panes = Vec::new();
    for (k, w) in scene.windows.iter().enumerate() {
        let place = format!(
            "windows[{k}]{}",
            w.name
                .as_ref()
                .map_or(String::new(), |n| format!(" \"{n}\""))
        );
        let fail = |m: &str| Error::at(path, &place, m);
        if !(w.corner.is_finite() && w.u.is_finite() && w.v.is_finite()) {
            return Err(fail("corner, u and v must be finite"));
        }
        let area = w.u.cross(w.v).length();
        let size = w.u.length().max(w.v.length());
        if !(area > 1e-10 && area > 1e-9 * size * size) {
            return Err(fail("the window has zero area"));
        }
        let corners = [
            w.corner,
            w.corner + w.u,
            w.corner + w.v,
            w.corner + w.u + w.v,
        ];
        let mut found = None;
        for (oi, q) in quads.iter().enumerate() {
            let Some(q) = q else { continue };
            let scale = q.u.length().max(q.v.length());
            let tol = 1e-6 * scale.max(1.0);
            let st: Vec<(f64, f64, f64)> = corners.iter().map(|c| q.coords(*c)).collect();
            let eps = 1e-9;
            if st.iter().all(|&(s, t, d)| {
                d <= tol && (-eps..=1.0 + eps).contains(&s) && (-eps..=1.0 + eps).contains(&t)
            }) {
                found = Some((oi, st));
                break;
            }
        }
        let Some((oi, st)) = found else {
            return Err(fail(
                "the window lies in no wall Quad (its corners must lie in the plane of one Quad \
                 object and inside it)",
            ));
        };
        let o = &scene.objects[oi];
        if o.emission.is_some() {
            return Err(fail("the wall quad holding the window emits light"));
        }
        // An axis-aligned rectangle in (s, t): the corners' s take two values, t two values.
        let ss: Vec<f64> = st.iter().map(|c| c.0.clamp(0.0, 1.0)).collect();
        let ts: Vec<f64> = st.iter().map(|c| c.1.clamp(0.0, 1.0)).collect();
        let (s0, s1) = (
            ss.iter().cloned().fold(f64::INFINITY, f64::min),
            ss.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        );
        let (t0, t1) = (
            ts.iter().cloned().fold(f64::INFINITY, f64::min),
            ts.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        );
        let aligned = ss
            .iter()
            .all(|s| (s - s0).abs() < 1e-7 || (s - s1).abs() < 1e-7)
            && ts
                .iter()
                .all(|t| (t - t0).abs() < 1e-7 || (t - t1).abs() < 1e-7);
        if !aligned {
            return Err(fail(
                "the window's edges must run along the wall quad's edges",
            ));
        }
        if s1 - s0 < 1e-9 || t1 - t0 < 1e-9 {
            return Err(fail("the window has zero area"));
        }
        for &(a0, a1, b0, b1, other) in &holes[oi] {
            if s0 < a1 - 1e-9 && a0 < s1 - 1e-9 && t0 < b1 - 1e-9 && b0 < t1 - 1e-9 {
                return Err(fail(&format!("the window overlaps windows[{other}]")));
            }
        }
        holes[oi].push((s0, s1, t0, t1, k));
        if let Some(g) = &w.glazing {
            if !scene.materials.contains_key(g) {
                return Err(fail(&format!(
                    "glazing material \"{g}\" is not in `materials`"
                )));
            }
            let q = quads[oi].expect("a quad");
            panes.push(Object {
                name: Some(format!(
                    "{} glazing",
                    w.name.clone().unwrap_or_else(|| format!("window {k}"))
                )),
                shape: Shape::Quad {
                    corner: q.point(s0, t0),
                    u: q.u * (s1 - s0),
                    v: q.v * (t1 - t0),
                },
                transform: Transform::default(),
                material: g.clone(),
                emission: None,
                flip_normals: o.flip_normals,
                face_normals: o.face_normals,
                compute_normals: false,
            });
        }
    }
    let mut out = scene.clone();
    out.objects.clear();
    for (oi, o) in scene.objects.iter().enumerate() {
        if holes[oi].is_empty() {
            out.objects.push(o.clone());
            continue;
        }
        let q = quads[oi].expect("holes only in quads");
        let mut s_edges = vec![0.0, 1.0];
        let mut t_edges = vec![0.0, 1.0];
        for &(s0, s1, t0, t1, _) in &holes[oi] {
            s_edges.extend([s0, s1]);
            t_edges.extend([t0, t1]);
        }
        for e in [&mut s_edges, &mut t_edges] {
            e.sort_by(f64::total_cmp);
            e.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        }
        let base = o.name.clone().unwrap_or_else(|| format!("object {oi}"));
        let mut piece = 0;
        for tw in t_edges.windows(2) {
            let tm = 0.5 * (tw[0] + tw[1]);
            let mut run: Option<(f64, f64)> = None;
            let mut flush = |run: &mut Option<(f64, f64)>, out: &mut Scene| {
                if let Some((a, b)) = run.take() {
                    piece += 1;
                    out.objects.push(Object {
                        name: Some(format!("{base} piece {piece}")),
                        shape: Shape::Quad {
                            corner: q.point(a, tw[0]),
                            u: q.u * (b - a),
                            v: q.v * (tw[1] - tw[0]),
                        },
                        transform: Transform::default(),
                        ..o.clone()
                    });
                }
            };
            for sw in s_edges.windows(2) {
                let sm = 0.5 * (sw[0] + sw[1]);
                let open = holes[oi]
                    .iter()
                    .any(|&(s0, s1, t0, t1, _)| sm > s0 && sm < s1 && tm > t0 && tm < t1);
                if open {
                    flush(&mut run, &mut out);
                } else {
                    run = Some((run.map_or(sw[0], |r| r.0), sw[1]));
                }
            }
            flush(&mut run, &mut out);
        }
    }
    out.objects.extend(panes);
    out.windows.clear();
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use luxest_render::scene::Window;

    fn wall_scene(windows: Vec<Window>) -> Scene {
        let mut s: Scene = luxest_io::fsio::parse_ron(
            Path::new("t.ron"),
            r#"(
                materials: { "white": Lambertian(reflectance: (0.5, 0.5, 0.5)),
                             "glass": ThinDielectric(ior: 1.5) },
                objects: [(
                    name: Some("wall"),
                    shape: Quad(corner: (0, 0, 0), u: (4, 0, 0), v: (0, 3, 0)),
                    transform: (translate: (0, 0, -2)),
                    material: "white",
                )],
            )"#,
        )
        .unwrap();
        s.windows = windows;
        s
    }

    fn window(corner: [f64; 3], u: [f64; 3], v: [f64; 3]) -> Window {
        Window {
            name: None,
            corner: corner.into(),
            u: u.into(),
            v: v.into(),
            glazing: None,
        }
    }

    fn area(s: &Scene) -> f64 {
        s.objects
            .iter()
            .map(|o| match &o.shape {
                Shape::Quad { u, v, .. } => u.cross(*v).length(),
                _ => 0.0,
            })
            .sum()
    }

    #[test]
    fn two_windows_leave_the_wall_minus_their_area() {
        let mut w2 = window([2.5, 1.0, -2.0], [0.0, 1.5, 0.0], [1.0, 0.0, 0.0]);
        w2.glazing = Some("glass".into());
        let s = wall_scene(vec![
            window([0.5, 0.8, -2.0], [1.2, 0.0, 0.0], [0.0, 1.4, 0.0]),
            w2,
        ]);
        let out = cut(&s, Path::new("t.ron")).unwrap().unwrap();
        let walls: Vec<&Object> = out
            .objects
            .iter()
            .filter(|o| o.material == "white")
            .collect();
        let wall_area: f64 = walls
            .iter()
            .map(|o| match &o.shape {
                Shape::Quad { u, v, .. } => u.cross(*v).length(),
                _ => 0.0,
            })
            .sum();
        assert!(
            (wall_area - (12.0 - 1.68 - 1.5)).abs() < 1e-9,
            "{wall_area}"
        );
        assert!((area(&out) - (12.0 - 1.68)).abs() < 1e-9);
        // Every piece faces the wall's way (+z) and lies in its plane.
        for o in &out.objects {
            let Shape::Quad { corner, u, v } = &o.shape else {
                panic!()
            };
            assert!(u.cross(*v).z > 0.0 && (corner.z + 2.0).abs() < 1e-12);
        }
        // The window's centre is open: no wall piece holds it.
        let c = Vec3::new(1.1, 1.5, -2.0);
        for o in &walls {
            let Shape::Quad { corner, u, v } = &o.shape else {
                panic!()
            };
            let q = WorldQuad {
                corner: *corner,
                u: *u,
                v: *v,
            };
            let (s, t, _) = q.coords(c);
            assert!(!((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t)));
        }
    }

    #[test]
    fn bad_windows_are_one_line_errors() {
        for (w, want) in [
            (
                window([1.0, 1.0, -2.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
                "zero area",
            ),
            (
                window([1.0, 1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
                "no wall Quad",
            ),
            (
                window([3.5, 1.0, -2.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
                "no wall Quad",
            ),
            (
                window([1.0, 1.0, -2.0], [1.0, 0.5, 0.0], [0.0, 1.0, 0.0]),
                "edges",
            ),
        ] {
            let e = cut(&wall_scene(vec![w]), Path::new("t.ron"))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(want) && e.contains("windows[0]") && !e.contains('\n'),
                "{e}"
            );
        }
        let a = window([1.0, 1.0, -2.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let b = window([1.5, 1.5, -2.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let e = cut(&wall_scene(vec![a, b]), Path::new("t.ron"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("overlaps windows[0]"), "{e}");
    }
}
