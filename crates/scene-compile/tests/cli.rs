//! The real `scene-compile` binary: exit codes, one-line errors, no panics, no partial output.

use std::path::PathBuf;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_scene-compile"))
}

fn scenes() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("luxest-cli-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn success_writes_the_compiled_scene() {
    let d = tmp("ok");
    let out = d.join("cb/scene.lxs");
    let o = bin()
        .arg(scenes().join("cornell-box.ron"))
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.is_file());
    let info = bin().arg("--info").arg(&out).output().unwrap();
    assert!(info.status.success());
    assert!(String::from_utf8_lossy(&info.stdout).contains("area_emitters: true"));
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn bad_input_exits_1_with_one_line_and_no_output() {
    let d = tmp("bad");
    let scene = d.join("bad.ron");
    std::fs::write(&scene, "Scene(materials: {}, objects: [], point_lights: [(position: (0.0, 0.0, 0.0), power: Intensity(-1.0))])").unwrap();
    let out = d.join("out.lxs");
    let o = bin().arg(&scene).arg("-o").arg(&out).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: ") && err.contains("bad.ron: point_lights[0].power"),
        "{err}"
    );
    assert!(!err.contains("panicked"));
    assert!(!out.exists());
    // A compiled scene that is not one.
    let o = bin().arg("--info").arg(&scene).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not a luxest compiled scene"));
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn usage_errors_exit_2_and_help_exits_0() {
    let o = bin().arg("--bogus").output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = bin().output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = bin().arg("--help").output().unwrap();
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stdout).contains("--out"));
}
