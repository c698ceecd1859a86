//! The fuzz targets on stable: each runs over its seed files (the repository's own scenes,
//! meshes, images and photometric files, and the regression inputs in `regressions/<target>/`)
//! and a fixed number of deterministic mutations of them. A panic fails the test; an abort or a
//! hang fails the test binary. The real fuzzing (libFuzzer, coverage-guided) is `fuzz/`.

use std::path::{Path, PathBuf};

/// Mutated inputs per target.
const MUTATIONS: usize = 3000;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Files under `dir` (relative to the repository root) whose names end in one of `exts`.
fn files(dir: &str, exts: &[&str]) -> Vec<Vec<u8>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    paths.sort();
    paths
        .into_iter()
        .filter(|p| {
            let name = p.to_string_lossy().to_ascii_lowercase();
            exts.iter().any(|e| name.ends_with(e))
        })
        .filter_map(|p| std::fs::read(p).ok())
        .collect()
}

/// The seeds of `target`: the repository's files of its kind and its regression inputs.
fn seeds(target: &str) -> Vec<Vec<u8>> {
    let mut s = match target {
        "scene" => files("scenes", &[".ron"]),
        "obj" => files("scenes/meshes", &[".obj"]),
        "gltf" => files("scenes/meshes", &[".glb", ".gltf"]),
        "mitsuba_xml" => mitsuba_seeds(),
        "ply" => [
            files(
                "crates/scene-compile/tests/data/mitsuba/meshes",
                &[".ply", ".serialized"],
            ),
            vec![ASCII_PLY.as_bytes().to_vec()],
        ]
        .concat(),
        "compiled" => vec![compiled_seed()],
        "exr" => files(
            "tests/fixtures/denoise",
            &["spp.alb.exr", "odd_000004spp.hdr.exr"],
        ),
        "ies" => [
            files("scenes/photometry", &[".ies"]),
            files("crates/photometry/tests/fixtures", &[".ies"]),
        ]
        .concat(),
        "ldt" => [
            files("scenes/photometry", &[".ldt"]),
            files("crates/photometry/tests/fixtures", &[".ldt"]),
        ]
        .concat(),
        "sensors" => sensors_seeds(),
        "scene_info" => scene_info_seeds(),
        "peer" => files("reports/lighting/office", &["radiance.csv"]),
        "texture_png" => [
            files("crates/render/tests/data/texture", &[".png"]),
            png_seeds(),
        ]
        .concat(),
        "texture_jpeg" => files("crates/render/tests/data/texture", &[".jpg"]),
        "texture_exr" => [
            files("crates/render/tests/data/texture", &[".exr"]),
            files(
                "tests/fixtures/denoise",
                &["spp.alb.exr", "odd_000004spp.hdr.exr"],
            ),
            files("crates/fuzz/regressions/exr", &[""]),
        ]
        .concat(),
        "texture_encoded" => encoded_texture_seeds(),
        _ => unreachable!("unknown target {target}"),
    };
    s.extend(files(&format!("crates/fuzz/regressions/{target}"), &[""]));
    assert!(!s.is_empty(), "no seeds for {target}");
    s
}

/// PNGs of the colour types and depths the texture decoder expands: grey 16-bit, grey and
/// alpha, RGBA, a palette with transparency, grey 2-bit.
fn png_seeds() -> Vec<Vec<u8>> {
    use png::{BitDepth::*, ColorType::*};
    let encode = |color, depth, w: u32, data: &[u8], palette: Option<(&[u8], &[u8])>| {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, w, 3);
        encoder.set_color(color);
        encoder.set_depth(depth);
        if let Some((entries, alphas)) = palette {
            encoder.set_palette(entries.to_vec());
            encoder.set_trns(alphas.to_vec());
        }
        let mut writer = encoder.write_header().expect("valid header");
        writer.write_image_data(data).expect("valid data");
        writer.finish().expect("finishes");
        bytes
    };
    let ramp = |n: usize| -> Vec<u8> { (0..n).map(|i| (i * 37 % 256) as u8).collect() };
    vec![
        encode(Grayscale, Sixteen, 3, &ramp(18), None),
        encode(GrayscaleAlpha, Eight, 3, &ramp(18), None),
        encode(Rgba, Eight, 3, &ramp(36), None),
        encode(
            Indexed,
            Eight,
            3,
            &[0, 1, 2, 2, 1, 0, 1, 1, 1],
            Some((&ramp(9), &[0, 128])),
        ),
        encode(
            Grayscale,
            Two,
            4,
            &[0b0001_1011, 0b1110_0100, 0b0101_1010],
            None,
        ),
    ]
}

/// Textures as the compiled scene stores them: the PNG, JPEG and EXR fixtures.
fn encoded_texture_seeds() -> Vec<Vec<u8>> {
    let dir = root().join("crates/render/tests/data/texture");
    ["bitmap.png", "pattern_grey.jpg", "rgba_half.exr"]
        .iter()
        .map(|name| {
            let options = luxest_render::texture::TextureOptions::default();
            let t = luxest_render::texture::Texture::load(&dir.join(name), &options)
                .expect("fixture loads");
            let mut bytes = Vec::new();
            t.encode(&mut bytes);
            bytes
        })
        .collect()
}

/// A small compiled scene (the Cornell box), as scene-compile writes it.
/// An ASCII PLY with normals, texture coordinates (as s, t), a quad face and an extra element.
const ASCII_PLY: &str = "ply\nformat ascii 1.0\ncomment seed\nelement vertex 4\n\
property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n\
property float nz\nproperty float s\nproperty float t\nelement face 1\n\
property list uchar int vertex_indices\nelement edge 1\nproperty int vertex1\n\
property int vertex2\nend_header\n0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n\
0 1 0 0 0 1 0 1\n4 0 1 2 3\n0 1\n";

/// The importer's test scene as it is (its include and meshes are not found where the fuzz
/// target looks) and self-contained: the included file's elements inlined and the mesh shapes
/// cut, so that mutations reach the translation of every element.
fn mitsuba_seeds() -> Vec<Vec<u8>> {
    let dir = root().join("crates/scene-compile/tests/data/mitsuba");
    let scene = std::fs::read_to_string(dir.join("scene.xml")).unwrap();
    let part = std::fs::read_to_string(dir.join("parts/materials.xml")).unwrap();
    let inner = part
        .split_once('>')
        .and_then(|(_, rest)| rest.rsplit_once("</scene>"))
        .map(|(body, _)| body)
        .unwrap();
    let mut inlined = scene.replace("<include filename=\"parts/materials.xml\"/>", inner);
    for kind in ["obj", "ply"] {
        let open = format!("<shape type=\"{kind}\"");
        if let Some(start) = inlined.find(&open) {
            let end = start + inlined[start..].find("</shape>").unwrap() + "</shape>".len();
            inlined.replace_range(start..end, "");
        }
    }
    vec![scene.into_bytes(), inlined.into_bytes(), part.into_bytes()]
}

fn compiled_seed() -> Vec<u8> {
    let (mut scene, _) =
        scene_compile::compile_file(&root().join("scenes/cornell-box.ron")).expect("compiles");
    scene.encode()
}

/// Sensor results as `estimate sensors` writes them: points on an integrating sphere's wall,
/// and a 3 x 2 calculation surface with its batch values (what `report` reads).
fn sensors_seeds() -> Vec<Vec<u8>> {
    use luxest_io::color::Rgb;
    use luxest_io::math::Vec3;
    use luxest_io::sensors::{SensorGrid, SensorResults, SensorSetResult, SensorValue};
    let run = luxest_io::meta::RunInfo::new("local-estimate", 1000, 1, 0.5, "0123abcd");
    let point = |p: Vec3, n: Vec3, v: f64| SensorValue::new(p, n, v, 1.0, Rgb::splat(v));
    let wall = SensorSetResult {
        name: "wall".into(),
        grid: None,
        kind: None,
        points: vec![
            point(
                Vec3::new(0.0, -0.9999, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                200.0,
            ),
            point(
                Vec3::new(0.9999, 0.0, 0.0),
                Vec3::new(-1.0, 0.0, 0.0),
                201.0,
            ),
        ],
        batches: Vec::new(),
    };
    let up = Vec3::new(0.0, 1.0, 0.0);
    let points: Vec<SensorValue> = (0..6)
        .map(|k| {
            let p = Vec3::new(1.0 + (k % 3) as f64, 0.75, 2.0 - (k / 3) as f64);
            point(p, up, 100.0 + k as f64)
        })
        .collect();
    let batches: Vec<Vec<f64>> = [-1.0, 1.0]
        .iter()
        .map(|d| points.iter().map(|p| p.value + d).collect())
        .collect();
    let plane = SensorSetResult {
        name: "work-plane".into(),
        grid: Some(SensorGrid {
            nu: 3,
            nv: 2,
            origin: Vec3::new(0.0, 0.75, 3.0),
            u: Vec3::new(4.0, 0.0, 0.0),
            v: Vec3::new(0.0, 0.0, -3.0),
            margin_m: 0.5,
        }),
        kind: None,
        points,
        batches,
    };
    [vec![wall], vec![plane]]
        .into_iter()
        .map(|sets| {
            let results = SensorResults {
                scene: "seed".into(),
                run: run.clone(),
                unit: "lx".into(),
                singularity: "ball".into(),
                sets,
                glare: Vec::new(),
            };
            luxest_io::fsio::to_ron_string(&results).into_bytes()
        })
        .collect()
}

/// Compiled headers as `scene-compile --info` prints them: the Cornell box (area light), and a
/// floor under the office's two luminaire files, one of them twice (luminaire groups).
fn scene_info_seeds() -> Vec<Vec<u8>> {
    let (cornell, _) =
        scene_compile::compile_file(&root().join("scenes/cornell-box.ron")).expect("compiles");
    let text = r#"Scene(name: "lamps",
        materials: { "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) },
        objects: [(name: "floor", shape: Quad(corner: (0.0, 0.0, 0.0), u: (0.0, 0.0, 2.0), v: (2.0, 0.0, 0.0)), material: "w")],
        luminaires: [
            (name: "a", file: "photometry/troffer-600-led.ies", position: (0.5, 2.0, 0.5)),
            (name: "b", file: "photometry/troffer-600-led.ies", position: (1.5, 2.0, 0.5), multiplier: 0.8),
            (name: "c", file: "photometry/pendant-linear-4000.ldt", position: (1.0, 2.0, 1.5)),
        ])"#;
    let path = root().join("scenes/lamps.ron");
    let scene = luxest_io::fsio::parse_ron(&path, text).expect("parses");
    let (lamps, _) = scene_compile::compile(&scene, &path).expect("compiles");
    [cornell, lamps]
        .iter()
        .map(|s| scene_compile::cli::info_text(s).into_bytes())
        .collect()
}

/// xorshift64*: deterministic mutations, the same on every machine.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Bytes a parser of numbers and text is most sensitive to.
const INTERESTING: &[&[u8]] = &[
    b"0",
    b"-1",
    b"1e308",
    b"-1e308",
    b"NaN",
    b"inf",
    b"4294967295",
    b"18446744073709551616",
    b"\0",
    b"\xff",
    b"(",
    b")",
    b"[",
    b"]",
    b",",
    b"\n",
    b"\"",
    b"e",
    b".",
    b"-",
    b"99999999",
];

/// One mutation of `seed`: a few random edits (byte changes, interesting tokens, deletions,
/// duplications, truncation).
fn mutate(rng: &mut Rng, seed: &[u8]) -> Vec<u8> {
    let mut v = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(v.len() + 1);
        match rng.below(6) {
            0 if !v.is_empty() => {
                let i = at.min(v.len() - 1);
                v[i] = rng.next() as u8;
            }
            1 => {
                let t = INTERESTING[rng.below(INTERESTING.len())];
                v.splice(at..at, t.iter().copied());
            }
            2 if !v.is_empty() => {
                let end = (at + 1 + rng.below(16)).min(v.len());
                v.drain(at.min(end)..end);
            }
            3 if !v.is_empty() => {
                let start = rng.below(v.len());
                let end = (start + 1 + rng.below(64)).min(v.len());
                let chunk: Vec<u8> = v[start..end].to_vec();
                v.splice(at..at, chunk);
            }
            4 => v.truncate(at),
            _ => {
                // Replace a digit run by an interesting number: the parsers' ranges.
                if let Some(i) = (at..v.len()).find(|&i| v[i].is_ascii_digit()) {
                    let end = (i..v.len())
                        .find(|&j| !v[j].is_ascii_digit())
                        .unwrap_or(v.len());
                    let t = INTERESTING[rng.below(7)];
                    v.splice(i..end, t.iter().copied());
                }
            }
        }
    }
    v
}

#[test]
fn every_target_survives_its_seeds_and_their_mutations() {
    for (name, target) in luxest_fuzz::TARGETS {
        let seeds = seeds(name);
        for s in &seeds {
            target(s);
        }
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ name.len() as u64);
        for k in 0..MUTATIONS {
            let input = mutate(&mut rng, &seeds[k % seeds.len()]);
            target(&input);
        }
    }
}

/// Not a test: writes every target's seeds to `$LUXEST_FUZZ_SEEDS/<target>/seed-N`, the starting
/// corpora of the libFuzzer runs (docs/fuzzing.md):
/// `LUXEST_FUZZ_SEEDS=fuzz/seeds cargo test -p luxest-fuzz --test smoke -- --ignored export_seeds`.
#[test]
#[ignore = "exports the seed corpora for cargo fuzz; run on request"]
fn export_seeds() {
    let dir = PathBuf::from(std::env::var("LUXEST_FUZZ_SEEDS").expect("set LUXEST_FUZZ_SEEDS"));
    for (name, _) in luxest_fuzz::TARGETS {
        let d = dir.join(name);
        std::fs::create_dir_all(&d).unwrap();
        for (i, s) in seeds(name).iter().enumerate() {
            std::fs::write(d.join(format!("seed-{i}")), s).unwrap();
        }
    }
}
