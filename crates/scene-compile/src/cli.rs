//! The `scene-compile` command line: compile (or `--check`) an authored scene, or print a
//! compiled scene's header (`--info`).

use crate::{compile, referenced_files, scene_name};
use clap::Parser;
use luxest_io::cli::Console;
use luxest_io::fsio::to_ron_string;
use luxest_io::outputs::{path_component, Format, OutputPlan};
use luxest_io::Result;
use luxest_render::compiled::CompiledScene;
use std::path::{Path, PathBuf};

/// Compile an authored luxest scene into one self-contained scene file.
#[derive(Parser, Debug)]
#[command(name = "scene-compile", version, about)]
pub struct Args {
    /// The scene: authored (.ron), or Mitsuba 3 (.xml), glTF 2.0 (.gltf, .glb) or OBJ+MTL
    /// (.obj) translated on the way; with --info a compiled scene.
    pub input: PathBuf,
    /// Output file, *.lxs [default: build/<scene name>/scene.lxs].
    #[arg(short, long, conflicts_with = "check")]
    pub out: Option<PathBuf>,
    /// Validate and load everything, print the summary, write nothing.
    #[arg(long)]
    pub check: bool,
    /// Print the header (features manifest, emitters, sensors, stats) of a compiled scene.
    #[arg(long, conflicts_with_all = ["out", "check", "export_mitsuba", "export_ron"])]
    pub info: bool,
    /// A parameter of a Mitsuba 3 scene, as Mitsuba's own `-D name=value` (repeatable; takes
    /// precedence over the scene's `<default>`).
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Also write the scene as luxest RON to this file (for an imported scene: its
    /// translation, to read and edit; file paths relative to the file written).
    #[arg(long, value_name = "FILE")]
    pub export_ron: Option<PathBuf>,
    #[command(flatten)]
    pub console: Console,
    /// Also write the scene for Mitsuba 3 into this directory (scene.xml and one OBJ per
    /// material): a cross-check of any scene with Mitsuba (`mitsuba -D spp=256 scene.xml`).
    #[arg(long, value_name = "DIR", conflicts_with = "check")]
    pub export_mitsuba: Option<PathBuf>,
}

/// What `--info` prints: the compiled scene's header as RON, then its content hash as the
/// comment line `// content hash H`, by which `report --scene-info` matches the header to
/// sensor results (their `run.scene_hash`).
pub fn info_text(scene: &CompiledScene) -> String {
    format!(
        "{}\n// content hash {}\n",
        to_ron_string(&scene.header),
        scene.content_hash
    )
}

/// Runs the command line.
pub fn run(args: Args) -> Result<()> {
    if args.info {
        let scene = CompiledScene::load(&args.input)?;
        return luxest_io::cli::print(&info_text(&scene));
    }
    let defines = args
        .define
        .iter()
        .map(|d| match d.split_once('=') {
            Some((k, v)) if !k.is_empty() => Ok((k.to_string(), v.to_string())),
            _ => Err(luxest_io::Error::Usage(format!(
                "-D {d}: expected NAME=VALUE"
            ))),
        })
        .collect::<Result<Vec<_>>>()?;
    let imported = crate::import::read_scene_with(&args.input, &defines)?;
    for w in &imported.warnings {
        args.console.note(format_args!("warning: {w}"));
    }
    let authored = imported.scene;
    // The output, planned before the work: not the scene file, a mesh or a photometric file it
    // refers to, nor a directory or device; the default stays inside build/.
    let out = match &args.out {
        Some(o) => o.clone(),
        None => {
            let name = scene_name(&authored, &args.input);
            let name = path_component(&name, &args.input, "name")?;
            Path::new("build").join(name).join("scene.lxs")
        }
    };
    let inputs: Vec<PathBuf> = std::iter::once(args.input.clone())
        .chain(referenced_files(&authored, &args.input))
        .collect();
    let outputs: Vec<&PathBuf> = (!args.check)
        .then_some(&out)
        .into_iter()
        .chain(&args.export_ron)
        .collect();
    let mut plan = OutputPlan::new(&inputs, outputs.iter().copied())?;
    if let Some(o) = &args.out {
        Format::Lxs.check(o, "-o/--out")?;
    }
    let (mut scene, report) = compile(&authored, &args.input)?;
    for w in &report.warnings {
        args.console.note(format_args!("warning: {w}"));
    }
    let bytes = scene.encode();
    let summary = {
        let s = &scene.header.stats;
        format!(
            "{}: {} triangles, {} vertices, {} emitters, {} sensor points, hash {}",
            scene.header.name,
            s.triangles,
            s.vertices,
            scene.header.emitters.len(),
            scene
                .header
                .sensors
                .iter()
                .map(|x| x.points.len())
                .sum::<usize>(),
            scene.content_hash
        )
    };
    let ron_text = args
        .export_ron
        .as_ref()
        .map(|p| crate::import::export_ron(&authored, &args.input, p));
    if args.check {
        if let (Some(p), Some(text)) = (&args.export_ron, &ron_text) {
            plan.write_bytes(p, text.as_bytes())?;
            plan.commit()?;
        }
        args.console.note(format_args!("ok {summary}"));
        return Ok(());
    }
    let export = match &args.export_mitsuba {
        Some(dir) => {
            let files = crate::mitsuba::export(&scene, &args.input)?;
            let paths: Vec<PathBuf> = files.iter().map(|(name, _)| dir.join(name)).collect();
            // Every output, the compiled scene's included, checked together before writing.
            plan = OutputPlan::new(
                &inputs,
                std::iter::once(&out).chain(&paths).chain(&args.export_ron),
            )?;
            Some((dir, files, paths))
        }
        None => None,
    };
    plan.write_bytes(&out, &bytes)?;
    if let (Some(p), Some(text)) = (&args.export_ron, &ron_text) {
        plan.write_bytes(p, text.as_bytes())?;
    }
    if let Some((_, files, paths)) = &export {
        for ((_, data), path) in files.iter().zip(paths) {
            plan.write_bytes(path, data)?;
        }
    }
    plan.commit()?;
    if let Some((dir, files, _)) = &export {
        args.console.note(format_args!(
            "wrote the Mitsuba 3 scene {} ({} meshes)",
            dir.join("scene.xml").display(),
            files.len() - 1
        ));
    }
    args.console
        .note(format_args!("wrote {} ({summary})", out.display()));
    Ok(())
}
