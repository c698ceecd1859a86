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
pub const TARGETS: [(&str, Target); 16] = [
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
    ("texture_png", texture_png),
    ("texture_jpeg", texture_jpeg),
    ("texture_exr", texture_exr),
    ("texture_encoded", texture_encoded),
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

/// A PNG texture: decoding, then what a texture does with the image ([`use_texture_image`]).
pub fn texture_png(data: &[u8]) {
    let path = Path::new(NOWHERE).join("t.png");
    use_texture_image(&path, luxest_io::texture_image::decode_png(&path, data));
}

/// A JPEG texture: decoding, then what a texture does with the image.
pub fn texture_jpeg(data: &[u8]) {
    let path = Path::new(NOWHERE).join("t.jpg");
    use_texture_image(&path, luxest_io::texture_image::decode_jpeg(&path, data));
}

/// An OpenEXR texture: decoding (channels R, G, B, A or Y, A; finite values), then what a
/// texture does with the image.
pub fn texture_exr(data: &[u8]) {
    let path = Path::new(NOWHERE).join("t.exr");
    use_texture_image(
        &path,
        luxest_io::texture_image::decode_exr(&path, data.to_vec()),
    );
}

/// A texture as the compiled scene stores it (`Texture::decode`), then lookups.
pub fn texture_encoded(data: &[u8]) {
    let path = Path::new(NOWHERE).join("s.lxs");
    if let Ok((texture, _)) = luxest_render::texture::Texture::decode(&path, data) {
        use_texture(&texture);
    }
}

/// Builds textures of a decoded image with two sets of options, looks them up, and checks that
/// each one's encoding decodes to the same texture.
fn use_texture_image(
    path: &Path,
    image: luxest_io::Result<luxest_io::texture_image::TextureImage>,
) {
    use luxest_render::texture::{Encoding, Filter, Texture, TextureOptions, UvTransform, Wrap};
    let Ok(image) = image else {
        return;
    };
    let linear = TextureOptions {
        encoding: Some(Encoding::Linear),
        wrap: Wrap::Mirror,
        filter: Filter::Nearest,
        uv_transform: UvTransform([[2.0, 0.5, 0.1], [-0.3, 1.5, 0.25]]),
    };
    for options in [TextureOptions::default(), linear] {
        let Ok(texture) = Texture::from_image(&image, &options) else {
            continue;
        };
        use_texture(&texture);
        let mut bytes = Vec::new();
        texture.encode(&mut bytes);
        let (back, len) = Texture::decode(path, &bytes).expect("a texture's encoding decodes");
        assert_eq!(len, bytes.len());
        assert!(back == texture, "the decoded texture differs");
    }
}

/// The lookups a renderer makes of a texture; all must be finite (the texels are).
fn use_texture(texture: &luxest_render::texture::Texture) {
    for (uv, footprint) in [
        ([0.3, 0.7], 0.0),
        ([-1.2, 5.5], 0.01),
        ([0.5, 0.5], 0.3),
        ([1e12, -1e300], 2.0),
        ([f64::NAN, 0.1], f64::INFINITY),
    ] {
        let v = texture.eval(uv, footprint);
        assert!(v.iter().all(|c| c.is_finite()), "lookup {v:?}");
    }
    let a = texture.average();
    // A small triangle: the mean's cost grows with the texels it covers, not its code paths.
    let m = texture.mean_over_triangle([[0.1, 0.1], [0.14, 0.11], [0.12, 0.16]]);
    assert!(
        a.iter().chain(&m).all(|c| c.is_finite()),
        "means {a:?} {m:?}"
    );
}

/// The queries the compiler and the estimators make of a parsed photometric file.
fn use_photometry(p: &luxest_photometry::Photometry) {
    let _ = p.flux_from_table_lm();
    let _ = p.max_cd();
    for (c, g) in [(0.0, 0.0), (90.0, 45.0), (359.9, 180.0), (-10.0, 200.0)] {
        let _ = p.intensity_cd(c, g);
    }
}
