//! obscura scene files (`.toml`): several meshes and built-in primitives placed in one
//! scene, with an optional camera. The format is documented for users, with a complete
//! example, in `docs/scene-files.md`.
//!
//! Input: the path of a `.toml` file. Output: a [`Scene`] whose objects follow the
//! `[[object]]` tables in file order (a mesh file holding several objects contributes
//! them all, in its own order), so face ids follow the file too.
//!
//! - `mesh = "path"` (relative to the scene file, inside its folder tree by the rule of
//!   `super::reference`: an absolute path or one leading out by `..` or a symbolic
//!   link is an [`Error::OutsideReference`] unless
//!   [`LoadOptions::allow_outside_references`](super::LoadOptions) is set) loads any
//!   mesh format of [`super::load_objects`]; a file referenced several times is read
//!   once and its
//!   meshes are shared (`Arc`). Each of its objects is placed with the table's
//!   transform composed with the object's own (`table * own`).
//! - `primitive = "box" | "sphere" | "torus" | "cone" | "grid"` uses the generators of
//!   [`crate::scene::demo`] with the table's parameters.
//! - Transform: `matrix` (16 numbers, row-major, affine), or `translate`, `rotate`
//!   (degrees about x, then y, then z, fixed axes: `R = Rz Ry Rx`) and `scale` (a number
//!   or `[x, y, z]`), composed as `T R S`.
//!
//! Errors name `scene.toml:line`: syntax, an unknown key (`deny_unknown_fields`), a
//! wrong type, a value out of range, a parameter that does not apply, a missing or
//! unsupported mesh file (the error names that file and the referencing line), an
//! invalid camera. Errors inside a referenced file name that file and its line or
//! element, plus the referencing line.
//!
//! A UTF-8 byte-order mark at the start of the file is skipped (by the TOML parser).
//! Warnings from a mesh file are given that file's name.
//!
//! Complexity: parsing is linear in the file; the cost is that of the referenced
//! loaders and generators. Source: obscura's own format (TOML 1.0 syntax).

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DMat4, DVec3};
use serde::Deserialize;
use toml::Spanned;

use super::reference::{Sources, Syntax};
use super::{LoadOptions, Loaded, extension, line_of_offset, load_objects_in, palette_color};
use crate::scene::{Camera, Mesh, ObjectDesc, Projection, Scene, demo};
use crate::{Error, Result};

/// Most faces the primitives of one scene file may generate together (a typo in
/// `segments` should not exhaust memory, nor should a dozen primitives at the limit).
pub const MAX_PRIMITIVE_FACES: u64 = 20_000_000;

/// Most faces all the objects of one scene file may place together, every placement
/// of a mesh counting its faces again (a 1.2 MB file placing one mesh 10,000 times
/// described 200 million faces and ran out of memory). Checked table by table, before
/// the objects are added; the memory budget ([`super::LoadOptions::memory_limit`]) is
/// checked at the same time with [`PLACED_FACE_BYTES`] and [`PLACED_VERTEX_BYTES`].
pub const MAX_PLACED_FACES: u64 = 100_000_000;

/// Bytes a placed face is estimated to take once the scene is viewed (the prepared
/// view's offsets, indices, face and object ids), for the memory budget.
pub const PLACED_FACE_BYTES: u64 = 32;

/// Bytes a placed vertex is estimated to take (its world, eye and screen positions in
/// the prepared view, its outcode), for the memory budget.
pub const PLACED_VERTEX_BYTES: u64 = 80;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    up: Option<Spanned<[f64; 3]>>,
    camera: Option<Spanned<CameraSpec>>,
    #[serde(default, rename = "object")]
    objects: Vec<Spanned<ObjectSpec>>,
    #[serde(default, rename = "cell")]
    cells: Vec<Spanned<CellSpec>>,
    #[serde(default, rename = "portal")]
    portals: Vec<Spanned<PortalSpec>>,
    /// A Quake tools' portal file (PRT1) giving the cells instead of the tables.
    prt: Option<Spanned<String>>,
}

/// A convex cell: `planes`, or a ground-plane polygon `floor` extruded by `height`
/// from `base`, or an axis-aligned box `min`..`max`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CellSpec {
    name: Spanned<String>,
    planes: Option<Spanned<Vec<[f64; 4]>>>,
    floor: Option<Spanned<Vec<[f64; 2]>>>,
    height: Option<Spanned<f64>>,
    base: Option<Spanned<f64>>,
    min: Option<Spanned<[f64; 3]>>,
    max: Option<Spanned<[f64; 3]>>,
}

/// A portal: the two cells it joins (by name) and its convex polygon.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PortalSpec {
    cells: Spanned<[String; 2]>,
    polygon: Spanned<Vec<[f64; 3]>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSpec {
    eye: [f64; 3],
    target: [f64; 3],
    up: Option<Spanned<[f64; 3]>>,
    fov: Option<f64>,
    ortho_height: Option<f64>,
    near: Option<f64>,
    far: Option<f64>,
    /// The lens's shift of the image window, in units of its width and height.
    shift: Option<[f64; 2]>,
    /// The pixels' width over their height.
    pixel_aspect: Option<f64>,
}

#[derive(Deserialize)]
#[serde(untagged, expecting = "a number or an array [x, y, z]")]
enum Scale {
    Uniform(f64),
    Axes([f64; 3]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectSpec {
    name: Option<String>,
    mesh: Option<Spanned<String>>,
    primitive: Option<Spanned<String>>,
    // Primitive parameters.
    size: Option<Spanned<[f64; 3]>>,
    radius: Option<Spanned<f64>>,
    height: Option<Spanned<f64>>,
    major: Option<Spanned<f64>>,
    minor: Option<Spanned<f64>>,
    width: Option<Spanned<f64>>,
    depth: Option<Spanned<f64>>,
    segments: Option<Spanned<u32>>,
    rings: Option<Spanned<u32>>,
    sides: Option<Spanned<u32>>,
    nx: Option<Spanned<u32>>,
    nz: Option<Spanned<u32>>,
    // Appearance and flags.
    color: Option<Spanned<[f64; 3]>>,
    closed: Option<bool>,
    convex: Option<bool>,
    // Placement.
    translate: Option<Spanned<[f64; 3]>>,
    rotate: Option<Spanned<[f64; 3]>>,
    scale: Option<Spanned<Scale>>,
    matrix: Option<Spanned<Vec<f64>>>,
    // Cells and portals: the cells (by name) that hold the object.
    cells: Option<Spanned<Vec<String>>>,
    // Occluder mesh: a mesh file, or a box, in the table's coordinates.
    occluder: Option<Spanned<String>>,
    occluder_box: Option<Spanned<[[f64; 3]; 2]>>,
}

/// The primitives and the parameters each accepts.
const PRIMITIVES: [(&str, &[&str]); 5] = [
    ("box", &["size"]),
    ("sphere", &["radius", "segments", "rings"]),
    ("torus", &["major", "minor", "segments", "sides"]),
    ("cone", &["radius", "height", "segments"]),
    ("grid", &["width", "depth", "nx", "nz"]),
];

/// Reads a scene file, with the default [`LoadOptions`]: meshes only inside its folder
/// tree.
pub fn load(path: &Path) -> Result<Scene> {
    let options = LoadOptions::default();
    let mut sources = Sources::new(&options);
    let mut scene = load_in(path, &mut sources)?;
    scene.set_source_files(sources.into_files());
    Ok(scene)
}

/// [`load`] within a load: its options say which meshes may be read, and the files
/// read are recorded in `sources`.
pub(crate) fn load_in(path: &Path, sources: &mut Sources<'_>) -> Result<Scene> {
    let bytes = sources.read(path)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let line = line_of_offset(
            &String::from_utf8_lossy(e.as_bytes()),
            e.utf8_error().valid_up_to(),
        );
        Error::parse(path, line, "not valid UTF-8 (TOML files are UTF-8)")
    })?;
    let file: SceneFile = toml::from_str(&text).map_err(|e| {
        let line = e.span().map_or(1, |s| line_of_offset(&text, s.start));
        Error::parse(path, line, e.message().trim().to_string())
    })?;
    let budget = crate::budget::MemoryBudget::from_option(sources.options().memory_limit);
    SceneReader {
        path,
        line_starts: super::LineIndex::new(&text),
        text: &text,
        dir: path.parent().unwrap_or(Path::new("")).to_path_buf(),
        cache: HashMap::new(),
        primitive_faces: std::cell::Cell::new(0),
        sources,
        budget,
        placed: (0, 0),
    }
    .read(file)
}

/// A mesh file read once (its report goes to the scene on that first read).
struct CachedFile {
    objects: Vec<ObjectDesc>,
    up: Option<DVec3>,
}

struct SceneReader<'a, 'o> {
    path: &'a Path,
    /// Finds the line of a span in O(log lines) (counting the newlines before it for
    /// every referenced mesh file made many files quadratic).
    line_starts: super::LineIndex,
    /// The file's text (element spans inside an array are found in it).
    text: &'a str,
    /// What the load may read and has read.
    sources: &'a mut Sources<'o>,
    dir: PathBuf,
    cache: HashMap<PathBuf, Arc<CachedFile>>,
    /// Faces of the primitives generated so far (see [`MAX_PRIMITIVE_FACES`]).
    primitive_faces: std::cell::Cell<u64>,
    /// The memory budget of the load.
    budget: crate::budget::MemoryBudget,
    /// Faces and vertices placed so far, each placement counted (see
    /// [`MAX_PLACED_FACES`]).
    placed: (u64, u64),
}

impl SceneReader<'_, '_> {
    fn line(&self, span: &Range<usize>) -> usize {
        self.line_starts.line(span.start)
    }

    fn error(&self, span: &Range<usize>, message: impl Into<String>) -> Error {
        Error::parse(self.path, self.line(span), message)
    }

    fn read(mut self, file: SceneFile) -> Result<Scene> {
        let mut scene = Scene::new();
        let mut file_up = None;
        // Every table's objects first, counted (meshes are shared, so this is cheap),
        // so that totals over the cap or the budget are refused before any object is
        // added (adding checks and bounds every vertex of every placement).
        let mut placed = Vec::with_capacity(file.objects.len());
        for (k, spec) in file.objects.iter().enumerate() {
            let span = spec.span();
            let descs = self.objects_of(spec.get_ref(), &span, k, &mut scene, &mut file_up)?;
            self.count_placed(&descs, &span)?;
            placed.push((span, descs, k));
        }
        // For each table, the scene's objects it placed.
        let mut table_objects: Vec<Vec<u32>> = vec![Vec::new(); file.objects.len()];
        for (span, descs, k) in placed {
            for d in descs {
                let name = d.name.clone();
                let i = scene.add(d).map_err(|e| {
                    self.error(&span, format!("object \"{name}\" cannot be placed: {e}"))
                })?;
                table_objects[k].push(i as u32);
            }
        }
        self.occluders(&file, &table_objects, &mut scene)?;
        self.cells(&file, &table_objects, &mut scene)?;
        let up = match &file.up {
            Some(up) => Some(self.direction(up.get_ref(), &up.span(), "up")?),
            None => file_up,
        };
        if let Some(up) = up {
            scene.set_up(up);
        }
        scene.ensure_not_empty(&self.path.display().to_string())?;
        if let Some(cam) = &file.camera {
            let camera = self.camera(cam.get_ref(), &cam.span(), &scene)?;
            scene.set_camera(Some(camera));
        }
        Ok(scene)
    }

    /// The tables' `occluder` and `occluder_box`: each object's occluder mesh, checked
    /// ([`Scene::set_occluder`]); an error at the key's line names the object.
    fn occluders(
        &mut self,
        file: &SceneFile,
        table_objects: &[Vec<u32>],
        scene: &mut Scene,
    ) -> Result<()> {
        for (k, spec) in file.objects.iter().enumerate() {
            let o = spec.get_ref();
            let span = match (&o.occluder, &o.occluder_box) {
                (None, None) => continue,
                (Some(_), Some(b)) => {
                    return Err(self.error(
                        &b.span(),
                        "give either `occluder` or `occluder_box`, not both",
                    ));
                }
                (Some(m), None) => m.span(),
                (None, Some(b)) => b.span(),
            };
            let [object] = table_objects[k][..] else {
                return Err(self.error(
                    &span,
                    format!(
                        "an occluder mesh needs a table that places one object (this one \
                         places {})",
                        table_objects[k].len()
                    ),
                ));
            };
            let table = self.transform(o, &spec.span())?;
            let (mesh, transform) = if let Some(b) = &o.occluder_box {
                let [min, max] = b.get_ref().map(DVec3::from_array);
                if !(min.is_finite() && max.is_finite() && min.cmplt(max).all()) {
                    return Err(self.error(
                        &span,
                        "`occluder_box` is [[min x, y, z], [max x, y, z]], finite, max above \
                         min on every axis",
                    ));
                }
                (Arc::new(demo::box_mesh(min, max)), table)
            } else {
                let m = o.occluder.as_ref().expect("matched above");
                let f = self.mesh_file(m, scene)?;
                let [fo] = &f.objects[..] else {
                    return Err(self.error(
                        &span,
                        format!(
                            "\"{}\" holds {} objects: an occluder mesh file holds one",
                            m.get_ref(),
                            f.objects.len()
                        ),
                    ));
                };
                (fo.mesh.clone(), table * fo.transform)
            };
            scene
                .set_occluder(object as usize, &mesh, transform)
                .map_err(|e| match e {
                    Error::InvalidObject { object, message } => {
                        self.error(&span, format!("object \"{object}\": {message}"))
                    }
                    e => self.error(&span, e.to_string()),
                })?;
        }
        Ok(())
    }

    /// `prt = "file.prt"`: the cells of a PRT1 file, each leaf the hull of its
    /// portals, the objects inside a hull assigned
    /// ([`crate::cull::portals::prt::assign_objects_inside`]). Not with `[[cell]]`,
    /// `[[portal]]` or an object's `cells`.
    fn prt_cells(
        &mut self,
        file: &SceneFile,
        prt: &Spanned<String>,
        scene: &mut Scene,
    ) -> Result<()> {
        use crate::cull::portals::prt::{assign_objects_inside, parse_prt};
        if let Some(c) = file.cells.first() {
            return Err(self.error(&c.span(), "give either `prt` or [[cell]] tables, not both"));
        }
        if let Some(p) = file.portals.first() {
            return Err(self.error(
                &p.span(),
                "give either `prt` or [[portal]] tables, not both",
            ));
        }
        if let Some(c) = file.objects.iter().find_map(|o| o.get_ref().cells.as_ref()) {
            return Err(self.error(
                &c.span(),
                "`cells` names [[cell]] tables; with `prt` an object goes in the leaf whose \
                 portals' hull holds it",
            ));
        }
        let span = prt.span();
        let (full, reference) = self.resolve_reference(prt)?;
        let bytes = self
            .sources
            .read(&full)
            .map_err(|e| with_reference(e, &reference))?;
        let text = String::from_utf8(bytes)
            .map_err(|_| self.error(&span, format!("\"{}\" is not UTF-8 text", prt.get_ref())))?;
        let mut graph = parse_prt(&text, &full).map_err(|e| with_reference(e, &reference))?;
        assign_objects_inside(&mut graph, scene);
        scene.set_cells(Some(Arc::new(graph)));
        Ok(())
    }

    /// The `[[cell]]` and `[[portal]]` tables: the scene's cells and portals, checked
    /// ([`CellGraph::validate`](crate::cull::portals::CellGraph::validate)); objects
    /// go in the cells their table names, or, without `cells`, in every cell their
    /// bounds meet.
    fn cells(
        &mut self,
        file: &SceneFile,
        table_objects: &[Vec<u32>],
        scene: &mut Scene,
    ) -> Result<()> {
        use crate::cull::portals::floorplan::{assign_objects, convex_ccw, prism_planes};
        use crate::cull::portals::{Cell, CellGraph, CellIssueKind, Portal};
        use crate::geom::Plane;
        if let Some(prt) = &file.prt {
            return self.prt_cells(file, prt, scene);
        }
        if file.cells.is_empty() {
            if let Some(p) = file.portals.first() {
                return Err(self.error(&p.span(), "a [[portal]] needs [[cell]] tables"));
            }
            if let Some(c) = file.objects.iter().find_map(|o| o.get_ref().cells.as_ref()) {
                return Err(self.error(
                    &c.span(),
                    "`cells` names cells, but the file has no [[cell]] table",
                ));
            }
            return Ok(());
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let mut cells: Vec<Cell> = Vec::new();
        for spec in &file.cells {
            let c = spec.get_ref();
            let span = spec.span();
            let name = c.name.get_ref().clone();
            if cells.iter().any(|k| k.name == name) {
                return Err(self.error(&c.name.span(), format!("a second cell named \"{name}\"")));
            }
            let kinds = [
                c.planes.is_some(),
                c.floor.is_some(),
                c.min.is_some() || c.max.is_some(),
            ];
            if kinds.iter().filter(|&&k| k).count() != 1 {
                return Err(self.error(
                    &span,
                    format!("cell \"{name}\": give exactly one of `planes`, `floor` (with `height`), or `min` and `max`"),
                ));
            }
            if c.floor.is_none() && (c.height.is_some() || c.base.is_some()) {
                return Err(self.error(
                    &span,
                    format!("cell \"{name}\": `height` and `base` go with `floor`"),
                ));
            }
            let planes = if let Some(pl) = &c.planes {
                let mut planes = Vec::new();
                for v in pl.get_ref() {
                    let normal = DVec3::new(v[0], v[1], v[2]);
                    if !finite(v) || normal.length() == 0.0 {
                        return Err(self.error(
                            &pl.span(),
                            format!("cell \"{name}\": plane {v:?}: needs a finite, non-zero normal [a, b, c, d]"),
                        ));
                    }
                    planes.push(Plane { normal, d: v[3] });
                }
                planes
            } else if let Some(floor) = &c.floor {
                let poly: Vec<glam::DVec2> = floor
                    .get_ref()
                    .iter()
                    .map(|p| glam::DVec2::new(p[0], p[1]))
                    .collect();
                let poly = convex_ccw(&poly).map_err(|m| {
                    self.error(&floor.span(), format!("cell \"{name}\": floor polygon {m}"))
                })?;
                let base = c.base.as_ref().map_or(0.0, |b| *b.get_ref());
                let Some(height) = &c.height else {
                    return Err(self.error(
                        &span,
                        format!("cell \"{name}\": a `floor` needs a `height`"),
                    ));
                };
                let h = *height.get_ref();
                if !(h.is_finite() && h > 0.0 && base.is_finite()) {
                    return Err(self.error(
                        &height.span(),
                        format!("cell \"{name}\": height must be positive, base finite"),
                    ));
                }
                prism_planes(&poly, base, base + h)
            } else {
                let (Some(min), Some(max)) = (&c.min, &c.max) else {
                    return Err(self.error(
                        &span,
                        format!("cell \"{name}\": a box needs both `min` and `max`"),
                    ));
                };
                let (lo, hi) = (
                    DVec3::from_array(*min.get_ref()),
                    DVec3::from_array(*max.get_ref()),
                );
                if !(lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all()) {
                    return Err(self.error(
                        &max.span(),
                        format!("cell \"{name}\": `max` must exceed `min` on every axis"),
                    ));
                }
                let mut planes = Vec::new();
                for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                    planes.push(Plane::from_point_normal(hi, axis));
                    planes.push(Plane::from_point_normal(lo, -axis));
                }
                planes
            };
            cells.push(Cell {
                name,
                planes,
                objects: Vec::new(),
            });
        }
        let find = |n: &str, span: &Range<usize>| {
            cells
                .iter()
                .position(|c| c.name == n)
                .map(|i| i as u32)
                .ok_or_else(|| self.error(span, format!("no [[cell]] named \"{n}\"")))
        };
        let mut portals = Vec::new();
        for spec in &file.portals {
            let p = spec.get_ref();
            let [a, b] = p.cells.get_ref();
            let cs = [find(a, &p.cells.span())?, find(b, &p.cells.span())?];
            if cs[0] == cs[1] {
                return Err(self.error(
                    &p.cells.span(),
                    format!("a portal from cell \"{a}\" to itself"),
                ));
            }
            let polygon: Vec<DVec3> = p
                .polygon
                .get_ref()
                .iter()
                .map(|v| DVec3::from_array(*v))
                .collect();
            if polygon.len() < 3 || !polygon.iter().all(|v| v.is_finite()) {
                return Err(self.error(
                    &p.polygon.span(),
                    "a portal polygon needs at least 3 finite vertices",
                ));
            }
            portals.push(Portal { cells: cs, polygon });
        }
        let mut graph = CellGraph::new(cells, portals);
        assign_objects(&mut graph, scene);
        for (k, spec) in file.objects.iter().enumerate() {
            let Some(names) = &spec.get_ref().cells else {
                continue;
            };
            let mut ids = Vec::new();
            for n in names.get_ref() {
                ids.push(find_in(&graph, n).ok_or_else(|| {
                    self.error(&names.span(), format!("no [[cell]] named \"{n}\""))
                })?);
            }
            for cell in &mut graph.cells {
                cell.objects.retain(|o| !table_objects[k].contains(o));
            }
            for id in ids {
                graph.cells[id].objects.extend(&table_objects[k]);
            }
        }
        for cell in &mut graph.cells {
            cell.objects.sort_unstable();
            cell.objects.dedup();
        }
        let report = graph.diagnose(Some(scene));
        if let Some(issue) = report.errors().next() {
            let span = match issue.kind {
                CellIssueKind::PortalOffBoundary { portal, .. }
                | CellIssueKind::DegeneratePortal { portal }
                | CellIssueKind::NonPlanarPortal { portal, .. }
                | CellIssueKind::NonConvexPortal { portal }
                | CellIssueKind::BadPortalCells { portal } => file.portals[portal].span(),
                CellIssueKind::OpenCell { cell }
                | CellIssueKind::EmptyCell { cell }
                | CellIssueKind::Leak { cell, .. }
                | CellIssueKind::BadObject { cell, .. }
                | CellIssueKind::ObjectOutside { cell, .. }
                | CellIssueKind::NoGeometry { cell } => file.cells[cell].span(),
                CellIssueKind::Overlap { b, .. } => file.cells[b].span(),
            };
            return Err(self.error(&span, issue.message.clone()));
        }
        for w in report.warnings() {
            scene.report_mut().messages.push(w.message.clone());
        }
        scene.set_cells(Some(Arc::new(graph)));
        Ok(())
    }

    /// Adds the faces and vertices a table places to the totals, refusing totals over
    /// [`MAX_PLACED_FACES`] or the memory budget, at the table's line.
    fn count_placed(&mut self, descs: &[ObjectDesc], span: &Range<usize>) -> Result<()> {
        let (faces, vertices) = descs.iter().fold(self.placed, |(f, v), d| {
            (
                f.saturating_add(d.mesh.polygon_count() as u64),
                v.saturating_add(d.mesh.positions().len() as u64),
            )
        });
        self.placed = (faces, vertices);
        if faces > MAX_PLACED_FACES {
            return Err(self.error(
                span,
                format!(
                    "the objects placed up to this table have {faces} faces, more than the \
                     {MAX_PLACED_FACES} a scene file may place (each placement of a mesh \
                     counts its faces again)"
                ),
            ));
        }
        let bytes = faces
            .saturating_mul(PLACED_FACE_BYTES)
            .saturating_add(vertices.saturating_mul(PLACED_VERTEX_BYTES));
        self.budget
            .check(
                "faces placed by the scene file (each placement counted)",
                faces,
                bytes,
            )
            .map_err(|e| e.budget_at(format!("{}:{}", self.path.display(), self.line(span))))
    }

    /// The objects one `[[object]]` table places.
    fn objects_of(
        &mut self,
        spec: &ObjectSpec,
        span: &Range<usize>,
        k: usize,
        scene: &mut Scene,
        file_up: &mut Option<DVec3>,
    ) -> Result<Vec<ObjectDesc>> {
        let transform = self.transform(spec, span)?;
        let color = match &spec.color {
            Some(c) => {
                let v = c.get_ref();
                if !v.iter().all(|x| (0.0..=1.0).contains(x)) {
                    return Err(self.error(
                        &c.span(),
                        format!("color {v:?}: components must be in 0..=1"),
                    ));
                }
                Some(v.map(|x| x as f32))
            }
            None => None,
        };
        let mut placed = match (&spec.mesh, &spec.primitive) {
            (Some(_), Some(p)) => {
                return Err(self.error(&p.span(), "give either `mesh` or `primitive`, not both"));
            }
            (None, None) => {
                return Err(self.error(
                    span,
                    "this object has neither `mesh = \"file\"` nor `primitive = \"...\"`",
                ));
            }
            (Some(mesh), None) => {
                if let Some((param, s)) = self.parameters(spec).into_iter().next() {
                    return Err(self.error(
                        &s,
                        format!(
                            "`{param}` is a primitive parameter; it does not apply to a mesh file"
                        ),
                    ));
                }
                let file = self.mesh_file(mesh, scene)?;
                if file_up.is_none() {
                    *file_up = file.up;
                }
                let base = spec.name.clone().unwrap_or_else(|| {
                    Path::new(mesh.get_ref()).file_stem().map_or_else(
                        || format!("object {k}"),
                        |s| s.to_string_lossy().into_owned(),
                    )
                });
                let several = file.objects.len() > 1;
                file.objects
                    .iter()
                    .map(|o| ObjectDesc {
                        name: if several {
                            format!("{base}/{}", o.name)
                        } else {
                            base.clone()
                        },
                        mesh: o.mesh.clone(),
                        transform: transform * o.transform,
                        color: o.color,
                        closed: o.closed,
                        convex: o.convex,
                    })
                    .collect()
            }
            (None, Some(kind)) => {
                let (mesh, closed, convex) = self.primitive(spec, kind)?;
                let name = spec
                    .name
                    .clone()
                    .unwrap_or_else(|| format!("{} {k}", kind.get_ref()));
                vec![ObjectDesc {
                    name,
                    mesh: Arc::new(mesh),
                    transform,
                    color: palette_color(k),
                    // Known by construction: no edge adjacency to build (for a grid
                    // of 20 million quads it took 43 % of the loading).
                    closed: Some(closed),
                    convex: Some(convex),
                }]
            }
        };
        for d in &mut placed {
            if let Some(c) = color {
                d.color = c;
            }
            if spec.closed.is_some() {
                d.closed = spec.closed;
            }
            if spec.convex.is_some() {
                d.convex = spec.convex;
            }
        }
        Ok(placed)
    }

    /// The path a file reference (a string of the scene file) stands for, checked by
    /// the scene's source rules (inside the scene's folder unless allowed), and the
    /// "referenced from FILE:LINE" text its read errors carry. A refused reference is
    /// an error at its line.
    fn resolve_reference(&self, r: &Spanned<String>) -> Result<(PathBuf, String)> {
        let span = r.span();
        let reference = format!(
            "referenced from {}:{}",
            self.path.display(),
            self.line(&span)
        );
        let full = self
            .sources
            .resolve(
                self.path,
                &format!("line {}", self.line(&span)),
                r.get_ref(),
                Syntax::Path,
            )
            .map_err(|e| match e {
                Error::Format { message, .. } => self.error(&span, message),
                e @ Error::Io { .. } => with_reference(e, &reference),
                e => e,
            })?;
        Ok((full, reference))
    }

    /// Loads (once) the mesh file a table references.
    fn mesh_file(&mut self, mesh: &Spanned<String>, scene: &mut Scene) -> Result<Arc<CachedFile>> {
        let span = mesh.span();
        let rel = Path::new(mesh.get_ref());
        let full = self.dir.join(rel);
        match extension(&full).as_deref() {
            Some("toml") => {
                return Err(self.error(
                    &span,
                    format!(
                        "\"{}\": a scene file cannot include another scene file",
                        rel.display()
                    ),
                ));
            }
            Some(e) if super::MESH_EXTENSIONS.contains(&e) => {}
            _ => {
                return Err(self.error(
                    &span,
                    format!(
                        "\"{}\": unsupported mesh file type (expected .obj, .gltf, .glb, .stl or .ply)",
                        rel.display()
                    ),
                ));
            }
        }
        let (full, reference) = self.resolve_reference(mesh)?;
        let key = std::fs::canonicalize(&full).unwrap_or_else(|_| full.clone());
        if let Some(file) = self.cache.get(&key) {
            return Ok(file.clone());
        }
        let Loaded {
            objects,
            report,
            up,
        } = load_objects_in(&full, self.sources).map_err(|e| with_reference(e, &reference))?;
        // The mesh file's warnings do not name it (its caller would); here the caller
        // is the scene file, so they get the mesh file's name, the counts of dropped
        // and triangulated faces too.
        scene.report_mut().merge_from_file(&report, &full);
        if objects.iter().all(|o| o.mesh.polygon_count() == 0) {
            scene
                .report_mut()
                .messages
                .push(format!("{}: no usable face ({reference})", full.display()));
        }
        let file = Arc::new(CachedFile { objects, up });
        self.cache.insert(key, file.clone());
        Ok(file)
    }

    /// The primitive parameters given in a table, with their spans.
    fn parameters(&self, s: &ObjectSpec) -> Vec<(&'static str, Range<usize>)> {
        let mut out = Vec::new();
        let mut add = |name: &'static str, span: Option<Range<usize>>| {
            if let Some(span) = span {
                out.push((name, span));
            }
        };
        add("size", s.size.as_ref().map(Spanned::span));
        add("radius", s.radius.as_ref().map(Spanned::span));
        add("height", s.height.as_ref().map(Spanned::span));
        add("major", s.major.as_ref().map(Spanned::span));
        add("minor", s.minor.as_ref().map(Spanned::span));
        add("width", s.width.as_ref().map(Spanned::span));
        add("depth", s.depth.as_ref().map(Spanned::span));
        add("segments", s.segments.as_ref().map(Spanned::span));
        add("rings", s.rings.as_ref().map(Spanned::span));
        add("sides", s.sides.as_ref().map(Spanned::span));
        add("nx", s.nx.as_ref().map(Spanned::span));
        add("nz", s.nz.as_ref().map(Spanned::span));
        out
    }

    fn primitive(&self, s: &ObjectSpec, kind: &Spanned<String>) -> Result<(Mesh, bool, bool)> {
        let name = kind.get_ref().as_str();
        let Some(&(_, accepted)) = PRIMITIVES.iter().find(|(n, _)| *n == name) else {
            let known: Vec<&str> = PRIMITIVES.iter().map(|(n, _)| *n).collect();
            return Err(self.error(
                &kind.span(),
                format!("unknown primitive \"{name}\" (known: {})", known.join(", ")),
            ));
        };
        for (param, span) in self.parameters(s) {
            if !accepted.contains(&param) {
                return Err(self.error(
                    &span,
                    format!(
                        "`{param}` does not apply to a {name} (it takes: {})",
                        accepted.join(", ")
                    ),
                ));
            }
        }
        let length = |v: &Option<Spanned<f64>>, default: f64, what: &str| -> Result<f64> {
            match v {
                None => Ok(default),
                Some(v) if v.get_ref().is_finite() && *v.get_ref() > 0.0 => Ok(*v.get_ref()),
                Some(v) => Err(self.error(
                    &v.span(),
                    format!("{what} = {} must be a positive finite number", v.get_ref()),
                )),
            }
        };
        let count = |v: &Option<Spanned<u32>>, default: u32, min: u32, what: &str| -> Result<u32> {
            match v {
                None => Ok(default),
                Some(v) if *v.get_ref() >= min => Ok(*v.get_ref()),
                Some(v) => Err(self.error(
                    &v.span(),
                    format!("{what} = {} must be at least {min}", v.get_ref()),
                )),
            }
        };
        let too_many = |faces: u64| -> Result<()> {
            let before = self.primitive_faces.get();
            if faces > MAX_PRIMITIVE_FACES {
                Err(self.error(
                    &kind.span(),
                    format!("this {name} would have {faces} faces (at most {MAX_PRIMITIVE_FACES})"),
                ))
            } else if before + faces > MAX_PRIMITIVE_FACES {
                Err(self.error(
                    &kind.span(),
                    format!(
                        "this {name} would have {faces} faces, {} with the primitives before \
                         it (at most {MAX_PRIMITIVE_FACES} in a scene file)",
                        before + faces
                    ),
                ))
            } else {
                self.primitive_faces.set(before + faces);
                Ok(())
            }
        };
        Ok(match name {
            "box" => {
                let size = match &s.size {
                    None => DVec3::ONE,
                    Some(v) if v.get_ref().iter().all(|x| x.is_finite() && *x > 0.0) => {
                        DVec3::from_array(*v.get_ref())
                    }
                    Some(v) => {
                        return Err(self.error(
                            &v.span(),
                            format!(
                                "size {:?} must be three positive finite numbers",
                                v.get_ref()
                            ),
                        ));
                    }
                };
                (demo::box_mesh(-size * 0.5, size * 0.5), true, true)
            }
            "sphere" => {
                let radius = length(&s.radius, 1.0, "radius")?;
                let segments = count(&s.segments, 32, 3, "segments")?;
                let rings = count(&s.rings, 16, 2, "rings")?;
                too_many(2 * u64::from(segments) * u64::from(rings))?;
                (demo::uv_sphere_mesh(radius, segments, rings), true, true)
            }
            "torus" => {
                let major = length(&s.major, 1.0, "major")?;
                let minor = length(&s.minor, 0.25, "minor")?;
                let segments = count(&s.segments, 48, 3, "segments")?;
                let sides = count(&s.sides, 16, 3, "sides")?;
                too_many(u64::from(segments) * u64::from(sides))?;
                (demo::torus_mesh(major, minor, segments, sides), true, false)
            }
            "cone" => {
                let radius = length(&s.radius, 1.0, "radius")?;
                let height = length(&s.height, 2.0, "height")?;
                let segments = count(&s.segments, 32, 3, "segments")?;
                too_many(u64::from(segments) + 1)?;
                (demo::cone_mesh(radius, height, segments), true, true)
            }
            _ => {
                let width = length(&s.width, 1.0, "width")?;
                let depth = length(&s.depth, 1.0, "depth")?;
                let nx = count(&s.nx, 1, 1, "nx")?;
                let nz = count(&s.nz, 1, 1, "nz")?;
                too_many(u64::from(nx) * u64::from(nz))?;
                (demo::grid_mesh(width, depth, nx, nz), false, false)
            }
        })
    }

    /// The table's object-to-world transform (`matrix`, or `T R S`).
    fn transform(&self, s: &ObjectSpec, span: &Range<usize>) -> Result<DMat4> {
        let finite3 = |v: &Spanned<[f64; 3]>, what: &str| -> Result<DVec3> {
            let a = *v.get_ref();
            if a.iter().all(|x| x.is_finite()) {
                Ok(DVec3::from_array(a))
            } else {
                Err(self.error(&v.span(), format!("{what} {a:?} must be finite")))
            }
        };
        let m = if let Some(matrix) = &s.matrix {
            if s.translate.is_some() || s.rotate.is_some() || s.scale.is_some() {
                return Err(self.error(
                    &matrix.span(),
                    "give either `matrix` or `translate`/`rotate`/`scale`, not both",
                ));
            }
            let v = matrix.get_ref();
            if v.len() != 16 {
                return Err(self.error(
                    &matrix.span(),
                    format!(
                        "matrix needs 16 finite numbers (row-major 4x4), found {}",
                        v.len()
                    ),
                ));
            }
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                let at = element_span(self.text, &matrix.span(), k);
                return Err(self.error(
                    &at,
                    format!(
                        "matrix entry {} (row {}, column {}) is {}: the 16 numbers must be \
                         finite",
                        k + 1,
                        k / 4 + 1,
                        k % 4 + 1,
                        v[k]
                    ),
                ));
            }
            if v[12..16] != [0.0, 0.0, 0.0, 1.0] {
                return Err(self.error(
                    &matrix.span(),
                    format!(
                        "matrix must be affine: its last row is {:?}, expected [0, 0, 0, 1]",
                        &v[12..16]
                    ),
                ));
            }
            // Row-major in the file, column-major in glam: transpose.
            DMat4::from_cols_slice(v).transpose()
        } else {
            let t = match &s.translate {
                Some(v) => finite3(v, "translate")?,
                None => DVec3::ZERO,
            };
            let r = match &s.rotate {
                Some(v) => finite3(v, "rotate")?,
                None => DVec3::ZERO,
            };
            let scale = match &s.scale {
                None => DVec3::ONE,
                Some(v) => {
                    let sv = match v.get_ref() {
                        Scale::Uniform(u) => DVec3::splat(*u),
                        Scale::Axes(a) => DVec3::from_array(*a),
                    };
                    if !sv.is_finite() || sv.x == 0.0 || sv.y == 0.0 || sv.z == 0.0 {
                        return Err(self.error(
                            &v.span(),
                            format!(
                                "scale {:?} must be finite and non-zero (a zero scale flattens the object)",
                                sv.to_array()
                            ),
                        ));
                    }
                    // A factor as large as coordinates may be, or as small as objects.
                    let (lo, hi) = (crate::scene::MIN_EXTENT, crate::scene::MAX_COORDINATE);
                    if let Some(f) = sv
                        .to_array()
                        .into_iter()
                        .find(|f| !(lo..=hi).contains(&f.abs()))
                    {
                        let what = if f.abs() > hi {
                            "overflow"
                        } else {
                            "underflow"
                        };
                        return Err(self.error(
                            &v.span(),
                            format!(
                                "scale factor {f:e} is out of the range accepted, {lo:e} to \
                                 {hi:e} in magnitude: the object's coordinates (and their \
                                 products) would {what}"
                            ),
                        ));
                    }
                    sv
                }
            };
            DMat4::from_translation(t)
                * DMat4::from_rotation_z(r.z.to_radians())
                * DMat4::from_rotation_y(r.y.to_radians())
                * DMat4::from_rotation_x(r.x.to_radians())
                * DMat4::from_scale(scale)
        };
        if crate::scene::transform_orientation(&m).is_none() {
            // Judged on scaled columns: only dependent columns are singular, not a
            // determinant that overflows. Pointed at the key that made it.
            let at = [
                s.matrix.as_ref().map(Spanned::span),
                s.scale.as_ref().map(Spanned::span),
                s.rotate.as_ref().map(Spanned::span),
            ]
            .into_iter()
            .flatten()
            .next()
            .unwrap_or_else(|| span.clone());
            return Err(self.error(&at, "the transform is singular (it flattens the object)"));
        }
        Ok(m)
    }

    fn direction(&self, v: &[f64; 3], span: &Range<usize>, what: &str) -> Result<DVec3> {
        // Any length: 1e308 or 1e-300 is scaled before it is normalized.
        if let Some(d) = crate::geom::unit_direction(DVec3::from_array(*v)) {
            Ok(d)
        } else {
            Err(self.error(
                span,
                format!("{what} {v:?} must be a finite non-zero vector"),
            ))
        }
    }

    /// The `[camera]` table as a checked camera; near and far default to the range
    /// that holds the scene's box along the view axis.
    fn camera(&self, c: &CameraSpec, span: &Range<usize>, scene: &Scene) -> Result<Camera> {
        let projection = match (c.fov, c.ortho_height) {
            (Some(_), Some(_)) => {
                return Err(self.error(span, "give either `fov` or `ortho_height`, not both"));
            }
            (_, Some(height)) => Projection::Orthographic { height },
            (fov, None) => Projection::Perspective {
                fov_y_degrees: fov.unwrap_or(45.0),
            },
        };
        let eye = DVec3::from_array(c.eye);
        let target = DVec3::from_array(c.target);
        let up = match &c.up {
            Some(u) => self.direction(u.get_ref(), &u.span(), "[camera] up")?,
            None => scene.up(),
        };
        let mut camera = Camera {
            eye,
            target,
            up,
            projection,
            near: 1.0,
            far: 2.0,
            lens: crate::scene::Lens {
                shift: c.shift.map_or(glam::DVec2::ZERO, glam::DVec2::from_array),
                pixel_aspect: c.pixel_aspect.unwrap_or(1.0),
            },
        };
        camera.fit_depth_range(&scene.bounds());
        if let Some(n) = c.near {
            camera.near = n;
        }
        if let Some(f) = c.far {
            camera.far = f;
        }
        camera
            .validate()
            .map_err(|e| self.error(span, format!("[camera]: {e}")))?;
        Ok(camera)
    }
}

/// The span of the first character of element `k` (from 0) of the array at `span` in
/// `text`, for its line (the whole array when it cannot be found).
fn element_span(text: &str, span: &Range<usize>, k: usize) -> Range<usize> {
    let Some(body) = text.get(span.clone()) else {
        return span.clone();
    };
    let (mut depth, mut index, mut comment) = (0usize, 0usize, false);
    for (i, c) in body.char_indices() {
        if comment {
            comment = c != '\n';
            continue;
        }
        match c {
            '#' => comment = true,
            '[' => depth += 1,
            ']' => depth = depth.saturating_sub(1),
            ',' if depth == 1 => index += 1,
            c if depth == 1 && index == k && !c.is_whitespace() => {
                return span.start + i..span.start + i + 1;
            }
            _ => {}
        }
    }
    span.clone()
}

/// Adds "referenced from scene.toml:N" to an error from a referenced file, keeping the
/// referenced file's own name and line.
fn with_reference(e: Error, reference: &str) -> Error {
    match e {
        Error::Io { path, source } => Error::Io {
            path,
            source: std::io::Error::new(source.kind(), format!("{source} ({reference})")),
        },
        Error::Parse {
            path,
            line,
            message,
        } => Error::Parse {
            path,
            line,
            message: format!("{message} ({reference})"),
        },
        Error::Format {
            path,
            element,
            message,
        } => Error::Format {
            path,
            element,
            message: format!("{message} ({reference})"),
        },
        Error::OutsideReference {
            path,
            element,
            reference: written,
            reason,
        } => Error::OutsideReference {
            path,
            element: format!("{element} ({reference})"),
            reference: written,
            reason,
        },
        other => other,
    }
}

fn find_in(graph: &crate::cull::portals::CellGraph, name: &str) -> Option<usize> {
    graph.cells.iter().position(|c| c.name == name)
}
