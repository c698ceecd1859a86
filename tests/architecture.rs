//! Tidy tests of the workspace's architecture (in the spirit of rust-analyzer's): the crate
//! graph's invariants and the one-place rule for contracts, checked on every `cargo test`.
//!
//! - No stage crate depends on another stage crate: what two stages share lives in
//!   `luxest-io` (contracts), `luxest-render` (rendering) or `luxest-exact` (exact solutions).
//! - `denoise` and `evaluate` depend, even transitively, on neither `luxest-render` nor Embree,
//!   so a researcher who swaps the tracer builds them without Embree installed.
//! - `luxest-io` and `luxest-exact` link no Embree.
//! - No Rust source outside `crates/io/src/header.rs` spells a header key (a string literal
//!   opening with `luxest.`): every reader and writer goes through `luxest_io::header`.
//! - No library code outside `crates/io/src/naming.rs` composes a file name of the contract
//!   (`<name>_<spp, 6 digits>spp.<kind>.exr`, `_ref.`, `le.`, `.sensors.ron`): every stage goes
//!   through `luxest_io::naming`.
//! - Every stage binary is the three-line `main` over its library and `luxest_io::cli::main`,
//!   so all stages share one exit-code and error convention.
//! - Every library source file opens with a `//!` module doc.
//!
//! The crate graph is read from `Cargo.lock`, which cargo brings up to date with every
//! `Cargo.toml` before it builds this test, so the check costs no build and no network.

use crate::util::repo_root;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The stage crates: one binary each, swappable through the Makefile's variables.
const STAGES: [&str; 7] = [
    "scene-compile",
    "trace",
    "aov-write",
    "estimate",
    "denoise",
    "evaluate",
    "report",
];

/// Package name -> names of its dependencies, from `Cargo.lock`.
fn lock_graph() -> BTreeMap<String, Vec<String>> {
    let text = std::fs::read_to_string(repo_root().join("Cargo.lock")).unwrap();
    let mut graph = BTreeMap::new();
    for block in text.split("[[package]]").skip(1) {
        let mut name = None;
        let mut deps = Vec::new();
        let mut in_deps = false;
        for line in block.lines().map(str::trim) {
            if let Some(v) = line.strip_prefix("name = ") {
                name = Some(v.trim_matches('"').to_string());
            } else if line.starts_with("dependencies = [") {
                in_deps = true;
            } else if in_deps && line == "]" {
                in_deps = false;
            } else if in_deps {
                // `"name"` or `"name version"` when the lock holds several versions.
                let entry = line.trim_end_matches(',').trim_matches('"');
                deps.push(entry.split(' ').next().unwrap().to_string());
            }
        }
        graph
            .entry(name.expect("every [[package]] has a name"))
            .or_insert_with(Vec::new)
            .extend(deps);
    }
    graph
}

/// Every package `root` depends on, directly or not. The lock's lists include dev-dependencies,
/// so this is, if anything, more than the crate's library and binary link.
fn closure(graph: &BTreeMap<String, Vec<String>>, root: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut stack = vec![root.to_string()];
    while let Some(p) = stack.pop() {
        for d in graph.get(&p).into_iter().flatten() {
            if seen.insert(d.clone()) {
                stack.push(d.clone());
            }
        }
    }
    seen
}

#[test]
fn no_stage_crate_depends_on_another_stage() {
    let graph = lock_graph();
    for stage in STAGES {
        let deps = graph
            .get(stage)
            .unwrap_or_else(|| panic!("{stage} missing from Cargo.lock"));
        let bad: Vec<_> = deps
            .iter()
            .filter(|d| STAGES.contains(&d.as_str()))
            .collect();
        assert!(
            bad.is_empty(),
            "stage {stage} depends on stage(s) {bad:?}: move what they share into luxest-io, \
             luxest-render or luxest-exact"
        );
    }
}

#[test]
fn denoise_and_evaluate_build_without_embree() {
    let graph = lock_graph();
    for krate in ["denoise", "evaluate", "report", "luxest-io", "luxest-exact"] {
        let deps = closure(&graph, krate);
        assert!(
            !deps.contains("luxest-render"),
            "{krate} depends on luxest-render (and so on Embree)"
        );
        let embree: Vec<_> = deps.iter().filter(|d| d.contains("embree")).collect();
        assert!(embree.is_empty(), "{krate} links {embree:?}");
    }
    // The check can fail: the renderer does link Embree.
    assert!(closure(&graph, "luxest-render").contains("embree"));
}

/// The `.rs` files under `dir`, recursively (nothing under `fixtures/`).
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries {
        let path = entry.unwrap().path();
        if path.is_dir() {
            if path
                .file_name()
                .is_some_and(|n| n != "fixtures" && n != "target")
            {
                rust_files(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

fn workspace_rust_files() -> Vec<PathBuf> {
    let root = repo_root();
    let mut files = Vec::new();
    rust_files(&root.join("crates"), &mut files);
    rust_files(&root.join("tests"), &mut files);
    files.sort();
    assert!(files.len() > 50, "found only {} Rust files", files.len());
    files
}

#[test]
fn header_keys_are_spelled_only_in_the_header_module() {
    let root = repo_root();
    let header = root.join("crates/io/src/header.rs");
    // The needle is built so that this file does not match itself.
    let needle = format!("\"{}.", "luxest");
    let mut offenders = Vec::new();
    for path in workspace_rust_files() {
        if path == header {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        for (i, line) in text.lines().enumerate() {
            if line.contains(&needle) {
                let rel = path.strip_prefix(&root).unwrap().display().to_string();
                offenders.push(format!("{rel}:{}: {}", i + 1, line.trim()));
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "header keys spelled outside luxest_io::header (use its constants):\n{}",
        offenders.join("\n")
    );
    assert!(std::fs::read_to_string(&header).unwrap().contains(&needle));
}

#[test]
fn every_library_file_opens_with_a_module_doc() {
    let root = repo_root();
    let missing: Vec<_> = workspace_rust_files()
        .into_iter()
        .filter(|p| p.file_name().is_some_and(|n| n != "main.rs"))
        .filter(|p| {
            !std::fs::read_to_string(p)
                .unwrap()
                .trim_start()
                .starts_with("//!")
        })
        .map(|p| p.strip_prefix(&root).unwrap().display().to_string())
        .collect();
    assert!(missing.is_empty(), "no //! module doc: {missing:?}");
}

/// The lines of library code in `path` (before its `#[cfg(test)]` module), comments left out.
fn library_code_lines(path: &Path) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .enumerate()
        .take_while(|(_, l)| !l.trim_start().starts_with("#[cfg(test)]"))
        .filter(|(_, l)| !l.trim_start().starts_with("//"))
        .map(|(i, l)| (i + 1, l.to_string()))
        .collect()
}

#[test]
fn file_names_are_composed_only_in_the_naming_module() {
    let root = repo_root();
    let naming = root.join("crates/io/src/naming.rs");
    // A 6-digit count, the level tags and the sensor-results suffix: what composing a name of
    // the contract by hand looks like.
    let patterns = [
        ":06}",
        "}spp",
        "spp.{",
        "spp.hdr",
        "_ref.",
        "le.hdr",
        ".sensors.ron\"",
        ".sensors.csv\"",
    ];
    let mut offenders = Vec::new();
    for path in workspace_rust_files() {
        let in_library = path.components().any(|c| c.as_os_str() == "src");
        if path == naming || !in_library || !path.starts_with(root.join("crates")) {
            continue;
        }
        for (n, line) in library_code_lines(&path) {
            if patterns.iter().any(|p| line.contains(p)) {
                let rel = path.strip_prefix(&root).unwrap().display().to_string();
                offenders.push(format!("{rel}:{n}: {}", line.trim()));
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "file names composed outside luxest_io::naming:\n{}",
        offenders.join("\n")
    );
    // The check can fail: the naming module itself composes them.
    let own = library_code_lines(&naming);
    assert!(own.iter().any(|(_, l)| l.contains(":06}")));
}

#[test]
fn every_stage_binary_is_the_three_line_main() {
    let root = repo_root();
    for stage in STAGES {
        let main = root.join("crates").join(stage).join("src/main.rs");
        let text = std::fs::read_to_string(&main).unwrap();
        let lines: Vec<_> = text.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 3, "{}: {text}", main.display());
        assert!(
            lines[0] == "fn main() -> std::process::ExitCode {"
                && lines[1].trim().starts_with("luxest_io::cli::main(")
                && lines[2] == "}",
            "{} is not the three-line main over luxest_io::cli::main:\n{text}",
            main.display()
        );
    }
}

#[test]
fn every_test_file_is_compiled_into_its_one_test_binary() {
    // Packages with `autotests = false` compile tests/main.rs only: a tests/*.rs file that
    // main.rs does not name as a module would never run.
    let root = repo_root();
    let mut checked = 0;
    for dir in [root.join("tests"), root.join("crates/photometry/tests")] {
        let main = std::fs::read_to_string(dir.join("main.rs")).unwrap();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
                continue;
            };
            if path.extension().is_some_and(|e| e == "rs") && stem != "main" {
                assert!(
                    main.lines().any(|l| l.trim() == format!("mod {stem};")),
                    "{} is not a module of {}: its tests never run",
                    path.display(),
                    dir.join("main.rs").display()
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 10, "only {checked} test files found");
}

/// The `pub mod` names declared in a module file (`lib.rs` or `mod.rs`).
fn public_modules(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod "))
        .filter_map(|rest| rest.strip_suffix(';'))
        .map(str::to_string)
        .collect()
}

#[test]
fn every_public_module_is_in_its_crates_module_list() {
    let root = repo_root();
    let mut files: Vec<PathBuf> = workspace_rust_files()
        .into_iter()
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n == "lib.rs" || n == "mod.rs")
        })
        .collect();
    files.sort();
    let mut missing = Vec::new();
    let mut listed = 0;
    for path in &files {
        let text = std::fs::read_to_string(path).unwrap();
        let doc: String = text
            .lines()
            .filter(|l| l.trim_start().starts_with("//!"))
            .collect::<Vec<_>>()
            .join("\n");
        for m in public_modules(&text) {
            // Named in the doc as `m` (a rustdoc link [`m`] included).
            if doc.contains(&format!("`{m}`")) {
                listed += 1;
            } else {
                let rel = path.strip_prefix(&root).unwrap().display();
                missing.push(format!("{rel}: pub mod {m}"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "public modules missing from their crate's //! module list (name each as [`module`]):\n{}",
        missing.join("\n")
    );
    // The check can fail: the crates do declare public modules.
    assert!(listed > 50, "only {listed} public modules found");
}

/// The top-level directories of the repository whose paths docs and comments name; paths under
/// the generated ones (`build/`, `data/`, `runs/`, `target/`, the trained `models/`, the
/// fuzzers' `fuzz/` corpora and logs) are not checked.
const CHECKED_ROOTS: &[&str] = &[
    "crates/",
    "docs/",
    "pipelines/",
    "python/",
    "scripts/",
    "training/",
    "data-gen/",
    "tests/",
    "scenes/",
    ".ci/",
];

/// Repository paths named in `text`: tokens starting with one of [`CHECKED_ROOTS`] (at the
/// start of a word), without trailing punctuation; tokens with a placeholder or pattern
/// (`<name>`, `*`, `{a,b}`, `$(VAR)`, `%`) are left out.
fn named_paths(text: &str) -> Vec<String> {
    let is_path_char = |c: char| c.is_ascii_alphanumeric() || "_./-".contains(c);
    let mut out = Vec::new();
    let bytes: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < bytes.len() {
        let at_word_start = i == 0 || !(is_path_char(bytes[i - 1]) || bytes[i - 1] == '\\');
        if at_word_start {
            let rest: String = bytes[i..bytes.len().min(i + 16)].iter().collect();
            if CHECKED_ROOTS.iter().any(|r| rest.starts_with(r)) {
                let mut j = i;
                while j < bytes.len() && is_path_char(bytes[j]) {
                    j += 1;
                }
                let next = bytes.get(j).copied().unwrap_or(' ');
                let token: String = bytes[i..j].iter().collect();
                let token = token.trim_end_matches(['.', '-']).to_string();
                if !"<*{$%[".contains(next) && !token.contains("..") {
                    out.push(token);
                }
                i = j;
                continue;
            }
        }
        i += 1;
    }
    out
}

/// Every file whose comments and text may name repository paths: the docs, the README, Rust
/// and Python sources, Make fragments and scripts (not fixtures or generated reports).
fn documented_files() -> Vec<PathBuf> {
    let root = repo_root();
    let mut files = workspace_rust_files();
    for dir in [
        "docs",
        "training",
        "pipelines",
        "python",
        "data-gen",
        "scripts",
        ".ci",
    ] {
        let mut stack = vec![root.join(dir)];
        while let Some(d) = stack.pop() {
            let Ok(entries) = std::fs::read_dir(&d) else {
                continue;
            };
            for e in entries {
                let p = e.unwrap().path();
                let name = p.file_name().unwrap().to_string_lossy().to_string();
                if p.is_dir() {
                    if name != "__pycache__" && name != "fixtures" {
                        stack.push(p);
                    }
                } else if [".md", ".py", ".mk", ".sh"]
                    .iter()
                    .any(|x| name.ends_with(x))
                    || dir == ".ci"
                {
                    files.push(p);
                }
            }
        }
    }
    files.push(root.join("README.md"));
    files.push(root.join("Makefile"));
    files.sort();
    files
}

/// The lines of `path` that are prose: every line of Markdown, Make and shell files, the comment
/// lines of Rust and Python sources (their string literals name test inputs, not the tree).
fn prose_lines(path: &Path) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    let ext = path.extension().map(|e| e.to_string_lossy().to_string());
    let comment = match ext.as_deref() {
        Some("rs") => Some("//"),
        Some("py") => Some("#"),
        _ => None,
    };
    text.lines()
        .enumerate()
        .filter(|(_, l)| comment.is_none_or(|c| l.trim_start().starts_with(c)))
        .map(|(i, l)| (i + 1, l.to_string()))
        .collect()
}

#[test]
fn every_repository_path_named_in_docs_and_comments_exists() {
    let root = repo_root();
    let mut dangling = Vec::new();
    let mut checked = 0;
    for path in documented_files() {
        for (n, line) in prose_lines(&path) {
            for named in named_paths(&line) {
                checked += 1;
                // From the root, or from a folder the file is in (a crate names its own).
                let exists = path
                    .ancestors()
                    .take_while(|a| a.starts_with(&root))
                    .any(|a| a.join(&named).exists());
                if !exists {
                    let rel = path.strip_prefix(&root).unwrap().display();
                    dangling.push(format!("{rel}:{n}: {named}"));
                }
            }
        }
    }
    assert!(
        dangling.is_empty(),
        "paths named in docs and comments that do not exist:\n{}",
        dangling.join("\n")
    );
    assert!(checked > 200, "only {checked} paths named");
}

#[test]
fn named_paths_finds_paths_and_skips_patterns() {
    let found = named_paths(
        "see `crates/io/src/naming.rs`, docs/architecture.md. Not xcrates/a or \
         crates/<name>/src, build/x, tests/fixtures/*.json or pipelines/$(X).mk",
    );
    assert_eq!(found, ["crates/io/src/naming.rs", "docs/architecture.md"]);
}
