//! glTF 2.0 (`.gltf` JSON with external or base64 `data:` buffers, and binary `.glb`),
//! parsed and validated by the `gltf` crate.
//!
//! Input: the bytes of the file (and its directory, for external buffers). Output: one
//! object per node that has a mesh, in depth-first order of the default scene's node
//! hierarchy (of scene 0 when there is no default `scene`, with a warning when there
//! are other scenes: they are alternatives, drawn on top of each other they would
//! overlap; of the parentless nodes when there is no scene at all). A node a scene
//! lists twice is placed once (warning). The object's transform is
//! the node's world transform: the product of the matrices (or translation, rotation,
//! scale) from the root down. A mesh used by several nodes is built once and shared.
//! Up is +y (`Loaded::up`), as the format defines.
//!
//! Faces: the triangles of `TRIANGLES`, `TRIANGLE_STRIP` and `TRIANGLE_FAN`
//! primitives, indexed or not, in primitive order; each triangle is one face. Strip
//! and fan triangles with a repeated index (the usual way of joining strips) are
//! skipped without taking an id. `POINTS` and `LINES*` primitives are skipped with a
//! warning. Colour: the primitive's material `baseColorFactor` (RGB, linear, as obscura
//! uses); textures are not read.
//!
//! Accessors are read here, not by the crate's reader, so that every offset, stride
//! and count is checked against its buffer view and buffer: a malformed file gives an
//! error naming the mesh, primitive and accessor instead of a panic. Sparse accessors
//! and normalized integer positions (`KHR_mesh_quantization`) are supported. The
//! primitives of a mesh that share one POSITION accessor (the usual layout of a
//! multi-material mesh: one vertex array, an index range per material) share its
//! vertices: the accessor is decoded once per mesh.
//!
//! Container: the content decides, not the extension. A file starting with the GLB
//! magic `glTF` is a GLB (also when named `.gltf`); one starting with `{` (after an
//! optional byte-order mark and white space) is JSON (also when named `.glb`); any
//! other start is an error naming the first bytes in hex and what was expected.
//!
//! Buffers: the GLB binary chunk, base64 `data:` URIs, and files inside the glTF's own
//! folder tree, by the rule every loader follows (`super::reference`): absolute
//! paths, `file:` URIs and references leading out of the folder (by `..` or a symbolic
//! link) are refused unless
//! [`LoadOptions::allow_outside_references`](super::LoadOptions) is set; remote
//! (`http:`, `https:`...) URIs are always refused. Image URIs are never read (textures
//! are not used), so they are not checked. A UTF-8 byte-order mark before the JSON is
//! skipped, as the specification allows.
//!
//! Messages never quote the values decoded from a buffer (a buffer may be another
//! file, and its bytes are not the glTF's to print): they name the accessor and the
//! position of the element instead.
//!
//! Errors (naming the file and the element): invalid JSON or GLB container, a missing,
//! remote or short buffer (naming it and its URI), an accessor outside its buffer view,
//! a wrong accessor type, a non-finite position or node transform, a position beyond
//! [`MAX_COORDINATE`] (in the accessor, or in world space
//! under a node's transform), an index not below the primitive's vertex count, a node
//! with two parents, a scene root that has a parent, a cycle of children.
//! Nodes whose world transform is singular (scale 0, used to hide nodes) and
//! primitives that are points or lines are skipped, with one warning for each kind.
//!
//! Complexity: O(file size + nodes); a mesh's bounds are found once, however many
//! nodes place it. Source: the Khronos glTF 2.0 specification
//! (sections 3.5 Nodes and hierarchy, 3.6 Binary data storage, 3.7.2 Meshes).

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use ::gltf as gl;
use gl::accessor::{DataType, Dimensions};
use gl::mesh::Mode;
use glam::{DMat4, DQuat, DVec3};

use super::reference::{Sources, Syntax};
use super::{
    LoadOptions, Loaded, MAX_COORDINATE, Tally, clamp_color, coordinate_out_of_range,
    palette_color, strip_bom,
};
use crate::scene::{Material, Mesh, MeshBuilder, ObjectDesc};
use crate::{Error, Result};

/// Most elements an accessor without a buffer view (all zeros but for its sparse
/// substitutions) may declare.
pub const MAX_VIEWLESS_COUNT: usize = 1 << 24;

/// Loads a glTF or GLB file from its bytes (`path` names it and locates its buffers),
/// with the default [`LoadOptions`]: buffers only inside the file's folder tree.
pub fn load(path: &Path, bytes: &[u8]) -> Result<Loaded> {
    let options = LoadOptions::default();
    load_in(path, bytes, &mut Sources::new(&options))
}

/// [`load`] within a load: its options say which buffers may be read, and the buffer
/// files read are recorded in `sources`.
pub(crate) fn load_in(path: &Path, bytes: &[u8], sources: &mut Sources<'_>) -> Result<Loaded> {
    check_container(path, bytes)?;
    check_glb_header(path, bytes)?;
    let element = if bytes.starts_with(b"glTF") {
        "GLB container"
    } else {
        "document"
    };
    let invalid = |e: gl::Error| Error::format(path, element, e.to_string());
    let json = if bytes.starts_with(b"glTF") {
        bytes
    } else {
        strip_bom(bytes)
    };
    // Parsed first without the crate's validation, whose checks index the accessors a
    // primitive names before checking that they exist: those indices are checked here,
    // then the document is validated.
    let gltf = gl::Gltf::from_slice_without_validation(json).map_err(invalid)?;
    check_accessor_indices(path, gltf.document.as_json())?;
    let document = gl::Document::from_json(gltf.document.into_json()).map_err(invalid)?;
    let doc = &document;
    let buffers = load_buffers(path, doc, gltf.blob, sources)?;
    let mut budget = decode_budget(&buffers);
    let mut loaded = Loaded {
        up: Some(DVec3::Y),
        ..Loaded::default()
    };

    let node_count = doc.nodes().len();
    let mut parent: Vec<Option<usize>> = vec![None; node_count];
    for node in doc.nodes() {
        for child in node.children() {
            if let Some(p) = parent[child.index()] {
                return Err(Error::format(
                    path,
                    format!("node {}", child.index()),
                    format!(
                        "is a child of both node {p} and node {} (nodes must form trees)",
                        node.index()
                    ),
                ));
            }
            parent[child.index()] = Some(node.index());
        }
    }
    if let Some(node) = first_in_cycle(&parent) {
        return Err(Error::format(
            path,
            format!("node {node}"),
            "is its own ancestor: its children form a cycle (nodes must form trees)",
        ));
    }
    let mut warnings = Warnings::default();
    let listed: Vec<gl::Node<'_>> = if let Some(scene) = doc.default_scene() {
        scene.nodes().collect()
    } else if let Some(first) = doc.scenes().next() {
        let n = doc.scenes().len();
        if n > 1 {
            loaded.report.messages.push(format!(
                "the file has {n} scenes and no default `scene`: scene 0 is drawn, the \
                 others are left out (alternatives drawn together would overlap)"
            ));
        }
        first.nodes().collect()
    } else {
        doc.nodes()
            .filter(|n| parent[n.index()].is_none())
            .collect()
    };
    // A scene lists each node once (glTF 2.0, 5.29); a repeated one would be drawn twice
    // in the same place, every face fighting its copy.
    let mut placed = vec![false; node_count];
    let mut roots = Vec::with_capacity(listed.len());
    for node in listed {
        if std::mem::replace(&mut placed[node.index()], true) {
            warnings
                .repeated_roots
                .add(|| format!("node {}", node.index()));
        } else {
            roots.push(node);
        }
    }
    // Every node has at most one parent, so walking down from parentless roots visits
    // each node once; a root with a parent would be part of a cycle or a subtree.
    for root in &roots {
        if let Some(p) = parent[root.index()] {
            return Err(Error::format(
                path,
                format!("node {}", root.index()),
                format!("is a scene root but also a child of node {p}"),
            ));
        }
    }

    let mut meshes: Vec<Option<Arc<Mesh>>> = vec![None; doc.meshes().len()];
    let mut colors: Vec<[f32; 3]> = vec![[0.8; 3]; doc.meshes().len()];
    // A mesh's bounds, found once however many nodes place it.
    let mut mesh_bounds: Vec<Option<crate::geom::Aabb>> = vec![None; doc.meshes().len()];
    let mut stack: Vec<(gl::Node<'_>, DMat4)> = Vec::new();
    for root in roots {
        stack.push((root, DMat4::IDENTITY));
        while let Some((node, parent_world)) = stack.pop() {
            let node_name = node
                .name()
                .map_or_else(|| format!("node {}", node.index()), str::to_string);
            let local = local_transform(&node).map_err(|m| {
                Error::format(path, format!("node {} ({node_name})", node.index()), m)
            })?;
            let world = parent_world * local;
            if !world.is_finite() {
                return Err(Error::format(
                    path,
                    format!("node {} ({node_name})", node.index()),
                    "the transform (composed with its parents') is not finite",
                ));
            }
            // Children in file order: push them reversed onto the stack.
            let children: Vec<_> = node.children().collect();
            for child in children.into_iter().rev() {
                stack.push((child, world));
            }
            let Some(mesh) = node.mesh() else { continue };
            let m = mesh.index();
            if meshes[m].is_none() {
                let (built, color) = build_mesh(
                    path,
                    &mesh,
                    &buffers,
                    &mut budget,
                    &mut loaded,
                    &mut warnings,
                )?;
                meshes[m] = Some(Arc::new(built));
                colors[m] = color;
            }
            let shared = meshes[m].clone().expect("built above");
            if shared.face_count() == 0 {
                continue; // only points or lines
            }
            // Affine (checked per node), so this is the 3x3 part's determinant.
            let det = world.determinant();
            if det == 0.0 || !det.is_finite() {
                warnings
                    .singular_nodes
                    .add(|| format!("node {} ({node_name})", node.index()));
                continue;
            }
            let bounds = *mesh_bounds[m].get_or_insert_with(|| shared.bounds());
            if let Some(why) = world_out_of_range(&shared, bounds, &world) {
                return Err(Error::format(
                    path,
                    format!("node {} ({node_name})", node.index()),
                    format!("mesh {}: {why}", mesh.index()),
                ));
            }
            loaded.objects.push(ObjectDesc {
                name: node_name,
                mesh: shared,
                transform: world,
                color: colors[m],
                closed: None,
                convex: None,
            });
        }
    }
    warnings.finish(&mut loaded.report.messages);
    Ok(loaded)
}

/// The warnings a file may repeat many times, one line per kind.
#[derive(Default)]
struct Warnings {
    skipped_primitives: Tally,
    singular_nodes: Tally,
    repeated_roots: Tally,
}

impl Warnings {
    fn finish(self, messages: &mut Vec<String>) {
        self.skipped_primitives.finish(messages, |n| {
            format!("{n} primitive(s) skipped: points and lines are not surfaces")
        });
        self.singular_nodes.finish(messages, |n| {
            format!(
                "{n} node(s) with a singular transform (a zero scale, used to hide a node) skipped"
            )
        });
        self.repeated_roots.finish(messages, |n| {
            format!("{n} node(s) listed again by the scene placed once")
        });
    }
}

/// A node that is its own ancestor, if any (`parent` holds each node's only parent).
fn first_in_cycle(parent: &[Option<usize>]) -> Option<usize> {
    // 0: not seen, 1: reaches a root, 2: on the chain being walked.
    let mut state = vec![0u8; parent.len()];
    let mut chain = Vec::new();
    for start in 0..parent.len() {
        let mut at = Some(start);
        while let Some(n) = at {
            match state[n] {
                1 => break,
                2 => return Some(n),
                _ => {}
            }
            state[n] = 2;
            chain.push(n);
            at = parent[n];
        }
        for n in chain.drain(..) {
            state[n] = 1;
        }
    }
    None
}

/// Where a mesh placed by `world` leaves the accepted coordinate range, if it does: the
/// message names the vertex (the scene would refuse it without knowing the node).
fn world_out_of_range(mesh: &Mesh, bounds: crate::geom::Aabb, world: &DMat4) -> Option<String> {
    if bounds.is_empty() {
        return None;
    }
    // A linear image of a box reaches its extremes at the box's corners.
    let inside = bounds
        .corners()
        .iter()
        .all(|&c| coordinate_out_of_range(world.transform_point3(c).to_array()).is_none());
    if inside {
        return None;
    }
    let (_, indices, _) = mesh.polygon_arrays();
    indices.iter().find_map(|&i| {
        let w = world.transform_point3(mesh.positions()[i as usize]);
        coordinate_out_of_range(w.to_array()).map(|_| {
            format!(
                "a vertex is placed beyond the largest coordinate accepted, \
                 {MAX_COORDINATE:e}, by the node's transform"
            )
        })
    })
}

/// A node's local matrix in `f64`: its `matrix`, or `T R S` from its translation,
/// rotation (normalised: exporters write quaternions rounded to `f32`) and scale.
fn local_transform(node: &gl::Node<'_>) -> std::result::Result<DMat4, String> {
    let m = match node.transform() {
        gl::scene::Transform::Matrix { matrix } => {
            let m = DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)));
            if m.row(3) != glam::DVec4::W {
                return Err(format!(
                    "matrix is not affine (last row {:?}, not [0, 0, 0, 1])",
                    m.row(3).to_array()
                ));
            }
            m
        }
        gl::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let q = DQuat::from_array(rotation.map(f64::from));
            if !(q.length() > 0.0) {
                return Err(format!("rotation {rotation:?} is not a unit quaternion"));
            }
            DMat4::from_scale_rotation_translation(
                DVec3::from_array(scale.map(f64::from)),
                q.normalize(),
                DVec3::from_array(translation.map(f64::from)),
            )
        }
    };
    if m.is_finite() {
        Ok(m)
    } else {
        Err("the transform is not finite".into())
    }
}

/// The GLB magic number: the bytes `glTF` (0x46546C67 little-endian).
const GLB_MAGIC: &[u8; 4] = b"glTF";

/// Bytes shown in hex, for messages about binary content (never the raw bytes).
fn hex(bytes: &[u8]) -> String {
    let hex: Vec<String> = bytes.iter().map(|b| format!("{b:02X}")).collect();
    hex.join(" ")
}

/// Refuses a file that is neither a GLB container nor JSON before either parser sees
/// it, naming what it starts with: a `.glb` must start with the magic `glTF` (a JSON
/// glTF named `.glb` is read as JSON), and any other content must be JSON (an object,
/// `{`, after an optional byte-order mark and white space). A `.gltf` holding a GLB
/// container is read as GLB: the content decides, not the extension.
fn check_container(path: &Path, bytes: &[u8]) -> Result<()> {
    if bytes.starts_with(GLB_MAGIC) {
        return Ok(());
    }
    if strip_bom(bytes).trim_ascii_start().starts_with(b"{") {
        return Ok(());
    }
    let head = &bytes[..bytes.len().min(4)];
    let glb = super::extension(path).as_deref() == Some("glb");
    let (element, expected) = if glb {
        (
            "GLB header",
            format!(
                "the magic number is {}, expected {} (\"glTF\"): not a binary glTF file",
                hex(head),
                hex(GLB_MAGIC)
            ),
        )
    } else {
        (
            "document",
            format!(
                "starts with the bytes {}: neither a GLB container (magic {}, \"glTF\") nor \
                 a JSON glTF (an object starting with '{{')",
                hex(head),
                hex(GLB_MAGIC)
            ),
        )
    };
    Err(Error::format(path, element, expected))
}

/// Refuses GLB headers the `gltf` crate would mishandle (a length below the header's
/// own size underflows there).
fn check_glb_header(path: &Path, bytes: &[u8]) -> Result<()> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let word = |i: usize| {
        bytes
            .get(i..i + 4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(Error::format(
            path,
            "GLB header",
            format!("truncated: {} bytes, the header alone has 12", bytes.len()),
        ));
    };
    if version != 2 {
        return Err(Error::format(
            path,
            "GLB header",
            format!("version {version} is not supported (glTF 2.0 only)"),
        ));
    }
    if (length as usize) < 12 + 8 || length as usize > bytes.len() {
        return Err(Error::format(
            path,
            "GLB header",
            format!(
                "truncated or corrupt: the header announces {length} bytes, the file has {}",
                bytes.len()
            ),
        ));
    }
    Ok(())
}

/// An error naming the first primitive that refers to an accessor the document does
/// not have.
fn check_accessor_indices(path: &Path, root: &gl::json::Root) -> Result<()> {
    let n = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let used = primitive
                .attributes
                .values()
                .chain(&primitive.indices)
                .chain(primitive.targets.iter().flatten().flat_map(|t| {
                    [&t.positions, &t.normals, &t.tangents]
                        .into_iter()
                        .flatten()
                }));
            if let Some(bad) = used.map(|a| a.value()).find(|&a| a >= n) {
                return Err(Error::format(
                    path,
                    format!("mesh {m} primitive {p}"),
                    format!("refers to accessor {bad}, and the document has {n}"),
                ));
            }
        }
    }
    Ok(())
}

/// Reads a buffer held in a file (a URI that is not a `data:` one), resolved by the
/// rule of [`super::reference`]: only a regular file, at most the buffer's declared
/// length read. Errors name the glTF file and `element` (the buffer and its URI), then
/// the file that could not be read; a reference the rule refuses is an
/// [`Error::OutsideReference`] naming the buffer.
fn read_buffer_file(
    path: &Path,
    index: usize,
    element: &str,
    uri: &str,
    length: usize,
    sources: &mut Sources<'_>,
) -> Result<Vec<u8>> {
    let file = sources
        .resolve(path, &format!("buffer {index}"), uri, Syntax::Uri)
        .map_err(|e| match e {
            Error::Format { message, .. } => Error::format(path, element, message),
            Error::Io { path: file, source } => {
                Error::format(path, element, format!("{}: {source}", file.display()))
            }
            other => other,
        })?;
    let io = |e: std::io::Error| Error::format(path, element, format!("{}: {e}", file.display()));
    super::check_regular_file(&file).map_err(io)?;
    let mut data = Vec::new();
    std::io::Read::read_to_end(
        &mut std::io::Read::take(std::fs::File::open(&file).map_err(io)?, length as u64),
        &mut data,
    )
    .map_err(io)?;
    sources.record(&file);
    Ok(data)
}

/// Reads every buffer (GLB binary chunk, `data:` URI, or file next to the glTF).
fn load_buffers(
    path: &Path,
    doc: &gl::Document,
    mut blob: Option<Vec<u8>>,
    sources: &mut Sources<'_>,
) -> Result<Vec<Vec<u8>>> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let element = match buffer.source() {
            gl::buffer::Source::Uri(uri) if !uri.starts_with("data:") => {
                format!("buffer {} (uri \"{uri}\")", buffer.index())
            }
            _ => format!("buffer {}", buffer.index()),
        };
        let data = match buffer.source() {
            gl::buffer::Source::Uri(uri) if !uri.starts_with("data:") => {
                gl::buffer::Data(read_buffer_file(
                    path,
                    buffer.index(),
                    &element,
                    uri,
                    buffer.length(),
                    sources,
                )?)
            }
            // Only `data:` URIs and the GLB chunk reach the crate, which is given no
            // folder to read files from.
            source => gl::buffer::Data::from_source_and_blob(source, None, &mut blob)
                .map_err(|e| Error::format(path, element.clone(), e.to_string()))?,
        };
        if data.0.len() < buffer.length() {
            return Err(Error::format(
                path,
                element,
                format!(
                    "truncated: declares {} bytes but holds {}",
                    buffer.length(),
                    data.0.len()
                ),
            ));
        }
        out.push(data.0);
    }
    Ok(out)
}

/// How many values (components) a file's accessors may decode in all: four per byte
/// of its buffers, plus one accessor of [`MAX_VIEWLESS_COUNT`] three-component elements
/// without a buffer view. What is charged is what the meshes hold: a POSITION
/// accessor once per mesh that reads it (its primitives share the vertices), an index
/// accessor once per primitive that reads it (each makes its own faces), and the
/// implicit indices of a primitive without an index accessor. Without a limit, a small
/// file naming the same accessor many times could ask for any amount of memory.
fn decode_budget(buffers: &[Vec<u8>]) -> usize {
    let bytes: usize = buffers.iter().map(Vec::len).sum();
    bytes
        .saturating_mul(4)
        .saturating_add(3 * MAX_VIEWLESS_COUNT)
}

/// Builds the mesh of a glTF mesh (all its triangle primitives) and its first colour.
fn build_mesh(
    path: &Path,
    mesh: &gl::Mesh<'_>,
    buffers: &[Vec<u8>],
    budget: &mut usize,
    loaded: &mut Loaded,
    warnings: &mut Warnings,
) -> Result<(Mesh, [f32; 3])> {
    let mesh_name = match mesh.name() {
        Some(n) => format!("mesh {} \"{n}\"", mesh.index()),
        None => format!("mesh {}", mesh.index()),
    };
    let mut b = MeshBuilder::new();
    let mut materials: HashMap<Option<usize>, u32> = HashMap::new();
    let mut first_color = None;
    // POSITION accessor -> index of its first vertex in the builder.
    let mut vertex_base: HashMap<usize, u32> = HashMap::new();
    for prim in mesh.primitives() {
        let what = format!("{mesh_name} primitive {}", prim.index());
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            warnings
                .skipped_primitives
                .add(|| format!("{what} ({mode:?})"));
            continue;
        }
        let Some(pos) = prim.get(&gl::Semantic::Positions) else {
            return Err(Error::format(path, what, "no POSITION attribute"));
        };
        let pos_element = format!("{what} accessor {} (POSITION)", pos.index());
        if pos.dimensions() != Dimensions::Vec3 {
            return Err(Error::format(
                path,
                pos_element,
                format!("type {:?}, expected VEC3", pos.dimensions()),
            ));
        }
        let n = pos.count();
        let base = match vertex_base.get(&pos.index()) {
            Some(&base) => base,
            None => {
                let base = b.vertex_count() as u32;
                let xyz = read_accessor(&pos, 3, buffers, budget)
                    .map_err(|m| Error::format(path, &pos_element, m))?;
                for (i, p) in xyz.chunks_exact(3).enumerate() {
                    let p = DVec3::new(p[0], p[1], p[2]);
                    // The values are not quoted: they come from a buffer (see the
                    // module docs).
                    if !p.is_finite() {
                        return Err(Error::format(
                            path,
                            pos_element,
                            format!("element {i} is not finite (NaN or infinite)"),
                        ));
                    }
                    if coordinate_out_of_range(p.to_array()).is_some() {
                        return Err(Error::format(
                            path,
                            pos_element,
                            format!(
                                "element {i} is beyond the largest coordinate accepted, \
                                 {MAX_COORDINATE:e}"
                            ),
                        ));
                    }
                    b.push_position(p);
                }
                vertex_base.insert(pos.index(), base);
                base
            }
        };
        let (indices, index_element) = match prim.indices() {
            Some(acc) => {
                let element = format!("{what} accessor {} (indices)", acc.index());
                let integer = matches!(
                    acc.data_type(),
                    DataType::U8 | DataType::U16 | DataType::U32
                );
                if acc.dimensions() != Dimensions::Scalar || !integer || acc.normalized() {
                    return Err(Error::format(
                        path,
                        element,
                        format!(
                            "indices must be unsigned integer scalars, found {:?} {:?}",
                            acc.dimensions(),
                            acc.data_type()
                        ),
                    ));
                }
                let values = read_accessor(&acc, 1, buffers, budget)
                    .map_err(|m| Error::format(path, &element, m))?;
                (
                    values.into_iter().map(|v| v as u64).collect::<Vec<u64>>(),
                    element,
                )
            }
            None => {
                spend(budget, n).map_err(|m| Error::format(path, &pos_element, m))?;
                ((0..n as u64).collect(), pos_element.clone())
            }
        };
        if let Some(k) = indices.iter().position(|&i| i >= n as u64) {
            return Err(Error::format(
                path,
                index_element,
                format!("element {k} is not a vertex of the primitive (it has {n} vertices)"),
            ));
        }
        let material = prim.material();
        let factor = material.pbr_metallic_roughness().base_color_factor();
        let color = clamp_color([factor[0], factor[1], factor[2]].map(f64::from));
        first_color.get_or_insert(color);
        let mid = *materials.entry(material.index()).or_insert_with(|| {
            let name = match (material.name(), material.index()) {
                (Some(n), _) => n.to_string(),
                (None, Some(i)) => format!("material {i}"),
                (None, None) => "default".to_string(),
            };
            b.push_material(Material { name, color })
        });
        let idx = |k: usize| base + indices[k] as u32;
        // Indices are checked above; the builder's error would quote an index.
        let mut push = |t: [u32; 3]| {
            b.push_face(&t, Some(mid)).map(|_| ()).map_err(|_| {
                Error::format(
                    path,
                    &index_element,
                    "a triangle refers to a missing vertex",
                )
            })
        };
        let len = indices.len();
        match mode {
            Mode::Triangles => {
                if len % 3 != 0 {
                    return Err(Error::format(
                        path,
                        index_element,
                        format!("{len} indices do not make whole triangles"),
                    ));
                }
                for k in (0..len).step_by(3) {
                    push([idx(k), idx(k + 1), idx(k + 2)])?;
                }
            }
            Mode::TriangleStrip | Mode::TriangleFan => {
                for i in 0..len.saturating_sub(2) {
                    // Orientation per the specification (3.7.2.1): strips alternate.
                    let t = if mode == Mode::TriangleFan {
                        [idx(i + 1), idx(i + 2), idx(0)]
                    } else if i % 2 == 0 {
                        [idx(i), idx(i + 1), idx(i + 2)]
                    } else {
                        [idx(i), idx(i + 2), idx(i + 1)]
                    };
                    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                        continue; // a joining triangle, not a face
                    }
                    push(t)?;
                }
            }
            _ => unreachable!("other modes skipped above"),
        }
    }
    let (built, report) = b.finish();
    loaded.report.merge(&report);
    Ok((
        built,
        first_color.unwrap_or_else(|| palette_color(mesh.index())),
    ))
}

/// Reads an accessor of `components` per element (1 or 3) as `f64`, checking every
/// range against its buffer view and buffer, applying sparse substitution and integer
/// normalization.
/// `budget` is the number of values the file may still decode (see [`decode_budget`]).
fn read_accessor(
    acc: &gl::Accessor<'_>,
    components: usize,
    buffers: &[Vec<u8>],
    budget: &mut usize,
) -> std::result::Result<Vec<f64>, String> {
    let data_type = acc.data_type();
    let size = data_type.size();
    let elem = components * size;
    let count = acc.count();
    let normalized = acc.normalized();
    let total = count
        .checked_mul(components)
        .filter(|&t| t <= 1 << 31)
        .ok_or_else(|| format!("count {count} is too large"))?;
    let mut out = Vec::new();
    match acc.view() {
        Some(view) => {
            let bytes = view_bytes(&view, buffers)?;
            let stride = view.stride().unwrap_or(elem);
            if stride < elem {
                return Err(format!(
                    "buffer view {} has stride {stride}, smaller than the {elem}-byte element",
                    view.index()
                ));
            }
            if count > 0 {
                let need = stride
                    .checked_mul(count - 1)
                    .and_then(|s| s.checked_add(elem))
                    .and_then(|s| s.checked_add(acc.offset()));
                if need.is_none_or(|need| need > bytes.len()) {
                    return Err(format!(
                        "{count} elements from offset {} overrun buffer view {} ({} bytes)",
                        acc.offset(),
                        view.index(),
                        bytes.len()
                    ));
                }
            }
            spend(budget, total)?;
            out.reserve(total);
            for i in 0..count {
                let at = acc.offset() + i * stride;
                for c in 0..components {
                    out.push(decode(&bytes[at + c * size..], data_type, normalized));
                }
            }
        }
        // Without a buffer view the values are zeros (before sparse substitution); no
        // file size bounds the count then, so a limit does.
        None => {
            if count > MAX_VIEWLESS_COUNT {
                return Err(format!(
                    "{count} elements without a buffer view (at most {MAX_VIEWLESS_COUNT})"
                ));
            }
            spend(budget, total)?;
            out.resize(total, 0.0);
        }
    }
    if let Some(sparse) = acc.sparse() {
        let k = sparse.count();
        let indices = sparse.indices();
        let index_size = match indices.index_type() {
            gl::accessor::sparse::IndexType::U8 => 1,
            gl::accessor::sparse::IndexType::U16 => 2,
            gl::accessor::sparse::IndexType::U32 => 4,
        };
        let index_bytes = view_bytes(&indices.view(), buffers)?;
        let values = sparse.values();
        let value_bytes = view_bytes(&values.view(), buffers)?;
        let fits = |offset: usize, each: usize, len: usize| {
            k.checked_mul(each)
                .and_then(|s| s.checked_add(offset))
                .is_some_and(|end| end <= len)
        };
        if !fits(indices.offset(), index_size, index_bytes.len())
            || !fits(values.offset(), elem, value_bytes.len())
        {
            return Err(format!(
                "sparse: {k} substitutions overrun their buffer views"
            ));
        }
        for s in 0..k {
            let at = indices.offset() + s * index_size;
            let target = match index_size {
                1 => usize::from(index_bytes[at]),
                2 => usize::from(u16::from_le_bytes([index_bytes[at], index_bytes[at + 1]])),
                _ => u32::from_le_bytes([
                    index_bytes[at],
                    index_bytes[at + 1],
                    index_bytes[at + 2],
                    index_bytes[at + 3],
                ]) as usize,
            };
            if target >= count {
                return Err(format!(
                    "sparse substitution {s} targets an element beyond the accessor's \
                     count, {count}"
                ));
            }
            for c in 0..components {
                let at = values.offset() + s * elem + c * size;
                out[target * components + c] = decode(&value_bytes[at..], data_type, normalized);
            }
        }
    }
    Ok(out)
}

/// Takes `values` from the file's decode budget (see [`decode_budget`]).
fn spend(budget: &mut usize, values: usize) -> std::result::Result<(), String> {
    *budget = budget.checked_sub(values).ok_or_else(|| {
        format!(
            "the file's accessors decode to more values than it can hold ({values} more here; \
             a POSITION accessor counts once per mesh, indices once per primitive)"
        )
    })?;
    Ok(())
}

/// The bytes of a buffer view, checked against its buffer.
fn view_bytes<'b>(
    view: &gl::buffer::View<'_>,
    buffers: &'b [Vec<u8>],
) -> std::result::Result<&'b [u8], String> {
    let b = view.buffer().index();
    let buffer = buffers
        .get(b)
        .ok_or_else(|| format!("buffer view {} uses missing buffer {b}", view.index()))?;
    view.offset()
        .checked_add(view.length())
        .and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| {
            format!(
                "buffer view {} (bytes {}..+{}) overruns buffer {b} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                buffer.len()
            )
        })
}

/// One little-endian component as `f64` (normalized integers map to `[-1, 1]` or
/// `[0, 1]` as the specification says). `bytes` holds at least the component.
fn decode(bytes: &[u8], data_type: DataType, normalized: bool) -> f64 {
    match data_type {
        DataType::I8 => {
            let v = f64::from(bytes[0] as i8);
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        DataType::U8 => {
            let v = f64::from(bytes[0]);
            if normalized { v / 255.0 } else { v }
        }
        DataType::I16 => {
            let v = f64::from(i16::from_le_bytes([bytes[0], bytes[1]]));
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U16 => {
            let v = f64::from(u16::from_le_bytes([bytes[0], bytes[1]]));
            if normalized { v / 65535.0 } else { v }
        }
        DataType::U32 => f64::from(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
        DataType::F32 => f64::from(f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
    }
}
