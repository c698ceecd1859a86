//! `make bench` for denoise: milliseconds per megapixel of the default model (models/default.onnx)
//! on 2 threads, in the default tiling (1024² cores with 96 pixels of context) for 512², 1024²
//! (one tile) and 2048² (four tiles: the context overhead included), and for 1024² in 256² tiles.
//! Inputs are synthetic features of the right statistics (inference time does not depend on the
//! values), as many as the model takes (no emission). Run: `cargo bench -p denoise`; the
//! comparison with the peer is `make bench-denoise`.

use denoise::{Denoiser, Feature, Tiling};
use luxest_io::image::RgbImage;
use luxest_io::progress::Progress;
use std::path::Path;
use std::time::Instant;

fn features(size: usize, kinds: &[Feature]) -> Vec<RgbImage> {
    // hdr, alb, nrm, then emi / ema (zero: no emitter in view) where the model takes them.
    assert_eq!(kinds[..3], [Feature::Hdr, Feature::Alb, Feature::Nrm]);
    let mut images = vec![RgbImage::new(size, size); kinds.len()];
    for y in 0..size {
        for x in 0..size {
            let i = y * size + x;
            let v = ((x * 31 + y * 17) % 97) as f32 / 97.0;
            images[0].pixels[i] = [v * 2.0, v, 0.5 * v];
            images[1].pixels[i] = [0.5, 0.5 * v, 0.3];
            images[2].pixels[i] = [0.0, 0.6, 0.8];
        }
    }
    images
}

fn main() {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/default.onnx");
    let threads = 2;
    let mut denoiser = Denoiser::load(&model, threads).unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(1)
    });
    println!(
        "denoise benchmark: {} on {threads} threads",
        model.display()
    );
    for (size, tiling) in [
        (512, Tiling::default()),
        (1024, Tiling::default()),
        (2048, Tiling::default()),
        (
            1024,
            Tiling {
                tile: 256,
                overlap: 96,
            },
        ),
    ] {
        let images = features(size, denoiser.features());
        let refs: Vec<&RgbImage> = images.iter().collect();
        denoiser.denoise(&refs, tiling, &Progress::off()).unwrap(); // warm-up: allocations, kernel selection
        let runs = 3;
        let start = Instant::now();
        for _ in 0..runs {
            denoiser.denoise(&refs, tiling, &Progress::off()).unwrap();
        }
        let seconds = start.elapsed().as_secs_f64() / runs as f64;
        let mp = (size * size) as f64 / 1e6;
        println!(
            "  {size}x{size}, tile {} + {} context: {:.0} ms/image, {:.0} ms/megapixel",
            tiling.tile,
            tiling.overlap,
            1e3 * seconds,
            1e3 * seconds / mp
        );
    }
}
