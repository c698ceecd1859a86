//! The Embree wrapper: the only module that talks to Embree — Debian's Embree 3 through
//! `embree::sys` by default, Embree 4 through its own declarations with the `embree4` feature
//! (`embree4_sys`).
//!
//! [`RayTracer`] owns one Embree device and one committed scene built from world-space
//! triangles. After construction it is immutable, and Embree's traversal functions are
//! thread-safe on a committed scene, so it is `Send + Sync` and shared by reference between
//! worker threads. Workers should call [`enable_flush_to_zero`] once, as Embree recommends
//! (denormals otherwise slow traversal down by orders of magnitude).
//!
//! Conventions: distances along rays are in metres with unit-length directions; a hit's
//! `geometric_normal` is Embree's `Ng`, which for our counter-clockwise triangles is the
//! unnormalised `(b - a) x (c - a)` (a test pins this, so the pipeline has one front side).

#[cfg(not(feature = "embree4"))]
use embree::sys;
#[cfg(feature = "embree4")]
#[path = "embree4_sys.rs"]
mod sys;
use luxest_io::error::{Error, Result};
use luxest_io::math::Vec3;
use std::ptr;

/// Sets the flush-to-zero and denormals-are-zero bits of this thread's SSE control register.
pub fn enable_flush_to_zero() {
    #[cfg(target_arch = "x86_64")]
    #[allow(deprecated)]
    // SAFETY: setting MXCSR bits only changes how this thread's float ops treat denormals.
    unsafe {
        use std::arch::x86_64::{_mm_getcsr, _mm_setcsr};
        _mm_setcsr(_mm_getcsr() | 0x8040);
    }
}

/// A closest-hit query result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray.
    pub t: f64,
    /// Triangle index in the compiled scene.
    pub triangle: u32,
    /// Barycentric coordinates: the point is `(1-u-v) a + u b + v c`.
    pub u: f64,
    pub v: f64,
    /// Unnormalised `(b - a) x (c - a)`.
    pub geometric_normal: Vec3,
}

/// A ray for the stream interface: origin, unit direction and the interval `[tnear, tfar]`.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3,
    pub direction: Vec3,
    pub tnear: f64,
    pub tfar: f64,
}

pub struct RayTracer {
    device: sys::RTCDevice,
    scene: sys::RTCScene,
    triangles: usize,
    /// The cut-out test the filter functions call (Embree holds a pointer to the inner box).
    _mask: Option<Box<Box<Mask>>>,
}

/// Whether a hit is kept: called with the triangle, the hit's barycentric (u, v) and the
/// ray's origin and direction (a source of randomness for stochastic opacity). Must be cheap
/// and thread-safe: Embree calls it during traversal, for every query kind.
pub type Mask = dyn Fn(u32, f32, f32, [f32; 6]) -> bool + Send + Sync;

/// Embree's filter function for both closest-hit and occlusion queries: rejects the hits the
/// mask says are not there, so traversal goes on past them. The hit and ray arrays are
/// Embree's SoA layouts (`RTCHitN`: Ng_x, Ng_y, Ng_z, u, v, primID, …; `RTCRayN`: org_x,
/// org_y, org_z, tnear, dir_x, dir_y, dir_z, …, each `N` entries).
unsafe extern "C" fn mask_filter(args: *const sys::RTCFilterFunctionNArguments) {
    // SAFETY: Embree passes valid arguments; `geometryUserPtr` is the `Box<Mask>` the
    // tracer owns for as long as the scene exists.
    unsafe {
        let a = &*args;
        let n = a.N as usize;
        let mask = &*(a.geometryUserPtr as *const Box<Mask>);
        let hit = a.hit as *const f32;
        let ray = a.ray as *const f32;
        for i in 0..n {
            let valid = a.valid.add(i);
            if *valid == 0 {
                continue;
            }
            let u = *hit.add(3 * n + i);
            let v = *hit.add(4 * n + i);
            let prim = *(hit.add(5 * n + i) as *const u32);
            let r = |k: usize| *ray.add(k * n + i);
            if !mask(prim, u, v, [r(0), r(1), r(2), r(4), r(5), r(6)]) {
                *valid = 0;
            }
        }
    }
}

// SAFETY: the scene is committed before `RayTracer` is returned and never modified afterwards;
// Embree documents rtcIntersect*/rtcOccluded* as thread-safe on committed scenes.
unsafe impl Send for RayTracer {}
unsafe impl Sync for RayTracer {}

impl Drop for RayTracer {
    fn drop(&mut self) {
        // SAFETY: both handles were created by us and are released exactly once.
        unsafe {
            sys::rtcReleaseScene(self.scene);
            sys::rtcReleaseDevice(self.device);
        }
    }
}

fn device_error(device: sys::RTCDevice) -> Option<String> {
    // SAFETY: `device` is a live device handle.
    let code = unsafe { sys::rtcGetDeviceError(device) };
    (code != sys::RTCError::NONE).then(|| format!("Embree error {code:?}"))
}

fn make_ray(origin: Vec3, direction: Vec3, tnear: f64, tfar: f64) -> sys::RTCRay {
    sys::RTCRay {
        org_x: origin.x as f32,
        org_y: origin.y as f32,
        org_z: origin.z as f32,
        tnear: tnear as f32,
        dir_x: direction.x as f32,
        dir_y: direction.y as f32,
        dir_z: direction.z as f32,
        time: 0.0,
        tfar: if tfar.is_finite() {
            tfar as f32
        } else {
            f32::INFINITY
        },
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

fn empty_hit() -> sys::RTCHit {
    sys::RTCHit {
        Ng_x: 0.0,
        Ng_y: 0.0,
        Ng_z: 0.0,
        u: 0.0,
        v: 0.0,
        primID: u32::MAX,
        geomID: u32::MAX,
        instID: [u32::MAX],
        #[cfg(feature = "embree4")]
        instPrimID: [u32::MAX],
    }
}

fn context(coherent: bool) -> sys::RTCIntersectContext {
    // The C API initialises this with an inline function (rtcInitIntersectContext).
    sys::RTCIntersectContext {
        flags: if coherent {
            sys::RTCIntersectContextFlags::COHERENT
        } else {
            sys::RTCIntersectContextFlags::INCOHERENT
        },
        filter: None,
        instID: [u32::MAX],
    }
}

fn to_hit(rh: &sys::RTCRayHit) -> Option<Hit> {
    (rh.hit.geomID != u32::MAX).then(|| Hit {
        t: rh.ray.tfar as f64,
        triangle: rh.hit.primID,
        u: rh.hit.u as f64,
        v: rh.hit.v as f64,
        geometric_normal: Vec3::new(rh.hit.Ng_x as f64, rh.hit.Ng_y as f64, rh.hit.Ng_z as f64),
    })
}

impl RayTracer {
    /// Builds the acceleration structure over world-space triangles. `robust` trades a little
    /// speed for watertight hits on shared edges (used where sensors sit on edges and corners).
    pub fn new(positions: &[[f32; 3]], indices: &[[u32; 3]], robust: bool) -> Result<RayTracer> {
        RayTracer::with_mask(positions, indices, robust, None)
    }

    /// [`RayTracer::new`] where the hits `mask` rejects are not there, for every query.
    pub fn with_mask(
        positions: &[[f32; 3]],
        indices: &[[u32; 3]],
        robust: bool,
        mask: Option<Box<Mask>>,
    ) -> Result<RayTracer> {
        let fail = |m: String| Error::Usage(format!("cannot build the Embree scene: {m}"));
        // SAFETY: plain FFI calls following the Embree 3 API; buffers are allocated by Embree
        // with the sizes we pass, and filled within those sizes.
        unsafe {
            let device = sys::rtcNewDevice(c"verbose=0".as_ptr());
            if device.is_null() {
                return Err(fail(
                    "rtcNewDevice failed (unsupported CPU or missing libembree3?)".into(),
                ));
            }
            let scene = sys::rtcNewScene(device);
            let mut tracer = RayTracer {
                device,
                scene,
                triangles: indices.len(),
                _mask: mask.map(Box::new),
            };
            let flags = if robust {
                sys::RTCSceneFlags::ROBUST
            } else {
                sys::RTCSceneFlags::NONE
            };
            sys::rtcSetSceneFlags(scene, flags);
            sys::rtcSetSceneBuildQuality(scene, sys::RTCBuildQuality::HIGH);
            if !indices.is_empty() {
                let geom = sys::rtcNewGeometry(device, sys::RTCGeometryType::TRIANGLE);
                let vb = sys::rtcSetNewGeometryBuffer(
                    geom,
                    sys::RTCBufferType::VERTEX,
                    0,
                    sys::RTCFormat::FLOAT3,
                    12,
                    positions.len(),
                ) as *mut [f32; 3];
                let ib = sys::rtcSetNewGeometryBuffer(
                    geom,
                    sys::RTCBufferType::INDEX,
                    0,
                    sys::RTCFormat::UINT3,
                    12,
                    indices.len(),
                ) as *mut [u32; 3];
                if vb.is_null() || ib.is_null() {
                    sys::rtcReleaseGeometry(geom);
                    return Err(fail(
                        device_error(device).unwrap_or_else(|| "out of memory".into()),
                    ));
                }
                ptr::copy_nonoverlapping(positions.as_ptr(), vb, positions.len());
                ptr::copy_nonoverlapping(indices.as_ptr(), ib, indices.len());
                if let Some(m) = tracer._mask.as_mut() {
                    let user: *mut Box<Mask> = &mut **m;
                    sys::rtcSetGeometryUserData(geom, user as *mut std::os::raw::c_void);
                    sys::rtcSetGeometryIntersectFilterFunction(geom, Some(mask_filter));
                    sys::rtcSetGeometryOccludedFilterFunction(geom, Some(mask_filter));
                }
                sys::rtcCommitGeometry(geom);
                sys::rtcAttachGeometry(scene, geom);
                sys::rtcReleaseGeometry(geom);
            }
            sys::rtcCommitScene(scene);
            if let Some(e) = device_error(device) {
                return Err(fail(e));
            }
            Ok(tracer)
        }
    }

    /// Builds the tracer for a compiled scene.
    pub fn for_scene(scene: &crate::compiled::CompiledScene, robust: bool) -> Result<RayTracer> {
        RayTracer::new(&scene.positions, &scene.indices, robust)
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// Closest hit along `origin + t direction`, t in `[tnear, tfar]`.
    pub fn intersect(&self, origin: Vec3, direction: Vec3, tnear: f64, tfar: f64) -> Option<Hit> {
        let mut rh = sys::RTCRayHit {
            ray: make_ray(origin, direction, tnear, tfar),
            hit: empty_hit(),
        };
        let mut ctx = context(false);
        // SAFETY: committed scene, valid aligned ray-hit and context.
        unsafe { sys::rtcIntersect1(self.scene, &mut ctx, &mut rh) };
        to_hit(&rh)
    }

    /// Whether anything blocks the segment `origin + t direction`, t in `[tnear, tfar]`.
    pub fn occluded(&self, origin: Vec3, direction: Vec3, tnear: f64, tfar: f64) -> bool {
        let mut ray = make_ray(origin, direction, tnear, tfar);
        let mut ctx = context(false);
        // SAFETY: as above.
        unsafe { sys::rtcOccluded1(self.scene, &mut ctx, &mut ray) };
        ray.tfar == f32::NEG_INFINITY
    }

    /// Closest hits for a batch of rays through Embree's stream interface (`rtcIntersect1M`),
    /// which reorders rays internally for coherence. `out[i]` receives the hit of `rays[i]`.
    pub fn intersect_many(&self, rays: &[Ray], out: &mut Vec<Option<Hit>>) {
        let mut buf: Vec<sys::RTCRayHit> = rays
            .iter()
            .map(|r| sys::RTCRayHit {
                ray: make_ray(r.origin, r.direction, r.tnear, r.tfar),
                hit: empty_hit(),
            })
            .collect();
        let mut ctx = context(false);
        if !buf.is_empty() {
            // SAFETY: `buf` holds `len` contiguous, aligned RTCRayHit values.
            unsafe {
                sys::rtcIntersect1M(
                    self.scene,
                    &mut ctx,
                    buf.as_mut_ptr(),
                    buf.len() as u32,
                    std::mem::size_of::<sys::RTCRayHit>(),
                )
            };
        }
        out.clear();
        out.extend(buf.iter().map(to_hit));
    }

    /// Visibility for a batch of segments (`rtcOccluded1M`); `out[i]` is true if blocked.
    pub fn occluded_many(&self, rays: &[Ray], out: &mut Vec<bool>) {
        let mut buf: Vec<sys::RTCRay> = rays
            .iter()
            .map(|r| make_ray(r.origin, r.direction, r.tnear, r.tfar))
            .collect();
        let mut ctx = context(false);
        if !buf.is_empty() {
            // SAFETY: `buf` holds `len` contiguous, aligned RTCRay values.
            unsafe {
                sys::rtcOccluded1M(
                    self.scene,
                    &mut ctx,
                    buf.as_mut_ptr(),
                    buf.len() as u32,
                    std::mem::size_of::<sys::RTCRay>(),
                )
            };
        }
        out.clear();
        out.extend(buf.iter().map(|r| r.tfar == f32::NEG_INFINITY));
    }
}

/// Packet queries of one width: the valid-mask type, the packet builder and
/// `RayTracer::$intersect` / `RayTracer::$occluded`.
macro_rules! packet_queries {
    ($width:literal, $align:literal, $valid:ident, $build:ident, $ray:ident, $rayhit:ident,
     $rtc_intersect:ident, $rtc_occluded:ident, $intersect:ident, $occluded:ident) => {
        /// The valid mask of a packet. Embree reads it with aligned vector loads, so it sits
        /// on the packet's own alignment (a plain `[i32; N]` is only 4-aligned: rtcIntersect8
        /// crashed on one).
        #[repr(C, align($align))]
        struct $valid([i32; $width]);

        /// Up to N rays as an Embree packet, with its valid mask (lanes beyond `rays.len()`
        /// inactive).
        fn $build(rays: &[Ray]) -> ($valid, sys::$ray) {
            assert!(
                rays.len() <= $width,
                "a packet holds at most {} rays",
                $width
            );
            let mut valid = $valid([0; $width]);
            // SAFETY: all-zero bytes are a valid packet (plain f32/u32 arrays).
            let mut p: sys::$ray = unsafe { std::mem::zeroed() };
            for (i, r) in rays.iter().enumerate() {
                let ray = make_ray(r.origin, r.direction, r.tnear, r.tfar);
                valid.0[i] = -1;
                (p.org_x[i], p.org_y[i], p.org_z[i]) = (ray.org_x, ray.org_y, ray.org_z);
                (p.dir_x[i], p.dir_y[i], p.dir_z[i]) = (ray.dir_x, ray.dir_y, ray.dir_z);
                (p.tnear[i], p.tfar[i], p.mask[i]) = (ray.tnear, ray.tfar, ray.mask);
            }
            (valid, p)
        }

        impl RayTracer {
            /// Closest hits for up to N rays as one packet; `out[i]` receives the hit of
            /// `rays[i]`, lanes beyond `rays.len()` are inactive.
            pub fn $intersect(&self, rays: &[Ray], out: &mut [Option<Hit>; $width]) {
                let (valid, ray) = $build(rays);
                let mut p = sys::$rayhit {
                    ray,
                    // SAFETY: all-zero bytes are a valid hit packet (plain f32/u32 arrays).
                    hit: unsafe { std::mem::zeroed() },
                };
                p.hit.geomID = [u32::MAX; $width];
                let mut ctx = context(false);
                debug_assert_eq!(
                    valid.0.as_ptr() as usize % $align,
                    0,
                    "valid mask misaligned"
                );
                // SAFETY: `valid` and `p` (the sys type's repr) are aligned packets of N lanes.
                unsafe { sys::$rtc_intersect(valid.0.as_ptr(), self.scene, &mut ctx, &mut p) };
                for (i, o) in out.iter_mut().enumerate() {
                    *o = (i < rays.len() && p.hit.geomID[i] != u32::MAX).then(|| Hit {
                        t: p.ray.tfar[i] as f64,
                        triangle: p.hit.primID[i],
                        u: p.hit.u[i] as f64,
                        v: p.hit.v[i] as f64,
                        geometric_normal: Vec3::new(
                            p.hit.Ng_x[i] as f64,
                            p.hit.Ng_y[i] as f64,
                            p.hit.Ng_z[i] as f64,
                        ),
                    });
                }
            }

            /// Visibility for up to N segments as one packet; `out[i]` is true if `rays[i]`
            /// is blocked.
            pub fn $occluded(&self, rays: &[Ray], out: &mut [bool; $width]) {
                let (valid, mut p) = $build(rays);
                let mut ctx = context(false);
                debug_assert_eq!(
                    valid.0.as_ptr() as usize % $align,
                    0,
                    "valid mask misaligned"
                );
                // SAFETY: as in the closest-hit query.
                unsafe { sys::$rtc_occluded(valid.0.as_ptr(), self.scene, &mut ctx, &mut p) };
                for (i, o) in out.iter_mut().enumerate() {
                    *o = i < rays.len() && p.tfar[i] == f32::NEG_INFINITY;
                }
            }
        }
    };
}

packet_queries!(
    8,
    32,
    Valid8,
    packet8,
    RTCRay8,
    RTCRayHit8,
    rtcIntersect8,
    rtcOccluded8,
    intersect8,
    occluded8
);
packet_queries!(
    16,
    64,
    Valid16,
    packet16,
    RTCRay16,
    RTCRayHit16,
    rtcIntersect16,
    rtcOccluded16,
    intersect16,
    occluded16
);

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square in the z = 0 plane facing +z, and a second one at z = 1.
    fn two_squares() -> RayTracer {
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        let i = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        RayTracer::new(&p, &i, true).unwrap()
    }

    #[test]
    fn closest_hit_distance_barycentrics_and_normal() {
        enable_flush_to_zero();
        let rt = two_squares();
        let h = rt
            .intersect(
                Vec3::new(0.75, 0.25, -2.0),
                Vec3::new(0.0, 0.0, 1.0),
                0.0,
                f64::INFINITY,
            )
            .unwrap();
        assert!((h.t - 2.0).abs() < 1e-6);
        assert_eq!(h.triangle, 0);
        // (0.75, 0.25) = (1-u-v) a + u b + v c with a=(0,0), b=(1,0), c=(1,1): u = 0.5, v = 0.25.
        assert!((h.u - 0.5).abs() < 1e-6 && (h.v - 0.25).abs() < 1e-6);
        assert!(
            h.geometric_normal.z > 0.0,
            "front side must be (b-a)x(c-a) = +z, got {:?}",
            h.geometric_normal
        );
        assert!(rt
            .intersect(
                Vec3::new(2.0, 2.0, -1.0),
                Vec3::new(0.0, 0.0, 1.0),
                0.0,
                10.0
            )
            .is_none());
        assert!(rt
            .intersect(
                Vec3::new(0.5, 0.5, -2.0),
                Vec3::new(0.0, 0.0, 1.0),
                0.0,
                1.5
            )
            .is_none());
    }

    #[test]
    fn occlusion_respects_the_segment() {
        let rt = two_squares();
        let o = Vec3::new(0.5, 0.5, 0.5);
        let up = Vec3::new(0.0, 0.0, 1.0);
        assert!(rt.occluded(o, up, 0.0, 1.0));
        assert!(!rt.occluded(o, up, 0.0, 0.4));
        assert!(!rt.occluded(o, Vec3::new(1.0, 0.0, 0.0), 0.0, 10.0));
    }

    #[test]
    fn streams_agree_with_single_rays() {
        let rt = two_squares();
        let mut rays = Vec::new();
        let mut r = crate::sampling::Rng::new(9, 0);
        for _ in 0..1000 {
            let origin = Vec3::new(r.next_f64() * 2.0 - 0.5, r.next_f64() * 2.0 - 0.5, 0.5);
            let direction = crate::sampling::uniform_sphere(r.next_f64(), r.next_f64());
            rays.push(Ray {
                origin,
                direction,
                tnear: 0.0,
                tfar: 3.0,
            });
        }
        let (mut hits, mut occ) = (Vec::new(), Vec::new());
        rt.intersect_many(&rays, &mut hits);
        rt.occluded_many(&rays, &mut occ);
        for (i, ray) in rays.iter().enumerate() {
            assert_eq!(
                hits[i],
                rt.intersect(ray.origin, ray.direction, ray.tnear, ray.tfar)
            );
            assert_eq!(occ[i], hits[i].is_some());
        }
        // Packets of 16, then of 8, the last one partial (inactive lanes report nothing).
        check_packets::<16>(&rays[..997], &hits, |c, h, o| {
            rt.intersect16(c, h);
            rt.occluded16(c, o);
        });
        check_packets::<8>(&rays[..997], &hits, |c, h, o| {
            rt.intersect8(c, h);
            rt.occluded8(c, o);
        });
    }

    /// Packet queries of width N (`query` fills hits and occlusion for a chunk) against the
    /// single-ray hits of the same rays.
    fn check_packets<const N: usize>(
        rays: &[Ray],
        hits: &[Option<Hit>],
        query: impl Fn(&[Ray], &mut [Option<Hit>; N], &mut [bool; N]),
    ) {
        let (mut h, mut o) = ([None; N], [false; N]);
        for (k, chunk) in rays.chunks(N).enumerate() {
            query(chunk, &mut h, &mut o);
            for i in 0..N {
                let want = hits
                    .get(N * k + i)
                    .copied()
                    .flatten()
                    .filter(|_| i < chunk.len());
                assert_eq!(h[i], want, "width {N} packet {k} lane {i}");
                assert_eq!(o[i], want.is_some(), "width {N} packet {k} lane {i}");
            }
        }
    }

    #[test]
    fn empty_scene_hits_nothing() {
        let rt = RayTracer::new(&[], &[], false).unwrap();
        assert!(rt
            .intersect(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), 0.0, f64::INFINITY)
            .is_none());
    }
}
