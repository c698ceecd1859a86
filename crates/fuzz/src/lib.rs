//! The bodies of the fuzz targets: every parser of untrusted input, as a function of the raw
//! bytes that must return (an `Ok` or a one-line error) and never panic, abort or hang.
//!
//! `fuzz/` (its own workspace, cargo-fuzz and libFuzzer) wraps each function in a
//! `fuzz_target!`; `tests/smoke.rs` here runs them on stable over the repository's own files and
//! a few thousand deterministic mutations of each, so `cargo test` (and `make test`) exercises
//! them without libFuzzer. See docs/fuzzing.md.

use std::path::Path;

/// Where the inputs "are", for messages and for relative references (mesh and photometric
/// files of a scene, external glTF buffers): a directory that does not exist, so a fuzzed
/// reference reads nothing.
const NOWHERE: &str = "/nonexistent-luxest-fuzz";

/// A fuzz target's body: any bytes in, nothing out, no panic.
pub type Target = fn(&[u8]);

/// The targets by name, as `fuzz/fuzz_targets/<name>.rs` and the smoke run know them.
pub const TARGETS: [(&str, Target); 12] = [
    ("scene", scene),
    ("obj", obj),
    ("gltf", gltf),
    ("mitsuba_xml", mitsuba_xml),
    ("ply", ply),
    ("compiled", compiled),
    ("exr", exr),
    ("ies", ies),
    ("ldt", ldt),
    ("sensors", sensors),
    ("scene_info", scene_info),
    ("peer", peer),
];

/// A scene file: RON parsing, validation and, for scenes whose tessellation is small, the whole
/// compile (a fuzzer would otherwise spend its time on legitimately large spheres and grids).
pub fn scene(data: &[u8]) {
    use luxest_render::scene::{Scene, Sensor, Shape};
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new(NOWHERE).join("scene.ron");
    let Ok(scene) = luxest_io::fsio::parse_ron::<Scene>(&path, text) else {
        return;
    };
    if scene_compile::validate::check_scene(&path, &scene).is_err() {
        return;
    }
    let small = scene.calculation_surfaces.is_empty()
        && scene.objects.iter().all(|o| match o.shape {
            Shape::Sphere { subdivisions, .. } => subdivisions <= 4,
            _ => true,
        })
        && scene.sensors.iter().all(|s| match s {
            Sensor::Grid { counts, .. } => counts.0 as u64 * counts.1 as u64 <= 4096,
            _ => true,
        });
    if small {
        let _ = scene_compile::compile(&scene, &path);
    }
}

/// A Wavefront OBJ mesh.
pub fn obj(data: &[u8]) {
    let _ = scene_compile::meshes::load_obj_bytes(&Path::new(NOWHERE).join("m.obj"), data);
}

/// A glTF 2.0 file (JSON `.gltf` or binary `.glb`).
pub fn gltf(data: &[u8]) {
    let _ = scene_compile::meshes::load_gltf_bytes(&Path::new(NOWHERE).join("m.glb"), data);
}

/// A Mitsuba 3 XML scene: parsing, `$` substitution, includes (which read nothing: they are
/// looked up where no file is), references, transforms and the translation of every element;
/// a translation that validates is compiled when its tessellation is small.
pub fn mitsuba_xml(data: &[u8]) {
    use luxest_render::scene::Shape;
    let path = Path::new(NOWHERE).join("scene.xml");
    let Ok(imported) = scene_compile::import::mitsuba_xml::import_bytes(&path, data) else {
        return;
    };
    let scene = imported.scene;
    if scene_compile::validate::check_scene(&path, &scene).is_err() {
        return;
    }
    let small = scene.objects.len() <= 64
        && scene
            .objects
            .iter()
            .all(|o| !matches!(o.shape, Shape::Sphere { .. }));
    if small {
        let _ = scene_compile::compile(&scene, &path);
    }
}

/// A Stanford PLY mesh (ASCII or binary); the same bytes as a Mitsuba `.serialized` mesh (its
/// first and second mesh).
pub fn ply(data: &[u8]) {
    let _ = scene_compile::ply::load_ply_bytes(&Path::new(NOWHERE).join("m.ply"), data);
    for index in [0, 1] {
        let _ = scene_compile::serialized::load_serialized_bytes(
            &Path::new(NOWHERE).join("m.serialized"),
            data,
            index,
        );
    }
}

/// A compiled scene file (magic, schema, hash, header, arrays): as given, then with its content
/// hash made right, so that mutations reach the header and array parsers behind the hash check
/// (a fuzzer cannot forge an xxh3-128 by mutation).
pub fn compiled(data: &[u8]) {
    let path = Path::new(NOWHERE).join("s.lxs");
    let _ = luxest_render::compiled::CompiledScene::decode(&path, data);
    if data.len() >= 32 {
        let mut fixed = data.to_vec();
        let hash = xxhash_rust::xxh3::xxh3_128(&data[32..]);
        fixed[16..32].copy_from_slice(&hash.to_le_bytes());
        if let Ok(scene) = luxest_render::compiled::CompiledScene::decode(&path, &fixed) {
            // What the stages do next with a loaded scene: its consistency check.
            let _ = scene.check_consistency();
        }
    }
}

/// An OpenEXR image as the stages read it.
pub fn exr(data: &[u8]) {
    let _ = luxest_io::exr::read_rgb_bytes(&Path::new(NOWHERE).join("i.exr"), data.to_vec());
}

/// An IES LM-63 photometric file as the compiler reads it (text, or refused as binary), then
/// what the compiler asks of it.
pub fn ies(data: &[u8]) {
    let Ok(text) = luxest_photometry::text_of("f.ies", data.to_vec()) else {
        return;
    };
    if let Ok(p) = luxest_photometry::ies::parse_ies_str("f.ies", &text) {
        use_photometry(&p);
    }
}

/// A EULUMDAT photometric file as the compiler reads it, then what the compiler asks of it.
pub fn ldt(data: &[u8]) {
    let Ok(text) = luxest_photometry::text_of("f.ldt", data.to_vec()) else {
        return;
    };
    if let Ok(p) = luxest_photometry::ldt::parse_ldt_str("f.ldt", &text) {
        use_photometry(&p);
    }
}

/// Sensor results (`.sensors.ron`), then what `report` and `evaluate sensors` do with them:
/// the calculation surfaces' figures (jackknife over the batches) and each kind of exact case's
/// geometry check and rows.
pub fn sensors(data: &[u8]) {
    let path = Path::new(NOWHERE).join("results.ron");
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(results) = luxest_io::fsio::parse_ron::<luxest_io::sensors::SensorResults>(&path, text)
    else {
        return;
    };
    if let Ok(surfaces) = report::input::surfaces(&path, &results) {
        for s in &surfaces {
            let _ = s.stats(&path);
        }
    }
    for spec in [
        "sphere:I=100,R=1,rho=0.5",
        "sobolev:I=100,h1=1,h2=1,rho1=0.5,rho2=0.5,bin=0.1",
        "cie171-5.8:flux=1e4,area=96,rho=0.5,x=2,y=2,z=2",
    ] {
        let case = luxest_exact::cases::Case::parse(spec).expect("a valid case");
        if case.check_geometry(&results).is_ok() {
            let _ = case.rows(&results);
        }
    }
}

/// A compiled scene's header as `scene-compile --info` prints it, as `report --scene-info`
/// reads it: the header's partial view, its content-hash line, the luminaire groups.
pub fn scene_info(data: &[u8]) {
    let path = Path::new(NOWHERE).join("scene.info.ron");
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok((header, _hash)) = report::scene_info::parse(&path, text) {
        let _ = report::scene_info::light_sources(&path, &header);
    }
}

/// A peer program's illuminances (`report --peer`, CSV), then the check of its sets.
pub fn peer(data: &[u8]) {
    let path = Path::new(NOWHERE).join("peer.csv");
    if let Ok(p) = report::peer::parse(&path, data) {
        let _ = report::peer::check_sets(&path, &p, &["work-plane"], &path);
    }
}

/// The queries the compiler and the estimators make of a parsed photometric file.
fn use_photometry(p: &luxest_photometry::Photometry) {
    let _ = p.flux_from_table_lm();
    let _ = p.max_cd();
    for (c, g) in [(0.0, 0.0), (90.0, 45.0), (359.9, 180.0), (-10.0, 200.0)] {
        let _ = p.intensity_cd(c, g);
    }
}
