//! Test helpers: hermetic temporary directories and running a stage in-process.

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

/// Runs `denoise` in-process.
pub fn denoise(args: &[&str]) -> StageResult {
    run_stage("denoise", args, denoise::cli::run)
}

/// Runs `evaluate` in-process.
pub fn evaluate(args: &[&str]) -> StageResult {
    run_stage("evaluate", args, evaluate::cli::run)
}
