//! The `denoise` command line: one or more noisy `<img>_<spp>spp.hdr.exr` in, each
//! `<img>_<spp>spp.dn.exr` out, features found next to them by the OIDN naming.

use crate::feature::names;
use crate::{feature_path, output_path, Denoiser, Feature, Tiling};
use clap::Parser;
use luxest_io::cli::CommonArgs;
use luxest_io::exr::{read_rgb_finite, write_rgb_to};
use luxest_io::header;
use luxest_io::image::RgbImage;
use luxest_io::naming::preview_path;
use luxest_io::outputs::{Format, OutputPlan};
use luxest_io::png::write_preview_png_auto_to;
use luxest_io::progress::Progress;
use luxest_io::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Denoise path-traced (or local-estimate) radiance images with an ONNX U-Net.
///
/// Each NOISY file `<img>.hdr.exr` needs the features the model takes next to it
/// (`<img>.alb.exr`, `<img>.nrm.exr`, and `<img>.emi.exr` / `<img>.ema.exr` for models that
/// take the emission, as aov-write names them) unless --alb/--nrm/--emi/--ema name them;
/// the result is `<img>.dn.exr` with the input's header attributes plus luxest.denoiser,
/// luxest.denoiseSeconds (wall-clock seconds of inference, excluding I/O),
/// luxest.denoiseCpuSeconds (its CPU seconds, all threads) and luxest.featureSeconds (the render
/// seconds recorded in the feature images, i.e. what the albedo and normal cost), so that the
/// image's whole cost can be added up.
#[derive(Parser, Debug)]
#[command(name = "denoise", version)]
#[command(mut_arg("seed", |a| a.help("Accepted like every stage's; inference is deterministic and draws no random numbers")))]
pub struct Args {
    /// Noisy radiance images, `<img>.hdr.exr`.
    #[arg(required = true)]
    pub noisy: Vec<PathBuf>,
    /// The ONNX model (training/export.py) [default: models/default.onnx in the working
    /// directory, else in the luxest checkout this program was built from].
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Output file (only with one input) [default: <img>.dn.exr next to the input].
    #[arg(short, long, conflicts_with = "out_dir")]
    pub out: Option<PathBuf>,
    /// Write outputs into this directory instead of next to the inputs.
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    /// Albedo image (only with one input) [default: <img>.alb.exr].
    #[arg(long)]
    pub alb: Option<PathBuf>,
    /// Normal image (only with one input) [default: <img>.nrm.exr].
    #[arg(long)]
    pub nrm: Option<PathBuf>,
    /// Emission image, for models that take it (only with one input) [default: <img>.emi.exr].
    #[arg(long)]
    pub emi: Option<PathBuf>,
    /// Antialiased emission image, for models that take it (only with one input) [default:
    /// <img>.ema.exr].
    #[arg(long)]
    pub ema: Option<PathBuf>,
    /// Take whichever feature images the model needs from beside this name instead of the
    /// input's (`<img>.alb.exr`, ... for `<img>.hdr.exr`, which need not exist): a
    /// local-estimate image is denoised with a path-traced level's features this way (only
    /// with one input; not with --alb, --nrm, --emi, --ema).
    #[arg(long, value_name = "IMG.hdr.exr", conflicts_with_all = ["alb", "nrm", "emi", "ema"])]
    pub features_of: Option<PathBuf>,
    /// Tile core size in pixels (a multiple of 16); larger images are denoised in tiles.
    #[arg(long, default_value_t = Tiling::default().tile)]
    pub tile: usize,
    /// Context around each tile in pixels (a multiple of 16).
    #[arg(long, default_value_t = Tiling::default().overlap)]
    pub overlap: usize,
    /// Also write an sRGB PNG preview of each output next to it (`.dn.png`).
    #[arg(long)]
    pub preview: bool,
    /// Denoise even with albedo/normal features of fewer samples per pixel than the model's
    /// `luxest.feature_samples` (refused otherwise): for measuring how a model does with
    /// features it was not trained for.
    #[arg(long)]
    pub any_feature_samples: bool,
    #[command(flatten)]
    pub common: CommonArgs,
}

impl Args {
    /// The file named on the command line for a feature (--alb, --nrm, --emi, --ema; hdr is the
    /// input itself).
    fn feature(&self, feature: Feature) -> Option<&PathBuf> {
        match feature {
            Feature::Hdr => None,
            Feature::Alb => self.alb.as_ref(),
            Feature::Nrm => self.nrm.as_ref(),
            Feature::Emi => self.emi.as_ref(),
            Feature::Ema => self.ema.as_ref(),
        }
    }
}

/// The model file's path relative to a luxest checkout (and to the working directory).
pub const DEFAULT_MODEL: &str = "models/default.onnx";

/// The model used without --model: [`DEFAULT_MODEL`] in `working_dir` (the process's: `""`)
/// if it is there (the Makefile's and the README's commands run in the checkout), else in the
/// checkout whose crate `crates/denoise` is at `crate_dir` (the one this program was built
/// from, so that `target/release/denoise img.hdr.exr` works from any directory). A usage error
/// naming both places when neither has it.
pub fn default_model(working_dir: &Path, crate_dir: &Path) -> Result<PathBuf> {
    let here = working_dir.join(DEFAULT_MODEL);
    if here.is_file() {
        return Ok(here);
    }
    let root = crate_dir.ancestors().nth(2).unwrap_or(Path::new("/"));
    let checkout = root.join(DEFAULT_MODEL);
    if checkout.is_file() {
        return Ok(checkout);
    }
    Err(Error::Usage(format!(
        "no --model given, and the default model {DEFAULT_MODEL} is neither in the working \
         directory nor at {}; give --model PATH",
        checkout.display()
    )))
}

/// One input image's denoising: where its features are and where its result goes.
struct Job {
    noisy: PathBuf,
    features: Vec<PathBuf>,
    out: PathBuf,
    preview: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    keep_freed_memory();
    let tiling = Tiling {
        tile: args.tile,
        overlap: args.overlap,
    };
    tiling.validate()?;
    let single = args.noisy.len() == 1;
    let per_image = args.out.is_some() || args.features_of.is_some();
    if !single && (per_image || Feature::ALL.iter().any(|&f| args.feature(f).is_some())) {
        return Err(Error::Usage(
            "-o/--out, --alb, --nrm, --emi, --ema and --features-of need exactly one input image"
                .into(),
        ));
    }
    if let Some(of) = &args.features_of {
        if feature_path(of, Feature::Alb).is_none() {
            return Err(Error::Usage(format!(
                "--features-of {}: name an image <img>.hdr.exr whose features sit beside it",
                of.display()
            )));
        }
    }
    let model = match &args.model {
        Some(m) => m.clone(),
        None => default_model(Path::new(""), Path::new(env!("CARGO_MANIFEST_DIR")))?,
    };
    let mut denoiser = Denoiser::load(&model, args.common.thread_count())?;
    let model_name = model
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    // A feature named for a model that does not take it would be ignored: refused instead.
    if let Some(f) = Feature::ALL
        .into_iter()
        .find(|&f| args.feature(f).is_some() && !denoiser.features().contains(&f))
    {
        let takes: Vec<&str> = denoiser.features().iter().map(|f| f.name()).collect();
        return Err(Error::Usage(format!(
            "--{0}: the model {1} does not take the {0} feature (it takes {2})",
            f.name(),
            model.display(),
            takes.join(", ")
        )));
    }
    let jobs = args
        .noisy
        .iter()
        .map(|noisy| job(&args, &denoiser, &model_name, noisy))
        .collect::<Result<Vec<Job>>>()?;
    // Every input (model, images, features) and every output of the run, checked before
    // anything is written: no output may replace an input or another output.
    let inputs =
        std::iter::once(model.clone()).chain(jobs.iter().flat_map(|j| j.features.iter().cloned()));
    let outputs = jobs
        .iter()
        .flat_map(|j| std::iter::once(j.out.clone()).chain(j.preview.clone()));
    let mut plan = OutputPlan::new(inputs, outputs)?;
    if let Some(out) = &args.out {
        Format::Exr.check(out, "-o/--out")?;
    }
    // What each image's line will say, printed once every output is in place: a line per
    // image as it was denoised announced outputs that a later image's failure then withheld.
    let mut done = Vec::new();
    let console = args.common.console;
    // The pixels of the run: those of the images read so far, the others taken to be the
    // first one's size until they are read.
    let (mut progress, mut pixels_read, mut first) = (Progress::off(), 0u64, 0u64);
    for (n, job) in jobs.iter().enumerate() {
        let images = job
            .features
            .iter()
            .map(|p| read_checked(p))
            .collect::<Result<Vec<RgbImage>>>()?;
        let (w, h) = (images[0].width, images[0].height);
        tiling.check_memory(w, h)?;
        let pixels = (w * h) as u64;
        if n == 0 {
            // The resource rule: the run's plan, its images taken to be the first one's size.
            console.announce(&work_plan(
                &mut denoiser,
                tiling,
                (w, h),
                jobs.len(),
                args.common.thread_count(),
            )?);
            progress = console.progress("denoise", Some(pixels * jobs.len() as u64), "pixels");
            first = pixels;
        } else {
            progress.set_total(pixels_read + pixels + first * (jobs.len() - n - 1) as u64);
        }
        pixels_read += pixels;
        for (image, path) in images.iter().zip(&job.features).skip(1) {
            if (image.width, image.height) != (w, h) {
                return Err(Error::input(
                    path,
                    format!(
                        "size {}x{} differs from the noisy image's {w}x{h} ({})",
                        image.width,
                        image.height,
                        job.noisy.display()
                    ),
                ));
            }
        }
        if !args.any_feature_samples {
            check_feature_samples(
                denoiser.features(),
                &images,
                &job.features,
                denoiser.feature_samples(),
                &model,
            )?;
        }
        let (start, cpu_start) = (Instant::now(), process_cpu_seconds());
        let refs: Vec<&RgbImage> = images.iter().collect();
        let mut result = denoiser
            .denoise(&refs, tiling, &progress)
            .map_err(|e| match e {
                Error::Usage(m) => Error::input(&job.noisy, m),
                e => e,
            })?;
        let seconds = start.elapsed().as_secs_f64();
        let cpu_seconds = cpu_start.zip(process_cpu_seconds()).map(|(a, b)| b - a);
        result.attributes = images[0].attributes.clone();
        // The features' cost (aov-write's seconds) is part of the denoised image's cost.
        let mut feature_seconds = 0.0f64;
        for (image, path) in images.iter().zip(&job.features).skip(1) {
            let s = header::parse::<f64>(path, &image.attributes, header::SECONDS)?;
            feature_seconds = feature_seconds.max(s.unwrap_or(0.0));
        }
        result.set_attribute(header::FEATURE_SECONDS, feature_seconds);
        result.set_attribute(header::DENOISER, &model_name);
        result.set_attribute(header::DENOISE_SECONDS, seconds);
        if let Some(cpu) = cpu_seconds {
            result.set_attribute(header::DENOISE_CPU_SECONDS, cpu);
        }
        write_rgb_to(&mut plan, &job.out, &result)?;
        if let Some(p) = &job.preview {
            write_preview_png_auto_to(&mut plan, p, &result)?;
        }
        done.push(format!(
            "denoise: {} ({w}x{h}, {:.1} ms/megapixel)",
            job.out.display(),
            1e3 * seconds / (w * h) as f64 * 1e6
        ));
    }
    progress.finish();
    // All outputs of the run appear together, or none (a later failure leaves nothing).
    plan.commit()?;
    for line in done {
        console.note(line);
    }
    Ok(())
}

/// Refuses an albedo or normal image (`images[i]` of feature `features[i]`, read from
/// `paths[i]`) whose header records fewer samples per pixel than `required`, the model's
/// `luxest.feature_samples`: a model trained on antialiased features only (aov-write
/// --min-samples) denoises the features of a 1-spp image poorly, several dB below what it is
/// measured at (docs/measurements.md). An image without `luxest.samples` (not aov-write's) is
/// taken as it is.
pub fn check_feature_samples(
    features: &[Feature],
    images: &[RgbImage],
    paths: &[PathBuf],
    required: u64,
    model: &Path,
) -> Result<()> {
    for ((feature, image), path) in features.iter().zip(images).zip(paths) {
        if !matches!(feature, Feature::Alb | Feature::Nrm) {
            continue;
        }
        if let Some(n) = header::parse::<u64>(path, &image.attributes, header::SAMPLES)? {
            if n < required {
                return Err(Error::input(
                    path,
                    format!(
                        "{} feature of {n} samples per pixel, but the model {} takes features \
                         of at least {required} (write them with aov-write --min-samples \
                         {required})",
                        feature.name(),
                        model.display()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The plan of denoising `images` images of `w` x `h` pixels (the first image's size).
fn work_plan(
    denoiser: &mut Denoiser,
    tiling: Tiling,
    (w, h): (usize, usize),
    images: usize,
    threads: usize,
) -> Result<luxest_io::limits::WorkPlan> {
    let start = Instant::now();
    let per_pixel = denoiser.seconds_per_pixel(tiling)?;
    let pixels = (w * h * images) as f64;
    Ok(luxest_io::limits::WorkPlan {
        stage: "denoise".into(),
        work: format!("{images} image(s) of {w}x{h} pixels (the first one's size)"),
        units: pixels,
        unit: "pixels",
        seconds: pixels * per_pixel,
        threads,
        memory_bytes: tiling.memory(w, h),
        calibration_seconds: start.elapsed().as_secs_f64(),
        levers: "the images given and --tile".into(),
    })
}

/// The CPU seconds (user + system, all threads) this process has used so far, from the clock
/// Python's `time.process_time` reads too (`CLOCK_PROCESS_CPUTIME_ID`); None outside 64-bit Linux.
fn process_cpu_seconds() -> Option<f64> {
    #[cfg(all(target_os = "linux", target_pointer_width = "64"))]
    {
        use std::os::raw::{c_int, c_long};
        #[repr(C)]
        struct Timespec {
            tv_sec: c_long,
            tv_nsec: c_long,
        }
        extern "C" {
            fn clock_gettime(clock: c_int, time: *mut Timespec) -> c_int;
        }
        // Linux's time.h: CLOCK_PROCESS_CPUTIME_ID 2.
        const CLOCK_PROCESS_CPUTIME_ID: c_int = 2;
        let mut t = Timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: clock_gettime writes one timespec (two longs on 64-bit Linux) through the
        // pointer, which points at one.
        let ok = unsafe { clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &mut t) } == 0;
        ok.then_some(t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64)
    }
    #[cfg(not(all(target_os = "linux", target_pointer_width = "64")))]
    None
}

/// Lets the C allocator keep and reuse the memory that is freed, instead of returning every large
/// block to the kernel (glibc maps blocks of more than 128 KiB to 32 MiB afresh and unmaps them
/// when freed, and trims the heap's top): each image, tile and ONNX Runtime arena region is
/// then page-faulted in once per process rather than once per allocation. A 1024² image took
/// about 250 000 page faults of 4 KiB without it and 208 000 with it; their kernel time is part
/// of the CPU time per megapixel compared with OIDN's (docs/measurements.md, *denoise*). The
/// process is short-lived and its peak memory is unchanged: nothing freed is lost, only kept.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn mallopt(
                param: std::os::raw::c_int,
                value: std::os::raw::c_int,
            ) -> std::os::raw::c_int;
        }
        // glibc's malloc.h: M_TRIM_THRESHOLD -1, M_MMAP_THRESHOLD -3.
        const M_TRIM_THRESHOLD: std::os::raw::c_int = -1;
        const M_MMAP_THRESHOLD: std::os::raw::c_int = -3;
        // SAFETY: mallopt only changes the allocator's thresholds; it is called before any
        // other thread exists. Its result (0 where a value is refused) changes nothing else.
        unsafe {
            mallopt(M_MMAP_THRESHOLD, std::os::raw::c_int::MAX);
            mallopt(M_TRIM_THRESHOLD, std::os::raw::c_int::MAX);
        }
    }
}

/// Where `noisy`'s features are (checked to be files) and where its outputs go.
fn job(args: &Args, denoiser: &Denoiser, model_name: &str, noisy: &Path) -> Result<Job> {
    let out = match (&args.out, &args.out_dir) {
        (Some(o), _) => o.clone(),
        (None, dir) => {
            let o = output_path(noisy).ok_or_else(|| {
                Error::Usage(format!(
                    "{}: input name must end in .hdr.exr (or give -o)",
                    noisy.display()
                ))
            })?;
            match dir {
                Some(d) => d.join(o.file_name().unwrap_or_default()),
                None => o,
            }
        }
    };
    let mut features = Vec::new();
    for &feature in denoiser.features() {
        let path = match feature {
            Feature::Hdr => Some(noisy.to_path_buf()),
            _ => args
                .feature(feature)
                .cloned()
                .or_else(|| feature_path(args.features_of.as_deref().unwrap_or(noisy), feature)),
        };
        let path = path.ok_or_else(|| {
            Error::input(
                noisy,
                format!(
                    "the model needs the {} feature, found next to a noisy image named \
                     <img>.hdr.exr (this name is not); name it with --{}",
                    feature.name(),
                    feature.name()
                ),
            )
        })?;
        if path.is_dir() {
            return Err(Error::input(
                &path,
                format!("is a directory, not the {} feature image", feature.name()),
            ));
        }
        if !path.is_file() {
            return Err(Error::input(
                &path,
                format!(
                    "missing {} feature image (the model {model_name} takes {})",
                    feature.name(),
                    names(denoiser.features())
                ),
            ));
        }
        features.push(path);
    }
    let preview = args.preview.then(|| preview_path(&out));
    Ok(Job {
        noisy: noisy.to_path_buf(),
        features,
        out,
        preview,
    })
}

/// Reads an input image: finite and not empty, naming the file otherwise.
fn read_checked(path: &Path) -> Result<RgbImage> {
    let image = read_rgb_finite(path)?;
    if image.width == 0 || image.height == 0 {
        return Err(Error::input(path, "image is empty"));
    }
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn features_of_fewer_samples_than_the_model_takes_are_refused() {
        let image = |samples: Option<u64>| {
            let mut img = RgbImage::new(2, 2);
            if let Some(n) = samples {
                img.set_attribute(header::SAMPLES, n);
            }
            img
        };
        let features = [Feature::Hdr, Feature::Alb, Feature::Nrm, Feature::Emi];
        let paths: Vec<PathBuf> = ["a.hdr.exr", "a.alb.exr", "a.nrm.exr", "a.emi.exr"]
            .map(PathBuf::from)
            .to_vec();
        let model = Path::new("m.onnx");
        // A 1-spp image: its own features (1 sample), antialiased ones (16), the emission of
        // the image's own sample count whatever the model.
        let own = [
            image(Some(1)),
            image(Some(1)),
            image(Some(1)),
            image(Some(1)),
        ];
        let antialiased = [
            image(Some(1)),
            image(Some(16)),
            image(Some(16)),
            image(Some(1)),
        ];
        assert!(check_feature_samples(&features, &own, &paths, 1, model).is_ok());
        assert!(check_feature_samples(&features, &antialiased, &paths, 16, model).is_ok());
        let err = check_feature_samples(&features, &own, &paths, 16, model)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("a.alb.exr") && err.contains("alb feature of 1 samples"),
            "{err}"
        );
        assert!(
            err.contains("--min-samples 16") && !err.contains('\n') && !err.contains("  "),
            "{err}"
        );
        // The normal alone short of the count; an image without the header is taken as it is.
        let short_normal = [image(Some(1)), image(Some(16)), image(Some(8)), image(None)];
        let err = check_feature_samples(&features, &short_normal, &paths, 16, model)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("a.nrm.exr") && err.contains("8 samples"),
            "{err}"
        );
        let unknown = [image(None), image(None), image(None), image(None)];
        assert!(check_feature_samples(&features, &unknown, &paths, 16, model).is_ok());
    }

    #[cfg(all(target_os = "linux", target_pointer_width = "64"))]
    #[test]
    fn process_cpu_seconds_counts_seconds_of_work() {
        // A busy loop of 0.3 s wall-clock gets at least a tenth of a core even on a loaded
        // machine; a clock in the wrong unit (ms, ns) would be off by orders of magnitude.
        let before = process_cpu_seconds().unwrap();
        let start = Instant::now();
        let mut x = 0u64;
        while start.elapsed().as_secs_f64() < 0.3 {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        let busy = process_cpu_seconds().unwrap() - before;
        assert!(
            (0.03..100.0).contains(&busy),
            "{busy} CPU-s in a 0.3 s busy loop"
        );
    }

    /// Without --model, the model is the working directory's models/default.onnx or else the
    /// one of the checkout two levels above the crate's directory, in that order; where
    /// neither exists, one usage error names both places.
    #[test]
    fn the_default_model_is_found_in_the_checkout_the_program_was_built_from() {
        struct Temp(PathBuf);
        impl Drop for Temp {
            fn drop(&mut self) {
                let _ = std::fs::remove_dir_all(&self.0);
            }
        }
        let tmp =
            Temp(std::env::temp_dir().join(format!("luxest-dn-default-{}", std::process::id())));
        let (cwd, root) = (tmp.0.join("cwd"), tmp.0.join("checkout"));
        let crate_dir = root.join("crates/denoise");
        std::fs::create_dir_all(&crate_dir).unwrap();
        std::fs::create_dir_all(&cwd).unwrap();
        let e = default_model(&cwd, &crate_dir).unwrap_err();
        assert!(matches!(e, Error::Usage(_)));
        let msg = e.to_string();
        assert!(msg.contains(DEFAULT_MODEL), "{msg}");
        assert!(
            msg.contains(&root.join(DEFAULT_MODEL).display().to_string()),
            "{msg}"
        );
        for dir in [&root, &cwd] {
            std::fs::create_dir_all(dir.join("models")).unwrap();
            std::fs::write(dir.join(DEFAULT_MODEL), b"onnx").unwrap();
        }
        // Both have one: the working directory's wins; without it, the checkout's.
        assert_eq!(
            default_model(&cwd, &crate_dir).unwrap(),
            cwd.join(DEFAULT_MODEL)
        );
        std::fs::remove_file(cwd.join(DEFAULT_MODEL)).unwrap();
        assert_eq!(
            default_model(&cwd, &crate_dir).unwrap(),
            root.join(DEFAULT_MODEL)
        );
        // This build's own checkout has the committed model (the test runs in crates/denoise,
        // which has none).
        let built = default_model(Path::new(""), Path::new(env!("CARGO_MANIFEST_DIR"))).unwrap();
        assert!(built.is_absolute() && built.ends_with(DEFAULT_MODEL) && built.is_file());
    }
}
