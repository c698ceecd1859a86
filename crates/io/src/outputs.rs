//! The one place where a stage decides what it will write: an [`OutputPlan`] is made from *all*
//! of a run's inputs and outputs before anything is written, and every output goes through it.
//!
//! What the plan refuses, before any work is done:
//! - an output that is the same file as an input (same path after resolving `.`, `..` and
//!   symbolic links, or the same device and inode, so a hard link counts too);
//! - two outputs that are the same file (`-o o.exr --stderr-out o.exr`, also `a/./o.exr`);
//! - an output path that exists and is not a regular file: a directory, a device node such as
//!   `/dev/null`, a FIFO, a socket or a symbolic link. A rename swaps *any* directory entry, so
//!   without this check a stage run as root would replace the system's null device;
//! - (with [`path_component`]) a default output name built from a scene's `name` that would
//!   leave the output root (`"../../x"`, `"/tmp/x"`, `""`).
//!
//! How it writes: each output goes to a hidden temporary `.NAME.tmp-PID-N@HOST` beside its final
//! path (the same file system, so the final rename is atomic). [`OutputPlan::commit`] renames
//! them all only after every one of them was written, so a run whose second output fails leaves
//! neither (the temporaries are removed, also when the plan is dropped uncommitted; a write
//! beyond `ulimit -f` is such a failure, see `cli::main`). A process killed mid-write (SIGKILL)
//! cannot clean up: every later plan reading from or writing into the same directory removes
//! the temporaries of processes of this host that no longer exist (`/proc/PID`). A temporary of
//! another host (a shared file system under a cluster's jobs) is never removed: whether its
//! process lives cannot be told from here.

use crate::error::{Error, Result};
use std::io::Write;
use std::os::unix::fs::MetadataExt;
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The identity of a path: its normalised absolute form and, when it exists, (device, inode).
#[derive(Clone, Debug)]
struct Identity {
    normal: PathBuf,
    inode: Option<(u64, u64)>,
}

impl Identity {
    fn of(path: &Path) -> Identity {
        Identity {
            normal: normalise(path),
            inode: std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino())),
        }
    }
    fn same_as(&self, other: &Identity) -> bool {
        self.normal == other.normal
            || matches!((self.inode, other.inode), (Some(a), Some(b)) if a == b)
    }
}

/// The absolute form of `path` with `.` and `..` resolved and symbolic links of its existing part
/// resolved (as the kernel would: the longest existing prefix is canonicalised, the rest, which
/// does not exist and so holds no links, is normalised lexically).
pub fn normalise(path: &Path) -> PathBuf {
    let absolute = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()
            .unwrap_or_else(|_| PathBuf::from("/"))
            .join(path)
    };
    let components: Vec<Component> = absolute.components().collect();
    for split in (1..=components.len()).rev() {
        let prefix: PathBuf = components[..split].iter().collect();
        if let Ok(mut resolved) = prefix.canonicalize() {
            for c in &components[split..] {
                match c {
                    Component::ParentDir => {
                        resolved.pop();
                    }
                    Component::Normal(n) => resolved.push(n),
                    _ => {}
                }
            }
            return resolved;
        }
    }
    absolute
}

/// What kind of thing, other than a regular file, `path` names; `None` if it is a regular file or
/// does not exist.
fn non_regular_kind(path: &Path) -> Option<&'static str> {
    crate::fsio::non_regular(std::fs::symlink_metadata(path).ok()?.file_type())
}

/// The nearest existing ancestor directory entry of `path` that is not a directory (so the
/// output's directory cannot be created), with what it is.
fn blocking_ancestor(path: &Path) -> Option<(PathBuf, &'static str)> {
    for dir in path.ancestors().skip(1) {
        if dir.as_os_str().is_empty() {
            return None;
        }
        match std::fs::metadata(dir) {
            Ok(m) if m.is_dir() => return None,
            Ok(_) => {
                let kind = non_regular_kind(dir).unwrap_or("a regular file");
                return Some((dir.to_path_buf(), kind));
            }
            Err(_) => continue,
        }
    }
    None
}

/// Checks that `value` (the scene file's `field`) can be one component of a default output path:
/// not empty, not `.` or `..`, without path separators or control characters. The error names
/// the file and the field.
pub fn path_component<'a>(value: &'a str, source: &Path, field: &str) -> Result<&'a str> {
    let problem = if value.is_empty() {
        Some("is empty".to_string())
    } else if value == "." || value == ".." {
        Some(format!("{value:?} would leave the output directory"))
    } else if value.contains('/') || value.contains('\\') {
        Some(format!(
            "{value:?} contains a path separator; it names files in the output directory, so it \
             must be a plain name"
        ))
    } else if value.chars().any(|c| c.is_control()) {
        Some(format!("{value:?} contains a control character"))
    } else {
        None
    };
    match problem {
        Some(p) => Err(Error::at(source, field, p)),
        None => Ok(value),
    }
}

/// The formats a stage writes to a file the user names, each with the one file-name ending that
/// names it. A stage checks every such path with [`Format::check`] before it does any work, so
/// that `-o x.png` on a stage that writes OpenEXR is refused instead of producing an EXR named
/// `.png` (which viewers and the next stage would misread).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// An OpenEXR image (f32, ZIP scanlines).
    Exr,
    /// An 8-bit sRGB PNG image.
    Png,
    /// A RON document.
    Ron,
    /// A CSV table.
    Csv,
    /// A compiled scene.
    Lxs,
}

impl Format {
    /// Every format, for the prefix check.
    pub const ALL: [Format; 5] = [
        Format::Exr,
        Format::Png,
        Format::Ron,
        Format::Csv,
        Format::Lxs,
    ];

    /// The file-name ending, with its dot.
    pub fn ending(self) -> &'static str {
        match self {
            Format::Exr => ".exr",
            Format::Png => ".png",
            Format::Ron => ".ron",
            Format::Csv => ".csv",
            Format::Lxs => ".lxs",
        }
    }

    /// What a file of this format is, for messages.
    pub fn description(self) -> &'static str {
        match self {
            Format::Exr => "an OpenEXR image",
            Format::Png => "a PNG image",
            Format::Ron => "a RON document",
            Format::Csv => "a CSV table",
            Format::Lxs => "a compiled scene",
        }
    }

    /// The format whose ending `path`'s file name has (ASCII case ignored), if any.
    pub fn of(path: &Path) -> Option<Format> {
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        Format::ALL
            .into_iter()
            .find(|f| name.len() > f.ending().len() && name.ends_with(f.ending()))
    }

    /// Refuses `path`, given with the command-line `option`, unless its file name ends with this
    /// format's ending (ASCII case ignored): a usage error naming the option, the path and the
    /// format written.
    pub fn check(self, path: &Path, option: &str) -> Result<()> {
        if Format::of(path) == Some(self) {
            return Ok(());
        }
        Err(Error::Usage(format!(
            "{option} {}: this writes {}; name the file *{}",
            path.display(),
            self.description(),
            self.ending()
        )))
    }
}

/// Refuses an output *prefix* (given with `option`; the stage appends `_<level>.<kind>.exr`, and
/// `example` is such a file name) that has no file-name part (`..`, `/`), names a directory
/// (`out/`, or an existing one: `-o out/` wrote `out_000016spp.hdr.exr` beside `out`, not in
/// it) or whose file name already ends like a file of one of the [`Format`]s (`-o out/img.exr`
/// would write `out/img.exr_000016spp.hdr.exr`): none is what the user asked for.
pub fn check_prefix(prefix: &Path, option: &str, example: &Path) -> Result<()> {
    let problem = if prefix.file_name().is_none() {
        "has no file-name part to prefix the file names with".to_string()
    } else if prefix.to_string_lossy().ends_with('/') || prefix.is_dir() {
        "names a directory".to_string()
    } else if let Some(f) = Format::of(prefix) {
        format!("ends in {}", f.ending())
    } else {
        return Ok(());
    };
    Err(Error::Usage(format!(
        "{option} {}: {problem}, but it is a prefix (of file names such as {}); give a prefix \
         such as out/img",
        prefix.display(),
        example.display()
    )))
}

/// A temporary written and waiting for [`OutputPlan::commit`].
#[derive(Debug)]
struct Staged {
    temp: PathBuf,
    dest: PathBuf,
}

/// All outputs of one run: checked against each other and the inputs, written to temporaries,
/// committed together. See the module documentation.
#[derive(Debug)]
pub struct OutputPlan {
    inputs: Vec<(PathBuf, Identity)>,
    outputs: Vec<(PathBuf, Identity)>,
    staged: Vec<Staged>,
    /// Directories this plan created for outputs not yet committed, outermost first: removed
    /// again (when empty) if the run fails, so that a failed run leaves no empty folders.
    made_dirs: Vec<PathBuf>,
}

/// Inode identity printed as "the same file as".
fn describe_clash(a: &Path, b: &Path) -> String {
    if a == b {
        "is given twice".to_string()
    } else {
        format!("is the same file as {}", b.display())
    }
}

impl OutputPlan {
    /// Checks the run's outputs against its inputs and each other and against non-regular
    /// targets (see the module documentation), and removes stale temporaries of dead processes
    /// in the output directories. Nothing is written yet.
    pub fn new<I, O>(inputs: I, outputs: O) -> Result<OutputPlan>
    where
        I: IntoIterator,
        I::Item: AsRef<Path>,
        O: IntoIterator,
        O::Item: AsRef<Path>,
    {
        let inputs: Vec<(PathBuf, Identity)> = inputs
            .into_iter()
            .map(|p| (p.as_ref().to_path_buf(), Identity::of(p.as_ref())))
            .collect();
        // A run in a directory, reading or writing, clears the temporaries that runs killed
        // there left behind (its output directories are cleared as they are planned).
        let mut cleared: Vec<&Path> = Vec::new();
        for dir in inputs.iter().filter_map(|(_, id)| id.normal.parent()) {
            if !cleared.contains(&dir) {
                remove_stale_temporaries(dir);
                cleared.push(dir);
            }
        }
        let mut plan = OutputPlan {
            inputs,
            outputs: Vec::new(),
            staged: Vec::new(),
            made_dirs: Vec::new(),
        };
        for out in outputs {
            plan.add_output(out.as_ref())?;
        }
        Ok(plan)
    }

    /// Adds an output known only during the run (a progressive stage's final image, named by
    /// the samples it reached), with the same checks as [`OutputPlan::new`].
    pub fn add_output(&mut self, out: &Path) -> Result<()> {
        if out.as_os_str().is_empty() {
            return Err(Error::Usage("an output path is empty".into()));
        }
        if let Some(kind) = non_regular_kind(out) {
            return Err(Error::input(
                out,
                format!("output exists and is {kind}; refusing to replace it"),
            ));
        }
        if let Some((dir, kind)) = blocking_ancestor(out) {
            return Err(Error::input(
                out,
                format!(
                    "cannot create the output's directory: {} exists and is {kind}",
                    dir.display()
                ),
            ));
        }
        let id = Identity::of(out);
        if let Some((input, _)) = self.inputs.iter().find(|(_, i)| i.same_as(&id)) {
            return Err(Error::input(
                out,
                format!(
                    "output would overwrite the input {}; choose another output path",
                    input.display()
                ),
            ));
        }
        if let Some((other, _)) = self.outputs.iter().find(|(_, i)| i.same_as(&id)) {
            return Err(Error::input(
                out,
                format!(
                    "two outputs of this run would be the same file: {} {}",
                    out.display(),
                    describe_clash(out, other)
                ),
            ));
        }
        if let Some(dir) = id.normal.parent() {
            if !self
                .outputs
                .iter()
                .any(|(_, o)| o.normal.parent() == Some(dir))
            {
                remove_stale_temporaries(dir);
            }
        }
        self.outputs.push((out.to_path_buf(), id));
        Ok(())
    }

    /// The planned outputs, in the order given.
    pub fn outputs(&self) -> impl Iterator<Item = &Path> {
        self.outputs.iter().map(|(p, _)| p.as_path())
    }

    /// Writes the planned output `path` to its temporary: `fill` produces the content. Nothing
    /// appears at `path` until [`OutputPlan::commit`].
    pub fn write(
        &mut self,
        path: &Path,
        fill: impl FnOnce(&mut dyn Write) -> Result<()>,
    ) -> Result<()> {
        let Some((dest, _)) = self.outputs.iter().find(|(p, _)| p == path) else {
            // A stage writing a file it did not plan is a bug in the stage; refuse the write so
            // that the checks above cannot be bypassed.
            return Err(Error::input(
                path,
                "internal error: output was not declared in the run's output plan",
            ));
        };
        let dest = dest.clone();
        if self.staged.iter().any(|s| s.dest == dest) {
            return Err(Error::input(
                path,
                "internal error: output written twice in one run",
            ));
        }
        if let Some(dir) = dest.parent().filter(|d| !d.as_os_str().is_empty()) {
            let mut missing: Vec<PathBuf> = dir
                .ancestors()
                .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
                .map(Path::to_path_buf)
                .collect();
            missing.reverse();
            let made = std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e));
            // Recorded even on failure: whatever part of the chain was made is removed again.
            self.made_dirs.extend(missing);
            made?;
        }
        let temp = temporary_for(&dest);
        let result = (|| {
            let file = std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&temp)
                .map_err(|e| Error::io(&dest, e))?;
            let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
            fill(&mut w)?;
            let file = w
                .into_inner()
                .map_err(|e| Error::io(&dest, e.into_error()))?;
            file.sync_all().map_err(|e| Error::io(&dest, e))
        })();
        // Recorded even on failure, so that the temporary is removed with the others.
        self.staged.push(Staged { temp, dest });
        result
    }

    /// Writes `bytes` as the planned output `path` (see [`OutputPlan::write`]).
    pub fn write_bytes(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        self.write(path, |w| w.write_all(bytes).map_err(|e| Error::io(path, e)))
    }

    /// Moves every output written so far into place. The targets are checked once more (a
    /// directory entry created meanwhile that is not a regular file is still refused) before any
    /// is renamed. The plan stays usable for outputs not yet written (a progressive stage commits
    /// each snapshot as it completes).
    pub fn commit(&mut self) -> Result<()> {
        for s in &self.staged {
            if let Some(kind) = non_regular_kind(&s.dest) {
                let e = Error::input(
                    &s.dest,
                    format!("output exists and is {kind}; refusing to replace it"),
                );
                self.discard();
                return Err(e);
            }
        }
        let staged = std::mem::take(&mut self.staged);
        // The directories now hold (or are about to hold) the committed outputs.
        let made = std::mem::take(&mut self.made_dirs);
        let mut result = Ok(());
        for s in &staged {
            if result.is_ok() {
                result = std::fs::rename(&s.temp, &s.dest).map_err(|e| Error::io(&s.dest, e));
            }
            if result.is_err() {
                let _ = std::fs::remove_file(&s.temp);
            }
        }
        if result.is_err() {
            // Nothing of this commit may stay behind: its folders go too, where empty.
            self.made_dirs = made;
            self.discard();
        }
        result
    }

    /// Removes every temporary written and not committed.
    fn discard(&mut self) {
        for s in self.staged.drain(..) {
            let _ = std::fs::remove_file(&s.temp);
        }
        // Innermost first; a directory that holds anything (a committed output, a user's
        // file written meanwhile) stays.
        for dir in self.made_dirs.drain(..).rev() {
            let _ = std::fs::remove_dir(&dir);
        }
    }
}

impl Drop for OutputPlan {
    fn drop(&mut self) {
        self.discard();
    }
}

/// The temporary `.NAME.tmp-PID-N@HOST` beside `dest`, unique within the process (and, with
/// the host, among the hosts sharing a file system).
fn temporary_for(dest: &Path) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let mut name = dest
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let n = N.fetch_add(1, Ordering::Relaxed);
    let tail = match this_host() {
        Some(host) => format!(".tmp-{}-{n}@{host}", std::process::id()),
        None => format!(".tmp-{}-{n}", std::process::id()),
    };
    // File names are at most 255 bytes: a long output name is shortened in its temporary.
    while 1 + name.len() + tail.len() > 255 {
        name.pop();
    }
    dest.with_file_name(format!(".{name}{tail}"))
}

/// This host's name as temporaries carry it (`/proc/sys/kernel/hostname`, characters other
/// than letters, digits, `.`, `_` and `-` replaced by `_`, at most 64), if it can be read.
fn this_host() -> Option<&'static str> {
    static HOST: std::sync::OnceLock<Option<String>> = std::sync::OnceLock::new();
    HOST.get_or_init(|| {
        let raw = std::fs::read_to_string("/proc/sys/kernel/hostname").ok()?;
        let host: String = raw
            .trim()
            .chars()
            .take(64)
            .map(|c| {
                if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        (!host.is_empty()).then_some(host)
    })
    .as_deref()
}

/// The process id in a temporary's name `.NAME.tmp-PID`, `.NAME.tmp-PID-N` or
/// `.NAME.tmp-PID-N@HOST`, if it is one of this host's (a name without a host is taken as this
/// host's, as temporaries were named before hosts were added).
fn temporary_owner(file_name: &str) -> Option<u32> {
    if !file_name.starts_with('.') {
        return None;
    }
    let (_, tail) = file_name.rsplit_once(".tmp-")?;
    let tail = match tail.split_once('@') {
        Some((t, host)) if Some(host) == this_host() => t,
        Some(_) => return None,
        None => tail,
    };
    let pid = tail.split_once('-').map_or(tail, |(pid, n)| {
        if n.bytes().all(|b| b.is_ascii_digit()) && !n.is_empty() {
            pid
        } else {
            ""
        }
    });
    if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    pid.parse().ok()
}

/// Removes regular-file temporaries in `dir` whose writing process is gone. Only on systems with
/// `/proc` (elsewhere liveness cannot be told, and nothing is removed).
fn remove_stale_temporaries(dir: &Path) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let me = std::process::id();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temporary_owner) else {
            continue;
        };
        let is_file = entry.file_type().map(|t| t.is_file()).unwrap_or(false);
        if is_file && pid != me && !Path::new("/proc").join(pid.to_string()).exists() {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Dir(PathBuf);
    impl Dir {
        fn new(tag: &str) -> Dir {
            static N: AtomicUsize = AtomicUsize::new(0);
            let p = std::env::temp_dir().join(format!(
                "luxest-outputs-{}-{tag}-{}",
                std::process::id(),
                N.fetch_add(1, Ordering::Relaxed)
            ));
            let _ = std::fs::remove_dir_all(&p);
            std::fs::create_dir_all(&p).unwrap();
            Dir(p)
        }
        fn files(&self) -> Vec<String> {
            let mut v: Vec<String> = std::fs::read_dir(&self.0)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        }
    }
    impl Drop for Dir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    #[test]
    fn a_format_is_named_by_its_ending_alone() {
        let of = |p: &str| Format::of(Path::new(p));
        assert_eq!(of("out/img.exr"), Some(Format::Exr));
        assert_eq!(of("IMG.EXR"), Some(Format::Exr), "ASCII case is ignored");
        assert_eq!(of("a_000016spp.hdr.exr"), Some(Format::Exr));
        assert_eq!(of("x.sensors.ron"), Some(Format::Ron));
        assert_eq!(of("t.csv"), Some(Format::Csv));
        assert_eq!(of("build/a/scene.lxs"), Some(Format::Lxs));
        assert_eq!(of("p.png"), Some(Format::Png));
        // The ending alone is a hidden file's name, not a format; nor are near misses.
        for p in [".exr", "x.exr.bak", "xexr", "x.ex", "out/", "..", "/"] {
            assert_eq!(of(p), None, "{p}");
        }
        assert!(Format::Exr.check(Path::new("a/b.Exr"), "-o").is_ok());
        let e = Format::Png
            .check(Path::new("p.exr"), "--preview")
            .unwrap_err();
        assert!(matches!(e, Error::Usage(_)));
        assert_eq!(
            e.to_string(),
            "--preview p.exr: this writes a PNG image; name the file *.png"
        );
        let e = Format::Csv
            .check(Path::new("report"), "-o/--out")
            .unwrap_err();
        assert!(
            e.to_string().ends_with("a CSV table; name the file *.csv"),
            "{e}"
        );
    }

    #[test]
    fn a_prefix_must_not_end_like_a_file() {
        let example = Path::new("x_000001spp.hdr.exr");
        assert!(check_prefix(Path::new("out/img"), "-o", example).is_ok());
        assert!(check_prefix(Path::new("out/img.v2"), "-o", example).is_ok());
        let e = check_prefix(Path::new("out/img.EXR"), "-o", example).unwrap_err();
        assert!(matches!(e, Error::Usage(_)));
        assert_eq!(
            e.to_string(),
            "-o out/img.EXR: ends in .exr, but it is a prefix (of file names such as \
             x_000001spp.hdr.exr); give a prefix such as out/img"
        );
        let e = check_prefix(Path::new("a/.."), "-o", example).unwrap_err();
        assert!(e.to_string().contains("has no file-name part"), "{e}");
        for dir in [PathBuf::from("out/"), std::env::temp_dir()] {
            let e = check_prefix(&dir, "-o", example).unwrap_err();
            assert!(e.to_string().contains(": names a directory, but"), "{e}");
        }
    }

    fn err(r: Result<OutputPlan>) -> String {
        r.map(|_| ()).unwrap_err().to_string()
    }

    #[test]
    fn output_equal_to_an_input_is_refused_by_path_link_and_inode() {
        let d = Dir::new("in");
        let input = d.0.join("s.ron");
        std::fs::write(&input, "x").unwrap();
        std::fs::create_dir(d.0.join("sub")).unwrap();
        std::os::unix::fs::symlink(&d.0, d.0.join("link")).unwrap();
        std::fs::hard_link(&input, d.0.join("hard.ron")).unwrap();
        for out in [
            input.clone(),
            d.0.join("./s.ron"),
            d.0.join("sub/../s.ron"),
            d.0.join("link/s.ron"),
            d.0.join("hard.ron"),
        ] {
            let e = err(OutputPlan::new([&input], [&out]));
            assert!(e.contains("would overwrite the input"), "{out:?}: {e}");
            assert!(e.starts_with(&out.display().to_string()), "{e}");
        }
        assert_eq!(std::fs::read(&input).unwrap(), b"x");
    }

    #[test]
    fn two_outputs_naming_one_file_are_refused() {
        let d = Dir::new("outs");
        std::fs::create_dir(d.0.join("sub")).unwrap();
        std::os::unix::fs::symlink(d.0.join("sub"), d.0.join("link")).unwrap();
        let a = d.0.join("sub/o.exr");
        for b in [
            a.clone(),
            d.0.join("sub/./o.exr"),
            d.0.join("sub/../sub/o.exr"),
            d.0.join("link/o.exr"),
            d.0.join("new/../sub/o.exr"),
        ] {
            let e = err(OutputPlan::new(Vec::<PathBuf>::new(), [&a, &b]));
            assert!(e.contains("would be the same file"), "{b:?}: {e}");
        }
        assert!(OutputPlan::new(Vec::<PathBuf>::new(), [&a, &d.0.join("sub/p.exr")]).is_ok());
    }

    #[test]
    fn non_regular_targets_are_refused() {
        let d = Dir::new("nonreg");
        std::fs::create_dir(d.0.join("adir")).unwrap();
        std::fs::write(d.0.join("target"), "t").unwrap();
        std::os::unix::fs::symlink(d.0.join("target"), d.0.join("alink")).unwrap();
        let fifo = d.0.join("afifo");
        let ok = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .map(|s| s.success())
            .unwrap_or(false);
        let mut cases = vec![
            (d.0.join("adir"), "a directory"),
            (d.0.join("alink"), "a symbolic link"),
            (PathBuf::from("/dev/null"), "a device node"),
        ];
        if ok {
            cases.push((fifo, "a FIFO"));
        }
        for (path, kind) in cases {
            let e = err(OutputPlan::new(Vec::<PathBuf>::new(), [&path]));
            assert!(e.contains(kind) && e.contains("refusing"), "{path:?}: {e}");
        }
        assert_eq!(std::fs::read(d.0.join("target")).unwrap(), b"t");
    }

    #[test]
    fn outputs_under_a_file_or_device_are_refused_naming_it() {
        let d = Dir::new("under");
        std::fs::write(d.0.join("afile"), "t").unwrap();
        for (path, blocker, kind) in [
            (d.0.join("afile/x.csv"), d.0.join("afile"), "a regular file"),
            (
                d.0.join("afile/sub/x.csv"),
                d.0.join("afile"),
                "a regular file",
            ),
            (
                PathBuf::from("/dev/null/x"),
                PathBuf::from("/dev/null"),
                "a device node",
            ),
        ] {
            let e = err(OutputPlan::new(Vec::<PathBuf>::new(), [&path]));
            let want = format!(
                "cannot create the output's directory: {} exists and is {kind}",
                blocker.display()
            );
            assert!(e.contains(&want), "{path:?}: {e}");
        }
        // A directory that does not exist yet is fine: the plan creates it when writing.
        OutputPlan::new(Vec::<PathBuf>::new(), [d.0.join("new/dir/x.csv")]).unwrap();
        assert_eq!(std::fs::read(d.0.join("afile")).unwrap(), b"t");
    }

    #[test]
    fn outputs_are_committed_together_or_not_at_all() {
        let d = Dir::new("commit");
        let (a, b) = (d.0.join("a.ron"), d.0.join("b.csv"));
        {
            let mut plan = OutputPlan::new(Vec::<PathBuf>::new(), [&a, &b]).unwrap();
            plan.write_bytes(&a, b"first").unwrap();
            assert!(!a.exists(), "nothing appears before commit");
            let r = plan.write(&b, |_| Err(Error::input(&b, "simulated failure")));
            assert!(r.is_err());
            // The stage returns its error; the plan is dropped uncommitted.
        }
        assert_eq!(d.files(), Vec::<String>::new(), "nothing left behind");
        let mut plan = OutputPlan::new(Vec::<PathBuf>::new(), [&a, &b]).unwrap();
        plan.write_bytes(&a, b"first").unwrap();
        plan.write_bytes(&b, b"second").unwrap();
        plan.commit().unwrap();
        assert_eq!(d.files(), vec!["a.ron", "b.csv"]);
        assert_eq!(std::fs::read(&b).unwrap(), b"second");
        // An undeclared output is refused.
        let mut plan = OutputPlan::new(Vec::<PathBuf>::new(), [&a]).unwrap();
        assert!(plan.write_bytes(&d.0.join("c"), b"x").is_err());
    }

    #[test]
    fn a_failed_run_leaves_no_folders_it_made() {
        let d = Dir::new("folders");
        let (a, b) = (d.0.join("new/deeper/a.ron"), d.0.join("kept/b.csv"));
        std::fs::create_dir(d.0.join("kept")).unwrap();
        {
            let mut plan = OutputPlan::new(Vec::<PathBuf>::new(), [&a, &b]).unwrap();
            plan.write_bytes(&a, b"first").unwrap();
            assert!(d.0.join("new/deeper").is_dir());
            let r = plan.write(&b, |_| Err(Error::input(&b, "simulated failure")));
            assert!(r.is_err());
        }
        // The folders the plan made are gone; the one that was there stays.
        assert_eq!(d.files(), vec!["kept"]);
        assert_eq!(std::fs::read_dir(d.0.join("kept")).unwrap().count(), 0);
        // A committed run keeps its folders, also when a later plan into them fails.
        let mut plan = OutputPlan::new(Vec::<PathBuf>::new(), [&a]).unwrap();
        plan.write_bytes(&a, b"first").unwrap();
        plan.commit().unwrap();
        let c = d.0.join("new/deeper/c.ron");
        let mut plan = OutputPlan::new(Vec::<PathBuf>::new(), [&c]).unwrap();
        assert!(plan
            .write(&c, |_| Err(Error::input(&c, "simulated failure")))
            .is_err());
        drop(plan);
        assert_eq!(std::fs::read(&a).unwrap(), b"first");
        // A commit refused (a target became a FIFO meanwhile) removes the folders it made
        // where they are empty; this one holds the FIFO, a file not the run's, and stays.
        let e = d.0.join("other/e.ron");
        let mut plan = OutputPlan::new(Vec::<PathBuf>::new(), [&e]).unwrap();
        plan.write_bytes(&e, b"x").unwrap();
        let f = d.0.join("other2/f.ron");
        let mut plan2 = OutputPlan::new(Vec::<PathBuf>::new(), [&f]).unwrap();
        plan2.write_bytes(&f, b"x").unwrap();
        std::fs::create_dir(&f).unwrap();
        assert!(plan2.commit().is_err());
        assert!(d.0.join("other2/f.ron").is_dir(), "the user's entry stays");
        drop(plan);
        assert!(
            !d.0.join("other").exists(),
            "the uncommitted plan's folder is gone"
        );
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_removed() {
        let d = Dir::new("stale");
        // PIDs above the kernel's maximum (4194304) cannot be alive.
        std::fs::write(d.0.join(".o.exr.tmp-99999999"), "old").unwrap();
        std::fs::write(d.0.join(".o.exr.tmp-99999998-3"), "old").unwrap();
        let live = format!(".o.exr.tmp-{}-0", std::process::id());
        std::fs::write(d.0.join(&live), "mine").unwrap();
        std::fs::write(d.0.join("keep.tmp-1x"), "user file").unwrap();
        // Another host's temporary on a shared file system: its process may well live.
        let remote = ".o.exr.tmp-99999997-0@another-host".to_string();
        std::fs::write(d.0.join(&remote), "theirs").unwrap();
        let _plan = OutputPlan::new(Vec::<PathBuf>::new(), [d.0.join("o.exr")]).unwrap();
        assert_eq!(
            d.files(),
            vec![live.clone(), remote.clone(), "keep.tmp-1x".to_string()]
        );
        // A run that only reads from a directory clears it too.
        let host = this_host().unwrap();
        let dead = format!(".r.ron.tmp-99999996-0@{host}");
        std::fs::write(d.0.join(&dead), "old").unwrap();
        let elsewhere = Dir::new("stale-out");
        let _plan =
            OutputPlan::new([d.0.join("keep.tmp-1x")], [elsewhere.0.join("o.ron")]).unwrap();
        assert_eq!(d.files(), vec![live, remote, "keep.tmp-1x".to_string()]);
        assert_eq!(temporary_owner(".a.tmp-12"), Some(12));
        assert_eq!(temporary_owner(".a.tmp-12-7"), Some(12));
        assert_eq!(temporary_owner("a.tmp-12"), None);
        assert_eq!(temporary_owner(".a.tmp-12x"), None);
        let host = this_host().unwrap();
        assert_eq!(temporary_owner(&format!(".a.tmp-12-7@{host}")), Some(12));
        assert_eq!(temporary_owner(".a.tmp-12-7@another-host"), None);
        let t = temporary_for(&d.0.join("o.exr"));
        let t = t.file_name().unwrap().to_str().unwrap();
        assert_eq!(temporary_owner(t), Some(std::process::id()), "{t}");
        let long = temporary_for(&d.0.join("x".repeat(255)));
        assert!(long.file_name().unwrap().len() <= 255);
    }

    #[test]
    fn scene_names_must_be_plain_components() {
        let src = Path::new("scenes/a.ron");
        for bad in [
            "",
            ".",
            "..",
            "../../escaped",
            "/tmp/x",
            "a/b",
            "a\\b",
            "a\nb",
        ] {
            let e = path_component(bad, src, "name").unwrap_err().to_string();
            assert!(e.starts_with("scenes/a.ron: name: "), "{bad:?}: {e}");
        }
        assert_eq!(
            path_component("cornell-box", src, "name").unwrap(),
            "cornell-box"
        );
    }
}
