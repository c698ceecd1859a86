//! Tessellation of the analytic shapes into local-frame triangle meshes.

use luxest_io::math::Vec3;
use std::collections::HashMap;

/// A triangle mesh in an object's local frame. `normals`, when present, are per-vertex
/// shading normals; absent means flat shading. `uvs`, when present, are per-vertex texture
/// coordinates in glTF's convention ((0, 0) the image's top-left corner, v down).
#[derive(Clone, Debug, Default)]
pub struct LocalMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<[f64; 2]>>,
    pub triangles: Vec<[u32; 3]>,
}

/// Vertex normals as Mitsuba 3 computes them for a mesh without (`recompute_vertex_normals`):
/// each vertex the normalised sum of its faces' unit normals weighted by the face's angle at
/// the vertex; (1, 0, 0) where the sum vanishes, as Mitsuba's placeholder.
pub fn angle_weighted_normals(mesh: &LocalMesh) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let v = t.map(|i| mesh.positions[i as usize]);
        let Some(n) = (v[1] - v[0]).cross(v[2] - v[0]).try_normalize() else {
            continue;
        };
        for k in 0..3 {
            let (a, b) = (v[(k + 1) % 3] - v[k], v[(k + 2) % 3] - v[k]);
            if let (Some(a), Some(b)) = (a.try_normalize(), b.try_normalize()) {
                sums[t[k] as usize] += n * unit_angle(a, b);
            }
        }
    }
    sums.into_iter()
        .map(|s| s.try_normalize().unwrap_or(Vec3::new(1.0, 0.0, 0.0)))
        .collect()
}

/// The angle between unit vectors, accurate for small and large angles (Mitsuba's
/// `unit_angle`).
fn unit_angle(a: Vec3, b: Vec3) -> f64 {
    if a.dot(b) < 0.0 {
        std::f64::consts::PI - 2.0 * ((a + b).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((a - b).length() / 2.0).min(1.0).asin()
    }
}

impl LocalMesh {
    /// Appends `other`, keeping normals (and UVs) only if both have them (else flat
    /// everywhere, and no UVs).
    pub fn append(&mut self, other: LocalMesh) {
        let base = self.positions.len() as u32;
        let first = self.positions.is_empty();
        let keep_normals = (first || self.normals.is_some()) && other.normals.is_some();
        if keep_normals {
            let mut n = self.normals.take().unwrap_or_default();
            n.extend(other.normals.unwrap());
            self.normals = Some(n);
        } else {
            self.normals = None;
        }
        let keep_uvs = (first || self.uvs.is_some()) && other.uvs.is_some();
        if keep_uvs {
            let mut t = self.uvs.take().unwrap_or_default();
            t.extend(other.uvs.unwrap());
            self.uvs = Some(t);
        } else {
            self.uvs = None;
        }
        self.positions.extend(other.positions);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }
}

/// The parallelogram `corner + s u + t v` as two triangles facing `u x v`, with texture
/// coordinates (s, t), as on Mitsuba 3's `rectangle`: the image's first row along the `u` edge
/// from `corner`, its rows following `v`.
pub fn quad(corner: Vec3, u: Vec3, v: Vec3) -> LocalMesh {
    LocalMesh {
        positions: vec![corner, corner + u, corner + u + v, corner + v],
        normals: None,
        uvs: Some(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// A convex polygon fanned from its first vertex.
pub fn polygon(vertices: &[Vec3]) -> LocalMesh {
    LocalMesh {
        positions: vertices.to_vec(),
        normals: None,
        uvs: None,
        triangles: (1..vertices.len().saturating_sub(1) as u32)
            .map(|i| [0, i, i + 1])
            .collect(),
    }
}

/// An axis-aligned box centred on the origin with outward-facing sides.
pub fn cuboid(size: Vec3) -> LocalMesh {
    let h = size * 0.5;
    let mut mesh = LocalMesh::default();
    // For each axis and sign: a face whose (u x v) points outward.
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
            let unit = |i: usize, len: f64| {
                let mut c = [0.0; 3];
                c[i] = len;
                Vec3::from(c)
            };
            let mut centre = [0.0; 3];
            centre[axis] = sign * h[axis];
            let centre = Vec3::from(centre);
            // unit(a1) x unit(a2) = +unit(axis) for cyclic (axis, a1, a2).
            let (u, v) = if sign > 0.0 {
                (unit(a1, size[a1]), unit(a2, size[a2]))
            } else {
                (unit(a2, size[a2]), unit(a1, size[a1]))
            };
            mesh.append(quad(centre - u * 0.5 - v * 0.5, u, v));
        }
    }
    mesh
}

/// An icosphere: the icosahedron subdivided `level` times, vertices projected onto the sphere,
/// with radial normals. `20 * 4^level` triangles.
pub fn icosphere(radius: f64, level: u32) -> LocalMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pos: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).try_normalize().unwrap())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut cache: HashMap<(u32, u32), u32> = HashMap::with_capacity(tris.len() * 2);
        let mut midpoint = |a: u32, b: u32, pos: &mut Vec<Vec3>| {
            let key = (a.min(b), a.max(b));
            *cache.entry(key).or_insert_with(|| {
                let m = ((pos[a as usize] + pos[b as usize]) * 0.5)
                    .try_normalize()
                    .unwrap();
                pos.push(m);
                (pos.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for &[a, b, c] in &tris {
            let ab = midpoint(a, b, &mut pos);
            let bc = midpoint(b, c, &mut pos);
            let ca = midpoint(c, a, &mut pos);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    LocalMesh {
        normals: Some(pos.clone()),
        positions: pos.into_iter().map(|p| p * radius).collect(),
        uvs: None,
        triangles: tris,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angle_weighted_normals_of_a_cube_point_along_its_diagonals() {
        // A closed unit cube of 8 shared vertices: each corner meets three faces at 90° each
        // (however they are triangulated), so its normal is the outward diagonal; weighting by
        // area or by triangle count would tilt it where two triangles of a face meet.
        let positions: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        let mesh = LocalMesh {
            positions: positions.clone(),
            triangles,
            ..Default::default()
        };
        let c = Vec3::new(0.5, 0.5, 0.5);
        for (p, n) in positions.iter().zip(angle_weighted_normals(&mesh)) {
            let expected = (*p - c).try_normalize().unwrap();
            assert!((n - expected).length() < 1e-12, "{p:?}: {n:?}");
        }
    }

    fn signed_volume(m: &LocalMesh) -> f64 {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn box_faces_point_outward_and_enclose_its_volume() {
        let m = cuboid(Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(m.triangles.len(), 12);
        assert!((signed_volume(&m) - 6.0).abs() < 1e-12);
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.dot((a + b + c) * (1.0 / 3.0)) > 0.0, "inward face");
        }
    }

    #[test]
    fn icosphere_converges_to_the_sphere() {
        for level in 0..5 {
            let m = icosphere(2.0, level);
            assert_eq!(m.triangles.len(), 20 * 4usize.pow(level));
            // Every vertex on the sphere; outward orientation gives positive volume.
            assert!(m.positions.iter().all(|p| (p.length() - 2.0).abs() < 1e-12));
            assert!(signed_volume(&m) > 0.0);
        }
        // The inscribed polyhedron's volume approaches 4/3 pi r^3 from below.
        let v = signed_volume(&icosphere(1.0, 5));
        let exact = 4.0 / 3.0 * std::f64::consts::PI;
        assert!(v < exact && (exact - v) / exact < 2e-3, "{v}");
    }
}
