//! Loading scenes from files: one module per format, all going through
//! [`MeshBuilder`] so that bad faces are handled the same way.
//!
//! | extension | format | module |
//! | --- | --- | --- |
//! | `.obj` | Wavefront OBJ with objects, groups and MTL diffuse colours | [`obj`] |
//! | `.gltf`, `.glb` | glTF 2.0 (node hierarchy, base colour) | [`gltf`] |
//! | `.stl` | STL, binary or ASCII | [`stl`] |
//! | `.ply` | PLY, ASCII or binary (either byte order) | [`ply`] |
//! | `.toml` | an obscura scene file placing meshes (`docs/scene-files.md`) | [`toml_scene`] |
//!
//! Each format is behind a cargo feature of the same name (`obj`, which also reads MTL,
//! `gltf`, `stl`, `ply`, `toml-scene`), all on by default, so that an engine can depend
//! on the core alone (`default-features = false`). A file whose format is left out is
//! refused with [`Error::FormatDisabled`], which names the feature.
//!
//! Input: a path. Output: a [`Loaded`] (objects in file order, a [`LoadReport`], the
//! file's up axis when the format has one) or, through [`load_file`], a [`Scene`].
//!
//! Rules shared by every loader (see `docs/ARCHITECTURE.md`):
//! - a file named inside another (a glTF buffer, an OBJ `mtllib`, a scene file's mesh)
//!   is resolved by one rule, `reference`'s: relative to the referring file's folder
//!   and inside its tree, unless [`LoadOptions::allow_outside_references`] is set; every
//!   file a load reads is recorded ([`Scene::source_files`]);
//! - messages never quote bytes of a file other than the one being parsed (a glTF
//!   error names the accessor element, not the value its buffer holds);
//! - errors name the file and the line (text formats) or the element (binary and
//!   structured formats: facet, vertex, mesh, primitive, accessor);
//! - a non-finite coordinate (NaN, infinity, a value overflowing `f64`) is an error,
//!   found by the loader before the vertex reaches the builder;
//! - degenerate faces are dropped and counted, non-planar and concave n-gons are
//!   triangulated and counted, by [`MeshBuilder`];
//! - a coordinate beyond [`MAX_COORDINATE`] is an error too, naming the line or
//!   element (the scene would refuse it later, without knowing where it came from);
//! - a UTF-8 byte-order mark at the start of a text file (or of a text header) is
//!   skipped, as many Windows exporters write one;
//! - face ids follow the file's face order;
//! - warnings (in [`LoadReport::messages`]) name the line or element of the file loaded
//!   but not the file itself, which the caller knows (and prints once); they name any
//!   other file they are about (a material library). Warnings that may repeat (unknown
//!   materials, skipped primitives or nodes) are aggregated: one line with the count
//!   and the first few cases;
//! - an empty file, or one without a usable face, is [`Error::EmptyScene`], whose
//!   message carries the warnings that explain why (nodes skipped, primitives that are
//!   not surfaces, faces dropped).
//!
//! Complexity: every loader is linear in the size of its input, whatever the input
//! has many of (objects, groups, solids, header lines, materials, `usemtl` switches,
//! nodes, nesting depth, referenced files, corners on one line), plus the hashing of
//! vertex positions where a format needs welding: nothing is looked up by a linear
//! search, re-counted from the start, reset per object or read twice.
//! `cargo bench -p obscura --bench loaders` shows it, loading 23 such shapes at N and
//! 4N items and printing the ratio of the times. Files are read whole into memory.
//! (Triangulating one concave n-gon is the exception, bounded as `MeshBuilder` says.)

// The helpers below serve the loaders; a build that leaves every format out (or some)
// does not call them all.
#![cfg_attr(
    not(all(
        feature = "obj",
        feature = "gltf",
        feature = "stl",
        feature = "ply",
        feature = "toml-scene"
    )),
    allow(dead_code)
)]

#[cfg(feature = "gltf")]
pub mod gltf;
#[cfg(feature = "obj")]
pub mod mtl;
#[cfg(feature = "obj")]
pub mod obj;
#[cfg(feature = "ply")]
pub mod ply;
pub(crate) mod reference;
#[cfg(feature = "stl")]
pub mod stl;
#[cfg(feature = "toml-scene")]
pub mod toml_scene;

use std::path::Path;

use glam::DVec3;

use reference::Sources;

use super::{LoadReport, MAX_COORDINATE, MeshBuilder, ObjectDesc, Scene};
use crate::{Error, Result};

/// How a scene file is loaded: what it may read and how much it may build.
///
/// # Example
/// ```
/// use obscura::scene::load::LoadOptions;
/// let options = LoadOptions::default().with_allow_outside_references(true);
/// assert!(options.allow_outside_references);
/// assert!(options.memory_limit.is_none());
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct LoadOptions {
    /// Let a scene refer to files outside its own folder tree (absolute paths, `..`
    /// escapes, `file:` URIs). Off by default: a scene reads only inside the folder of
    /// the file that refers (the CLI's `--allow-outside-references`).
    pub allow_outside_references: bool,
    /// The memory budget of the load in bytes; `None` takes the default budget of a
    /// run (see the crate's memory budget).
    pub memory_limit: Option<u64>,
}

impl LoadOptions {
    /// Sets [`LoadOptions::allow_outside_references`].
    #[must_use]
    pub fn with_allow_outside_references(mut self, allow: bool) -> Self {
        self.allow_outside_references = allow;
        self
    }
}

/// What a mesh file yields before it is placed in a scene.
#[derive(Debug, Default)]
pub struct Loaded {
    /// The objects, in file order (face ids follow this order).
    pub objects: Vec<ObjectDesc>,
    /// What was fixed or dropped.
    pub report: LoadReport,
    /// The file's up axis when the format says (glTF: +y).
    pub up: Option<DVec3>,
}

/// The mesh formats [`load_objects`] reads, by lower-case extension.
pub const MESH_EXTENSIONS: [&str; 5] = ["obj", "gltf", "glb", "stl", "ply"];

/// Lower-case extension of a path, if it has one.
fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// Loads the objects of a mesh file (not a scene file), by extension.
///
/// A file that is empty or holds only white space yields no objects (the caller turns
/// that into [`Error::EmptyScene`]).
pub fn load_objects(path: &Path) -> Result<Loaded> {
    let options = LoadOptions::default();
    load_objects_in(path, &mut Sources::new(&options))
}

/// [`load_objects`] within a load: the files it reads are checked by and recorded in
/// `sources`.
pub(crate) fn load_objects_in(path: &Path, sources: &mut Sources<'_>) -> Result<Loaded> {
    let ext = extension(path);
    let Some(ext) = ext.filter(|e| MESH_EXTENSIONS.contains(&e.as_str())) else {
        return Err(Error::UnsupportedFormat {
            path: path.to_path_buf(),
        });
    };
    let bytes = sources.read(path)?;
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Ok(Loaded::default());
    }
    match ext.as_str() {
        #[cfg(feature = "obj")]
        "obj" => obj::load_in(path, &bytes, sources),
        #[cfg(feature = "gltf")]
        "gltf" | "glb" => gltf::load_in(path, &bytes, sources),
        #[cfg(feature = "stl")]
        "stl" => stl::load(path, bytes),
        #[cfg(feature = "ply")]
        "ply" => ply::load(path, &bytes),
        _ => {
            let _ = bytes;
            Err(format_disabled(path, &ext))
        }
    }
}

/// The format and cargo feature of each extension obscura reads.
const FORMAT_FEATURES: [(&str, &str, &str); 6] = [
    ("obj", "OBJ", "obj"),
    ("gltf", "glTF", "gltf"),
    ("glb", "glTF", "gltf"),
    ("stl", "STL", "stl"),
    ("ply", "PLY", "ply"),
    ("toml", "scene (.toml)", "toml-scene"),
];

/// [`Error::FormatDisabled`] for a file of a known extension whose feature this build
/// leaves out (with every feature on, never reached).
fn format_disabled(path: &Path, ext: &str) -> Error {
    let (format, feature) = FORMAT_FEATURES
        .iter()
        .find(|(e, _, _)| *e == ext)
        .map_or(("this", "?"), |&(_, format, feature)| (format, feature));
    Error::FormatDisabled {
        path: path.to_path_buf(),
        format,
        feature,
    }
}

/// Loads a scene file (`.toml`) or a mesh file into a scene, with the default
/// [`LoadOptions`].
pub fn load_file(path: &Path) -> Result<Scene> {
    load_file_with(path, &LoadOptions::default())
}

/// Loads a scene file (`.toml`) or a mesh file into a scene with `options`. The scene
/// lists every file read ([`Scene::source_files`]).
pub fn load_file_with(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let mut sources = Sources::new(options);
    let mut scene = if extension(path).as_deref() == Some("toml") {
        #[cfg(feature = "toml-scene")]
        {
            toml_scene::load_in(path, &mut sources)?
        }
        #[cfg(not(feature = "toml-scene"))]
        {
            return Err(format_disabled(path, "toml"));
        }
    } else {
        let loaded = load_objects_in(path, &mut sources)?;
        scene_from(loaded, &path.display().to_string())?
    };
    scene.set_source_files(sources.into_files());
    Ok(scene)
}

/// Places loaded objects in a new scene, refusing an empty result.
pub fn scene_from(loaded: Loaded, what: &str) -> Result<Scene> {
    let mut scene = Scene::new();
    for o in loaded.objects {
        // An object of a mesh file is named with the file: its name alone (often the
        // file's stem) does not say which file to fix.
        scene.add(o).map_err(|e| match e {
            Error::InvalidObject { object, message } => {
                Error::format(what, format!("object \"{object}\""), message)
            }
            e => e,
        })?;
    }
    scene.report_mut().merge(&loaded.report);
    if let Some(up) = loaded.up {
        scene.set_up(up);
    }
    scene.ensure_not_empty(what)?;
    Ok(scene)
}

/// Reads a whole file, naming it in the error. Only regular files: a device
/// (`/dev/zero`), a pipe or a directory named by a scene, an `mtllib` line or a glTF
/// buffer would be read without end, or block.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>> {
    let io = |e| Error::io(path, e);
    check_regular_file(path).map_err(io)?;
    std::fs::read(path).map_err(io)
}

/// An error unless `path` is a regular file (after following links).
pub(crate) fn check_regular_file(path: &Path) -> std::io::Result<()> {
    if std::fs::metadata(path)?.is_file() {
        Ok(())
    } else {
        Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file (a directory, device or pipe)",
        ))
    }
}

/// The file name without extension, for naming objects that have no name.
pub(crate) fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "mesh".to_string(), |s| s.to_string_lossy().into_owned())
}

/// Finishes a builder into an object, merging its report into `report`.
pub(crate) fn finish_object(
    name: String,
    builder: MeshBuilder,
    color: [f32; 3],
    report: &mut LoadReport,
) -> ObjectDesc {
    let (mesh, r) = builder.finish();
    report.merge(&r);
    ObjectDesc::new(name, mesh).with_color(color)
}

/// A colour for files that give none: the scene palette, by object order.
pub(crate) fn palette_color(k: usize) -> [f32; 3] {
    super::PALETTE[k % super::PALETTE.len()]
}

/// Clamps a colour read from a file into `0..=1` (non-finite components become 0).
pub(crate) fn clamp_color(c: [f64; 3]) -> [f32; 3] {
    c.map(|v| {
        if v.is_finite() {
            v.clamp(0.0, 1.0) as f32
        } else {
            0.0
        }
    })
}

/// The UTF-8 byte-order mark (U+FEFF) some exporters put at the start of text files.
pub(crate) const BOM: &[u8] = b"\xEF\xBB\xBF";

/// The bytes without a leading UTF-8 byte-order mark (lines are unchanged: the mark
/// is on line 1 and holds no line end).
pub(crate) fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(BOM).unwrap_or(bytes)
}

/// An error message for a coordinate beyond [`MAX_COORDINATE`], or `None` when every
/// coordinate of `p` is within it. Loaders call it where they know the line or element,
/// so the message is not left to [`Scene::add`], which only knows the object.
pub(crate) fn coordinate_out_of_range(p: [f64; 3]) -> Option<String> {
    let bad = p.into_iter().find(|c| c.abs() > MAX_COORDINATE)?;
    // A value read as `f32` (binary formats, glTF) is shown as the file wrote it,
    // `3e30` rather than `3.000000054977155e30`.
    let shown = if f64::from(bad as f32) == bad {
        format!("{:e}", bad as f32)
    } else {
        format!("{bad:e}")
    };
    Some(format!(
        "coordinate {shown} is beyond the largest coordinate accepted, {MAX_COORDINATE:e}"
    ))
}

/// How many cases an aggregated warning lists.
const TALLY_EXAMPLES: usize = 3;

/// Warnings of one kind gathered into one line: the count and the first few cases
/// (a file can hold a hundred thousand unknown materials; one line each would bury
/// every other message).
#[derive(Debug, Default)]
pub(crate) struct Tally {
    count: usize,
    examples: Vec<String>,
}

impl Tally {
    /// Counts one case; `example` describes it (called for the first few only).
    pub(crate) fn add(&mut self, example: impl FnOnce() -> String) {
        self.count += 1;
        if self.examples.len() < TALLY_EXAMPLES {
            self.examples.push(example());
        }
    }

    /// Pushes the one-line summary, if any case was counted: `summary(count)` says what
    /// happened (e.g. "3 unknown material(s); their faces use the object colour"),
    /// followed by the first cases.
    pub(crate) fn finish(self, messages: &mut Vec<String>, summary: impl FnOnce(usize) -> String) {
        if self.count == 0 {
            return;
        }
        let more = self.count - self.examples.len();
        let mut line = format!("{}: {}", summary(self.count), self.examples.join("; "));
        if more > 0 {
            line.push_str(&format!("; and {more} more"));
        }
        messages.push(line);
    }
}

/// The lines of a text, to find the line of many byte offsets in O(log lines) each
/// ([`line_of_offset`] counts from the start every time).
#[derive(Debug)]
pub(crate) struct LineIndex {
    /// Byte offset of the start of each line after the first.
    starts: Vec<usize>,
}

impl LineIndex {
    pub(crate) fn new(text: &str) -> Self {
        let starts = text
            .bytes()
            .enumerate()
            .filter(|&(_, b)| b == b'\n')
            .map(|(i, _)| i + 1)
            .collect();
        LineIndex { starts }
    }

    /// The 1-based line of a byte offset (as [`line_of_offset`]).
    pub(crate) fn line(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset) + 1
    }
}

/// The 1-based line of a byte offset in a text.
pub(crate) fn line_of_offset(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_index_agrees_with_counting() {
        for text in ["", "a", "\n", "a\nb", "a\n\nbc\n", "\r\nx\r\n"] {
            let index = LineIndex::new(text);
            for offset in 0..=text.len() + 1 {
                assert_eq!(
                    index.line(offset),
                    line_of_offset(text, offset),
                    "{text:?} at {offset}"
                );
            }
        }
    }
}
