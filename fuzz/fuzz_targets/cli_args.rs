//! The command line's argument parsing and output checks, without a library crate for
//! the CLI: its modules, `Cli` (`cli.rs`) among them, are compiled here from their
//! source files (`#[path]`).
//!
//! The fuzzed bytes are the arguments after `obscura`, separated by NUL bytes (or, when
//! the input holds none, by new lines; one at the end is dropped). Each argument list is
//! parsed by clap (an error is rendered, as the binary would print it). A list that
//! parses, and whose paths all stay inside a private folder the process works in, has
//! its outputs checked (`Outputs::stage`, which creates and removes the temporary files
//! beside them). A `render` or `compare` of a small scene of that folder at a small size
//! (at most 64x64 pixels, 1 or 2 threads, octree depth 8), and a `cull` or `export` of
//! such a scene, is then run whole; every fixed
//! file of the folder must be unchanged afterwards: an output that replaced an input is
//! saved as a soft finding (`findings/soft/cli_args-overwrote-*`) and the folder is
//! restored.
#![no_main]
#![allow(dead_code, unused_imports)]

#[path = "../../crates/obscura-cli/src/bench.rs"]
mod bench;
#[path = "../../crates/obscura-cli/src/cli.rs"]
mod cli;
#[path = "../../crates/obscura-cli/src/common.rs"]
mod common;
#[path = "../../crates/obscura-cli/src/compare.rs"]
mod compare;
#[path = "../../crates/obscura-cli/src/cull.rs"]
mod cull;
#[path = "../../crates/obscura-cli/src/export.rs"]
mod export;
#[path = "../../crates/obscura-cli/src/grid.rs"]
mod grid;
#[path = "../../crates/obscura-cli/src/lines.rs"]
mod lines;
#[path = "../../crates/obscura-cli/src/out.rs"]
mod out;
#[path = "../../crates/obscura-cli/src/outputs.rs"]
mod outputs;
#[path = "../../crates/obscura-cli/src/render.rs"]
mod render;

use std::path::{Component, Path, PathBuf};
use std::sync::OnceLock;

use clap::Parser;
use libfuzzer_sys::fuzz_target;

use crate::cli::{Cli, Command};
use crate::out::errln;

/// The fixed files of the working folder and their bytes.
static FILES: OnceLock<Vec<(PathBuf, Vec<u8>)>> = OnceLock::new();

const SCENE: &str = "[[object]]\nmesh = \"tri.obj\"\n[[object]]\nmesh = \"tri.gltf\"\n\
                     translate = [2, 0, 0]\n[[object]]\nprimitive = \"box\"\nscale = 0.5\n";

/// Makes the working folder (once), enters it, and records its files.
fn files() -> &'static [(PathBuf, Vec<u8>)] {
    FILES.get_or_init(|| {
        let _ = obscura_fuzz::findings_dir();
        let d = obscura_fuzz::temp_dir("cli");
        obscura_fuzz::write_reference_meshes(&d);
        std::fs::write(d.join("scene.toml"), SCENE).expect("scene.toml");
        std::env::set_current_dir(&d).expect("entering the working folder");
        let mut out = Vec::new();
        for name in [
            "scene.toml",
            "tri.obj",
            "tri.mtl",
            "tri.stl",
            "bin.stl",
            "tri.gltf",
            "tri.bin",
            "tri.glb",
            "tri.ply",
            "empty.obj",
            "sub/quad.obj",
        ] {
            out.push((PathBuf::from(name), std::fs::read(name).expect("fixture")));
        }
        out
    })
}

/// A path that stays inside the working folder: relative, without `..`.
fn inside(p: &Path) -> bool {
    p.components()
        .all(|c| matches!(c, Component::Normal(_) | Component::CurDir))
}

/// Restores the working folder, returning the files that had changed.
fn restore(files: &[(PathBuf, Vec<u8>)]) -> Vec<String> {
    let mut changed = Vec::new();
    for (p, bytes) in files {
        if std::fs::read(p).ok().as_deref() != Some(bytes.as_slice()) {
            changed.push(p.display().to_string());
            let _ = std::fs::remove_file(p);
            let _ = std::fs::remove_dir_all(p);
            std::fs::write(p, bytes).expect("restoring a fixture");
        }
    }
    #[cfg(unix)]
    if !std::fs::symlink_metadata("sub/link.obj").is_ok_and(|m| m.file_type().is_symlink()) {
        changed.push("sub/link.obj".to_string());
        let _ = std::fs::remove_file("sub/link.obj");
        let _ = std::os::unix::fs::symlink("../tri.obj", "sub/link.obj");
    }
    // Outputs the run wrote under new names: removed, so the folder stays small.
    for dir in [Path::new("."), Path::new("sub")] {
        let Ok(entries) = std::fs::read_dir(dir) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            let p = p.strip_prefix(".").unwrap_or(&p).to_path_buf();
            let fixed = files.iter().any(|(f, _)| *f == p)
                || p == Path::new("sub")
                || p == Path::new("sub/link.obj");
            if !fixed {
                let _ = std::fs::remove_file(&p);
                let _ = std::fs::remove_dir_all(&p);
            }
        }
    }
    changed
}

/// A scene that runs fast enough to render on every input.
fn small_scene(scene: Option<&str>) -> bool {
    match scene {
        None => false,
        Some(s) if s.starts_with("demo:") => matches!(s, "demo:cube" | "demo:seed-task"),
        Some(s) => inside(Path::new(s)),
    }
}

fn small_view(view: &mut common::ViewArgs, octree_depth: u32) -> bool {
    if view.size.is_none() {
        view.size = Some((32, 24));
    }
    let (w, h) = view.size.unwrap_or_default();
    w.saturating_mul(h) <= 64 * 64
        && view.threads.is_some_and(|t| (1..=2).contains(&t))
        && octree_depth <= 8
        && small_scene(view.scene.as_deref())
}

fuzz_target!(|data: &[u8]| {
    let files = files();
    let sep = if data.contains(&0) { 0 } else { b'\n' };
    // One separator at the end ends the last argument (a text file's last new line).
    let data = data.strip_suffix(&[sep]).unwrap_or(data);
    let mut args = vec!["obscura".to_string()];
    args.extend(
        data.split(|&b| b == sep)
            .map(|a| String::from_utf8_lossy(a).into_owned()),
    );
    if args.len() > 64 {
        return;
    }
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.render().to_string();
            return;
        }
    };
    let (scene, outs, naming): (Option<&str>, Vec<(&'static str, Option<&Path>)>, _) = match &cli.command {
        Command::Render(a) => (
            a.view.scene.as_deref(),
            vec![
                ("-o", Some(a.output.as_path())),
                ("--ids", a.ids.as_deref()),
                ("--depth", a.depth.as_deref()),
                ("--stats-json", a.stats_json.as_deref()),
            ],
            a.naming,
        ),
        Command::Compare(a) => (
            a.view.scene.as_deref(),
            vec![
                ("-o", Some(a.output.as_path())),
                ("--json", a.json.as_deref()),
            ],
            a.naming,
        ),
        Command::Bench(a) => (
            a.view.scene.as_deref(),
            vec![("--json", a.json.as_deref())],
            a.naming,
        ),
        Command::Lines(a) => (
            a.view.scene.as_deref(),
            vec![
                ("-o", Some(a.output.as_path())),
                ("--png", a.png.as_deref()),
                ("--json", a.json.as_deref()),
            ],
            a.naming,
        ),
        Command::Cull(a) => (
            a.view.scene.as_deref(),
            vec![
                ("--stats-json", a.stats_json.as_deref()),
                ("--kept", a.kept.as_deref()),
                ("--explain", a.explain.as_deref()),
            ],
            a.naming,
        ),
        Command::Export(a) => (
            a.view.scene.as_deref(),
            vec![("-o", Some(a.output.as_path()))],
            a.naming,
        ),
    };
    let walk_inside = match &cli.command {
        Command::Cull(a) => a.walk.as_deref().is_none_or(inside),
        _ => true,
    };
    let paths_inside = walk_inside
        && outs.iter().all(|(_, p)| p.is_none_or(inside))
        && scene.is_none_or(|s| s.starts_with("demo:") || inside(Path::new(s)));
    if !paths_inside {
        return;
    }
    drop(outputs::Outputs::stage(scene, &outs, naming));
    let run = match cli.command {
        Command::Render(mut a) => {
            let depth = a.tuning.octree_depth;
            small_view(&mut a.view, depth).then(|| render::run(&a).map_err(|e| e.to_string()))
        }
        Command::Compare(mut a) => {
            let depth = a.tuning.octree_depth;
            small_view(&mut a.view, depth).then(|| compare::run(&a).map_err(|e| e.to_string()))
        }
        Command::Cull(mut a) => small_view(&mut a.view, 0).then(|| cull::run(&a).map_err(|e| e.to_string())),
        Command::Export(mut a) => {
            small_view(&mut a.view, 0).then(|| export::run(&a).map_err(|e| e.to_string()))
        }
        Command::Bench(_) | Command::Lines(_) => None,
    };
    let changed = restore(files);
    if !changed.is_empty() {
        obscura_fuzz::soft_finding(
            "cli_args",
            "overwrote",
            data,
            &format!("{args:?} replaced {changed:?} (run: {run:?})"),
        );
    }
});
