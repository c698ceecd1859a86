//! The built-in scenes compile, round-trip, and carry the geometry and photometry they claim,
//! checked against closed-form values.

use crate::util::{repo_root, scene_compile, StageResult, TempDir};
use luxest_io::math::Vec3;
use luxest_render::compiled::{CompiledScene, Emitter};
use luxest_render::rt::RayTracer;
use std::f64::consts::PI;
use std::path::PathBuf;

fn compile(name: &str) -> CompiledScene {
    let path = repo_root().join("scenes").join(format!("{name}.ron"));
    let (scene, report) = scene_compile::compile_file(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(report.warnings.is_empty(), "{name}: {:?}", report.warnings);
    scene
}

/// Triangles `[first, first+count)`: (area, signed volume w.r.t. `centre`).
fn area_and_volume(s: &CompiledScene, first: u32, count: u32, centre: Vec3) -> (f64, f64) {
    let (mut area, mut vol) = (0.0, 0.0);
    for t in first..first + count {
        let [a, b, c] = s.triangle(t as usize).map(|p| p - centre);
        area += 0.5 * (b - a).cross(c - a).length();
        vol += a.dot(b.cross(c)) / 6.0;
    }
    (area, vol)
}

fn object<'a>(s: &'a CompiledScene, name: &str) -> &'a luxest_render::compiled::ObjectRange {
    s.header.objects.iter().find(|o| o.name == name).unwrap()
}

#[test]
fn every_scene_in_scenes_compiles_and_round_trips() {
    let mut n = 0;
    for entry in std::fs::read_dir(repo_root().join("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "ron") {
            let (mut scene, _) =
                scene_compile::compile_file(&path).unwrap_or_else(|e| panic!("{e}"));
            let bytes = scene.encode();
            let back = CompiledScene::decode(&path, &bytes).unwrap();
            assert_eq!(back, scene, "{}", path.display());
            n += 1;
        }
    }
    assert!(n >= 6, "expected the six built-in scenes, found {n}");
}

#[test]
fn compiled_file_is_written_atomically_and_reproducibly() {
    let dir = TempDir::new("cornell");
    let out = dir.path().join("a/scene.lxs");
    let scene = repo_root().join("scenes/cornell-box.ron");
    scene_compile(&[scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]).unwrap();
    let first = std::fs::read(&out).unwrap();
    scene_compile(&[scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]).unwrap();
    assert_eq!(
        std::fs::read(&out).unwrap(),
        first,
        "compilation must be deterministic"
    );
    assert_eq!(
        dir.files(),
        vec![out.clone()],
        "no temporary files may remain"
    );
    scene_compile(&["--info", out.to_str().unwrap()]).unwrap();
    // Options that --check or --info would ignore are usage errors; nothing is written.
    let other = dir.path().join("b/scene.lxs");
    let mitsuba = dir.path().join("m");
    for args in [
        vec![
            scene.to_str().unwrap(),
            "--check",
            "-o",
            other.to_str().unwrap(),
        ],
        vec![
            "--info",
            out.to_str().unwrap(),
            "--export-mitsuba",
            mitsuba.to_str().unwrap(),
        ],
    ] {
        let (code, msg) = scene_compile(&args).expect_err(&format!("{args:?}"));
        assert_eq!(code, 2, "{args:?}: {msg}");
        assert!(msg.contains("cannot be used with"), "{msg}");
        assert_eq!(dir.files(), vec![out.clone()], "{args:?} wrote something");
    }
}

#[test]
fn cornell_box_light_and_features() {
    let s = compile("cornell-box");
    let Emitter::Area {
        area_m2,
        radiance_rgb,
        flux_rgb,
        ..
    } = &s.header.emitters[0]
    else {
        panic!()
    };
    // Stored as f32: relative accuracy ~1e-7.
    assert!((area_m2 / (0.130 * 0.105) - 1.0).abs() < 1e-6);
    assert_eq!(radiance_rgb.0, [17.0, 12.0, 4.0]);
    assert!((flux_rgb.0[0] - PI * 17.0 * area_m2).abs() < 1e-12);
    let f = &s.header.features;
    assert!(
        f.area_emitters
            && !f.point_emitters
            && !f.specular_paths
            && !f.glossy
            && f.camera
            && f.sensors
    );
    assert_eq!(
        s.header
            .sensors
            .iter()
            .map(|x| x.points.len())
            .sum::<usize>(),
        105
    );
    // A camera ray over the blocks reaches the back wall (z = 0.5592) at the right distance.
    let rt = RayTracer::for_scene(&s, true).unwrap();
    let cam = s.header.camera.as_ref().unwrap();
    let target = Vec3::new(0.278, 0.45, 0.5592);
    let d = target - cam.position;
    let hit = rt
        .intersect(cam.position, d.try_normalize().unwrap(), 0.0, f64::INFINITY)
        .unwrap();
    assert!(
        (hit.t - d.length()).abs() < 1e-5,
        "{} vs {}",
        hit.t,
        d.length()
    );
    assert_eq!(object_of(&s, hit.triangle), "back-wall");
}

fn object_of(s: &CompiledScene, t: u32) -> &str {
    let o = s
        .header
        .objects
        .iter()
        .find(|o| (o.first_triangle..o.first_triangle + o.triangle_count).contains(&t));
    &o.unwrap().name
}

#[test]
fn sobolev_planes_face_the_source() {
    let s = compile("sobolev");
    let Emitter::Point {
        intensity_rgb,
        flux_rgb,
        position,
        ..
    } = &s.header.emitters[0]
    else {
        panic!()
    };
    assert_eq!(*position, Vec3::ZERO);
    assert!((intensity_rgb.luminance() - 100.0).abs() < 1e-9);
    assert!((flux_rgb.luminance() - 400.0 * PI).abs() < 1e-9);
    for t in 0..s.triangle_count() {
        let [a, b, c] = s.triangle(t);
        let n = (b - a).cross(c - a);
        // The normal points from the plane towards the source at the origin.
        assert!(n.dot(-a) > 0.0, "triangle {t} faces away from the source");
    }
    assert_eq!(s.header.sensors.len(), 2);
}

#[test]
fn integrating_sphere_tessellation_matches_its_stated_bounds() {
    let s = compile("integrating-sphere");
    assert_eq!(s.triangle_count(), 20 * 4usize.pow(6));
    let (area, vol) = area_and_volume(&s, 0, s.triangle_count() as u32, Vec3::ZERO);
    // Inward-facing: the signed volume is negative.
    assert!(vol < 0.0);
    let deficit = 1.0 - area / (4.0 * PI);
    eprintln!("integrating sphere: area deficit {deficit:e}");
    assert!(deficit > 0.0 && deficit < 8e-5, "area deficit {deficit:e}");
    // Every sensor is strictly inside every facet's plane.
    let min_plane_distance = (0..s.triangle_count())
        .map(|t| {
            let [a, b, c] = s.triangle(t);
            let n = (b - a).cross(c - a).try_normalize().unwrap();
            (a.dot(n)).abs()
        })
        .fold(f64::INFINITY, f64::min);
    eprintln!(
        "integrating sphere: max sagitta {:e}",
        1.0 - min_plane_distance
    );
    assert!(
        1.0 - min_plane_distance < 8e-5,
        "sagitta {:e}",
        1.0 - min_plane_distance
    );
    for p in &s.header.sensors[0].points {
        assert!(p.position.length() < min_plane_distance);
        assert!(p.normal.dot(-p.position) > 0.999 * p.position.length());
    }
}

#[test]
fn cie_room_is_closed_and_faces_inward() {
    let s = compile("cie171-5.8");
    let (area, vol) = area_and_volume(&s, 0, s.triangle_count() as u32, Vec3::splat(2.0));
    assert!((area - 96.0).abs() < 1e-9);
    assert!(
        (vol + 64.0).abs() < 1e-9,
        "inward box has volume -64, got {vol}"
    );
    let Emitter::Point { intensity_rgb, .. } = &s.header.emitters[0] else {
        panic!()
    };
    assert!((intensity_rgb.luminance() - 10000.0 / (4.0 * PI)).abs() < 1e-9);
    assert_eq!(s.header.sensors[0].points.len(), 256);
    assert_eq!(
        s.header.sensors[0].points[0].position,
        Vec3::new(0.125, 0.0, 0.125)
    );
}

#[test]
fn obj_torus_matches_the_analytic_torus() {
    let s = compile("obj-torus");
    let o = object(&s, "torus");
    assert_eq!(o.triangle_count, 48 * 24 * 2);
    let centre = Vec3::new(0.0, 0.3, 0.0);
    let (area, vol) = area_and_volume(&s, o.first_triangle, o.triangle_count, centre);
    let (big_r, r) = (0.3, 0.1);
    // Inscribed tessellation: slightly below the analytic area 4 pi^2 R r and volume 2 pi^2 R r^2.
    let (a_exact, v_exact) = (4.0 * PI * PI * big_r * r, 2.0 * PI * PI * big_r * r * r);
    assert!(
        area < a_exact && (a_exact - area) / a_exact < 0.01,
        "{area} vs {a_exact}"
    );
    assert!(
        vol > 0.0 && (v_exact - vol) / v_exact < 0.02,
        "{vol} vs {v_exact}"
    );
    assert!(s.header.features.smooth_normals && s.header.features.glossy);
    // Flux-specified emitter: pi L A equals the requested flux.
    assert!((s.header.emitters[0].flux_lm() - 2000.0).abs() < 1e-6);
}

#[test]
fn gltf_trefoil_keeps_node_transforms_and_orientation() {
    let s = compile("gltf-trefoil");
    let o = object(&s, "knot");
    assert_eq!(o.triangle_count, 256 * 12 * 2);
    let (_, vol) = area_and_volume(
        &s,
        o.first_triangle,
        o.triangle_count,
        Vec3::new(0.0, 0.2, 0.0),
    );
    assert!(vol > 0.0, "tube must face outward");
    // The node scale 0.1 applies: the knot (|x| <= 3 + tube) spans at most 0.7 m.
    let mut lo = Vec3::splat(f64::INFINITY);
    let mut hi = Vec3::splat(f64::NEG_INFINITY);
    for t in o.first_triangle..o.first_triangle + o.triangle_count {
        for p in s.triangle(t as usize) {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    assert!((hi.x - lo.x) < 0.7 && (hi.x - lo.x) > 0.5, "{lo:?} {hi:?}");
    // Emitter choice is proportional to luminous flux.
    let fluxes: Vec<f64> = s.header.emitters.iter().map(|e| e.flux_lm()).collect();
    let p0 = fluxes[0] / fluxes.iter().sum::<f64>();
    assert!((s.header.emitter_cdf[0] - p0).abs() < 1e-12);
    let f = &s.header.features;
    assert!(f.transmission && f.specular_paths && f.point_emitters && f.area_emitters);
}

#[test]
fn mirroring_and_flipping_keep_the_intended_front_side() {
    let dir = TempDir::new("mirror");
    let text = r#"Scene(
        materials: { "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) },
        objects: [
            (name: "plain", shape: Box(size: (1.0, 2.0, 3.0)), material: "w"),
            (name: "mirrored", shape: Box(size: (1.0, 2.0, 3.0)), transform: (scale: (-1.0, 1.0, 1.0)), material: "w"),
            (name: "flipped", shape: Box(size: (1.0, 2.0, 3.0)), material: "w", flip_normals: true),
            (name: "ball", shape: Sphere(radius: 1.0, subdivisions: 2), transform: (scale: (1.0, -2.0, 1.0)), material: "w"),
        ],
        point_lights: [(position: (5.0, 5.0, 5.0), power: Flux(100.0))],
    )"#;
    let path = dir.write("s.ron", text);
    let (s, _) = scene_compile::compile_file(&path).unwrap();
    let vol = |name: &str| {
        let o = object(&s, name);
        area_and_volume(&s, o.first_triangle, o.triangle_count, Vec3::ZERO).1
    };
    assert!((vol("plain") - 6.0).abs() < 1e-9);
    assert!((vol("mirrored") - 6.0).abs() < 1e-9);
    assert!((vol("flipped") + 6.0).abs() < 1e-9);
    assert!(vol("ball") > 0.0);
    // Shading normals of the mirrored sphere still point out of the surface.
    let o = object(&s, "ball");
    for t in o.first_triangle..o.first_triangle + o.triangle_count {
        let [a, b, c] = s.triangle(t as usize);
        let ng = (b - a).cross(c - a);
        for i in s.indices[t as usize] {
            assert!(Vec3::from(s.normals[i as usize]).dot(ng) > 0.0);
        }
    }
}

#[test]
fn generated_training_scenes_compile_and_are_reproducible() {
    // data-gen/generate.py (quick preset): every scene compiles, has a camera and an emitter,
    // and regenerating gives byte-identical files.
    let dir = TempDir::new("datagen");
    let gen = |out: &std::path::Path| {
        let status = std::process::Command::new("python3")
            .arg(repo_root().join("data-gen/generate.py"))
            .args(["--preset", "quick", "--side", "64", "--out"])
            .arg(out)
            .stderr(std::process::Stdio::null())
            .status()
            .expect("python3 runs");
        assert!(status.success());
    };
    gen(&dir.path().join("a"));
    gen(&dir.path().join("b"));
    let mut n = 0;
    for split in ["train", "valid", "test"] {
        for entry in std::fs::read_dir(dir.path().join("a").join(split)).unwrap() {
            let path = entry.unwrap().path();
            let twin = dir
                .path()
                .join("b")
                .join(split)
                .join(path.file_name().unwrap());
            assert_eq!(std::fs::read(&path).unwrap(), std::fs::read(&twin).unwrap());
            let (scene, _) = scene_compile::compile_file(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(scene.header.camera.is_some() && !scene.header.emitters.is_empty());
            n += 1;
        }
    }
    assert_eq!(n, 24);
}

/// `scene-compile scenes/<name>.ron -o <tmp>/s.lxs --export-mitsuba <tmp>/mi`: the directory, the
/// compiled scene and export paths, and the stage's result.
fn export_mitsuba(name: &str) -> (TempDir, PathBuf, PathBuf, StageResult) {
    let dir = TempDir::new("mitsuba");
    let (out, lxs) = (dir.path().join("mi"), dir.path().join("s.lxs"));
    let src = repo_root().join("scenes").join(format!("{name}.ron"));
    let r = scene_compile(&[
        src.to_str().unwrap(),
        "-o",
        lxs.to_str().unwrap(),
        "--export-mitsuba",
        out.to_str().unwrap(),
        "-q",
    ]);
    (dir, out, lxs, r)
}

#[test]
fn mitsuba_export_carries_every_triangle_material_emitter_and_the_camera() {
    // Export the Cornell box and the trefoil scene (glass, mirror, point light); read the OBJ
    // files back: every compiled triangle appears once, with its positions and winding; the
    // XML holds each group's BSDF, the area light's luminance, the point light's intensity and
    // the camera. A scene with a goniometric luminaire is refused with nothing written.
    for name in ["cornell-box", "gltf-trefoil"] {
        let (_dir, out, lxs, r) = export_mitsuba(name);
        r.unwrap();
        let s = CompiledScene::load(&lxs).unwrap();
        let xml = std::fs::read_to_string(out.join("scene.xml")).unwrap();
        let mut triangles = Vec::new();
        for line in xml.lines().filter(|l| l.contains(r#"<shape type="obj">"#)) {
            let file = line.split(r#"name="filename" value=""#).nth(1).unwrap();
            let file = &file[..file.find('"').unwrap()];
            let obj = std::fs::read_to_string(out.join(file)).unwrap();
            let v: Vec<[f32; 3]> = obj
                .lines()
                .filter_map(|l| l.strip_prefix("v "))
                .map(|l| {
                    let c: Vec<f32> = l.split(' ').map(|x| x.parse().unwrap()).collect();
                    [c[0], c[1], c[2]]
                })
                .collect();
            for f in obj.lines().filter_map(|l| l.strip_prefix("f ")) {
                // A corner is `v`, `v/vt`, `v//vn` or `v/vt/vn`: the position index first.
                let i: Vec<usize> = f
                    .split(' ')
                    .map(|x| x.split('/').next().unwrap().parse().unwrap())
                    .collect();
                triangles.push([v[i[0] - 1], v[i[1] - 1], v[i[2] - 1]]);
            }
        }
        let mut expected: Vec<[[f32; 3]; 3]> = s
            .indices
            .iter()
            .map(|t| t.map(|k| s.positions[k as usize]))
            .collect();
        let key = |t: &[[f32; 3]; 3]| format!("{t:?}");
        expected.sort_by_key(key);
        triangles.sort_by_key(key);
        assert_eq!(triangles, expected, "{name}: triangles (winding included)");
        let cam = s.header.camera.as_ref().unwrap();
        assert!(xml.contains(&format!(
            r#"<float name="fov" value="{:e}"/>"#,
            cam.vfov_deg
        )));
        for e in &s.header.emitters {
            match e {
                Emitter::Area { radiance_rgb, .. } => {
                    let r = radiance_rgb.0;
                    let want = format!(
                        r#"<emitter type="area"><rgb name="radiance" value="{:e}, {:e}, {:e}"/>"#,
                        r[0], r[1], r[2]
                    );
                    assert!(xml.contains(&want), "{name}: {want}");
                }
                Emitter::Point { intensity_rgb, .. } => {
                    let r = intensity_rgb.0;
                    let want = format!(
                        r#"<rgb name="intensity" value="{:e}, {:e}, {:e}"/>"#,
                        r[0], r[1], r[2]
                    );
                    assert!(xml.contains(&want), "{name}: {want}");
                }
                Emitter::Luminaire { .. } => unreachable!(),
                Emitter::Environment { map, .. } => {
                    let kind = if map.is_some() { "envmap" } else { "constant" };
                    let want = format!(r#"<emitter type="{kind}">"#);
                    assert!(xml.contains(&want), "{name}: {want}");
                }
            }
        }
        if name == "gltf-trefoil" {
            assert!(xml.contains(r#"<bsdf type="dielectric">"#));
            assert!(
                xml.contains(r#"<bsdf type="conductor"><string name="material" value="none"/>"#)
            );
        }
    }
    let (_dir, out, lxs, r) = export_mitsuba("office");
    let e = r.unwrap_err();
    assert_eq!(e.0, 1);
    assert!(
        e.1.contains("goniometric") && !e.1.contains('\n'),
        "{}",
        e.1
    );
    assert!(!lxs.exists() && !out.exists());
}
