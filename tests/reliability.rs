//! Bad or extreme input is refused with one line naming the file and the problem, no
//! run overwrites its inputs or a non-regular file, no run hangs, and no wrong input is accepted.
//! One table-driven test per class of cause.

use crate::util::{scene_compile, StageResult, TempDir};

const MATERIALS: &str = r#"materials: { "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) },"#;
const FLOOR: &str = r#"(name: "floor", shape: Quad(corner: (0.0, 0.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, -1.0)), material: "w"),"#;
const LIGHT: &str = r#"point_lights: [(position: (0.5, 1.0, -0.5), power: Intensity(10.0))],"#;

/// A scene with `head` (name, materials), `objects` and `lights`.
fn scene(head: &str, objects: &str, lights: &str) -> String {
    format!("Scene(\n    {head}\n    objects: [\n        {objects}\n    ],\n    {lights}\n)\n")
}

/// Compiles `text` into `dir/out/scene.lxs`; returns the error (code 1, one line) or `None`.
fn compile_error(text: &str) -> Option<String> {
    let dir = TempDir::new("rel-sc");
    let path = dir.write("scene.ron", text);
    let out = dir.path().join("out").join("scene.lxs");
    match scene_compile(&[path.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]) {
        Ok(()) => None,
        Err((code, msg)) => {
            assert_eq!(code, 1, "{msg}");
            assert!(!msg.contains('\n'), "one line: {msg}");
            assert!(!out.exists(), "nothing written on failure");
            Some(msg)
        }
    }
}

fn polygon(vertices: &str) -> String {
    format!(r#"(name: "p", shape: Polygon(vertices: [{vertices}]), material: "w"),"#)
}

/// Items 10, 14, 15, 19 (emission bounds): what scene-compile must refuse, with the place.
#[test]
fn scene_compile_refuses_wrong_scenes_with_the_place() {
    let two_materials = r#"materials: {
        "w": Lambertian(reflectance: (0.5, 0.5, 0.5)),
        "w": Lambertian(reflectance: (0.9, 0.9, 0.9)),
    },"#;
    let dup_object = format!("{FLOOR}\n{FLOOR}");
    let dup_light = r#"point_lights: [(name: "a", position: (0.5, 1.0, -0.5), power: Intensity(10.0)), (name: "a", position: (0.5, 1.0, -0.6), power: Intensity(10.0))],"#;
    let light_named_floor =
        r#"point_lights: [(name: "floor", position: (0.5, 1.0, -0.5), power: Intensity(10.0))],"#;
    let flux = |lm: &str| {
        format!(
            r#"(shape: Quad(corner: (0.0, 1.0, 0.0), u: (0.1, 0.0, 0.0), v: (0.0, 0.0, 0.1)), material: "w", emission: Flux(lumens: {lm})),"#
        )
    };
    let cases: Vec<(String, &[&str])> = vec![
        // 14: the second "w" would silently win.
        (
            scene(two_materials, FLOOR, LIGHT),
            &["scene.ron:4:", "duplicate key \"w\""],
        ),
        (
            scene(MATERIALS, &dup_object, LIGHT),
            &["objects[1].name", "duplicate name \"floor\"", "objects[0].name"],
        ),
        (
            scene(MATERIALS, FLOOR, dup_light),
            &["point_lights[1].name", "duplicate name \"a\""],
        ),
        (
            scene(MATERIALS, FLOOR, light_named_floor),
            &["point_lights[0].name", "duplicate name \"floor\""],
        ),
        // 14: a non-planar square (one corner 0.1 m up) and a non-convex arrow.
        (
            scene(
                MATERIALS,
                &polygon("(0,0,0), (1,0,0), (1,0.1,1), (0,0,1)"),
                LIGHT,
            ),
            &["objects[0].shape.vertices[", "not planar"],
        ),
        (
            scene(
                MATERIALS,
                &polygon("(0,0,0), (2,0,0), (2,0,2), (1,0,0.5), (0,0,2)"),
                LIGHT,
            ),
            &["objects[0].shape.vertices[3]", "not convex"],
        ),
        // A pentagram: every turn the same way, but it winds twice.
        (
            scene(
                MATERIALS,
                &polygon(
                    "(0,0,1), (0.588,0,-0.809), (-0.951,0,0.309), (0.951,0,0.309), (-0.588,0,-0.809)",
                ),
                LIGHT,
            ),
            &["objects[0].shape.vertices", "not convex"],
        ),
        // 19: a translation or a scale beyond f32 world coordinates is named as such.
        (
            scene(
                MATERIALS,
                r#"(name: "floor", shape: Quad(corner: (0.0, 0.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, -1.0)), material: "w", transform: (translate: (1e308, 0.0, 0.0))),"#,
                LIGHT,
            ),
            &[
                "objects[0].transform.translate[0]",
                "1e308 m is outside the world coordinates luxest can trace (±1e15 m)",
            ],
        ),
        // Beyond 1.8e18 m Embree aborted the process (a sensor at 2e18 m, a camera at 1e20 m).
        (
            scene(
                MATERIALS,
                FLOOR,
                r#"point_lights: [(position: (0.5, 1.0, -0.5), power: Intensity(10.0))], sensors: [Points(name: "far", points: [(position: (2e18, 0.5, 0.0), normal: (0.0, 1.0, 0.0))])],"#,
            ),
            &["sensors[0].points[0].position[0]", "2e18 m is outside the world coordinates"],
        ),
        (
            scene(
                MATERIALS,
                FLOOR,
                r#"point_lights: [(position: (0.5, 1.0, -1e20), power: Intensity(10.0))],"#,
            ),
            &["point_lights[0].position[2]", "-1e20 m is outside the world coordinates"],
        ),
        // A scene a nanometre across (lengths given in the wrong unit, or scaled away).
        (
            scene(
                MATERIALS,
                r#"(name: "floor", shape: Quad(corner: (0.0, 0.0, 0.0), u: (1e-9, 0.0, 0.0), v: (0.0, 0.0, -1e-9)), material: "w"),"#,
                r#"point_lights: [(position: (5e-10, 1e-9, -5e-10), power: Intensity(10.0))],"#,
            ),
            &["the geometry spans 1.41", "e-9 m, below the 1e-6 m luxest traces reliably"],
        ),
        // A Floor's corners the wrong way round turned the plane over (0 lx below the floor).
        (
            scene(
                MATERIALS,
                FLOOR,
                r#"point_lights: [(position: (0.5, 1.0, -0.5), power: Intensity(10.0))], calculation_surfaces: [(name: "p", area: Floor(min: (6.0, 0.0), max: (0.0, 4.0), y: 0.0), offset: 0.75)],"#,
            ),
            &["calculation_surfaces[0].area", "Floor min.x 6 is not below max.x 0"],
        ),
        // Grid points are a corner plus finite edges, each of which may be huge.
        (
            scene(
                MATERIALS,
                FLOOR,
                r#"point_lights: [(position: (0.5, 1.0, -0.5), power: Intensity(10.0))], sensors: [Grid(name: "g", corner: (0.0, 0.5, 0.0), u: (4e15, 0.0, 0.0), v: (0.0, 0.0, 1.0), counts: (2, 1))],"#,
            ),
            &["sensors \"g\", point 1", "3e15 m is outside the world coordinates"],
        ),
        (
            scene(
                MATERIALS,
                r#"(name: "floor", shape: Quad(corner: (0.0, 0.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, -1.0)), material: "w", transform: (scale: (1e300, 1.0, 1.0))),"#,
                LIGHT,
            ),
            &["objects[0]", "vertex 1: inf m is outside the world coordinates"],
        ),
        // 15: flux that overflows the estimators' arithmetic, at compile time.
        (
            scene(MATERIALS, &format!("{FLOOR}\n{}", flux("1e308")), ""),
            &["objects[1].emission.lumens", "1e308 lm exceeds 1e25 lm"],
        ),
        // A flux within bounds on an emitter so small that its luminance is not (it gave inf
        // pixels): 1e24 lm over 0.01 m² is 3.2e25 cd/m².
        (
            scene(MATERIALS, &format!("{FLOOR}\n{}", flux("1e24")), ""),
            &[
                "objects[1].emission",
                "1e24 lm from 1.000e-2 m² is a luminance of 3.183e25, above the 1e25",
            ],
        ),
        (
            scene(
                MATERIALS,
                FLOOR,
                r#"point_lights: [(position: (0.5, 1.0, -0.5), power: Intensity(1e300))],"#,
            ),
            &["point_lights[0].power", "1e300 exceeds 1e25"],
        ),
        // 19: bounds in scientific notation, not 309 digits.
        (
            scene(
                MATERIALS,
                &format!(
                    r#"{FLOOR} (shape: Quad(corner: (0.0, 1.0, 0.0), u: (0.1, 0.0, 0.0), v: (0.0, 0.0, 0.1)), material: "w", emission: Radiance((1e30, 1.0, 1.0))),"#
                ),
                "",
            ),
            &["objects[1].emission", "1e30 is outside [0, 1e25]"],
        ),
        // 10: the scene name becomes build/<name>/: it must not leave that directory.
        (
            scene(&format!(r#"name: "../../escaped", {MATERIALS}"#), FLOOR, LIGHT),
            &["scene.ron: name: ", "path separator"],
        ),
        (
            scene(&format!(r#"name: "/tmp/x", {MATERIALS}"#), FLOOR, LIGHT),
            &["scene.ron: name: ", "path separator"],
        ),
        (
            scene(&format!(r#"name: "", {MATERIALS}"#), FLOOR, LIGHT),
            &["scene.ron: name: is empty"],
        ),
        (
            scene(&format!(r#"name: "..", {MATERIALS}"#), FLOOR, LIGHT),
            &["scene.ron: name: ", "leave the output directory"],
        ),
    ];
    for (text, parts) in &cases {
        let msg = compile_error(text).unwrap_or_else(|| panic!("accepted:\n{text}"));
        for p in *parts {
            assert!(msg.contains(p), "expected {p:?} in: {msg}");
        }
    }
    // The same scenes made right compile: a planar convex polygon (collinear vertices allowed),
    // distinct names, the largest allowed flux.
    for text in [
        scene(
            MATERIALS,
            &polygon("(0,0,0), (1,0,0), (2,0,0), (2,0,2), (0,0,2)"),
            LIGHT,
        ),
        // The largest flux on an emitter large enough (1 m², a luminance of 3.2e24).
        scene(
            MATERIALS,
            &format!(
                "{FLOOR}\n{}",
                r#"(shape: Quad(corner: (0.0, 1.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, 1.0)), material: "w", emission: Flux(lumens: 1e25)),"#
            ),
            "",
        ),
        scene(
            &format!(r#"name: "cornell-box", {MATERIALS}"#),
            FLOOR,
            LIGHT,
        ),
    ] {
        assert_eq!(compile_error(&text), None, "{text}");
    }
}

/// Compiles a scene with one mesh object `shape` (e.g. `Obj(path: "m.obj")`) next to `files`;
/// returns the error or `None`.
fn compile_mesh_error(shape: &str, files: &[(&str, &[u8])]) -> Option<String> {
    let dir = TempDir::new("rel-mesh");
    for (name, content) in files {
        dir.write(name, content);
    }
    let text = scene(
        MATERIALS,
        &format!(r#"(name: "m", shape: {shape}, material: "w"),"#),
        LIGHT,
    );
    let path = dir.write("scene.ron", text);
    let out = dir.path().join("scene.lxs");
    match scene_compile(&[path.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]) {
        Ok(()) => None,
        Err((code, msg)) => {
            assert_eq!(code, 1, "{msg}");
            assert!(!msg.contains('\n'), "one line: {msg}");
            Some(msg)
        }
    }
}

/// A glTF file with one triangle (36 bytes in `tri.bin`), `nodes` as given, and a POSITION
/// accessor of `count` elements.
fn gltf(nodes: &str, count: usize) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":{nodes},
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"buffers":[{{"uri":"tri.bin","byteLength":36}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}]}}"#
    )
}

/// Items 2 and 19: glTF node cycles end with an error (they grew memory until abort); an
/// accessor beyond its buffer, a binary OBJ and an OBJ index error are named with their place.
#[test]
fn mesh_files_with_cycles_and_bad_sizes_are_refused_with_the_place() {
    let tri: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let good = gltf(r#"[{"mesh":0}]"#, 3);
    assert_eq!(
        compile_mesh_error(
            r#"Gltf(path: "m.gltf")"#,
            &[("m.gltf", good.as_bytes()), ("tri.bin", &tri)]
        ),
        None
    );
    let cases: Vec<(String, &[&str])> = vec![
        (
            gltf(r#"[{"mesh":0,"children":[1]},{"children":[0]}]"#, 3),
            &["m.gltf: node ", "reached twice", "cycle"],
        ),
        (
            gltf(r#"[{"mesh":0,"children":[0]}]"#, 3),
            &["m.gltf: node 0: ", "cycle"],
        ),
        // Found by fuzzing: an accessor that does not exist panicked in the gltf crate.
        (
            gltf(r#"[{"mesh":0}]"#, 3).replace(r#""POSITION":0"#, r#""POSITION":1"#),
            &["m.gltf: mesh 0 primitive 0: refers to accessor 1, but the file has 1"],
        ),
        // Found by fuzzing: a POSITION accessor that is not VEC3 of FLOAT tripped the gltf
        // crate's assertions; a stride below the element size and sparse accessors likewise.
        (
            gltf(r#"[{"mesh":0}]"#, 3).replace(r#""type":"VEC3""#, r#""type":"VEC2""#),
            &["m.gltf: mesh 0 primitive 0 Positions (accessor 0): is Vec2 F32, but must be VEC3 of FLOAT"],
        ),
        (
            gltf(r#"[{"mesh":0}]"#, 3).replace(r#""byteLength":36}]"#, r#""byteLength":36,"byteStride":4}]"#),
            &["Positions (accessor 0): buffer view 0 has a stride of 4 bytes, less than its 12-byte elements"],
        ),
        (
            gltf(r#"[{"mesh":0}]"#, 1000),
            &["m.gltf: mesh 0 primitive 0 Positions (accessor 0): 1000 elements need 12000 bytes, but buffer view 0 has 36"],
        ),
    ];
    for (text, parts) in &cases {
        let msg = compile_mesh_error(
            r#"Gltf(path: "m.gltf")"#,
            &[("m.gltf", text.as_bytes()), ("tri.bin", &tri)],
        )
        .unwrap_or_else(|| panic!("accepted {text}"));
        for p in *parts {
            assert!(msg.contains(p), "expected {p:?} in: {msg}");
        }
    }
    // Binary glTF headers the gltf crate's arithmetic does not survive (found by fuzzing: a
    // total length below the header's 12 bytes panicked with a subtraction overflow).
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    let glb_cases: Vec<(Vec<u8>, &str)> = vec![
        (
            [glb.clone(), 9u32.to_le_bytes().to_vec()].concat(),
            "total length of 9 bytes; the file has 12",
        ),
        (
            [glb.clone(), 4000u32.to_le_bytes().to_vec(), vec![0; 20]].concat(),
            "total length of 4000 bytes; the file has 32",
        ),
        (
            b"glTF\0\0\0\0\x09\0\0\0\0".to_vec(),
            "binary glTF version 0, only 2 is supported",
        ),
        (b"glTF\x02\0".to_vec(), "binary header truncated at 6 bytes"),
    ];
    for (content, want) in &glb_cases {
        let msg = compile_mesh_error(r#"Gltf(path: "m.glb")"#, &[("m.glb", content)])
            .unwrap_or_else(|| panic!("accepted {content:?}"));
        assert!(
            msg.contains("m.glb: malformed glTF: ") && msg.contains(want),
            "{want}: {msg}"
        );
    }
    let obj_cases: Vec<(&[u8], &[&str])> = vec![
        (
            b"v 0 0 0\nv 1 0 0\n\xff\xfe\x00\x01binary\n",
            &["m.obj: line 3: ", "not text"],
        ),
        (
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\n# a comment\nf 1 2 9\n",
            &["m.obj: line 5: ", "index out of bounds"],
        ),
    ];
    for (content, parts) in &obj_cases {
        let msg = compile_mesh_error(r#"Obj(path: "m.obj")"#, &[("m.obj", content)])
            .unwrap_or_else(|| panic!("accepted {content:?}"));
        for p in *parts {
            assert!(msg.contains(p), "expected {p:?} in: {msg}");
        }
    }
}

/// Items 4 and 12: `estimate exact` validates its parameters like scene-compile does; the
/// divergent Sobolev cases (rho1 = rho2 = 1, or 1.5) end at once instead of looping.
#[test]
fn estimate_exact_refuses_parameters_outside_their_domain() {
    for (args, want) in [
        (
            &["sobolev", "--rho1", "1", "--rho2", "1"][..],
            "rho1 rho2 must be below 1",
        ),
        (
            &["sobolev", "--rho1", "1.5"],
            "rho1: must be a number in [0, 1], got 1.5",
        ),
        (
            &["sobolev", "--h1", "0"],
            "h1: must be a finite number > 0 m, got 0",
        ),
        (
            &["sobolev", "--intensity=-5"],
            "intensity: must be a finite number > 0 cd",
        ),
        (&["sobolev", "--r=-1"], "r: must be a finite number >= 0 m"),
        (
            &["sobolev", "--r", "NaN"],
            "r: must be a finite number >= 0 m",
        ),
        (
            &["cie171", "--rho=-1"],
            "rho: must be a number in [0, 1), got -1",
        ),
        (
            &["sphere", "--rho", "1"],
            "rho: must be a number in [0, 1), got 1",
        ),
        (
            &["sphere", "--radius", "inf"],
            "radius: must be a finite number > 0 m",
        ),
        // Far beyond the planes' gap the value is below the quadrature's error bound and the
        // work grows (1e308 printed NaN after minutes).
        (
            &["sobolev", "--r", "1,1e308"],
            "r 1e308 m is beyond 10000 (h1 + h2) = 20000 m",
        ),
        (&["sobolev", "--r", "20001"], "is beyond 10000 (h1 + h2)"),
        // Solutions that overflow f64 (they printed inf).
        (&["sobolev", "--h1", "1e-200"], "in f64 arithmetic"),
        (&["sphere", "--radius", "1e-200"], "in f64 arithmetic"),
    ] {
        let argv: Vec<&str> = ["exact"].into_iter().chain(args.iter().copied()).collect();
        let start = std::time::Instant::now();
        let (code, msg) = crate::util::estimate(&argv).expect_err("must be refused");
        assert!(
            start.elapsed().as_secs_f64() < 5.0,
            "{args:?} took too long"
        );
        assert_eq!(code, 2, "{args:?}: {msg}");
        assert!(msg.contains(want), "{args:?}: expected {want:?} in {msg}");
    }
    crate::util::estimate(&[
        "exact", "sobolev", "--rho1", "1", "--rho2", "0.5", "--r", "0,1",
    ])
    .unwrap();
}

/// Writes a uniform 20x12 image of `value` with albedo, normal and (zero) emission features (emi,
/// ema) beside it; returns the hdr path.
fn uniform_with_features(dir: &TempDir, name: &str, value: f32) -> std::path::PathBuf {
    use luxest_io::exr::write_rgb;
    use luxest_io::image::RgbImage;
    let mut img = RgbImage::new(20, 12);
    img.pixels.iter_mut().for_each(|p| *p = [value; 3]);
    let hdr = dir.path().join(format!("{name}.hdr.exr"));
    write_rgb(&hdr, &img).unwrap();
    let mut alb = RgbImage::new(20, 12);
    alb.pixels.iter_mut().for_each(|p| *p = [0.5; 3]);
    write_rgb(&dir.path().join(format!("{name}.alb.exr")), &alb).unwrap();
    let mut nrm = RgbImage::new(20, 12);
    nrm.pixels.iter_mut().for_each(|p| *p = [0.0, 0.0, 1.0]);
    write_rgb(&dir.path().join(format!("{name}.nrm.exr")), &nrm).unwrap();
    // No emitter in view (models with the emission features read them; others ignore them).
    for kind in ["emi", "ema"] {
        write_rgb(
            &dir.path().join(format!("{name}.{kind}.exr")),
            &RgbImage::new(20, 12),
        )
        .unwrap();
    }
    hdr
}

/// Item 17: a uniform image at the f32 maximum (finite, valid) is refused naming the image and
/// the f32 range, not blaming the model; near it the model is used through an exact power-of-two
/// rescaling, and its result is the scaled result of the same image at 1e20 (the model is
/// scale-equivariant through its exposure input).
#[test]
fn denoise_handles_radiance_near_the_f32_limit() {
    let dir = TempDir::new("rel-dn-max");
    let model = crate::util::repo_root().join("models/default.onnx");
    let mut results = Vec::new();
    for (name, v) in [("a_000001spp", 1e20f32), ("b_000001spp", 1e36)] {
        let hdr = uniform_with_features(&dir, name, v);
        crate::util::denoise(&[hdr.to_str().unwrap(), "--model", model.to_str().unwrap()]).unwrap();
        let out = dir.path().join(format!("{name}.dn.exr"));
        results.push(luxest_io::exr::read_rgb(&out).unwrap());
    }
    for (a, b) in results[0].pixels.iter().zip(&results[1].pixels) {
        for c in 0..3 {
            let (a, b) = (a[c] as f64 * 1e16, b[c] as f64);
            assert!((a - b).abs() <= 1e-5 * b.abs(), "{a:e} vs {b:e}");
        }
    }
    let hdr = uniform_with_features(&dir, "m_000001spp", f32::MAX);
    let (code, msg) =
        crate::util::denoise(&[hdr.to_str().unwrap(), "--model", model.to_str().unwrap()])
            .unwrap_err();
    assert_eq!(code, 1, "{msg}");
    assert!(
        msg.starts_with(hdr.to_str().unwrap()) && msg.contains("exceeds the largest 32-bit float"),
        "{msg}"
    );
    assert!(!msg.contains("model produced"), "{msg}");
    assert!(!dir.path().join("m_000001spp.dn.exr").exists());
}

/// The other extreme: an image whose radiance is in a tiny unit. The autoexposure's 1e-4 floor
/// made the model see a dim image as black (the fixture's denoised mean came out 2.7 times
/// that of the same image at its own scale); now `denoise` brightens it by a power of two
/// (luxest_io::exposure::dim_exponent), so images differing by a power of two are denoised alike
/// to the bit, and like the bright image to within the model's own scale dependence (0.5 %
/// measured on this image; 0.05 dB on the Cornell box, docs/measurements.md, *Dim images*).
#[test]
fn denoise_brightens_dim_images() {
    let dir = TempDir::new("rel-dn-dim");
    let model = crate::util::repo_root().join("models/default.onnx");
    let fixture = crate::util::repo_root().join("tests/fixtures/denoise");
    let mut results = Vec::new();
    for (name, e) in [
        ("b_000004spp", 0),
        ("d_000004spp", -20),
        ("e_000004spp", -60),
    ] {
        let scale = 2f32.powi(e);
        for f in ["hdr", "alb", "nrm", "emi", "ema"] {
            let mut img =
                luxest_io::exr::read_rgb(&fixture.join(format!("odd_000004spp.{f}.exr"))).unwrap();
            if matches!(f, "hdr" | "emi" | "ema") {
                for p in &mut img.pixels {
                    *p = p.map(|c| c * scale);
                }
            }
            luxest_io::exr::write_rgb(&dir.path().join(format!("{name}.{f}.exr")), &img).unwrap();
        }
        let hdr = dir.path().join(format!("{name}.hdr.exr"));
        crate::util::denoise(&[hdr.to_str().unwrap(), "--model", model.to_str().unwrap()]).unwrap();
        let out = luxest_io::exr::read_rgb(&dir.path().join(format!("{name}.dn.exr"))).unwrap();
        let unscaled: Vec<f64> = out
            .pixels
            .iter()
            .flatten()
            .map(|&c| c as f64 / scale as f64)
            .collect();
        results.push(unscaled);
    }
    assert_eq!(
        results[1], results[2],
        "2^-20 and 2^-60 denoised differently"
    );
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (bright, dim) = (mean(&results[0]), mean(&results[1]));
    assert!(
        (dim / bright - 1.0).abs() < 0.02,
        "dim mean {dim} vs bright {bright}"
    );
}

/// Snapshot of files' bytes, to prove that a refused run changed none of them.
fn snapshot(paths: &[&std::path::Path]) -> Vec<Option<Vec<u8>>> {
    paths.iter().map(|p| std::fs::read(p).ok()).collect()
}

/// Runs `stage` on `args` expecting a refusal (exit 1) whose message contains `want`, and
/// checks that `protected` files are unchanged and that no new file appeared in `dir`.
fn expect_refusal(
    stage: fn(&[&str]) -> StageResult,
    dir: &TempDir,
    args: &[&str],
    want: &str,
    protected: &[&std::path::Path],
) {
    let before = snapshot(protected);
    let files = dir.files();
    let (code, msg) = stage(args).expect_err(&format!("{args:?} must be refused"));
    assert_eq!(code, 1, "{args:?}: {msg}");
    assert!(!msg.contains('\n'), "one line: {msg}");
    assert!(msg.contains(want), "{args:?}: expected {want:?} in {msg}");
    assert_eq!(
        snapshot(protected),
        before,
        "{args:?} changed a protected file"
    );
    assert_eq!(dir.files(), files, "{args:?} left a file behind");
}

/// Items 5, 6, 7, 19 for denoise: no output over an input (image, feature, model) or another
/// output, none over a FIFO or a directory; a directory given as a feature is called one.
#[test]
fn denoise_never_overwrites_inputs_or_non_regular_files() {
    let dir = TempDir::new("rel-dn-out");
    let model_src = crate::util::repo_root().join("tests/fixtures/denoise/tiny.onnx");
    let model = dir.path().join("model.onnx");
    std::fs::copy(&model_src, &model).unwrap();
    let hdr = uniform_with_features(&dir, "a_000001spp", 1.0);
    let alb = dir.path().join("a_000001spp.alb.exr");
    let nrm = dir.path().join("a_000001spp.nrm.exr");
    let fifo = dir.path().join("fifo.exr");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    std::fs::create_dir(dir.path().join("adir.exr")).unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let m = s(&model);
    let sub = dir.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    let dotted = format!("{}/../a_000001spp.hdr.exr", s(&sub));
    let protected: Vec<&std::path::Path> = vec![&hdr, &alb, &nrm, &model];
    for (out, extra, want) in [
        (s(&hdr), None, "would overwrite the input"),
        (dotted.clone(), None, "would overwrite the input"),
        (s(&alb), None, "would overwrite the input"),
        (s(&model), None, "would overwrite the input"),
        (s(&fifo), None, "is a FIFO; refusing to replace it"),
        (
            s(&dir.path().join("adir.exr")),
            None,
            "is a directory; refusing",
        ),
        (
            s(&dir.path().join("o.png")),
            Some("--preview"),
            "two outputs of this run would be the same file",
        ),
    ] {
        let mut args = vec![s(&hdr), "--model".into(), m.clone(), "-o".into(), out];
        args.extend(extra.map(String::from));
        let argv: Vec<&str> = args.iter().map(String::as_str).collect();
        expect_refusal(crate::util::denoise, &dir, &argv, want, &protected);
    }
    // A directory where the albedo should be is called a directory.
    let b = uniform_with_features(&dir, "b_000001spp", 1.0);
    let balb = dir.path().join("b_000001spp.alb.exr");
    std::fs::remove_file(&balb).unwrap();
    std::fs::create_dir(&balb).unwrap();
    let argv = [s(&b), "--model".into(), m.clone()];
    let argv: Vec<&str> = argv.iter().map(String::as_str).collect();
    expect_refusal(
        crate::util::denoise,
        &dir,
        &argv,
        "is a directory, not the alb feature image",
        &protected,
    );
}

/// A small valid EXR whose header is rewritten to claim `w`x`h` pixels (data and display
/// window), the rest of the file unchanged: a few hundred bytes claiming 100000² pixels.
fn exr_claiming(path: &std::path::Path, w: i32, h: i32) {
    use luxest_io::exr::write_rgb;
    use luxest_io::image::RgbImage;
    write_rgb(path, &RgbImage::new(2, 2)).unwrap();
    let mut bytes = std::fs::read(path).unwrap();
    for name in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
        let at = bytes
            .windows(name.len())
            .position(|w| w == name)
            .expect("window attribute")
            + name.len()
            + 4;
        for (k, v) in [0i32, 0, w - 1, h - 1].iter().enumerate() {
            bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// Item 3: an EXR whose header claims 100000² pixels is refused before reading, by the reader
/// and by the two stages that read images (it aborted in the exr crate's allocator).
#[test]
fn exr_headers_claiming_huge_images_are_refused_before_reading() {
    let dir = TempDir::new("rel-exr-huge");
    let huge = dir.path().join("h_000001spp.hdr.exr");
    exr_claiming(&huge, 100_000, 100_000);
    assert!(std::fs::metadata(&huge).unwrap().len() < 1000);
    let e = luxest_io::exr::read_rgb(&huge).unwrap_err().to_string();
    assert!(
        e.contains("header claims 100000x100000 pixels") || e.contains("needs"),
        "{e}"
    );
    let model = crate::util::repo_root().join("tests/fixtures/denoise/tiny.onnx");
    for f in ["alb", "nrm"] {
        exr_claiming(&dir.path().join(format!("h_000001spp.{f}.exr")), 2, 2);
    }
    let (code, msg) =
        crate::util::denoise(&[huge.to_str().unwrap(), "--model", model.to_str().unwrap()])
            .unwrap_err();
    assert_eq!(code, 1);
    assert!(msg.starts_with(huge.to_str().unwrap()), "{msg}");
    let reference = dir.path().join("ref.exr");
    luxest_io::exr::write_rgb(&reference, &luxest_io::image::RgbImage::new(2, 2)).unwrap();
    let (code, msg) = crate::util::evaluate(&[
        "images",
        "--reference",
        reference.to_str().unwrap(),
        huge.to_str().unwrap(),
        "-o",
        dir.path().join("r.csv").to_str().unwrap(),
    ])
    .unwrap_err();
    assert_eq!(code, 1);
    assert!(msg.starts_with(huge.to_str().unwrap()), "{msg}");
    // A header claiming an image that would fit in memory, but that no compression could
    // pack into the file's few hundred bytes (found by fuzzing: it allocated the claim first).
    exr_claiming(&huge, 4000, 4000);
    let e = luxest_io::exr::read_rgb(&huge).unwrap_err().to_string();
    assert!(
        e.contains("header claims 4000x4000 pixels, 192.0 MB of samples, more than its")
            && e.contains("bytes can hold with its compression"),
        "{e}"
    );
    // The same header claiming 2x2 (its true size) reads.
    exr_claiming(&huge, 2, 2);
    assert_eq!(luxest_io::exr::read_rgb(&huge).unwrap().width, 2);
}

/// Item 19 (denoise): an ONNX file of a newer IR version is one line naming the file, its IR
/// version and the supported one (ONNX Runtime's own message is a long C++ signature).
#[test]
fn onnx_of_a_newer_ir_version_is_one_line_with_both_versions() {
    let dir = TempDir::new("rel-onnx-ir");
    let mut bytes =
        std::fs::read(crate::util::repo_root().join("tests/fixtures/denoise/tiny.onnx")).unwrap();
    assert_eq!(bytes[0], 0x08, "ir_version is the ModelProto's first field");
    assert!(bytes[1] < 0x80, "a one-byte varint");
    bytes[1] = 99;
    let model = dir.write("new.onnx", &bytes);
    let hdr = uniform_with_features(&dir, "a_000001spp", 1.0);
    let (code, msg) =
        crate::util::denoise(&[hdr.to_str().unwrap(), "--model", model.to_str().unwrap()])
            .unwrap_err();
    assert_eq!(code, 1);
    assert!(msg.starts_with(model.to_str().unwrap()), "{msg}");
    assert!(msg.contains("ONNX IR version 99 is not supported"), "{msg}");
    assert!(
        msg.contains("up to 1"),
        "states the supported version: {msg}"
    );
    assert!(msg.len() < 300, "{msg}");
}

/// Sensor results of one wall point of the integrating sphere (exact 200 lx for
/// `sphere:I=100,R=1,rho=0.5`) with the given value, standard error and scene hash.
fn sphere_results(value: &str, se: &str, hash: &str) -> String {
    format!(
        r#"SensorResults(
    scene: "sphere",
    run: RunInfo(samples: 1000, seed: 1, seconds: 0.5, estimator: "local-estimate", scene_hash: "{hash}", program_version: "0.1.0"),
    unit: "lx",
    singularity: "ball",
    sets: [SensorSetResult(name: "wall", points: [
        SensorValue(position: (1.0, 0.0, 0.0), normal: (-1.0, 0.0, 0.0), value: 201.0, standard_error: 1.0, rgb: (0.0, 0.0, 0.0)),
        SensorValue(position: (0.0, 1.0, 0.0), normal: (0.0, -1.0, 0.0), value: {value}, standard_error: {se}, rgb: (0.0, 0.0, 0.0)),
    ])],
)
"#
    )
}

/// Item 11: `evaluate sensors` refuses results no estimate can produce (NaN values, zero,
/// negative or NaN standard errors, no scene hash), a --max-z of NaN, and case parameters
/// outside their domain or given twice; the same file made right passes.
#[test]
fn evaluate_sensors_refuses_wrong_results_and_parameters() {
    let dir = TempDir::new("rel-eval-sensors");
    let case = "sphere:I=100,R=1,rho=0.5";
    for (value, se, hash, want) in [
        (
            "NaN",
            "1.0",
            "h",
            "sets[\"wall\"].points[1]: value NaN is not a finite number",
        ),
        ("inf", "1.0", "h", "value inf is not a finite number"),
        (
            "199.0",
            "0.0",
            "h",
            "standard error 0 must be a finite number > 0",
        ),
        (
            "199.0",
            "-1.0",
            "h",
            "standard error -1 must be a finite number > 0",
        ),
        ("199.0", "NaN", "h", "standard error NaN must be"),
        ("199.0", "1.0", "", "results carry no scene hash"),
    ] {
        let path = dir.write("r.sensors.ron", sphere_results(value, se, hash));
        let (code, msg) =
            crate::util::evaluate(&["sensors", path.to_str().unwrap(), "--case", case])
                .expect_err("wrong results must be refused");
        assert_eq!(code, 1, "{msg}");
        assert!(
            msg.starts_with(path.to_str().unwrap()) && msg.contains(want),
            "{want}: {msg}"
        );
    }
    let path = dir.write("r.sensors.ron", sphere_results("199.0", "1.0", "h"));
    let p = path.to_str().unwrap();
    crate::util::evaluate(&["sensors", p, "--case", case, "--max-z", "1.5"]).unwrap();
    for (args, want) in [
        (
            vec!["--case", case, "--max-z", "NaN"],
            "must be a finite number > 0",
        ),
        (
            vec!["--case", case, "--max-z=-1"],
            "must be a finite number > 0",
        ),
        (
            vec!["--case", "sphere:I=100,R=0,rho=0.5"],
            "radius: must be a finite number > 0 m",
        ),
        (
            vec!["--case", "sphere:I=100,R=1,rho=1"],
            "rho: must be a number in [0, 1)",
        ),
        (
            vec!["--case", "cie171-5.8:flux=1,area=96,rho=-0.5,x=0,y=0,z=0"],
            "rho: must be a number in [0, 1)",
        ),
        (
            vec!["--case", "sphere:I=100,R=1,rho=0.5,rho=0.2"],
            "parameter rho is given twice",
        ),
    ] {
        let argv: Vec<&str> = ["sensors", p].into_iter().chain(args).collect();
        let (code, msg) = crate::util::evaluate(&argv).expect_err("must be refused");
        assert_eq!(code, 2, "{msg}");
        assert!(msg.contains(want), "{want}: {msg}");
    }
}

/// Item 11: `evaluate sensors --scene` refuses results whose scene hash is not the given
/// compiled scene's (results of another scene or an older compile), and a file that is not a
/// compiled scene; the hash it reads from the preamble is the one the renderer computes.
#[test]
fn evaluate_sensors_checks_the_scene_hash_of_the_results() {
    let dir = TempDir::new("rel-eval-hash");
    let lxs = cornell(&dir);
    let hash = luxest_render::compiled::CompiledScene::load(&lxs)
        .unwrap()
        .content_hash;
    assert_eq!(luxest_io::meta::compiled_scene_hash(&lxs).unwrap(), hash);
    let case = "sphere:I=100,R=1,rho=0.5";
    let scene = lxs.to_str().unwrap();
    let right = dir.write("right.sensors.ron", sphere_results("199.0", "1.0", &hash));
    crate::util::evaluate(&[
        "sensors",
        right.to_str().unwrap(),
        "--case",
        case,
        "--scene",
        scene,
    ])
    .unwrap();
    let other = "0123456789abcdef0123456789abcdef";
    let wrong = dir.write("wrong.sensors.ron", sphere_results("199.0", "1.0", other));
    let w = wrong.to_str().unwrap();
    let (code, msg) = crate::util::evaluate(&["sensors", w, "--case", case, "--scene", scene])
        .expect_err("results of another scene must be refused");
    assert_eq!(code, 1, "{msg}");
    assert!(
        msg.starts_with(w)
            && msg.contains(&format!("results are of scene hash {other}, but"))
            && msg.contains(&hash),
        "{msg}"
    );
    let (code, msg) = crate::util::evaluate(&["sensors", w, "--case", case, "--scene", w])
        .expect_err("a results file is no compiled scene");
    assert_eq!(code, 1, "{msg}");
    assert!(msg.contains("not a luxest compiled scene"), "{msg}");
}

/// Items 5, 6, 8 for evaluate: no report over an input image, results file or another report;
/// a report that cannot be written leaves none of the run's reports behind.
#[test]
fn evaluate_never_overwrites_inputs_and_commits_reports_together() {
    use luxest_io::exr::write_rgb;
    use luxest_io::image::RgbImage;
    let dir = TempDir::new("rel-eval-out");
    let reference = dir.path().join("ref.hdr.exr");
    let test = dir.path().join("t_000001spp.hdr.exr");
    let mut img = RgbImage::new(16, 16);
    img.pixels
        .iter_mut()
        .enumerate()
        .for_each(|(i, p)| *p = [i as f32 * 0.01; 3]);
    write_rgb(&reference, &img).unwrap();
    write_rgb(&test, &img).unwrap();
    let results = dir.write("r.sensors.ron", sphere_results("199.0", "1.0", "h"));
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let protected: Vec<&std::path::Path> = vec![&reference, &test, &results];
    let (r, t) = (s(&reference), s(&test));
    let csv = s(&dir.path().join("o.csv"));
    for (args, want) in [
        (
            vec!["images", "--reference", &r, &t, "-o", &r],
            "would overwrite the input",
        ),
        (
            vec!["images", "--reference", &r, &t, "-o", &t],
            "would overwrite the input",
        ),
        (
            vec!["images", "--reference", &r, &t, "-o", &csv, "--ron", &csv],
            "would be the same file",
        ),
        (
            vec![
                "sensors",
                &s(&results),
                "--case",
                "sphere:I=100,R=1,rho=0.5",
                "-o",
                &s(&results),
            ],
            "would overwrite the input",
        ),
    ] {
        expect_refusal(crate::util::evaluate, &dir, &args, want, &protected);
    }
    // The RON report's directory is a file: refused, and no report (the CSV) is left behind.
    std::fs::write(dir.path().join("blocker"), "x").unwrap();
    let ron = s(&dir.path().join("blocker/r.ron"));
    let files = dir.files();
    let (code, _) =
        crate::util::evaluate(&["images", "--reference", &r, &t, "-o", &csv, "--ron", &ron])
            .unwrap_err();
    assert_eq!(code, 1);
    assert_eq!(dir.files(), files, "no report left behind");
}

/// Runs a stage's `run` on `args` (program name first) like its binary; the error as printed.
fn stage<A: clap::Parser>(
    argv: &[&str],
    run: impl FnOnce(A) -> luxest_io::Result<()>,
) -> StageResult {
    match luxest_io::cli::parse::<A>(argv.iter().copied())
        .map_err(|e| (e.exit_code(), e.to_string()))?
    {
        None => Ok(()),
        Some(a) => run(a).map_err(|e| (e.exit_code(), e.to_string())),
    }
}

fn trace_stage(args: &[&str]) -> StageResult {
    let argv: Vec<&str> = ["trace"].into_iter().chain(args.iter().copied()).collect();
    stage::<trace::Args>(&argv, trace::run)
}

fn aov_write_stage(args: &[&str]) -> StageResult {
    let argv: Vec<&str> = ["aov-write"]
        .into_iter()
        .chain(args.iter().copied())
        .collect();
    stage::<aov_write::Args>(&argv, aov_write::run)
}

/// The Cornell box compiled into `dir`.
fn cornell(dir: &TempDir) -> std::path::PathBuf {
    let out = dir.path().join("cornell.lxs");
    let src = crate::util::repo_root().join("scenes/cornell-box.ron");
    scene_compile(&[src.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]).unwrap();
    out
}

/// Items 1 and 19: every camera stage states the allowed resolution range, and refuses a film
/// that does not fit in the available memory before allocating it (they aborted).
#[test]
fn camera_stages_size_the_film_before_allocating() {
    let dir = TempDir::new("rel-film");
    let lxs = cornell(&dir);
    let scene = lxs.to_str().unwrap();
    let out = dir.path().join("o").to_str().unwrap().to_string();
    let exr = dir.path().join("o.exr").to_str().unwrap().to_string();
    let needed = 32768u128 * 32768 * render_film_bytes();
    let available = luxest_io::limits::available_memory().unwrap_or(u64::MAX) as u128;
    for resolution in ["0x0", "100000x100000", "32768x32768"] {
        let runs: [(&str, StageResult); 3] = [
            (
                "trace",
                trace_stage(&[scene, "-o", &out, "--spp", "1", "--resolution", resolution]),
            ),
            (
                "aov-write",
                aov_write_stage(&[scene, "-o", &out, "--spp", "1", "--resolution", resolution]),
            ),
            (
                "estimate image",
                crate::util::estimate(&[
                    "image",
                    scene,
                    "-o",
                    &exr,
                    "--paths",
                    "10",
                    "--resolution",
                    resolution,
                ]),
            ),
        ];
        for (name, r) in runs {
            if resolution == "32768x32768" && needed <= available {
                // This machine could hold the film; rendering it is no test.
                continue;
            }
            let (code, msg) = r.expect_err(&format!("{name} {resolution} must be refused"));
            assert_eq!(code, 2, "{name}: {msg}");
            let want = if resolution == "32768x32768" {
                "a 32768x32768 film needs 51.5 GB of memory, more than the"
            } else {
                "each side in 1..=32768"
            };
            assert!(msg.contains(want), "{name} {resolution}: {msg}");
        }
    }
}

fn render_film_bytes() -> u128 {
    luxest_render::world::FILM_BYTES_PER_PIXEL as u128
}

/// Item 16: floor sensors exactly on the edges and corners of a 4 m `Box` room centred at the
/// origin (point source at the centre) read the same as their mirror images and as points
/// 1e-4 m inside, by the local estimate and by gather (some read 0 ± 0: the edge placement
/// pushed them out of the room through two of the walls).
#[test]
fn edge_and_corner_sensors_of_a_box_room_read_like_their_neighbours() {
    let dir = TempDir::new("rel-edges");
    let points: Vec<(f64, f64)> = vec![
        (2.0, 0.0),
        (-2.0, 0.0),
        (0.0, -2.0),
        (0.0, 2.0),
        (2.0, 2.0),
        (-2.0, -2.0),
        (2.0, -2.0),
        (-2.0, 2.0),
        (1.9999, 0.0),
        (-1.9999, -1.9999),
    ];
    let sensors: String = points
        .iter()
        .map(|(x, z)| format!("(position: ({x:?}, -2.0, {z:?}), normal: (0.0, 1.0, 0.0)),"))
        .collect();
    let text = format!(
        r#"Scene(
    materials: {{ "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
    objects: [(name: "room", shape: Box(size: (4.0, 4.0, 4.0)), material: "w", flip_normals: true)],
    point_lights: [(name: "s", position: (0.0, 0.0, 0.0), power: Flux(1000.0))],
    sensors: [Points(name: "floor", points: [{sensors}])],
)"#
    );
    let lxs = crate::util::compile_text(&dir, "box", &text);
    let out = dir.path().join("r.ron");
    for args in [
        vec!["sensors", "--paths", "40000"],
        vec!["gather", "--samples", "4000"],
    ] {
        let mut argv = args.clone();
        argv.extend([lxs.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        crate::util::estimate(&argv).unwrap();
        let r = luxest_io::sensors::SensorResults::read_ron(&out).unwrap();
        let v: Vec<(f64, f64)> = r.sets[0]
            .points
            .iter()
            .map(|p| (p.value, p.standard_error))
            .collect();
        let same = |a: usize, b: usize| {
            let (d, se) = (v[a].0 - v[b].0, (v[a].1.powi(2) + v[b].1.powi(2)).sqrt());
            assert!(
                v[a].0 > 1.0 && se > 0.0 && d.abs() < 4.5 * se,
                "{args:?}: point {:?} reads {:?}, point {:?} reads {:?}",
                points[a],
                v[a],
                points[b],
                v[b]
            );
        };
        // Edge midpoints: each like the one 1e-4 m inside; corners: each like the one inside.
        for a in 0..4 {
            same(a, 8);
        }
        for a in 4..8 {
            same(a, 9);
        }
    }
}

/// Items 5, 7, 18, 19 for scene-compile: no output over the scene, its meshes or a non-regular
/// file; a directory given as a mesh is called one; reflectance 1 compiles with a warning that
/// the result then depends on the depth cap.
#[test]
fn scene_compile_never_overwrites_its_sources() {
    let dir = TempDir::new("rel-sc-out");
    let mesh = dir.write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let text = scene(
        MATERIALS,
        &format!(r#"{FLOOR} (name: "m", shape: Obj(path: "m.obj"), material: "w"),"#),
        LIGHT,
    );
    let src = dir.write("s.ron", &text);
    let fifo = dir.path().join("fifo.lxs");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let protected: Vec<&std::path::Path> = vec![&src, &mesh];
    for (out, want) in [
        (s(&src), "would overwrite the input"),
        (s(&mesh), "would overwrite the input"),
        (s(&fifo), "is a FIFO; refusing"),
        (s(dir.path()), "is a directory; refusing"),
    ] {
        expect_refusal(
            scene_compile,
            &dir,
            &[&s(&src), "-o", &out, "-q"],
            want,
            &protected,
        );
    }
    std::fs::remove_file(&mesh).unwrap();
    std::fs::create_dir(&mesh).unwrap();
    let (code, msg) = scene_compile(&[&s(&src), "--check", "-q"]).unwrap_err();
    assert_eq!(code, 1);
    assert!(
        msg.contains("objects[1].shape.path") && msg.contains("is a directory, not a mesh file"),
        "{msg}"
    );
    // Reflectance 1: compiled, with the warning.
    let white = dir.write(
        "white.ron",
        scene(
            r#"materials: { "w": Lambertian(reflectance: (1.0, 0.5, 0.5)) },"#,
            FLOOR,
            LIGHT,
        ),
    );
    let (_, report) = scene_compile::compile_file(&white).unwrap();
    assert!(
        report
            .warnings
            .iter()
            .any(|w| w.contains("no material absorbs light in channel 0")
                && w.contains("--max-depth")),
        "{:?}",
        report.warnings
    );
    // The same white beside a material that absorbs: light is not trapped, no warning.
    let room = dir.write(
        "room.ron",
        scene(
            r#"materials: { "w": Lambertian(reflectance: (1.0, 0.5, 0.5)),
                            "grey": Lambertian(reflectance: (0.5, 0.5, 0.5)) },"#,
            &format!(
                "{FLOOR} (shape: Quad(corner: (0.0, 1.0, 0.0), u: (1.0, 0.0, 0.0), \
                 v: (0.0, 0.0, 1.0)), material: \"grey\")"
            ),
            LIGHT,
        ),
    );
    let (_, report) = scene_compile::compile_file(&room).unwrap();
    assert!(
        !report.warnings.iter().any(|w| w.contains("absorbs")),
        "{:?}",
        report.warnings
    );
}

/// Items 5, 6, 7, 8 for estimate, trace and aov-write: no output over the scene or another
/// output, none over a FIFO or a directory, checked before any work; a run whose later output
/// cannot be written leaves none of its outputs behind.
#[test]
fn camera_and_sensor_stages_never_overwrite_inputs_and_commit_together() {
    let dir = TempDir::new("rel-est-out");
    let lxs = cornell(&dir);
    // A scene file whose name is one of the run's default image names.
    let alb_named = dir.path().join("p_000001spp.alb.exr");
    let hdr_named = dir.path().join("s_000001spp.hdr.exr");
    std::fs::copy(&lxs, &alb_named).unwrap();
    std::fs::copy(&lxs, &hdr_named).unwrap();
    let fifo = dir.path().join("fifo.ron");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    // A regular file where the CSV's directory should be: the CSV cannot be written.
    dir.write("blocker", "x");
    std::fs::create_dir(dir.path().join("q_000001spp.nrm.exr")).unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let d = |name: &str| s(&dir.path().join(name));
    let scene = s(&lxs);
    let quick = ["--batches", "2", "--threads", "1"];
    let protected: Vec<&std::path::Path> = vec![&lxs, &alb_named, &hdr_named];
    type Stage = fn(&[&str]) -> StageResult;
    let est: Stage = crate::util::estimate;
    let trace: Stage = trace_stage;
    let aov: Stage = aov_write_stage;
    let over = "would overwrite the input";
    let twice = "two outputs of this run would be the same file";
    let cases: Vec<(Stage, Vec<String>, &str)> = vec![
        (
            est,
            vec!["sensors".into(), scene.clone(), "-o".into(), scene.clone()],
            over,
        ),
        (
            est,
            vec!["gather".into(), scene.clone(), "-o".into(), scene.clone()],
            over,
        ),
        (
            est,
            vec![
                "direct".into(),
                scene.clone(),
                "--bin-radius".into(),
                "0.1".into(),
                "-o".into(),
                scene.clone(),
            ],
            over,
        ),
        (
            est,
            vec![
                "image".into(),
                scene.clone(),
                "--resolution".into(),
                "8x8".into(),
                "-o".into(),
                scene.clone(),
            ],
            over,
        ),
        (
            est,
            vec![
                "image".into(),
                scene.clone(),
                "--resolution".into(),
                "8x8".into(),
                "-o".into(),
                d("o.exr"),
                "--stderr-out".into(),
                d("o.exr"),
            ],
            twice,
        ),
        (
            est,
            vec![
                "image".into(),
                scene.clone(),
                "--resolution".into(),
                "8x8".into(),
                "-o".into(),
                d("o.exr"),
                "--preview".into(),
                d("./o.exr"),
            ],
            twice,
        ),
        (
            est,
            vec![
                "sensors".into(),
                scene.clone(),
                "-o".into(),
                d("o.ron"),
                "--csv".into(),
                d("o.ron"),
            ],
            twice,
        ),
        (
            est,
            vec!["sensors".into(), scene.clone(), "-o".into(), s(&fifo)],
            "is a FIFO; refusing",
        ),
        (
            est,
            vec!["gather".into(), scene.clone(), "-o".into(), d("")],
            "is a directory; refusing",
        ),
        // The CSV cannot be written (its directory is a file): refused before the estimate,
        // so neither the RON nor the CSV appears.
        (
            est,
            vec![
                "sensors".into(),
                scene.clone(),
                "--paths".into(),
                "100".into(),
                "--near-samples".into(),
                "0".into(),
                "-o".into(),
                d("x.ron"),
                "--csv".into(),
                d("blocker/x.csv"),
            ],
            "cannot create the output's directory",
        ),
        (
            trace,
            vec![
                s(&hdr_named),
                "--spp".into(),
                "1".into(),
                "--resolution".into(),
                "8x8".into(),
                "-o".into(),
                d("s"),
            ],
            over,
        ),
        (
            trace,
            vec![
                scene.clone(),
                "--spp".into(),
                "2".into(),
                "--snapshots".into(),
                "1".into(),
                "--resolution".into(),
                "8x8".into(),
                "-o".into(),
                d("t"),
                "--preview".into(),
                d("t_000001spp.hdr.exr"),
            ],
            twice,
        ),
        (
            aov,
            vec![
                s(&alb_named),
                "--spp".into(),
                "1".into(),
                "--resolution".into(),
                "8x8".into(),
                "-o".into(),
                d("p"),
            ],
            over,
        ),
        // The normal image's path is a directory: the albedo must not be written either.
        (
            aov,
            vec![
                scene.clone(),
                "--spp".into(),
                "1".into(),
                "--resolution".into(),
                "8x8".into(),
                "-o".into(),
                d("q"),
            ],
            "is a directory; refusing",
        ),
    ];
    for (stage, args, want) in cases {
        let mut argv: Vec<&str> = args.iter().map(String::as_str).collect();
        if ["sensors", "gather", "direct"].contains(&argv[0]) {
            argv.extend(quick);
        } else {
            argv.extend(["--threads", "1"]);
        }
        expect_refusal(stage, &dir, &argv, want, &protected);
    }
    // The same runs with distinct outputs succeed and write what they planned.
    crate::util::estimate(&[
        "sensors",
        &scene,
        "--paths",
        "100",
        "--near-samples",
        "0",
        "-o",
        &d("x.ron"),
        "--csv",
        &d("x.csv"),
        "--batches",
        "2",
    ])
    .unwrap();
    aov_write_stage(&[
        &scene,
        "--spp",
        "2",
        "--snapshots",
        "1",
        "--resolution",
        "8x8",
        "-o",
        &d("r"),
    ])
    .unwrap();
    for f in [
        "x.ron",
        "x.csv",
        "r_000001spp.alb.exr",
        "r_000002spp.nrm.exr",
    ] {
        assert!(dir.path().join(f).is_file(), "{f} not written");
    }
}

/// Items 4 and 13: options that silently changed or disabled what they set, or never ended, are
/// usage errors stating the allowed range and unit.
#[test]
fn numeric_options_outside_their_range_are_usage_errors() {
    let dir = TempDir::new("rel-opts");
    let lxs = cornell(&dir);
    let scene = lxs.to_str().unwrap();
    let o = dir.path().join("o").to_str().unwrap().to_string();
    let positive_m = "must be a finite number > 0 m";
    // Outputs named as their stage writes them, so that the option is what gets refused.
    let (o_ron, o_exr) = (format!("{o}.ron"), format!("{o}.exr"));
    let est = |a: &[&str]| {
        let mut argv = a.to_vec();
        argv.insert(1, scene);
        argv.extend(["-o", if a[0] == "image" { &o_exr } else { &o_ron }]);
        crate::util::estimate(&argv)
    };
    let with_scene = |f: fn(&[&str]) -> StageResult, a: &[&str]| {
        let mut argv = vec![scene];
        argv.extend(a);
        argv.extend(["-o", &o]);
        f(&argv)
    };
    let cases: Vec<(StageResult, &str)> = vec![
        (est(&["sensors", "--near-radius=-0.1"]), positive_m),
        (est(&["sensors", "--near-radius", "NaN"]), positive_m),
        (est(&["sensors", "--eps=-0.1"]), positive_m),
        (est(&["sensors", "--edge-offset", "inf"]), positive_m),
        // Sensors moved out of the room (1e300 aborted the process): at most a tenth of it.
        (
            est(&["sensors", "--edge-offset", "1e300"]),
            "--edge-offset 1e300 m exceeds",
        ),
        (
            est(&["gather", "--edge-offset", "1"]),
            "m, a tenth of the scene's room scale",
        ),
        (
            est(&["sensors", "--max-depth", "0"]),
            "must be a whole number in [1, 1048576] bounces",
        ),
        (
            est(&["sensors", "--batches", "1"]),
            "must be a whole number in [2, 1048576] batches",
        ),
        (
            est(&["sensors", "--paths", "0"]),
            "must be a whole number >= 1 paths",
        ),
        (
            est(&["sensors", "--paths", "10"]),
            "--paths 10 is less than --batches 32",
        ),
        (est(&["image", "--eps=-0.1"]), positive_m),
        (est(&["image", "--eps", "NaN"]), positive_m),
        (est(&["image", "--pixel-samples", "0"]), "samples per pixel"),
        (est(&["image", "--max-depth", "0"]), "bounces"),
        (
            est(&["gather", "--samples", "0"]),
            "must be a whole number >= 1 paths",
        ),
        (
            est(&["gather", "--samples", "4"]),
            "--samples 4 is less than --batches 32",
        ),
        (est(&["direct", "--bin-radius=-1"]), positive_m),
        (
            est(&["sensors", "--threads", "5000"]),
            "in [0, 4096] threads (0: all cores)",
        ),
        (
            with_scene(trace_stage, &["--time", "inf"]),
            "must be a number in (0, 1000000] s",
        ),
        (
            with_scene(trace_stage, &["--spp", "4", "--snapshots", "0"]),
            "samples per pixel",
        ),
        (
            with_scene(trace_stage, &["--spp", "4", "--snapshots", "2,5"]),
            "5 exceeds --spp 4",
        ),
        (
            with_scene(trace_stage, &["--spp", "4", "--max-depth", "0"]),
            "bounces",
        ),
        (
            with_scene(aov_write_stage, &["--spp", "0"]),
            "samples per pixel",
        ),
        (
            with_scene(aov_write_stage, &["--spp", "4", "--snapshots", "0"]),
            "samples per pixel",
        ),
        (
            with_scene(aov_write_stage, &["--spp", "4", "--snapshots", "5"]),
            "5 exceeds --spp 4",
        ),
        (
            with_scene(aov_write_stage, &["--spp", "4", "--min-samples", "0"]),
            "samples per pixel",
        ),
    ];
    for (i, (r, want)) in cases.into_iter().enumerate() {
        let (code, msg) = r.expect_err(&format!("case {i} must be refused"));
        assert_eq!(code, 2, "case {i}: {msg}");
        assert!(msg.contains(want), "case {i}: expected {want:?} in {msg}");
    }
    assert!(dir.files().iter().all(|f| f == &lxs), "{:?}", dir.files());
}

/// Every output a user names with a fixed format must end like that format (an EXR named
/// `.png`, or a PNG named `.exr`, would be misread by viewers and by the next stage), and an
/// output prefix must not end like a file: a usage error (exit 2) naming the option and the
/// ending, before any work and with nothing written. The same runs with the right endings
/// succeed.
#[test]
fn outputs_end_like_the_format_written() {
    let dir = TempDir::new("rel-endings");
    let lxs = cornell(&dir);
    let model_src = crate::util::repo_root().join("tests/fixtures/denoise/tiny.onnx");
    let model = dir.path().join("model.onnx");
    std::fs::copy(&model_src, &model).unwrap();
    let hdr = uniform_with_features(&dir, "a_000001spp", 1.0);
    let reference = uniform_with_features(&dir, "r_000001spp", 2.0);
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let d = |name: &str| s(&dir.path().join(name));
    let (scene, hdr, reference, model) = (s(&lxs), s(&hdr), s(&reference), s(&model));
    let src = d("src.ron");
    std::fs::copy(crate::util::repo_root().join("scenes/sobolev.ron"), &src).unwrap();
    type Stage = fn(&[&str]) -> StageResult;
    let (est, trace, aov): (Stage, Stage, Stage) =
        (crate::util::estimate, trace_stage, aov_write_stage);
    let (dn, ev, sc): (Stage, Stage, Stage) = (
        crate::util::denoise,
        crate::util::evaluate,
        crate::util::scene_compile,
    );
    let one = ["--threads", "1"];
    let image = [
        &["image", &scene, "--paths", "40", "--resolution", "8x8"][..],
        &one,
    ]
    .concat();
    let tr = ["--spp", "1", "--resolution", "8x8", "--threads", "1"];
    let sensors = ["sensors", &scene, "--paths", "100", "--near-samples", "0"];
    let sensors = [&sensors[..], &["--batches", "2"], &one].concat();
    let images = ["images", "--reference", &reference, &hdr];
    let csv = d("ok.csv");
    let images_csv = [&images[..], &["-o", &csv]].concat();
    // (stage, arguments, the option, the wrong path, its right ending)
    let cases: Vec<(Stage, Vec<&str>, &str, String, &str)> = vec![
        (est, image.clone(), "-o/--out", d("le.png"), ".exr"),
        (est, image.clone(), "--stderr-out", d("se.ron"), ".exr"),
        (est, image.clone(), "--preview", d("le.exr"), ".png"),
        (est, image.clone(), "--preview", d("le"), ".png"),
        (est, sensors.clone(), "-o/--out", d("s.csv"), ".ron"),
        (est, sensors.clone(), "--csv", d("s.txt"), ".csv"),
        (
            trace,
            [&[scene.as_str()][..], &tr].concat(),
            "--preview",
            d("p.exr"),
            ".png",
        ),
        (
            dn,
            vec![&hdr, "--model", &model, "--threads", "1"],
            "-o/--out",
            d("dn.png"),
            ".exr",
        ),
        (ev, images.to_vec(), "-o/--out", d("e.ron"), ".csv"),
        (ev, images_csv, "--ron", d("e.csv"), ".ron"),
        (sc, vec![&src, "-q"], "-o/--out", d("scene.ron2"), ".lxs"),
    ];
    for (stage, mut args, option, path, ending) in cases {
        let flag = option.rsplit('/').next().unwrap();
        args.extend([flag, &path]);
        let files = dir.files();
        let (code, msg) = stage(&args).expect_err(&format!("{args:?} must be refused"));
        assert_eq!(code, 2, "{args:?}: {msg}");
        assert!(!msg.contains('\n'), "one line: {msg}");
        let want = format!("{option} {path}: this writes");
        assert!(msg.contains(&want), "{args:?}: {msg}");
        assert!(msg.ends_with(&format!("name the file *{ending}")), "{msg}");
        assert_eq!(dir.files(), files, "{args:?} wrote something");
        // The same run with the right ending succeeds and writes that file.
        let right = d(&format!("right{ending}"));
        *args.last_mut().unwrap() = &right;
        let _ = std::fs::remove_file(&right);
        stage(&args).unwrap_or_else(|(c, m)| panic!("{args:?}: exit {c}: {m}"));
        assert!(
            dir.path().join(format!("right{ending}")).is_file(),
            "{args:?}"
        );
    }
    // A prefix that ends like a file, or has no file-name part.
    for (stage, prefix, example) in [
        (trace, d("t.exr"), "t.exr_000001spp.hdr.exr"),
        (aov, d("t.png"), "t.png_000001spp.alb.exr"),
        (trace, "..".to_string(), "_000001spp.hdr.exr"),
    ] {
        let args = [&[scene.as_str()][..], &tr, &["-o", &prefix]].concat();
        let files = dir.files();
        let (code, msg) = stage(&args).expect_err(&format!("{args:?} must be refused"));
        assert_eq!(code, 2, "{args:?}: {msg}");
        assert!(msg.starts_with(&format!("-o/--out {prefix}: ")), "{msg}");
        assert!(msg.contains("but it is a prefix"), "{msg}");
        assert!(msg.contains(example), "{msg}");
        assert_eq!(dir.files(), files, "{args:?} wrote something");
    }
}

/// The sensor estimators keep every batch's sums for every point: --batches 2^20 over 20 000
/// points (1.3 TB) is refused before any work, stating both sizes, instead of aborting in the
/// allocator.
#[test]
fn sensor_batches_are_sized_before_allocating() {
    let dir = TempDir::new("rel-batches");
    let points: Vec<String> = (0..20_000)
        .map(|k| {
            format!(
                "(position: ({}, 0.0, {}), normal: (0.0, 1.0, 0.0))",
                (k % 200) as f64 * 0.005,
                -((k / 200) as f64) * 0.005
            )
        })
        .collect();
    let text = scene(
        MATERIALS,
        FLOOR,
        &format!(
            "{LIGHT} sensors: [Points(name: \"grid\", points: [{}])],",
            points.join(", ")
        ),
    );
    let lxs = crate::util::compile_text(&dir, "grid", &text);
    let lxs = lxs.to_str().unwrap();
    let needed = 20_000u128 * (1 << 20) * 64;
    let available = luxest_io::limits::available_memory().unwrap_or(u64::MAX) as u128;
    if needed <= available {
        return; // This machine could hold them; running it is no test.
    }
    let out = dir.path().join("o.ron");
    for sub in ["sensors", "gather", "direct"] {
        let mut args = vec![
            sub,
            lxs,
            "--batches",
            "1048576",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend(match sub {
            "gather" => &["--samples", "1048576"][..],
            "direct" => &["--paths", "1048576", "--bin-radius", "0.01"],
            _ => &["--paths", "1048576"],
        });
        let (code, msg) = crate::util::estimate(&args).expect_err(sub);
        assert_eq!(code, 2, "{sub}: {msg}");
        assert!(
            msg.contains("--batches 1048576 over 20000 sensor points needs 1.3 TB of memory"),
            "{sub}: {msg}"
        );
        assert!(!out.exists());
    }
}

/// Round two, "wrongly accepted": `report --scene-info` refuses the header of another compile of
/// a scene with the same name (only the names were compared: the report listed 4 luminaires
/// and their flux beside results from the 5-luminaire office), and a header without its content
/// hash line; the header of the results' own compile is accepted.
#[test]
fn report_refuses_the_scene_info_of_another_compile() {
    let dir = TempDir::new("rel-report-hash");
    let office = |lights: &str| {
        format!(
            r#"Scene(name: "office",
    materials: {{ "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
    objects: [(name: "floor", shape: Quad(corner: (0.0, 0.0, 0.0), u: (0.0, 0.0, 2.0), v: (2.0, 0.0, 0.0)), material: "w")],
    point_lights: [{lights}],
    calculation_surfaces: [(name: "work-plane", area: Floor(min: (0.0, 0.0), max: (2.0, 2.0), y: 0.0), offset: 0.75)])"#
        )
    };
    let one = r#"(name: "a", position: (1.0, 2.0, 1.0), power: Flux(1000.0))"#;
    let two = format!(r#"{one}, (name: "b", position: (1.5, 2.0, 1.0), power: Flux(1000.0))"#);
    let five = crate::util::compile_text(&dir, "five", &office(&two));
    let four = crate::util::compile_text(&dir, "four", &office(one));
    let results = dir.path().join("office.sensors.ron");
    crate::util::estimate(&[
        "sensors",
        five.to_str().unwrap(),
        "--paths",
        "64",
        "--batches",
        "2",
        "-o",
        results.to_str().unwrap(),
    ])
    .unwrap();
    let info = |name: &str, lxs: &std::path::Path| {
        let scene = luxest_render::compiled::CompiledScene::load(lxs).unwrap();
        dir.write(name, scene_compile::cli::info_text(&scene))
    };
    let (own, other) = (info("five.info.ron", &five), info("four.info.ron", &four));
    let no_hash = dir.write(
        "bare.info.ron",
        luxest_io::fsio::to_ron_string(
            &luxest_render::compiled::CompiledScene::load(&five)
                .unwrap()
                .header,
        ),
    );
    let run = |info: &std::path::Path, out: &str| {
        crate::util::report(&[
            results.to_str().unwrap(),
            "--scene-info",
            info.to_str().unwrap(),
            "-o",
            dir.path().join(out).to_str().unwrap(),
        ])
    };
    for (info, want) in [
        (&other, "with content hash"),
        (&no_hash, "has no \"// content hash H\" line"),
    ] {
        let (code, msg) = run(info, "refused").expect_err("must be refused");
        assert_eq!(code, 1, "{msg}");
        assert!(
            msg.starts_with(info.to_str().unwrap()) && msg.contains(want),
            "{msg}"
        );
        assert!(!dir.path().join("refused").exists(), "nothing written");
    }
    run(&own, "report").unwrap();
    let md = std::fs::read_to_string(dir.path().join("report/report.md")).unwrap();
    assert!(
        md.contains("\"b\"") || md.contains(" b"),
        "both lights listed: {md}"
    );
}

/// Round two, "wrongly accepted": `evaluate sensors` without `--scene` compared results of
/// another scene with the case (a max |z| of 18 373, exit 0); now a point off the case's
/// surfaces, or facing away from them, is refused, naming it. Results on the case's geometry,
/// within 1 % of its size, pass.
#[test]
fn evaluate_sensors_refuses_points_off_the_cases_geometry() {
    let dir = TempDir::new("rel-eval-geometry");
    let results = |position: &str, normal: &str| {
        sphere_results("199.0", "1.0", "h").replace(
            "(0.0, 1.0, 0.0), normal: (0.0, -1.0, 0.0)",
            &format!("{position}, normal: {normal}"),
        )
    };
    let sphere = "sphere:I=100,R=1,rho=0.5";
    let sobolev = "sobolev:I=100,h1=1,h2=1,rho1=0.5,rho2=0.5";
    for (position, normal, case, point, want) in [
        // The Cornell box's floor against the sphere: inside, not on the wall.
        (
            "(0.2, 0.0, 0.3)",
            "(0.0, 1.0, 0.0)",
            sphere,
            1,
            "is not on the case's sphere wall",
        ),
        // On the wall, facing out.
        ("(0.0, 1.0, 0.0)", "(0.0, 1.0, 0.0)", sphere, 1, "facing in"),
        (
            "(3.0, 0.0, 0.0)",
            "(-1.0, 0.0, 0.0)",
            sphere,
            1,
            "radius 1 about the origin",
        ),
        // The sphere's wall against the planes (its first point, (1, 0, 0), already).
        (
            "(0.0, 1.0, 0.0)",
            "(0.0, -1.0, 0.0)",
            sobolev,
            0,
            "the point (1, 0, 0) is not on plane 2 of the case (y = 1, facing -y)",
        ),
    ] {
        let path = dir.write("r.sensors.ron", results(position, normal));
        let (code, msg) =
            crate::util::evaluate(&["sensors", path.to_str().unwrap(), "--case", case])
                .expect_err(&format!("{position} must be refused for {case}"));
        assert_eq!(code, 1, "{msg}");
        assert!(
            msg.starts_with(&format!(
                "{}: sets[\"wall\"].points[{point}]",
                path.display()
            )) && msg.contains(want)
                && msg.contains("results of another scene?"),
            "{want}: {msg}"
        );
    }
    // On the wall within 1 % of the radius, facing in: compared.
    let path = dir.write(
        "r.sensors.ron",
        results("(0.0, 0.9999, 0.0)", "(0.0, -1.0, 0.0)"),
    );
    crate::util::evaluate(&["sensors", path.to_str().unwrap(), "--case", sphere]).unwrap();
}

/// Round two, "unclear first lines": inputs that exist but are not regular files are called
/// what they are (`/dev/null` as a mesh was "not found"; a FIFO would have hung the read), a
/// binary file given as IES or EULUMDAT is "not a text file" (it was "missing TILT= line"), and
/// a glTF node whose transform is not finite is named (it was "NaN m is outside the world
/// coordinates … after the object's transform").
#[test]
fn inputs_that_are_not_what_they_should_be_are_named_as_such() {
    let dir = TempDir::new("rel-not-files");
    let fifo = dir.path().join("fifo.obj");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    for (path, want) in [
        (
            "/dev/null",
            "/dev/null is a device node, not a regular file, as a mesh must be",
        ),
        (
            fifo.to_str().unwrap(),
            "fifo.obj is a FIFO, not a regular file",
        ),
    ] {
        let shape = format!(r#"Obj(path: "{path}")"#);
        let msg = compile_mesh_error(&shape, &[]).expect("refused");
        assert!(
            msg.contains("objects[0].shape.path") && msg.contains(want),
            "{msg}"
        );
    }
    // A binary file (a PNG's first bytes) given as a photometric file.
    let png = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x01".to_vec();
    for name in ["lamp.ies", "lamp.ldt"] {
        let d = TempDir::new("rel-binary-ies");
        d.write(name, &png);
        let text = scene(
            MATERIALS,
            FLOOR,
            &format!(r#"luminaires: [(name: "l", file: "{name}", position: (0.5, 1.0, -0.5))],"#),
        );
        let path = d.write("scene.ron", text);
        let (code, msg) = scene_compile(&[path.to_str().unwrap(), "--check", "-q"]).unwrap_err();
        assert_eq!(code, 1, "{msg}");
        assert!(
            msg.contains(name) && msg.contains("not a text file: byte 4 is 0x0d")
                || msg.contains("not a text file: byte 6 is 0x1a"),
            "{msg}"
        );
        assert!(!msg.contains("TILT"), "{msg}");
    }
    // glTF nodes with an infinite matrix element (1e39 overflows f32), scale, or a product of
    // finite transforms that overflows.
    let tri: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    // Ten nested nodes scaling by 3e38 each: every transform finite, their product beyond
    // f64 from the ninth on.
    let big = "[3e38,0,0,0, 0,3e38,0,0, 0,0,3e38,0, 0,0,0,1]";
    let chain: Vec<String> = (0..10)
        .map(|k| match k {
            9 => format!(r#"{{"mesh":0,"matrix":{big}}}"#),
            _ => format!(r#"{{"children":[{}],"matrix":{big}}}"#, k + 1),
        })
        .collect();
    let chain = format!("[{}]", chain.join(","));
    for (nodes, want) in [
        (
            r#"[{"mesh":0,"name":"arm","matrix":[1,0,0,0, 0,1,0,0, 0,0,1,0, 1e39,0,0,1]}]"#,
            "m.gltf: node 0 (\"arm\"): matrix[12] is inf; a transform must be finite",
        ),
        (
            r#"[{"mesh":0,"scale":[1,1e39,1]}]"#,
            "m.gltf: node 0: scale[1] is inf",
        ),
        (
            chain.as_str(),
            "m.gltf: node 8: its transform composed with its parents' exceeds f64",
        ),
    ] {
        let text = gltf(nodes, 3);
        let msg = compile_mesh_error(
            r#"Gltf(path: "m.gltf")"#,
            &[("m.gltf", text.as_bytes()), ("tri.bin", &tri)],
        )
        .unwrap_or_else(|| panic!("accepted {nodes}"));
        assert!(msg.contains(want), "{want}: {msg}");
        assert!(!msg.contains("world coordinates"), "{msg}");
    }
}

/// Round two, "hangs from the new defaults": the near field's backward samples default to
/// --paths (at most 20 000), so that in a closed room of reflectance 1, where every walk runs to
/// --max-depth, the near field plans at most about twice the light paths' work (with the old
/// fixed 20 000 at 64 paths it planned 40 times their work: hours). The plan counts every walk
/// as reaching --max-depth there.
#[test]
fn the_near_fields_work_follows_the_light_paths() {
    let dir = TempDir::new("rel-near-work");
    let lxs = crate::util::compile_text(&dir, "white", &white_room());
    let world = estimate::sensors::load_world(&lxs).unwrap();
    let room = world.room_scale;
    let placed = estimate::sensors::evaluation_points(&world, 1e-3 * room, 0.1 * room);
    assert!(
        placed.near_radius.iter().any(|&r| r > 0.0),
        "near-field sensors"
    );
    let plan = |near: u64| {
        estimate::work::sensors_plan(
            &world,
            &placed.points,
            &placed.near_radius,
            64,
            near,
            (1, 100_000, 1, 32),
        )
    };
    let light = plan(0);
    assert!(
        light
            .work
            .starts_with("64 light paths of ~1.0e5 collisions"),
        "{}",
        light.work
    );
    let default = estimate::cli::DEFAULT_NEAR_SAMPLES.min(64);
    let with_near = plan(default);
    assert!(
        with_near.units <= 3.0 * light.units,
        "{} vs {}",
        with_near.line(),
        light.line()
    );
    let old_default = plan(20_000);
    assert!(
        old_default.units > 10.0 * light.units,
        "{}",
        old_default.line()
    );
}

/// A closed 4 x 3 x 4 m room of reflectance 1 with a 1 m² lamp under its ceiling: no light path
/// ends before --max-depth. Sensors on the floor, one near a wall (in its near field).
pub fn white_room() -> String {
    r#"Scene(
    name: "white-room",
    camera: Camera(position: (2.0, 1.5, 0.3), look_at: (2.0, 1.5, 4.0), up: (0.0, 1.0, 0.0), vfov_deg: 60.0, resolution: (32, 32)),
    materials: { "w": Lambertian(reflectance: (1.0, 1.0, 1.0)) },
    objects: [
        (name: "room", shape: Box(size: (4.0, 3.0, 4.0)), transform: (translate: (2.0, 1.5, 2.0)), material: "w", flip_normals: true),
        (name: "lamp", shape: Quad(corner: (1.5, 2.999, 1.5), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, 1.0)), material: "w", emission: Flux(lumens: 1000.0)),
    ],
    sensors: [
        Grid(name: "floor", corner: (0.0, 0.0, 0.0), u: (4.0, 0.0, 0.0), v: (0.0, 0.0, 4.0), counts: (4, 4), normal: (0.0, 1.0, 0.0)),
        Points(name: "by-the-wall", points: [(position: (0.1, 0.0, 2.0), normal: (0.0, 1.0, 0.0))]),
    ],
)"#
    .to_string()
}
