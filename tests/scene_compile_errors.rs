//! Bad input to scene-compile: one line naming the file and the place, exit code 1 (2 for
//! usage), no panic, and no output file.

use crate::util::{scene_compile, TempDir};

const MATERIALS: &str = r#"materials: { "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) },"#;
const FLOOR: &str = r#"(name: "floor", shape: Quad(corner: (0.0, 0.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, -1.0)), material: "w"),"#;
const LIGHT: &str = r#"point_lights: [(position: (0.5, 1.0, -0.5), power: Intensity(10.0))],"#;

fn scene(materials: &str, objects: &str, lights: &str) -> String {
    format!("Scene(\n    {materials}\n    objects: [\n        {objects}\n    ],\n    {lights}\n)\n")
}

/// Compiles `text` (plus extra files) and expects failure: returns the message after checking
/// exit code 1, a single line, and that nothing was written.
fn expect_error(text: &str, extra: &[(&str, &[u8])]) -> String {
    let dir = TempDir::new("err");
    let path = dir.write("scene.ron", text);
    for (name, content) in extra {
        dir.write(name, content);
    }
    let before = dir.files();
    let out = dir.path().join("out").join("scene.lxs");
    let (code, msg) = scene_compile(&[path.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .expect_err("compiling bad input must fail");
    assert_eq!(code, 1, "{msg}");
    assert!(!msg.contains('\n'), "message must be one line: {msg}");
    assert_eq!(
        dir.files(),
        before,
        "a failed compile must leave no file behind"
    );
    msg
}

fn assert_has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "expected {p:?} in: {msg}");
    }
}

#[test]
fn valid_base_scene_compiles() {
    let dir = TempDir::new("ok");
    let path = dir.write("scene.ron", scene(MATERIALS, FLOOR, LIGHT));
    let out = dir.path().join("scene.lxs");
    scene_compile(&[path.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]).unwrap();
    assert!(out.is_file());
}

#[test]
fn unknown_field_names_line_and_field() {
    let obj = FLOOR.replace("material: \"w\"", "material: \"w\", colour: \"red\"");
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[]);
    // The object is on line 4 of the generated file.
    assert_has(&msg, &["scene.ron:4:", "colour"]);
}

#[test]
fn missing_field_is_named() {
    let obj = FLOOR.replace(", material: \"w\"", "");
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[]);
    assert_has(&msg, &["scene.ron:4:", "material"]);
}

#[test]
fn missing_mesh_file_is_named() {
    let obj = format!("{FLOOR}\n        (shape: Obj(path: \"meshes/nope.obj\"), material: \"w\"),");
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[]);
    assert_has(
        &msg,
        &["scene.ron: objects[1].shape.path", "nope.obj", "not found"],
    );
}

#[test]
fn malformed_obj_names_file_and_line() {
    let obj = format!("{FLOOR}\n        (shape: Obj(path: \"bad.obj\"), material: \"w\"),");
    let bad = b"# a comment\nv 0 0 0\nv 1 0 x\nv 0 1 0\nf 1 2 3\n";
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[("bad.obj", bad)]);
    assert_has(&msg, &["bad.obj: line 3: malformed OBJ"]);
}

#[test]
fn obj_face_out_of_range_is_an_error() {
    let obj = format!("{FLOOR}\n        (shape: Obj(path: \"bad.obj\"), material: \"w\"),");
    let bad = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n";
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[("bad.obj", bad)]);
    assert_has(&msg, &["bad.obj", "malformed OBJ", "out of bounds"]);
}

#[test]
fn nan_in_obj_names_the_vertex() {
    let obj = format!("{FLOOR}\n        (shape: Obj(path: \"nan.obj\"), material: \"w\"),");
    let bad = b"v 0 0 0\nv NaN 0 0\nv 0 1 0\nf 1 2 3\n";
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[("nan.obj", bad)]);
    assert_has(&msg, &["nan.obj: vertex 2", "non-finite"]);
}

#[test]
fn malformed_gltf_is_named() {
    let obj = format!("{FLOOR}\n        (shape: Gltf(path: \"bad.gltf\"), material: \"w\"),");
    let msg = expect_error(
        &scene(MATERIALS, &obj, LIGHT),
        &[("bad.gltf", br#"{"asset": 5}"#)],
    );
    assert_has(&msg, &["bad.gltf: malformed glTF"]);
    // A binary glTF cut short.
    let glb = std::fs::read(crate::util::repo_root().join("scenes/meshes/trefoil.glb")).unwrap();
    let obj = format!("{FLOOR}\n        (shape: Gltf(path: \"cut.glb\"), material: \"w\"),");
    let msg = expect_error(
        &scene(MATERIALS, &obj, LIGHT),
        &[("cut.glb", &glb[..glb.len() / 2])],
    );
    assert_has(&msg, &["cut.glb: "]);
}

#[test]
fn gltf_with_missing_buffer_file_is_named() {
    let gltf = br#"{"asset":{"version":"2.0"},"buffers":[{"uri":"gone.bin","byteLength":36}]}"#;
    let obj = format!("{FLOOR}\n        (shape: Gltf(path: \"m.gltf\"), material: \"w\"),");
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[("m.gltf", gltf)]);
    assert_has(&msg, &["m.gltf: buffer 0", "gone.bin"]);
}

#[test]
fn non_finite_scene_numbers_are_named() {
    let obj = FLOOR.replace("corner: (0.0, 0.0, 0.0)", "corner: (NaN, 0.0, 0.0)");
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[]);
    assert_has(
        &msg,
        &[
            "scene.ron: objects[0].shape.corner[0]",
            "not a finite number",
        ],
    );
    let light = LIGHT.replace("(0.5, 1.0, -0.5)", "(0.5, inf, -0.5)");
    let msg = expect_error(&scene(MATERIALS, FLOOR, &light), &[]);
    assert_has(
        &msg,
        &["point_lights[0].position[1]", "not a finite number"],
    );
}

#[test]
fn reflectance_outside_unit_interval_is_rejected() {
    for bad in ["1.2", "-0.1"] {
        let m = MATERIALS.replace("(0.5, 0.5, 0.5)", &format!("(0.5, {bad}, 0.5)"));
        let msg = expect_error(&scene(&m, FLOOR, LIGHT), &[]);
        assert_has(&msg, &["materials[\"w\"].reflectance", "outside [0, 1]"]);
    }
    let m = r#"materials: { "w": Glossy(diffuse: (0.6, 0.6, 0.6), specular: (0.5, 0.3, 0.3), roughness: 0.2) },"#;
    let msg = expect_error(&scene(m, FLOOR, LIGHT), &[]);
    assert_has(&msg, &["materials[\"w\"]", "exceeds 1"]);
}

#[test]
fn emitters_without_power_are_rejected() {
    let light = LIGHT.replace("Intensity(10.0)", "Intensity(0.0)");
    let msg = expect_error(&scene(MATERIALS, FLOOR, &light), &[]);
    assert_has(&msg, &["point_lights[0].power", "must be positive"]);
    let light = LIGHT.replace("Intensity(10.0)", "Flux(-3.0)");
    let msg = expect_error(&scene(MATERIALS, FLOOR, &light), &[]);
    assert_has(&msg, &["point_lights[0].power", "must be positive"]);
    let obj = FLOOR.replace(
        "material: \"w\"",
        "material: \"w\", emission: Radiance((0.0, 0.0, 0.0))",
    );
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[]);
    assert_has(&msg, &["objects[0].emission", "zero power"]);
    let obj = FLOOR.replace(
        "material: \"w\"",
        "material: \"w\", emission: Flux(lumens: -1.0)",
    );
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[]);
    assert_has(&msg, &["objects[0].emission.lumens", "must be positive"]);
}

#[test]
fn scene_without_emitter_is_rejected() {
    let msg = expect_error(&scene(MATERIALS, FLOOR, ""), &[]);
    assert_has(&msg, &["scene.ron: scene has no emitter"]);
}

#[test]
fn unknown_material_is_named() {
    let obj = FLOOR.replace("material: \"w\"", "material: \"steel\"");
    let msg = expect_error(&scene(MATERIALS, &obj, LIGHT), &[]);
    assert_has(&msg, &["objects[0].material", "unknown material \"steel\""]);
}

#[test]
fn degenerate_triangles_are_dropped_with_a_count() {
    let dir = TempDir::new("degenerate");
    // Two good triangles, one with a repeated vertex, one with collinear vertices.
    dir.write(
        "m.obj",
        "v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nv 2 0 0\nf 1 2 3\nf 1 3 4\nf 1 2 2\nf 1 2 5\n",
    );
    let obj = r#"(name: "mesh", shape: Obj(path: "m.obj"), material: "w"),"#;
    let path = dir.write("scene.ron", scene(MATERIALS, obj, LIGHT));
    let (compiled, report) = scene_compile::compile_file(&path).unwrap();
    assert_eq!(compiled.header.stats.triangles, 2);
    assert_eq!(compiled.header.stats.dropped_degenerate, 2);
    assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
    assert!(
        report.warnings[0].contains("objects[0] (mesh): dropped 2 degenerate triangles"),
        "{:?}",
        report.warnings
    );
    assert!((compiled.header.stats.total_area_m2 - 1.0).abs() < 1e-6);

    // An object with nothing but degenerate triangles is dropped with a warning; an emitting
    // one is an error.
    dir.write("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    let objs = format!(r#"{obj} (name: "flat", shape: Obj(path: "flat.obj"), material: "w"),"#);
    let path = dir.write("scene2.ron", scene(MATERIALS, &objs, LIGHT));
    let (compiled, report) = scene_compile::compile_file(&path).unwrap();
    assert_eq!(compiled.header.stats.triangles, 2);
    assert!(
        report
            .warnings
            .iter()
            .any(|w| w.contains("objects[1] (flat): dropped: no non-degenerate triangles")),
        "{:?}",
        report.warnings
    );
    let emitting = r#"(name: "flat", shape: Obj(path: "flat.obj"), material: "w", emission: Radiance((1.0, 1.0, 1.0))),"#;
    let msg = expect_error(
        &scene(MATERIALS, &format!("{FLOOR} {emitting}"), LIGHT),
        &[("flat.obj", b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")],
    );
    assert_has(
        &msg,
        &[
            "objects[1]",
            "emitting object has no non-degenerate triangles",
        ],
    );
}

#[test]
fn usage_errors_exit_with_two() {
    let (code, msg) = scene_compile(&["--no-such-flag", "x.ron"]).unwrap_err();
    assert_eq!(code, 2, "{msg}");
    let (code, _) = scene_compile(&[]).unwrap_err();
    assert_eq!(code, 2);
}

#[test]
fn missing_scene_file_is_named() {
    let (code, msg) = scene_compile(&["/nonexistent/dir/scene.ron"]).unwrap_err();
    assert_eq!(code, 1);
    assert_eq!(msg, "/nonexistent/dir/scene.ron: file not found");
}

#[test]
fn mitsuba_material_parameters_out_of_range_are_named() {
    for (material, parts) in [
        (
            r#"Conductor(eta: (0.2, 0.4, -1.0), k: (3.0, 2.0, 1.0))"#,
            &["materials[\"w\"].eta", "outside [0, 100]"][..],
        ),
        (
            r#"Conductor(eta: (0.0, 0.4, 1.0), k: (0.0, 2.0, 1.0))"#,
            &["materials[\"w\"]", "eta and k are both 0 in channel 0"][..],
        ),
        (
            r#"Conductor(eta: (0.2, 0.4, 1.0), k: (3.0, 2.0, 1.0), roughness: Some((distribution: Ggx, alpha: 0.0)))"#,
            &["materials[\"w\"].roughness.alpha", "0 is outside (0, 4]"][..],
        ),
        (
            r#"Plastic(diffuse_reflectance: (0.5, 1.5, 0.5))"#,
            &["materials[\"w\"].diffuse_reflectance", "outside [0, 1]"][..],
        ),
        (
            r#"Plastic(diffuse_reflectance: (0.5, 0.5, 0.5), ior: 1.0, roughness: Some((distribution: Beckmann, alpha: 0.1)))"#,
            &[
                "materials[\"w\"].ior",
                "a rough interface needs an index other than 1",
            ][..],
        ),
        (
            r#"RoughDielectric(ior: 11.0, roughness: (distribution: Ggx, alpha: 0.1))"#,
            &["materials[\"w\"].ior", "outside (0, 10]"][..],
        ),
        (
            r#"ThinDielectric(ior: -1.5)"#,
            &["materials[\"w\"].ior", "must be positive"][..],
        ),
        (
            r#"Blend(weight: 1.5, first: ThinDielectric(ior: 1.5), second: Lambertian(reflectance: (0.5, 0.5, 0.5)))"#,
            &["materials[\"w\"].weight", "outside [0, 1]"][..],
        ),
        (
            r#"Blend(weight: 0.5, first: ThinDielectric(ior: 1.5), second: Lambertian(reflectance: (0.5, 2.0, 0.5)))"#,
            &["materials[\"w\"].second.reflectance", "outside [0, 1]"][..],
        ),
    ] {
        let m = format!(r#"materials: {{ "w": {material} }},"#);
        let msg = expect_error(&scene(&m, FLOOR, LIGHT), &[]);
        assert_has(&msg, parts);
    }
}
