//! `make bench`: compile + load time of a scene holding a 1M-triangle mesh.
//!
//! Generates a 1000 x 500-quad heightfield (1 000 000 triangles, 501 501 vertices) as OBJ and
//! as binary glTF in a temporary directory, then times, best of 3: parsing + compiling the
//! authored scene, encoding + writing the compiled file, reading + verifying + decoding it,
//! and building the Embree BVH over it.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

const NX: usize = 1000;
const NZ: usize = 500;

fn height(i: usize, j: usize) -> f32 {
    let (x, z) = (i as f32 / NX as f32, j as f32 / NZ as f32);
    0.05 * (x * 37.0).sin() * (z * 23.0).cos()
}

fn write_obj(path: &Path) {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for j in 0..=NZ {
        for i in 0..=NX {
            writeln!(
                w,
                "v {} {} {}",
                i as f32 / NX as f32,
                height(i, j),
                j as f32 / NX as f32
            )
            .unwrap();
        }
    }
    let v = |i: usize, j: usize| j * (NX + 1) + i + 1;
    for j in 0..NZ {
        for i in 0..NX {
            writeln!(w, "f {} {} {}", v(i, j), v(i, j + 1), v(i + 1, j + 1)).unwrap();
            writeln!(w, "f {} {} {}", v(i, j), v(i + 1, j + 1), v(i + 1, j)).unwrap();
        }
    }
}

fn write_glb(path: &Path) {
    let mut pos = Vec::new();
    for j in 0..=NZ {
        for i in 0..=NX {
            for c in [i as f32 / NX as f32, height(i, j), j as f32 / NX as f32] {
                pos.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let mut idx = Vec::new();
    let v = |i: usize, j: usize| (j * (NX + 1) + i) as u32;
    for j in 0..NZ {
        for i in 0..NX {
            for k in [
                v(i, j),
                v(i, j + 1),
                v(i + 1, j + 1),
                v(i, j),
                v(i + 1, j + 1),
                v(i + 1, j),
            ] {
                idx.extend_from_slice(&k.to_le_bytes());
            }
        }
    }
    let nv = (NX + 1) * (NZ + 1);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":1}},"indices":0}}]}}],"buffers":[{{"byteLength":{}}}],"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{}}},{{"buffer":0,"byteOffset":{},"byteLength":{}}}],"accessors":[{{"bufferView":0,"componentType":5125,"count":{},"type":"SCALAR"}},{{"bufferView":1,"componentType":5126,"count":{},"type":"VEC3","min":[0,-0.05,0],"max":[1,0.05,0.5]}}]}}"#,
        idx.len() + pos.len(),
        idx.len(),
        idx.len(),
        pos.len(),
        idx.len() / 4,
        nv
    );
    let mut js = json.into_bytes();
    while js.len() % 4 != 0 {
        js.push(b' ');
    }
    let bin: Vec<u8> = idx.into_iter().chain(pos).collect();
    let total = 12 + 8 + js.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(&0x46546C67u32.to_le_bytes());
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F534Au32.to_le_bytes());
    out.extend_from_slice(&js);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E4942u32.to_le_bytes());
    out.extend_from_slice(&bin);
    std::fs::write(path, out).unwrap();
}

fn best_of<T>(n: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..n {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(r);
    }
    (best, last.unwrap())
}

fn main() {
    // `cargo bench` passes --bench; no other arguments are used.
    let dir = std::env::temp_dir().join(format!("luxest-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write_obj(&dir.join("grid.obj"));
    write_glb(&dir.join("grid.glb"));
    println!("scene-compile benchmark: 1 000 000-triangle heightfield, best of 3");
    for (label, shape) in [
        ("OBJ ", "Obj(path: \"grid.obj\")"),
        ("glTF", "Gltf(path: \"grid.glb\")"),
    ] {
        let scene = dir.join(format!("{}.ron", label.trim()));
        std::fs::write(
            &scene,
            format!(
                "Scene(materials: {{\"w\": Lambertian(reflectance: (0.5, 0.5, 0.5))}}, \
                 objects: [(shape: {shape}, material: \"w\")], \
                 point_lights: [(position: (0.5, 1.0, 0.25), power: Intensity(100.0))])"
            ),
        )
        .unwrap();
        let out = dir.join("scene.lxs");
        let (t_compile, (mut compiled, _)) =
            best_of(3, || scene_compile::compile_file(&scene).unwrap());
        assert_eq!(compiled.triangle_count(), 2 * NX * NZ);
        let (t_write, _) = best_of(3, || compiled.save(&out).unwrap());
        let size = std::fs::metadata(&out).unwrap().len();
        let (t_load, loaded) = best_of(3, || {
            luxest_render::compiled::CompiledScene::load(&out).unwrap()
        });
        let (t_bvh, rt) = best_of(3, || {
            luxest_render::rt::RayTracer::for_scene(&loaded, false).unwrap()
        });
        assert_eq!(rt.triangle_count(), 2 * NX * NZ);
        println!(
            "{label}: compile {:6.3} s | write {:6.3} s ({:.1} MB) | load {:6.3} s | Embree BVH {:6.3} s | compile+load {:6.3} s",
            t_compile,
            t_write,
            size as f64 / 1e6,
            t_load,
            t_bvh,
            t_compile + t_write + t_load
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
