//! The importers (Mitsuba 3 XML, glTF 2.0, OBJ+MTL): translations checked field by field
//! against the source file's numbers, compiled end to end, and every class of bad input
//! refused by the real binary with exit code 1 and one line naming the file and the place.
//!
//! `crates/scene-compile/tests/data/mitsuba/scene.xml` is loaded by Mitsuba 3 itself in
//! `crates/scene-compile/tests/data/mitsuba/check_with_mitsuba.py`, so its translation is
//! checked against a scene Mitsuba accepts.

use luxest_io::color::Rgb;
use luxest_io::math::{Affine, Vec3};
use luxest_render::scene::{
    Emission, Environment, Material, Microfacet, MicrofacetDistribution, Opacity, OpacityChannel,
    PointPower, Shape, Surface,
};
use luxest_render::texture::{Encoding, Filter, UvTransform, Wrap};
use scene_compile::import::{export_ron, mitsuba_xml, read_scene};
use std::path::{Path, PathBuf};
use std::process::Command;

fn data() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba")
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("luxest-import-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

fn affine(m: &Option<[[f64; 4]; 3]>) -> Affine {
    match m {
        Some([a, b, c]) => Affine::from_rows4([*a, *b, *c, [0.0, 0.0, 0.0, 1.0]]),
        None => Affine::IDENTITY,
    }
}

fn same_affine(a: &Affine, b: &Affine) -> bool {
    a.m.iter()
        .flatten()
        .zip(b.m.iter().flatten())
        .all(|(x, y)| close(*x, *y))
        && (a.t - b.t).length() < 1e-12
}

#[test]
fn mitsuba_scene_translates_field_by_field() {
    let path = data().join("scene.xml");
    let imp = read_scene(&path).unwrap();
    let s = &imp.scene;
    // <integrator> and the sensor's <sampler> are left out, each with a warning.
    assert_eq!(imp.warnings.len(), 2, "{:?}", imp.warnings);
    assert!(imp.warnings[0].contains("line 6: <integrator type=\"path\">: ignored"));
    assert!(imp.warnings[1].contains("<sampler type=\"independent\">: ignored"));

    // Camera: lookat from (0, 1, 5) to (0, 1, 0); fov 60 along x on a 64 x 32 film:
    // tan(vfov/2) = tan(30°) / 2.
    let cam = s.camera.as_ref().unwrap();
    assert_eq!(cam.resolution, (64, 32));
    assert!((cam.position - Vec3::new(0.0, 1.0, 5.0)).length() < 1e-15);
    assert!((cam.look_at - Vec3::new(0.0, 1.0, 4.0)).length() < 1e-15);
    assert!((cam.up - Vec3::new(0.0, 1.0, 0.0)).length() < 1e-15);
    let vfov = 2.0 * (30f64.to_radians().tan() / 2.0).atan().to_degrees();
    assert!(close(cam.vfov_deg, vfov), "{}", cam.vfov_deg);

    // Materials: $white substituted by its <default>, the included file's BSDFs, Mitsuba's
    // own bk7 index (its table) over an ext_ior of 1, the GGX α = 0.09 as roughness √α.
    let m = &s.materials;
    assert_eq!(m.len(), 14, "{:?}", m.keys());
    assert_eq!(
        m["white"],
        Material::Lambertian {
            reflectance: Rgb::splat(0.7)
        }
    );
    assert_eq!(
        m["glass"],
        Material::Dielectric {
            ior: 1.5046000480651855
        }
    );
    assert_eq!(
        m["mirror"],
        Material::Mirror {
            reflectance: Rgb([0.9, 0.8, 0.7])
        }
    );
    assert_eq!(
        m["rough"],
        Material::Conductor {
            eta: Rgb::splat(0.0),
            k: Rgb::WHITE,
            specular_reflectance: Rgb::WHITE,
            roughness: Some(Microfacet {
                distribution: MicrofacetDistribution::Ggx,
                alpha: 0.09
            })
        }
    );
    // The quad's inline BSDF, named after its element's place; a constant spectrum.
    assert_eq!(
        m["twosided@scene:117"],
        Material::Lambertian {
            reflectance: Rgb::splat(0.25)
        }
    );

    // Mitsuba's gold preset, as Mitsuba 3 evaluates it in RGB (its committed table).
    let au = scene_compile::import::mitsuba_tables::CONDUCTORS
        .iter()
        .find(|c| c.0 == "Au")
        .unwrap();
    assert_eq!(
        m["gold"],
        Material::Conductor {
            eta: Rgb(au.1),
            k: Rgb(au.2),
            specular_reflectance: Rgb::WHITE,
            roughness: Some(Microfacet {
                distribution: MicrofacetDistribution::Beckmann,
                alpha: 0.2
            })
        }
    );
    // plastic: polypropylene (1.49) in air (1.000277) by default, as Mitsuba's table has them.
    let air = 1.000277042388916;
    assert_eq!(
        m["varnish"],
        Material::Plastic {
            diffuse_reflectance: Rgb([0.3, 0.2, 0.1]),
            specular_reflectance: Rgb::WHITE,
            ior: 1.4900000095367432 / air,
            nonlinear: true,
            roughness: None
        }
    );
    assert_eq!(
        m["satin"],
        Material::Plastic {
            diffuse_reflectance: Rgb::splat(0.5),
            specular_reflectance: Rgb::WHITE,
            ior: 1.6 / air,
            nonlinear: false,
            roughness: Some(Microfacet {
                distribution: MicrofacetDistribution::Ggx,
                alpha: 0.3
            })
        }
    );
    assert_eq!(
        m["pane"],
        Material::ThinDielectric {
            ior: 1.5046000480651855 / air
        }
    );
    assert_eq!(
        m["frosted"],
        Material::RoughDielectric {
            ior: 1.3329999446868896 / air,
            roughness: Microfacet {
                distribution: MicrofacetDistribution::Beckmann,
                alpha: 0.05
            }
        }
    );
    assert_eq!(
        m["mix"],
        Material::Blend {
            weight: 0.25,
            first: Box::new(Material::Lambertian {
                reflectance: Rgb::splat(0.5)
            }),
            second: Box::new(Material::Conductor {
                eta: Rgb([0.2, 0.9, 1.1]),
                k: Rgb([3.9, 2.4, 2.2]),
                specular_reflectance: Rgb::WHITE,
                roughness: None
            })
        }
    );
    // spot: on-axis intensity, the cone along to_world's z, beam width 3/4 of the cutoff.
    let spot = s.point_lights.iter().find(|l| l.spot.is_some()).unwrap();
    assert_eq!(spot.position, Vec3::new(0.0, 2.5, 0.0));
    assert_eq!(spot.power, PointPower::Intensity(4.0));
    let cone = spot.spot.as_ref().unwrap();
    assert!((cone.direction - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-12);
    assert_eq!((cone.cutoff_deg, cone.beam_width_deg), (30.0, 22.5));
    // envmap: the file relative to the scene, the scale, the rotation (90° about y).
    match s.environment.as_ref().unwrap() {
        Environment::Map {
            path,
            scale,
            to_world,
        } => {
            assert_eq!((path.as_str(), *scale), ("sky.exr", 0.5));
            let want = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]];
            for (r, w) in to_world.iter().flatten().zip(want.iter().flatten()) {
                assert!((r - w).abs() < 1e-15, "{to_world:?}");
            }
        }
        other => panic!("{other:?}"),
    }

    let o = |name: &str| {
        s.objects
            .iter()
            .find(|o| o.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no object {name}"))
    };
    assert_eq!(s.objects.len(), 10);
    // serialized: mesh 1 of the file (version 4), relative to the scene.
    assert_eq!(
        o("tile").shape,
        Shape::Serialized {
            path: "meshes/two.serialized".into(),
            shape_index: 1
        }
    );

    // Textures: the bitmap's file, wrap, filter and to_uv (scale, then translate: u' = 2u + ½,
    // v' = 3v); raw bitmaps are linear, the others keep the file's encoding.
    let wood = &s.textures["wood"];
    assert_eq!(wood.path, "textures/wood.png");
    assert_eq!(
        (wood.encoding, wood.wrap, wood.filter),
        (None, Wrap::Mirror, Filter::Nearest)
    );
    assert_eq!(
        wood.uv_transform,
        Some(UvTransform([[2.0, 0.0, 0.5], [0.0, 3.0, 0.0]]))
    );
    let opacity_tex = "textures/alpha.png@scene:136";
    let alpha_tex = "textures/alpha.png@scene:144";
    assert_eq!(s.textures.len(), 3, "{:?}", s.textures.keys());
    assert_eq!(s.textures[opacity_tex].encoding, Some(Encoding::Linear));
    // A bare BSDF is one-sided; its bitmap colour multiplies a reflectance of 1.
    assert_eq!(
        m["diffuse@scene:130"],
        Material::Lambertian {
            reflectance: Rgb::WHITE
        }
    );
    assert_eq!(
        s.surfaces["diffuse@scene:130"],
        Surface {
            color: Some("wood".into()),
            roughness: None,
            opacity: None,
            normal: None,
            normal_scale: [1.0, 1.0],
            two_sided: false
        }
    );
    // mask: a stochastic cut-out with the bitmap's opacity; the bitmap α multiplies α = 1.
    let cu = scene_compile::import::mitsuba_tables::CONDUCTORS
        .iter()
        .find(|c| c.0 == "Cu")
        .unwrap();
    assert_eq!(
        m["mask@scene:135"],
        Material::Conductor {
            eta: Rgb(cu.1),
            k: Rgb(cu.2),
            specular_reflectance: Rgb::WHITE,
            roughness: Some(Microfacet {
                distribution: MicrofacetDistribution::Ggx,
                alpha: 1.0
            })
        }
    );
    assert_eq!(
        s.surfaces["mask@scene:135"],
        Surface {
            color: None,
            roughness: Some(alpha_tex.into()),
            opacity: Some(Opacity {
                texture: Some(opacity_tex.into()),
                channel: OpacityChannel::Luminance,
                value: 1.0,
                cutoff: None
            }),
            normal: None,
            normal_scale: [1.0, 1.0],
            two_sided: true
        }
    );
    // A shape without a BSDF gets Mitsuba's default: one-sided diffuse 0.5.
    let screen = s
        .objects
        .iter()
        .find(|o| o.name.as_deref() == Some("screen"))
        .unwrap();
    assert_eq!(screen.material, "diffuse (Mitsuba's default)");
    assert!(!s.surfaces[&screen.material].two_sided);
    assert_eq!(
        m[&screen.material],
        Material::Lambertian {
            reflectance: Rgb::splat(0.5)
        }
    );
    assert_eq!(
        screen.emission,
        Some(Emission::Texture {
            texture: "wood".into(),
            scale: Rgb::WHITE
        })
    );
    // Two-sided untextured materials need no surface entry.
    assert_eq!(s.surfaces.len(), 3, "{:?}", s.surfaces.keys());
    // rectangle: rotate 90° about x, scale 0.5, translate, composed in that order.
    let light = o("light");
    assert_eq!(
        light.shape,
        Shape::Quad {
            corner: Vec3::new(-1.0, -1.0, 0.0),
            u: Vec3::new(2.0, 0.0, 0.0),
            v: Vec3::new(0.0, 2.0, 0.0)
        }
    );
    let want = Affine {
        m: [[0.5, 0.0, 0.0], [0.0, 0.0, -0.5], [0.0, 0.5, 0.0]],
        t: Vec3::new(0.0, 2.9, 0.0),
    };
    assert!(same_affine(&affine(&light.transform.matrix), &want));
    assert_eq!(
        light.emission,
        Some(Emission::Radiance(Rgb([5.0, 4.0, 3.0])))
    );
    assert_eq!(light.material, "white");
    // cube: the box [-1, 1]³, scaled then translated, flipped.
    let room = o("room");
    assert_eq!(
        room.shape,
        Shape::Box {
            size: Vec3::splat(2.0)
        }
    );
    assert!(room.flip_normals && !room.face_normals);
    assert!(same_affine(
        &affine(&room.transform.matrix),
        &Affine {
            m: [[3.0, 0.0, 0.0], [0.0, 1.5, 0.0], [0.0, 0.0, 3.0]],
            t: Vec3::new(0.0, 1.5, 0.0)
        }
    ));
    // sphere: radius and centre.
    let ball = o("ball");
    assert_eq!(
        ball.shape,
        Shape::Sphere {
            radius: 0.5,
            subdivisions: mitsuba_xml::SPHERE_SUBDIVISIONS
        }
    );
    assert!(same_affine(
        &affine(&ball.transform.matrix),
        &Affine::translate(Vec3::new(1.0, 0.5, 0.0))
    ));
    assert_eq!(ball.material, "glass");
    // disk: a polygon with the unit disk's area π (shoelace formula), under a 4 x 4 matrix.
    let plate = o("plate");
    let Shape::Polygon { vertices } = &plate.shape else {
        panic!("{:?}", plate.shape)
    };
    assert_eq!(vertices.len(), mitsuba_xml::DISK_SEGMENTS);
    let area: f64 = (0..vertices.len())
        .map(|i| {
            let (a, b) = (vertices[i], vertices[(i + 1) % vertices.len()]);
            0.5 * (a.x * b.y - b.x * a.y)
        })
        .sum();
    assert!((area - std::f64::consts::PI).abs() < 1e-12, "{area}");
    assert!(same_affine(
        &affine(&plate.transform.matrix),
        &Affine {
            m: [[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.5]],
            t: Vec3::new(-1.0, 0.01, 1.0)
        }
    ));
    assert_eq!(plate.material, "mirror");
    // obj and ply: paths relative to the scene file.
    let tri = o("tri");
    assert_eq!(
        tri.shape,
        Shape::Obj {
            path: "meshes/triangle.obj".into(),
            usemtl: None
        }
    );
    assert!(tri.face_normals);
    assert_eq!(tri.material, "rough");
    assert_eq!(
        o("quad").shape,
        Shape::Ply {
            path: "meshes/quad.ply".into()
        }
    );
    // point: the intensity's luminance in candela, tinted by the RGB.
    assert_eq!(s.point_lights.len(), 2);
    let p = s.point_lights.iter().find(|l| l.spot.is_none()).unwrap();
    assert_eq!(p.position, Vec3::new(0.0, 3.0, 0.0));
    assert_eq!(
        p.power,
        PointPower::Intensity(Rgb([10.0, 20.0, 30.0]).luminance())
    );
    assert_eq!(p.color, Rgb([10.0, 20.0, 30.0]));
}

#[test]
fn mitsuba_scene_compiles_and_its_exported_ron_compiles_to_the_same_scene() {
    let path = data().join("scene.xml");
    let (compiled, _) = scene_compile::compile_file(&path).unwrap();
    let stats = &compiled.header.stats;
    // 4 rectangles of 2 + 12 (cube) + 20·4^6 (sphere) + 254 (disk fan) + 1 (OBJ) + 2 (PLY)
    // + 2 (serialized mesh 1).
    assert_eq!(
        stats.triangles,
        8 + 12 + 20 * 4u64.pow(mitsuba_xml::SPHERE_SUBDIVISIONS) + 254 + 1 + 2 + 2
    );
    // Two area emitters, point, spot and environment.
    assert_eq!(compiled.header.emitters.len(), 5);
    // The area light's radiance is Mitsuba's number, as cd/m².
    let area = compiled
        .header
        .emitters
        .iter()
        .find_map(|e| match e {
            luxest_render::compiled::Emitter::Area {
                radiance_rgb,
                area_m2,
                ..
            } => Some((*radiance_rgb, *area_m2)),
            _ => None,
        })
        .unwrap();
    assert_eq!(area.0, Rgb([5.0, 4.0, 3.0]));
    // The rectangle [-1, 1]² scaled by 0.5: 1 m².
    assert!((area.1 - 1.0).abs() < 1e-6, "{}", area.1);

    // --export-ron writes a RON scene in another directory that compiles to the same scene.
    let d = tmp("export");
    let out = d.join("sub/scene.ron");
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    let imp = read_scene(&path).unwrap();
    std::fs::write(&out, export_ron(&imp.scene, &path, &out)).unwrap();
    let (again, _) = scene_compile::compile_file(&out).unwrap();
    assert_eq!(again.content_hash, compiled.content_hash);
    std::fs::remove_dir_all(&d).unwrap();
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_scene-compile"))
}

/// Runs the binary on `scene` and returns its one error line (exit code 1, no output).
fn refused(scene: &Path) -> String {
    let out = scene.with_extension("lxs");
    let o = bin().arg(scene).arg("-o").arg(&out).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists());
    err
}

/// A minimal valid scene around `body` (a lit, two-sided rectangle).
fn xml(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <shape type="rectangle"><bsdf type="twosided"><bsdf type="diffuse"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
{body}
</scene>
"#
    )
}

#[test]
fn bad_mitsuba_input_is_one_line_naming_file_line_and_element() {
    let d = tmp("bad");
    let wood = data().join("textures/wood.png").display().to_string();
    let cases: &[(&str, String, &str)] = &[
        (
            "plugin",
            xml(r#"<shape type="cylinder"><bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#),
            "plugin.xml: line 4: <shape type=\"cylinder\">: unsupported shape \"cylinder\"",
        ),
        (
            "nan",
            xml(r#"<shape type="cube"><transform name="to_world"><translate x="nan"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#),
            "nan.xml: line 4: <translate>: [NaN, 0.0, 0.0] is not finite",
        ),
        (
            "matrix",
            xml(r#"<shape type="cube"><transform name="to_world"><matrix value="1 0 0 0 0 1 0 0 0 0 NaN 0 0 0 0 1"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#),
            "matrix.xml: line 4: <matrix>: an element is NaN: not finite",
        ),
        (
            "missing",
            xml(r#"<shape type="ply"><string name="filename" value="nowhere.ply"/>
    <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#),
            "missing.xml: line 4: <shape type=\"ply\">: file \"nowhere.ply\" not found",
        ),
        (
            "anisotropic",
            xml(r#"<bsdf type="twosided" id="a"><bsdf type="roughconductor"><string name="distribution" value="ggx"/>
    <float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.2"/></bsdf></bsdf>"#),
            "anisotropic.xml: line 4: <bsdf type=\"roughconductor\">: anisotropic roughness",
        ),
        (
            "spectral",
            xml(r#"<bsdf type="twosided" id="s"><bsdf type="diffuse"><spectrum name="reflectance" filename="paint.spd"/></bsdf></bsdf>"#),
            "spectral.xml: line 4: <spectrum name=\"reflectance\">: spectral data files are not supported",
        ),
        (
            "wavelengths",
            xml(r#"<bsdf type="twosided" id="s"><bsdf type="diffuse"><spectrum name="reflectance" value="400:0.1, 700:0.9"/></bsdf></bsdf>"#),
            "wavelengths.xml: line 4: <spectrum name=\"reflectance\">: spectrum \"400:0.1, 700:0.9\": only a constant value",
        ),
        (
            "parameter",
            xml(r#"<bsdf type="twosided" id="p"><bsdf type="diffuse"><float name="shininess" value="3"/></bsdf></bsdf>"#),
            "parameter.xml: line 4: <float name=\"shininess\">: parameter \"shininess\" of <bsdf type=\"diffuse\"> is not supported",
        ),
        (
            "undefined",
            xml(r#"<bsdf type="twosided" id="u"><bsdf type="diffuse"><rgb name="reflectance" value="$albedo"/></bsdf></bsdf>"#),
            "undefined.xml: line 4: undefined parameter $albedo",
        ),
        (
            "ref",
            xml(r#"<shape type="cube"><ref id="nothing"/></shape>"#),
            "ref.xml: line 4: <ref id=\"nothing\">: no object has the id \"nothing\"",
        ),
        (
            "medium",
            xml(r#"<medium type="homogeneous" id="fog"/>"#),
            "medium.xml: line 4: <medium type=\"homogeneous\" id=\"fog\">: <medium> is not supported",
        ),
        (
            "mirrored",
            xml(r#"<sensor type="perspective"><transform name="to_world"><scale x="-1"/></transform></sensor>"#),
            "mirrored.xml: line 4: <sensor type=\"perspective\">: the camera's to_world mirrors the image",
        ),
        (
            "cycle",
            xml(r#"<bsdf type="twosided" id="loop"><ref id="loop"/></bsdf>"#),
            "cycle.xml: line 4: <bsdf type=\"twosided\" id=\"loop\">: BSDFs nest deeper than 64",
        ),
        (
            "deep",
            xml(&format!("{}{}", "<bsdf type=\"twosided\">".repeat(100), "</bsdf>".repeat(100))),
            "deep.xml: line 4: <bsdf>: elements nest deeper than 64",
        ),
        (
            "twosided-normalmap",
            xml(&format!(r#"<bsdf type="twosided" id="t"><bsdf type="normalmap"><texture name="normalmap" type="bitmap"><string name="filename" value="{wood}"/></texture><bsdf type="diffuse"/></bsdf></bsdf>"#)),
            "twosided-normalmap.xml: line 4: <bsdf type=\"twosided\" id=\"t\">: twosided around a normalmap is not supported",
        ),
        (
            "normalmap-flag",
            xml(&format!(r#"<bsdf type="normalmap" id="f"><boolean name="use_shadowing_function" value="false"/><texture name="normalmap" type="bitmap"><string name="filename" value="{wood}"/></texture><bsdf type="diffuse"/></bsdf>"#)),
            "normalmap-flag.xml: line 4: <bsdf type=\"normalmap\" id=\"f\">: use_shadowing_function false is not supported",
        ),
        (
            "version",
            "<scene><shape type=\"cube\"/></scene>".to_string(),
            "version.xml: line 1: <scene>: the root element has no version attribute",
        ),
        (
            "malformed",
            "<scene version=\"3.0.0\">\n<shape type=\"cube\">\n</scene>\n".to_string(),
            "malformed.xml: line 3: malformed XML",
        ),
    ];
    for (name, text, want) in cases {
        let scene = d.join(format!("{name}.xml"));
        std::fs::write(&scene, text).unwrap();
        let err = refused(&scene);
        assert!(err.contains(want), "{name}: want {want:?}, got {err}");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn recursive_include_is_one_line_naming_the_include() {
    let d = tmp("include");
    std::fs::write(d.join("a.xml"), xml(r#"<include filename="b.xml"/>"#)).unwrap();
    std::fs::write(
        d.join("b.xml"),
        "<scene version=\"3.0.0\">\n    <include filename=\"a.xml\"/>\n</scene>\n",
    )
    .unwrap();
    let err = refused(&d.join("a.xml"));
    assert!(
        err.contains("b.xml: line 2: <include filename=\"") && err.contains("recursive include"),
        "{err}"
    );
    // An include of a file that does not exist names the including line.
    std::fs::write(d.join("c.xml"), xml(r#"<include filename="gone.xml"/>"#)).unwrap();
    let err = refused(&d.join("c.xml"));
    assert!(err.contains("c.xml: line 4: <include>: file"), "{err}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn obj_mtl_scene_translates_its_materials() {
    let d = tmp("obj");
    std::fs::write(
        d.join("room.mtl"),
        "# two materials\nnewmtl floor\nKa 1 1 1\nKd 0.5 0.4 0.3\nillum 1\n\n\
         newmtl lamp\nKd 0 0 0\nKe 10 9 8\nillum 0\n\nnewmtl shiny\nKd 0.3 0.3 0.3\n\
         Ks 0.5 0.5 0.5\nNs 98\nillum 2\n\nnewmtl glass\nNi 1.5\nd 0.1\nillum 7\n",
    )
    .unwrap();
    std::fs::write(
        d.join("room.obj"),
        "mtllib room.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nv 1 1 0\nv 1 1 1\n\
         usemtl floor\nf 1 3 2\nf 1 4 3\nusemtl lamp\nf 5 6 7\nusemtl shiny\nf 1 2 6\n\
         usemtl glass\nf 1 5 4\n",
    )
    .unwrap();
    let imp = read_scene(&d.join("room.obj")).unwrap();
    assert_eq!(imp.warnings.len(), 1, "{:?}", imp.warnings);
    assert!(imp.warnings[0].contains("room.mtl: line 3: Ka ignored"));
    let s = &imp.scene;
    assert_eq!(
        s.materials["floor"],
        Material::Lambertian {
            reflectance: Rgb([0.5, 0.4, 0.3])
        }
    );
    // Ns 98: Beckmann α = √(2 / 100) = 0.1414; Glossy's roughness is √α.
    match &s.materials["shiny"] {
        Material::Glossy { roughness, .. } => assert!(close(*roughness, 0.02f64.sqrt().sqrt())),
        other => panic!("{other:?}"),
    }
    assert_eq!(s.materials["glass"], Material::Dielectric { ior: 1.5 });
    let lamp = s.objects.iter().find(|o| o.material == "lamp").unwrap();
    assert_eq!(
        lamp.emission,
        Some(Emission::Radiance(Rgb([10.0, 9.0, 8.0])))
    );
    assert_eq!(
        lamp.shape,
        Shape::Obj {
            path: "room.obj".into(),
            usemtl: Some("lamp".into())
        }
    );
    let (compiled, _) = scene_compile::compile_file(&d.join("room.obj")).unwrap();
    assert_eq!(compiled.header.stats.triangles, 5);
    let lamp_range = compiled
        .header
        .objects
        .iter()
        .find(|o| o.name == "lamp")
        .unwrap();
    assert_eq!(lamp_range.triangle_count, 1);
    // map_Kd and d: a colour texture (relative to the OBJ) and a stochastic cut-out.
    std::fs::create_dir_all(d.join("tex")).unwrap();
    std::fs::copy(data().join("textures/wood.png"), d.join("tex/wood.png")).unwrap();
    std::fs::write(
        d.join("room.mtl"),
        "newmtl floor\nKd 1 1 1\nmap_Kd tex/wood.png\nd 0.5\nnewmtl lamp\nKe 1 1 1\n\
         newmtl shiny\nnewmtl glass\nillum 7\nd 0.2\n",
    )
    .unwrap();
    let s = read_scene(&d.join("room.obj")).unwrap().scene;
    assert_eq!(s.textures["tex/wood.png"].path, "tex/wood.png");
    assert_eq!(
        s.surfaces["floor"],
        Surface {
            color: Some("tex/wood.png".into()),
            roughness: None,
            opacity: Some(Opacity {
                texture: None,
                channel: OpacityChannel::Auto,
                value: 0.5,
                cutoff: None
            }),
            normal: None,
            normal_scale: [1.0, 1.0],
            two_sided: true
        }
    );
    // Glass is transparent by its model: d does not cut it out.
    assert!(!s.surfaces.contains_key("glass"));
    // A texture file that is not there is refused with the MTL line.
    std::fs::write(
        d.join("room.mtl"),
        "newmtl floor\nKd 1 1 1\nmap_Kd gone.png\nnewmtl lamp\nKe 1 1 1\nnewmtl shiny\nnewmtl glass\n",
    )
    .unwrap();
    let err = refused(&d.join("room.obj"));
    assert!(
        err.contains("room.mtl: line 3: texture") && err.contains("gone.png not found"),
        "{err}"
    );
    std::fs::remove_dir_all(&d).unwrap();
}

/// Base64 of little-endian f32s and u16s.
fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for i in 0..4 {
            if i <= c.len() {
                out.push(A[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[test]
fn gltf_scene_translates_nodes_materials_camera_and_lights() {
    let d = tmp("gltf");
    let mut buf = Vec::new();
    // Positions of one triangle, then its texture coordinates.
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 1.] {
        buf.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::copy(data().join("textures/wood.png"), d.join("leaf.png")).unwrap();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_clearcoat"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [{{"type": "point", "color": [1, 0.5, 0.25], "intensity": 40}}]}}}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1, 2, 3, 4]}}],
  "nodes": [
    {{"name": "floor", "mesh": 0, "translation": [0, -1, 0]}},
    {{"name": "lamp", "mesh": 1, "scale": [2, 2, 2]}},
    {{"camera": 0, "translation": [0, 0, 5]}},
    {{"extensions": {{"KHR_lights_punctual": {{"light": 0}}}}, "translation": [0, 3, 0]}},
    {{"name": "plant", "mesh": 2, "translation": [3, 0, 0]}}
  ],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.5, "aspectRatio": 2.0, "znear": 0.1}}}}],
  "materials": [
    {{"name": "paint", "pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.25, 0.125, 1], "metallicFactor": 0}}}},
    {{"name": "steel", "pbrMetallicRoughness": {{"baseColorFactor": [0.75, 0.75, 0.75, 1], "metallicFactor": 1, "roughnessFactor": 0.25}},
      "emissiveFactor": [1, 1, 1]}},
    {{"name": "leaf", "pbrMetallicRoughness": {{"baseColorFactor": [1, 1, 1, 0.8], "baseColorTexture": {{"index": 0}}, "metallicFactor": 0, "roughnessFactor": 0.5}},
      "alphaMode": "MASK", "alphaCutoff": 0.3, "normalTexture": {{"index": 1}}}}
  ],
  "images": [{{"uri": "leaf.png"}}],
  "samplers": [{{"magFilter": 9728, "wrapS": 33648, "wrapT": 33648}}],
  "textures": [{{"source": 0}}, {{"source": 0, "sampler": 0}}],
  "meshes": [
    {{"primitives": [{{"attributes": {{"POSITION": 0}}, "material": 0}}]}},
    {{"primitives": [{{"attributes": {{"POSITION": 0}}, "material": 1}}]}},
    {{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "material": 2}}]}}
  ],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 24}}],
  "buffers": [{{"byteLength": 60, "uri": "data:application/octet-stream;base64,{}"}}]
}}"#,
        base64(&buf)
    );
    let path = d.join("model.gltf");
    std::fs::write(&path, json).unwrap();
    let imp = read_scene(&path).unwrap();
    assert!(
        imp.warnings
            .iter()
            .any(|w| w.contains("KHR_materials_clearcoat")),
        "{:?}",
        imp.warnings
    );
    let s = &imp.scene;
    // glTF's dielectric (roughness 1 by default): a plastic of index 1.5, GGX α = 1.
    assert_eq!(
        s.materials["paint"],
        Material::Plastic {
            diffuse_reflectance: Rgb([0.5, 0.25, 0.125]),
            specular_reflectance: Rgb::WHITE,
            ior: 1.5,
            nonlinear: false,
            roughness: Some(Microfacet {
                distribution: MicrofacetDistribution::Ggx,
                alpha: 1.0
            })
        }
    );
    assert_eq!(
        s.materials["steel"],
        Material::Glossy {
            diffuse: Rgb::splat(0.0),
            specular: Rgb::splat(0.75),
            roughness: 0.25
        }
    );
    assert_eq!(s.objects.len(), 3);
    // baseColorTexture (default sampler: repeat, bilinear), alpha MASK at the cutoff with the
    // base colour's alpha, a normal map read linearly with its own sampler, its y reversed
    // (glTF's tangent-space y points towards decreasing v; scale 1).
    assert_eq!(
        s.surfaces["leaf"],
        Surface {
            color: Some("leaf.png".into()),
            roughness: None,
            opacity: Some(Opacity {
                texture: Some("leaf.png".into()),
                channel: OpacityChannel::Alpha,
                value: 0.800000011920929,
                cutoff: Some(0.30000001192092896)
            }),
            normal: Some("leaf.png'".into()),
            normal_scale: [1.0, -1.0],
            two_sided: true
        }
    );
    assert_eq!(
        (s.textures["leaf.png"].wrap, s.textures["leaf.png"].filter),
        (Wrap::Repeat, Filter::Bilinear)
    );
    let normal = &s.textures["leaf.png'"];
    assert_eq!(
        (normal.wrap, normal.filter, normal.encoding),
        (Wrap::Mirror, Filter::Nearest, Some(Encoding::Linear))
    );
    let floor = s.objects.iter().find(|o| o.material == "paint").unwrap();
    assert_eq!(
        floor.shape,
        Shape::Gltf {
            path: "model.gltf".into(),
            primitive: Some((0, 0))
        }
    );
    assert!(same_affine(
        &affine(&floor.transform.matrix),
        &Affine::translate(Vec3::new(0.0, -1.0, 0.0))
    ));
    let lamp = s.objects.iter().find(|o| o.material == "steel").unwrap();
    assert_eq!(lamp.emission, Some(Emission::Radiance(Rgb::WHITE)));
    let cam = s.camera.as_ref().unwrap();
    assert_eq!(cam.resolution, (1440, 720));
    assert!(close(cam.vfov_deg, 0.5f64.to_degrees()));
    assert!((cam.look_at - Vec3::new(0.0, 0.0, 4.0)).length() < 1e-12);
    let light = &s.point_lights[0];
    assert_eq!(light.position, Vec3::new(0.0, 3.0, 0.0));
    assert!(close(
        match light.power {
            PointPower::Intensity(i) => i,
            PointPower::Flux(_) => f64::NAN,
        },
        40.0 * Rgb([1.0, 0.5, 0.25]).luminance()
    ));
    // Compiled: the lamp triangle scaled by 2 has area 2 m².
    let (compiled, _) = scene_compile::compile_file(&path).unwrap();
    let area: f64 = compiled
        .header
        .emitters
        .iter()
        .filter_map(|e| match e {
            luxest_render::compiled::Emitter::Area { area_m2, .. } => Some(*area_m2),
            _ => None,
        })
        .sum();
    assert!((area - 2.0).abs() < 1e-6, "{area}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn define_gives_a_mitsuba_parameter_over_its_default() {
    let d = tmp("define");
    let scene = d.join("p.xml");
    std::fs::write(
        &scene,
        xml(r#"<default name="albedo" value="0.5"/>
    <bsdf type="twosided" id="grey"><bsdf type="diffuse"><rgb name="reflectance" value="$albedo"/></bsdf></bsdf>"#),
    )
    .unwrap();
    let out = d.join("p.ron");
    let o = bin()
        .args(["--check", "-D", "albedo=0.25", "--export-ron"])
        .arg(&out)
        .arg(&scene)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ron = std::fs::read_to_string(&out).unwrap();
    let grey = ron.find("\"grey\": Lambertian(").expect("the material");
    assert!(
        ron[grey..].contains("reflectance: (0.25, 0.25, 0.25)"),
        "{ron}"
    );
    // Malformed, or given to a format without parameters: usage errors (exit 2).
    let o = bin()
        .args(["--check", "-D", "albedo"])
        .arg(&scene)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn version_0_6_scenes_get_mitsubas_upgrade() {
    let d = tmp("legacy");
    std::fs::copy(data().join("textures/wood.png"), d.join("wood.png")).unwrap();
    std::fs::write(
        d.join("old.xml"),
        r#"<scene version="0.6.0">
    <default name="shiftX" value="1"/>
    <shape type="rectangle" id="wall">
        <transform name="toWorld"><translate x="$shiftX"/></transform>
        <bsdf type="diffuse">
            <texture type="bitmap" name="diffuseReflectance">
                <string name="filename" value="wood.png"/>
                <float name="uoffset" value="0.25"/>
                <float name="uscale" value="2"/>
                <float name="vscale" value="3"/>
            </texture>
        </bsdf>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
</scene>
"#,
    )
    .unwrap();
    let s = read_scene(&d.join("old.xml")).unwrap().scene;
    let wall = &s.objects[0];
    assert!(same_affine(
        &affine(&wall.transform.matrix),
        &Affine::translate(Vec3::new(1.0, 0.0, 0.0))
    ));
    // A `<default>` keeps its name as written (Mitsuba upgrades property names only), so
    // `$shiftX` resolves; diffuseReflectance → reflectance (the texture's colour);
    // uv' = scale · (uv + offset).
    assert_eq!(
        s.surfaces[&wall.material].color.as_deref(),
        Some("wood.png@old:6")
    );
    assert_eq!(
        s.textures["wood.png@old:6"].uv_transform,
        Some(UvTransform([[2.0, 0.0, 0.5], [0.0, 3.0, 0.0]]))
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_mitsuba_normalmap_is_the_surfaces_normal_map() {
    // normalmap(twosided(diffuse)) and normalmap(diffuse) (one-sided): the bitmap becomes the
    // surface's `normal` texture (raw: linear), Mitsuba's convention (scale (1, 1)).
    let d = tmp("normalmap");
    let scene = d.join("n.xml");
    let wood = data().join("textures/wood.png").display().to_string();
    let map = format!(
        r#"<texture name="normalmap" type="bitmap"><string name="filename" value="{wood}"/><boolean name="raw" value="true"/></texture>"#
    );
    std::fs::write(
        &scene,
        xml(&format!(
            r#"<shape type="rectangle"><bsdf type="normalmap" id="two">{map}<bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf></shape>
    <shape type="rectangle"><bsdf type="normalmap" id="one">{map}<bsdf type="diffuse"/></bsdf></shape>"#
        )),
    )
    .unwrap();
    let s = read_scene(&scene).unwrap().scene;
    for (name, two_sided) in [("two", true), ("one", false)] {
        let surface = &s.surfaces[name];
        let t = surface.normal.as_ref().expect("a normal map");
        assert_eq!(s.textures[t].encoding, Some(Encoding::Linear));
        assert!(s.textures[t].path.ends_with("wood.png"));
        assert_eq!(surface.normal_scale, [1.0, 1.0]);
        assert_eq!(surface.two_sided, two_sided, "{name}");
        assert_eq!(
            s.materials[name],
            Material::Lambertian {
                reflectance: Rgb::splat(0.5)
            }
        );
    }
    std::fs::remove_dir_all(&d).unwrap();
}
