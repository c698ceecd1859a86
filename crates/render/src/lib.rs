//! luxest-render: what the rendering stages (`scene-compile`, `trace`, `aov-write`, `estimate`)
//! share and the others never need.
//!
//! - [`scene`]: the authored scene format (RON) that people and `data-gen` write;
//! - [`compiled`]: the compiled, world-space scene every rendering stage reads;
//! - [`sampling`], [`sobol`], [`bsdf`], [`camera`]: seeded RNG, the path tracer's Sobol
//!   sampler and the sampling routines, material models, the pinhole camera and its pixel
//!   sampling;
//! - [`texture`]: bitmap textures (sRGB or linear, Mitsuba 3's wrap modes and filters,
//!   mip-mapped minification);
//! - [`luminaire`]: goniometric luminaires (photometric files) as delta lights and emitters;
//!   [`spot`]: spot lights' cones; [`environment`]: the environment emitter (constant sky,
//!   equirectangular map, a sun disk) and its sampling; [`sky`]: daylight skies with Radiance
//!   gensky's conventions (CIE overcast, clear and intermediate skies, the sun); [`portal`]:
//!   window portals and portal-masked sampling of the environment through them;
//! - [`rt`], [`world`]: the one wrapper around Embree, and the traced world built on it;
//!   [`light_bvh`]: the light BVH that chooses next-event estimation's light by its
//!   importance at the receiver;
//!   [`shading`]: shading frames (vertex normals, normal maps) as Mitsuba 3 defines them;
//! - [`parallel`]: deterministic parallel batches (its worker threads set Embree's
//!   flush-to-zero mode, hence here and not in `luxest-io`).

pub mod bsdf;
pub mod camera;
pub mod compiled;
pub mod environment;
pub mod light_bvh;
pub mod luminaire;
pub mod parallel;
pub mod portal;
pub mod rt;
pub mod sampling;
pub mod scene;
pub mod shading;
pub mod sky;
pub mod sobol;
pub mod spot;
pub mod texture;
pub mod world;
