//! Embree 4 behind the Embree 3 names [`crate::rt`] uses (the `embree4` feature): hand-written
//! declarations of the few Embree 4 calls the wrapper needs, with Embree 3's signatures on top
//! (Embree 4 dropped the intersection context and the stream queries: the context is ignored,
//! streams and packets are answered ray by ray).
//!
//! Linked against `libembree4.so` in the folder named by `LUXEST_EMBREE4_DIR` at build time
//! (crates/render/build.rs), e.g. the shared library of the PyPI wheel `embreex` 4.4.

#![allow(non_camel_case_types, non_snake_case, clippy::missing_safety_doc)]

use std::os::raw::{c_char, c_uint, c_void};
use std::ptr;

pub type RTCDevice = *mut c_void;
pub type RTCScene = *mut c_void;
pub type RTCGeometry = *mut c_void;

/// Embree 4's `RTCRay` (the same layout as Embree 3's).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct RTCRay {
    pub org_x: f32,
    pub org_y: f32,
    pub org_z: f32,
    pub tnear: f32,
    pub dir_x: f32,
    pub dir_y: f32,
    pub dir_z: f32,
    pub time: f32,
    pub tfar: f32,
    pub mask: u32,
    pub id: u32,
    pub flags: u32,
}

/// Embree 4's `RTCHit` with one instance level and the instance-array field (`instPrimID`),
/// which the 4.x builds carry by default.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct RTCHit {
    pub Ng_x: f32,
    pub Ng_y: f32,
    pub Ng_z: f32,
    pub u: f32,
    pub v: f32,
    pub primID: u32,
    pub geomID: u32,
    pub instID: [u32; 1],
    pub instPrimID: [u32; 1],
}

#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCRayHit {
    pub ray: RTCRay,
    pub hit: RTCHit,
}

/// Filter-function arguments (the same layout in Embree 3 and 4; the context differs).
#[repr(C)]
pub struct RTCFilterFunctionNArguments {
    pub valid: *mut i32,
    pub geometryUserPtr: *mut c_void,
    pub context: *mut c_void,
    pub ray: *mut c_void,
    pub hit: *mut c_void,
    pub N: c_uint,
}

pub type RTCFilterFunctionN = Option<unsafe extern "C" fn(*const RTCFilterFunctionNArguments)>;

/// Stand-in for Embree 3's intersection context (Embree 4 takes optional arguments instead:
/// their defaults, incoherent rays and every feature, are what the wrapper asks for).
#[allow(dead_code)]
pub struct RTCIntersectContext {
    pub flags: RTCIntersectContextFlags,
    pub filter: RTCFilterFunctionN,
    pub instID: [u32; 1],
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RTCIntersectContextFlags(pub u32);
impl RTCIntersectContextFlags {
    pub const INCOHERENT: Self = Self(0);
    pub const COHERENT: Self = Self(1);
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct RTCError(pub u32);
impl RTCError {
    pub const NONE: Self = Self(0);
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct RTCSceneFlags(pub u32);
impl RTCSceneFlags {
    pub const NONE: Self = Self(0);
    pub const ROBUST: Self = Self(1 << 2);
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct RTCBuildQuality(pub u32);
impl RTCBuildQuality {
    pub const HIGH: Self = Self(2);
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct RTCGeometryType(pub u32);
impl RTCGeometryType {
    pub const TRIANGLE: Self = Self(0);
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct RTCBufferType(pub u32);
impl RTCBufferType {
    pub const INDEX: Self = Self(0);
    pub const VERTEX: Self = Self(1);
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct RTCFormat(pub u32);
impl RTCFormat {
    pub const UINT3: Self = Self(0x5003);
    pub const FLOAT3: Self = Self(0x9003);
}

mod ffi {
    use super::*;
    #[link(name = "embree4")]
    extern "C" {
        pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
        pub fn rtcReleaseDevice(device: RTCDevice);
        pub fn rtcGetDeviceError(device: RTCDevice) -> RTCError;
        pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
        pub fn rtcReleaseScene(scene: RTCScene);
        pub fn rtcSetSceneFlags(scene: RTCScene, flags: RTCSceneFlags);
        pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: RTCBuildQuality);
        pub fn rtcCommitScene(scene: RTCScene);
        pub fn rtcNewGeometry(device: RTCDevice, kind: RTCGeometryType) -> RTCGeometry;
        pub fn rtcReleaseGeometry(geometry: RTCGeometry);
        pub fn rtcCommitGeometry(geometry: RTCGeometry);
        pub fn rtcAttachGeometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint;
        pub fn rtcSetNewGeometryBuffer(
            geometry: RTCGeometry,
            kind: RTCBufferType,
            slot: c_uint,
            format: RTCFormat,
            byte_stride: usize,
            item_count: usize,
        ) -> *mut c_void;
        pub fn rtcSetGeometryUserData(geometry: RTCGeometry, ptr: *mut c_void);
        pub fn rtcSetGeometryIntersectFilterFunction(geometry: RTCGeometry, f: RTCFilterFunctionN);
        pub fn rtcSetGeometryOccludedFilterFunction(geometry: RTCGeometry, f: RTCFilterFunctionN);
        pub fn rtcIntersect1(scene: RTCScene, rayhit: *mut RTCRayHit, args: *mut c_void);
        pub fn rtcOccluded1(scene: RTCScene, ray: *mut RTCRay, args: *mut c_void);
    }
}

pub use ffi::{
    rtcAttachGeometry, rtcCommitGeometry, rtcCommitScene, rtcGetDeviceError, rtcNewDevice,
    rtcNewGeometry, rtcNewScene, rtcReleaseDevice, rtcReleaseGeometry, rtcReleaseScene,
    rtcSetGeometryIntersectFilterFunction, rtcSetGeometryOccludedFilterFunction,
    rtcSetGeometryUserData, rtcSetNewGeometryBuffer, rtcSetSceneBuildQuality, rtcSetSceneFlags,
};

/// Embree 3's `rtcIntersect1` (the context ignored).
#[inline]
pub unsafe fn rtcIntersect1(scene: RTCScene, _c: *mut RTCIntersectContext, rh: *mut RTCRayHit) {
    unsafe { ffi::rtcIntersect1(scene, rh, ptr::null_mut()) }
}

/// Embree 3's `rtcOccluded1` (the context ignored).
#[inline]
pub unsafe fn rtcOccluded1(scene: RTCScene, _c: *mut RTCIntersectContext, ray: *mut RTCRay) {
    unsafe { ffi::rtcOccluded1(scene, ray, ptr::null_mut()) }
}

/// Embree 3's stream query, ray by ray (`stride` is the size of `RTCRayHit`).
pub unsafe fn rtcIntersect1M(
    scene: RTCScene,
    c: *mut RTCIntersectContext,
    rays: *mut RTCRayHit,
    n: u32,
    _stride: usize,
) {
    for i in 0..n as usize {
        unsafe { rtcIntersect1(scene, c, rays.add(i)) };
    }
}

/// Embree 3's stream occlusion query, ray by ray.
pub unsafe fn rtcOccluded1M(
    scene: RTCScene,
    c: *mut RTCIntersectContext,
    rays: *mut RTCRay,
    n: u32,
    _stride: usize,
) {
    for i in 0..n as usize {
        unsafe { rtcOccluded1(scene, c, rays.add(i)) };
    }
}

/// Packets of width N in Embree 3's SoA layout, answered lane by lane.
macro_rules! packets {
    ($n:literal, $ray:ident, $hit:ident, $rayhit:ident, $intersect:ident, $occluded:ident) => {
        #[repr(C)]
        pub struct $ray {
            pub org_x: [f32; $n],
            pub org_y: [f32; $n],
            pub org_z: [f32; $n],
            pub tnear: [f32; $n],
            pub dir_x: [f32; $n],
            pub dir_y: [f32; $n],
            pub dir_z: [f32; $n],
            pub time: [f32; $n],
            pub tfar: [f32; $n],
            pub mask: [u32; $n],
            pub id: [u32; $n],
            pub flags: [u32; $n],
        }

        #[repr(C)]
        pub struct $hit {
            pub Ng_x: [f32; $n],
            pub Ng_y: [f32; $n],
            pub Ng_z: [f32; $n],
            pub u: [f32; $n],
            pub v: [f32; $n],
            pub primID: [u32; $n],
            pub geomID: [u32; $n],
            pub instID: [[u32; $n]; 1],
        }

        #[repr(C)]
        pub struct $rayhit {
            pub ray: $ray,
            pub hit: $hit,
        }

        fn lane(p: &$ray, i: usize) -> RTCRay {
            RTCRay {
                org_x: p.org_x[i],
                org_y: p.org_y[i],
                org_z: p.org_z[i],
                tnear: p.tnear[i],
                dir_x: p.dir_x[i],
                dir_y: p.dir_y[i],
                dir_z: p.dir_z[i],
                time: p.time[i],
                tfar: p.tfar[i],
                mask: p.mask[i],
                id: p.id[i],
                flags: p.flags[i],
            }
        }

        pub unsafe fn $intersect(
            valid: *const i32,
            scene: RTCScene,
            c: *mut RTCIntersectContext,
            p: *mut $rayhit,
        ) {
            let p = unsafe { &mut *p };
            for i in 0..$n {
                if unsafe { *valid.add(i) } == 0 {
                    continue;
                }
                let mut rh = RTCRayHit {
                    ray: lane(&p.ray, i),
                    hit: RTCHit {
                        Ng_x: 0.0,
                        Ng_y: 0.0,
                        Ng_z: 0.0,
                        u: 0.0,
                        v: 0.0,
                        primID: u32::MAX,
                        geomID: u32::MAX,
                        instID: [u32::MAX],
                        instPrimID: [u32::MAX],
                    },
                };
                unsafe { rtcIntersect1(scene, c, &mut rh) };
                p.ray.tfar[i] = rh.ray.tfar;
                (p.hit.Ng_x[i], p.hit.Ng_y[i], p.hit.Ng_z[i]) =
                    (rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
                (p.hit.u[i], p.hit.v[i]) = (rh.hit.u, rh.hit.v);
                (p.hit.primID[i], p.hit.geomID[i]) = (rh.hit.primID, rh.hit.geomID);
            }
        }

        pub unsafe fn $occluded(
            valid: *const i32,
            scene: RTCScene,
            c: *mut RTCIntersectContext,
            p: *mut $ray,
        ) {
            let p = unsafe { &mut *p };
            for i in 0..$n {
                if unsafe { *valid.add(i) } == 0 {
                    continue;
                }
                let mut r = lane(p, i);
                unsafe { rtcOccluded1(scene, c, &mut r) };
                p.tfar[i] = r.tfar;
            }
        }
    };
}

mod p8 {
    use super::*;
    packets!(8, RTCRay8, RTCHit8, RTCRayHit8, rtcIntersect8, rtcOccluded8);
}
mod p16 {
    use super::*;
    packets!(
        16,
        RTCRay16,
        RTCHit16,
        RTCRayHit16,
        rtcIntersect16,
        rtcOccluded16
    );
}
pub use p16::{rtcIntersect16, rtcOccluded16, RTCRay16, RTCRayHit16};
pub use p8::{rtcIntersect8, rtcOccluded8, RTCRay8, RTCRayHit8};
