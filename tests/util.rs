//! Test helpers: hermetic temporary directories and running a stage in-process.

use luxest_io::sensors::SensorResults;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh directory under the system temp dir, removed when dropped.
pub struct TempDir(PathBuf);

impl TempDir {
    pub fn new(tag: &str) -> TempDir {
        static N: AtomicUsize = AtomicUsize::new(0);
        let n = N.fetch_add(1, Ordering::SeqCst);
        let p = std::env::temp_dir().join(format!("luxest-it-{}-{tag}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        TempDir(p)
    }
    pub fn path(&self) -> &Path {
        &self.0
    }
    pub fn write(&self, name: &str, content: impl AsRef<[u8]>) -> PathBuf {
        let p = self.0.join(name);
        if let Some(d) = p.parent() {
            std::fs::create_dir_all(d).unwrap();
        }
        std::fs::write(&p, content).unwrap();
        p
    }
    /// Every file in the directory tree (to prove that nothing was left behind).
    pub fn files(&self) -> Vec<PathBuf> {
        fn walk(d: &Path, out: &mut Vec<PathBuf>) {
            for e in std::fs::read_dir(d).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    walk(&p, out)
                } else {
                    out.push(p)
                }
            }
        }
        let mut v = Vec::new();
        walk(&self.0, &mut v);
        v.sort();
        v
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The repository root (this package's manifest directory).
/// What an in-process stage run returns: `Ok` or its exit code and one-line message.
pub type StageResult = Result<(), (u8, String)>;

pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs a stage's `run` in-process on `args` (program name excluded) after parsing them like
/// its binary; returns the error, if any, rendered as the binary would print it, with its exit
/// code.
fn run_stage<A: clap::Parser>(
    program: &str,
    args: &[&str],
    run: impl FnOnce(A) -> luxest_io::Result<()>,
) -> StageResult {
    let argv = std::iter::once(program).chain(args.iter().copied());
    let parsed = luxest_io::cli::parse::<A>(argv).map_err(|e| (e.exit_code(), e.to_string()))?;
    match parsed {
        None => Ok(()),
        Some(a) => run(a).map_err(|e| (e.exit_code(), e.to_string())),
    }
}

/// Runs `scene-compile` in-process (see [`run_stage`]).
pub fn scene_compile(args: &[&str]) -> StageResult {
    run_stage("scene-compile", args, scene_compile::run)
}

/// Runs `estimate` in-process.
pub fn estimate(args: &[&str]) -> StageResult {
    run_stage("estimate", args, estimate::run)
}

/// Compiles RON scene text into `dir/name.lxs` through the scene-compile stage.
pub fn compile_text(dir: &TempDir, name: &str, text: &str) -> PathBuf {
    let ron = dir.write(&format!("{name}.ron"), text);
    let out = dir.path().join(format!("{name}.lxs"));
    scene_compile(&[ron.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]).unwrap();
    out
}

/// Runs `estimate sensors` on the compiled scene `lxs` with `paths` light paths (and `extra`
/// arguments), writing `<lxs stem>.sensors.ron` beside it; returns the results read back.
pub fn estimate_sensors(lxs: &Path, paths: &str, extra: &[&str]) -> SensorResults {
    let out = lxs.with_extension("sensors.ron");
    let mut args = vec![
        "sensors",
        lxs.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--paths",
        paths,
    ];
    args.extend_from_slice(extra);
    estimate(&args).unwrap();
    SensorResults::read_ron(&out).unwrap()
}

/// Runs `denoise` in-process.
pub fn denoise(args: &[&str]) -> StageResult {
    run_stage("denoise", args, denoise::cli::run)
}

/// Runs `evaluate` in-process.
pub fn evaluate(args: &[&str]) -> StageResult {
    run_stage("evaluate", args, evaluate::cli::run)
}

/// A stage run as a process of its own, for the tests that kill it, limit its resources or read
/// its stderr: this test binary run again on the ignored test [`stage_child`], which runs
/// `stage` (`estimate`, `scene-compile`, `denoise`, `report`, ...) on `args` as the stage's
/// binary does (`luxest_io::cli::exit_status`: the same process setup, messages and exit
/// status), or a test helper named `slow-writer` (see [`stage_child`]).
pub fn stage_process(stage: &str, args: &[&str]) -> std::process::Command {
    limited_stage_process("", stage, args)
}

/// [`stage_process`] under the shell's resource limits `limits` (`-f 4`: files of at most four
/// blocks; `-v 4194304`: 4 GiB of address space), set in the child before it starts.
pub fn limited_stage_process(limits: &str, stage: &str, args: &[&str]) -> std::process::Command {
    let exe = std::env::current_exe().unwrap();
    let harness = [
        "--exact",
        "util::stage_child",
        "--ignored",
        "--nocapture",
        "--test-threads",
        "1",
        "--quiet",
    ];
    let mut c = if limits.is_empty() {
        let mut c = std::process::Command::new(exe);
        c.args(harness);
        c
    } else {
        let mut c = std::process::Command::new("sh");
        c.arg("-c")
            .arg(format!("ulimit {limits} && exec \"$0\" \"$@\""))
            .arg(exe)
            .args(harness);
        c
    };
    c.env("LUXEST_TEST_STAGE", stage)
        .env("LUXEST_TEST_ARGS", args.join("\u{1f}"))
        .stdout(std::process::Stdio::null());
    c
}

/// The child of [`stage_process`] (does nothing when run otherwise). `slow-writer OUT MARKER`
/// writes the first bytes of OUT through an output plan, creates MARKER and sleeps a minute
/// before finishing: a process caught mid-write, for the tests that kill it there.
#[test]
#[ignore = "run by util::stage_process in a process of its own"]
fn stage_child() {
    let Ok(stage) = std::env::var("LUXEST_TEST_STAGE") else {
        return;
    };
    let args = std::env::var("LUXEST_TEST_ARGS").unwrap_or_default();
    let args: Vec<&str> = args.split('\u{1f}').filter(|a| !a.is_empty()).collect();
    let argv = std::iter::once(stage.as_str()).chain(args.iter().copied());
    use luxest_io::cli::exit_status;
    let code = match stage.as_str() {
        "estimate" => exit_status(argv, estimate::run),
        "scene-compile" => exit_status(argv, scene_compile::run),
        "denoise" => exit_status(argv, denoise::cli::run),
        "report" => exit_status(argv, report::cli::run),
        "evaluate" => exit_status(argv, evaluate::cli::run),
        "trace" => exit_status(argv, trace::run),
        "aov-write" => exit_status(argv, aov_write::run),
        "slow-writer" => {
            let (out, marker) = (Path::new(args[0]), Path::new(args[1]));
            let mut plan =
                luxest_io::outputs::OutputPlan::new(Vec::<PathBuf>::new(), [out]).unwrap();
            plan.write(out, |w| {
                w.write_all(b"the first half").unwrap();
                w.flush().unwrap();
                std::fs::write(marker, "writing").unwrap();
                std::thread::sleep(std::time::Duration::from_secs(60));
                Ok(())
            })
            .unwrap();
            plan.commit().unwrap();
            0
        }
        other => panic!("no stage {other}"),
    };
    std::process::exit(code.into());
}

/// Runs `report` in-process.
pub fn report(args: &[&str]) -> StageResult {
    run_stage("report", args, report::cli::run)
}
