//! Meshes of planar convex polygons, and the builder that makes them from raw faces.
//!
//! Every loader and generator goes through [`MeshBuilder`], so the rules for bad
//! faces live in one place:
//! - an index out of range is an error (the loader adds the file and line);
//! - a face with fewer than three distinct vertices, or of zero area, is *degenerate*:
//!   it is dropped and counted (`LoadReport::degenerate_faces`), but still consumes its
//!   face id, so ids keep matching the file's face order;
//! - a planar face whose edges cross (a bow-tie quad, a pentagram) is
//!   *self-intersecting*: it is dropped and counted (`LoadReport::self_intersecting_faces`),
//!   keeping its face id. It has no inside a user would agree on (a bow-tie's two lobes
//!   turn opposite ways: its Newell area can be zero, which had it dropped as "zero
//!   area"; ear clipping a pentagram covers what the even-odd rule leaves out), so it is
//!   not guessed at. Faces of more than [`SELF_INTERSECTION_MAX_VERTICES`] vertices are
//!   not checked (the test is quadratic);
//! - a non-planar n-gon is triangulated and counted (`LoadReport::nonplanar_faces`);
//! - a planar but concave n-gon is triangulated silently (the pipeline wants convex
//!   polygons), counted in `LoadReport::concave_faces`.
//!
//! Triangles produced from one face keep that face's id.

use std::ops::Range;

use glam::DVec3;

use crate::geom::{self, Plane};

/// A material: a name and a diffuse colour (linear RGB in 0..=1).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// The material's name in its file.
    pub name: String,
    /// Diffuse colour.
    pub color: [f32; 3],
}

/// What a loader or generator had to fix or drop, to be reported to the user.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadReport {
    /// Faces dropped for having zero area or fewer than three distinct vertices.
    pub degenerate_faces: usize,
    /// Non-planar n-gons that were triangulated.
    pub nonplanar_faces: usize,
    /// Planar concave n-gons that were triangulated.
    pub concave_faces: usize,
    /// Faces dropped because their edges cross (see the module documentation).
    pub self_intersecting_faces: usize,
    /// Other warnings. Each names the line or element of the file loaded (`line 5: ...`,
    /// `node 3 (...)`) but not that file, which the caller knows and names once (a
    /// scene file's report names the mesh files its warnings come from); a warning
    /// about another file (a material library) names it.
    pub messages: Vec<String>,
    /// How many of `degenerate_faces`, `nonplanar_faces` and `self_intersecting_faces`
    /// a message already reports along with the file they come from
    /// ([`LoadReport::merge_from_file`]): [`LoadReport::warnings`] leaves them out of
    /// its own count lines.
    named_in_messages: [usize; 3],
}

impl LoadReport {
    /// Adds another report's counts and messages to this one.
    pub fn merge(&mut self, other: &LoadReport) {
        self.degenerate_faces += other.degenerate_faces;
        self.nonplanar_faces += other.nonplanar_faces;
        self.concave_faces += other.concave_faces;
        self.self_intersecting_faces += other.self_intersecting_faces;
        self.messages.extend(other.messages.iter().cloned());
        self.named_in_messages[0] += other.named_in_messages[0];
        self.named_in_messages[1] += other.named_in_messages[1];
        self.named_in_messages[2] += other.named_in_messages[2];
    }

    /// Adds the report of another file (a mesh placed by a scene file): its counts
    /// are added, and each of its warnings, counts included, becomes a message that
    /// starts with `file`, so that the user reads which file dropped the faces rather
    /// than the scene file's name alone.
    pub fn merge_from_file(&mut self, other: &LoadReport, file: &std::path::Path) {
        self.degenerate_faces += other.degenerate_faces;
        self.nonplanar_faces += other.nonplanar_faces;
        self.concave_faces += other.concave_faces;
        self.named_in_messages[0] += other.degenerate_faces;
        self.named_in_messages[1] += other.nonplanar_faces;
        self.self_intersecting_faces += other.self_intersecting_faces;
        self.named_in_messages[2] += other.self_intersecting_faces;
        let file = file.display();
        self.messages
            .extend(other.warnings().into_iter().map(|w| format!("{file}: {w}")));
    }

    /// One line per kind of warning, for the user; empty when there is nothing to say.
    #[must_use]
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        let degenerate = self.degenerate_faces - self.named_in_messages[0];
        if degenerate > 0 {
            w.push(format!(
                "{degenerate} degenerate face(s) (zero area or < 3 distinct vertices) dropped",
            ));
        }
        let self_intersecting = self.self_intersecting_faces - self.named_in_messages[2];
        if self_intersecting > 0 {
            w.push(format!(
                "{self_intersecting} self-intersecting face(s) (edges crossing, like a bow-tie quad) dropped",
            ));
        }
        let nonplanar = self.nonplanar_faces - self.named_in_messages[1];
        if nonplanar > 0 {
            w.push(format!("{nonplanar} non-planar face(s) triangulated"));
        }
        w.extend(self.messages.iter().cloned());
        w
    }
}

/// A mesh: vertex positions and planar convex polygons, each carrying the local id of
/// the face it came from (several polygons share an id when a face was triangulated).
///
/// Polygons are stored flat (`polygon_starts` / `polygon_indices`, like a CSR matrix)
/// so that million-face meshes cost a few allocations, not millions.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    positions: Vec<DVec3>,
    polygon_starts: Vec<u32>,
    polygon_indices: Vec<u32>,
    polygon_face: Vec<u32>,
    face_count: u32,
    face_material: Vec<u32>,
    materials: Vec<Material>,
}

impl Mesh {
    /// Vertex positions (object space).
    #[must_use]
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// Number of polygons (after triangulation of non-convex faces).
    #[must_use]
    pub fn polygon_count(&self) -> usize {
        self.polygon_face.len()
    }

    /// Number of triangles its polygons make (a polygon of `n` vertices makes `n - 2`).
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.polygon_starts
            .windows(2)
            .map(|w| (w[1] - w[0]) as usize - 2)
            .sum()
    }

    /// Number of face ids this mesh uses (including dropped degenerate faces).
    #[must_use]
    pub fn face_count(&self) -> u32 {
        self.face_count
    }

    /// The vertex indices of polygon `i`, counter-clockwise seen from its front.
    #[inline]
    #[must_use]
    pub fn polygon(&self, i: usize) -> &[u32] {
        let s = self.polygon_starts[i] as usize;
        let e = self.polygon_starts[i + 1] as usize;
        &self.polygon_indices[s..e]
    }

    /// The local face id of polygon `i`.
    #[inline]
    #[must_use]
    pub fn polygon_face(&self, i: usize) -> u32 {
        self.polygon_face[i]
    }

    /// The CSR arrays: `starts` (one more than the polygon count) and `indices`.
    #[must_use]
    pub fn polygon_arrays(&self) -> (&[u32], &[u32], &[u32]) {
        (
            &self.polygon_starts,
            &self.polygon_indices,
            &self.polygon_face,
        )
    }

    /// Whether every polygon is a triangle.
    #[must_use]
    pub fn is_triangle_mesh(&self) -> bool {
        self.polygon_indices.len() == 3 * self.polygon_face.len()
    }

    /// The polygons that came from local face `face` (empty if it was dropped).
    #[must_use]
    pub fn polygons_of_face(&self, face: u32) -> Range<usize> {
        let lo = self.polygon_face.partition_point(|&f| f < face);
        let hi = self.polygon_face.partition_point(|&f| f <= face);
        lo..hi
    }

    /// The polygon's vertices.
    #[must_use]
    pub fn polygon_points(&self, i: usize) -> Vec<DVec3> {
        self.polygon(i)
            .iter()
            .map(|&v| self.positions[v as usize])
            .collect()
    }

    /// The plane of polygon `i` by Newell's method (object space).
    #[must_use]
    pub fn polygon_plane(&self, i: usize) -> Option<Plane> {
        Plane::newell(&self.polygon_points(i))
    }

    /// The materials referenced by faces.
    #[must_use]
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The material of a local face, if faces carry materials.
    #[must_use]
    pub fn face_material(&self, face: u32) -> Option<&Material> {
        let m = *self.face_material.get(face as usize)?;
        self.materials.get(m as usize)
    }

    /// The box of the vertices actually used by polygons.
    #[must_use]
    pub fn bounds(&self) -> geom::Aabb {
        geom::Aabb::from_points(
            self.polygon_indices
                .iter()
                .map(|&i| self.positions[i as usize]),
        )
    }
}

/// Why a face was refused (as opposed to dropped): the loader turns this into an
/// [`crate::Error`] naming the file and line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FaceError {
    /// A vertex index is not below the number of vertices.
    IndexOutOfRange {
        /// The offending (0-based) index.
        index: u64,
        /// How many vertices there are.
        count: usize,
    },
}

impl std::fmt::Display for FaceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FaceError::IndexOutOfRange { index, count } => write!(
                f,
                "vertex index {index} is out of range (the mesh has {count} vertices, indices 0..{})",
                count.saturating_sub(1)
            ),
        }
    }
}

/// What [`MeshBuilder::push_face`] did with a face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceOutcome {
    /// Kept as one polygon.
    Kept,
    /// Split into this many triangles (non-planar or concave).
    Triangulated(usize),
    /// Dropped as degenerate.
    Dropped,
}

/// Relative tolerance for planarity: a vertex farther than this times the face's
/// diameter from the Newell plane makes the face non-planar.
pub const PLANARITY_TOLERANCE: f64 = 1e-6;

/// Relative tolerance for degeneracy: a face whose area is below this times its
/// diameter squared has zero area.
pub const DEGENERACY_TOLERANCE: f64 = 1e-14;

/// The largest face [`MeshBuilder`] checks for crossing edges (the test compares every
/// pair of edges).
pub const SELF_INTERSECTION_MAX_VERTICES: usize = 256;

/// Whether two edges of a polygon that share no vertex cross or touch, in the plane of
/// its largest triangle (`points` scaled near 1 by the caller). `false` for a polygon
/// whose points are all collinear, and above [`SELF_INTERSECTION_MAX_VERTICES`].
fn edges_cross(points: &[DVec3]) -> bool {
    let n = points.len();
    if !(4..=SELF_INTERSECTION_MAX_VERTICES).contains(&n) {
        return false;
    }
    // The plane: the largest cross product of two edges from the first vertex (the
    // Newell normal of a bow-tie can be zero).
    let o = points[0];
    let mut normal = DVec3::ZERO;
    for i in 1..n - 1 {
        let c = (points[i] - o).cross(points[i + 1] - o);
        if c.length_squared() > normal.length_squared() {
            normal = c;
        }
    }
    if normal == DVec3::ZERO {
        return false;
    }
    // Project along the normal's largest axis.
    let a = normal.abs();
    let (u, v) = if a.x >= a.y && a.x >= a.z {
        (1, 2)
    } else if a.y >= a.z {
        (2, 0)
    } else {
        (0, 1)
    };
    let q: Vec<(f64, f64)> = points.iter().map(|p| (p[u], p[v])).collect();
    let orient = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
        (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
    };
    for i in 0..n {
        let (a, b) = (q[i], q[(i + 1) % n]);
        // Edges that share no vertex with edge i: j from i + 2, and not the edge
        // before i (which is edge n - 1 when i = 0).
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let (c, d) = (q[j], q[(j + 1) % n]);
            let (d1, d2) = (orient(a, b, c), orient(a, b, d));
            let (d3, d4) = (orient(c, d, a), orient(c, d, b));
            // Strictly opposite signs (compared, not multiplied: no underflow).
            let apart = |x: f64, y: f64| (x < 0.0 && y > 0.0) || (x > 0.0 && y < 0.0);
            if apart(d1, d2) && apart(d3, d4) {
                return true;
            }
        }
    }
    false
}

/// Whether a triangle has zero area by [`DEGENERACY_TOLERANCE`], at any scale.
fn triangle_is_degenerate(a: DVec3, b: DVec3, c: DVec3) -> bool {
    let test = |p: &[DVec3]| {
        let (a, b, c) = (p[0], p[1], p[2]);
        let n = (b - a).cross(c - a);
        let diam2 = (b - a)
            .length_squared()
            .max((c - a).length_squared())
            .max((c - b).length_squared());
        !(n.length() > DEGENERACY_TOLERANCE * diam2)
    };
    let p = [a, b, c];
    // Rarely taken: a zero-area verdict that may come from overflow or underflow.
    test(&p) && normalizing_scale(&p).is_none_or(|k| test(&p.map(|v| v * k)))
}

/// The power of two that brings the points' largest coordinate near 1, when their own
/// scale can overflow or underflow the products of the face tests (a coordinate
/// beyond 1e60, or all below 1e-60; the tests are scale-free otherwise). The tests
/// square lengths of cross products, fourth powers of the coordinates: with the
/// former bounds of 1e150, a triangle 1e-100 across had a squared normal of 1e-400,
/// zero, and was dropped as of zero area while one of 1e-200 (normalized) was kept.
/// `None` for a normal scale, or zero or not finite.
fn normalizing_scale(points: &[DVec3]) -> Option<f64> {
    let s = points
        .iter()
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    if !(s.is_finite() && s > 0.0) || (1e-60..=1e60).contains(&s) {
        return None;
    }
    // A power of two: the scaling itself rounds nothing (short of subnormals).
    Some(2f64.powi(-(s.log2().round() as i32)))
}

/// Builds a [`Mesh`] from vertices and faces, applying the rules of the module doc.
#[derive(Debug, Default)]
pub struct MeshBuilder {
    mesh: Mesh,
    report: LoadReport,
    scratch: Vec<u32>,
    points: Vec<DVec3>,
    /// A work bound for triangulating faces instead of [`geom::triangulate`]'s (tests
    /// of the fanned case).
    #[cfg(test)]
    ear_work_budget: Option<usize>,
}

impl MeshBuilder {
    /// An empty builder.
    #[must_use]
    pub fn new() -> Self {
        let mut b = Self::default();
        b.mesh.polygon_starts.push(0);
        b
    }

    /// An empty builder with room for `vertices` and `faces` triangles.
    #[must_use]
    pub fn with_capacity(vertices: usize, faces: usize) -> Self {
        let mut b = Self::new();
        b.mesh.positions.reserve(vertices);
        b.mesh.polygon_starts.reserve(faces);
        b.mesh.polygon_indices.reserve(faces * 3);
        b.mesh.polygon_face.reserve(faces);
        b
    }

    /// Number of vertices so far.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.mesh.positions.len()
    }

    /// Number of face ids used so far.
    #[must_use]
    pub fn face_count(&self) -> u32 {
        self.mesh.face_count
    }

    /// Adds a vertex and returns its index. The caller must have checked that it is
    /// finite (loaders report non-finite coordinates with their file and line).
    pub fn push_position(&mut self, p: DVec3) -> u32 {
        debug_assert!(p.is_finite(), "loaders must refuse non-finite coordinates");
        self.mesh.positions.push(p);
        (self.mesh.positions.len() - 1) as u32
    }

    /// Adds a material and returns its index.
    pub fn push_material(&mut self, material: Material) -> u32 {
        self.mesh.materials.push(material);
        (self.mesh.materials.len() - 1) as u32
    }

    /// Adds a warning message to the report.
    pub fn warn(&mut self, message: impl Into<String>) {
        self.report.messages.push(message.into());
    }

    /// Adds a face (vertex indices, counter-clockwise seen from the front) with an
    /// optional material. The face takes the next face id whatever happens to it.
    pub fn push_face(
        &mut self,
        indices: &[u32],
        material: Option<u32>,
    ) -> Result<FaceOutcome, FaceError> {
        let count = self.mesh.positions.len();
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= count) {
            return Err(FaceError::IndexOutOfRange {
                index: u64::from(bad),
                count,
            });
        }
        let face = self.mesh.face_count;
        self.mesh.face_count += 1;
        if let Some(m) = material {
            if self.mesh.face_material.len() < face as usize {
                // Earlier faces had no material: give them an explicit "none".
                self.mesh.face_material.resize(face as usize, u32::MAX);
            }
            self.mesh.face_material.push(m);
        } else if !self.mesh.face_material.is_empty() {
            self.mesh.face_material.push(u32::MAX);
        }
        Ok(self.add_polygon_checked(indices, face))
    }

    fn add_polygon_checked(&mut self, indices: &[u32], face: u32) -> FaceOutcome {
        let pos = &self.mesh.positions;
        if indices.len() == 3 {
            // Fast path for triangles.
            let (a, b, c) = (
                pos[indices[0] as usize],
                pos[indices[1] as usize],
                pos[indices[2] as usize],
            );
            if triangle_is_degenerate(a, b, c) {
                self.report.degenerate_faces += 1;
                return FaceOutcome::Dropped;
            }
            self.emit(indices, face);
            return FaceOutcome::Kept;
        }
        // Remove repeated vertices (consecutive, and closing) by position.
        self.scratch.clear();
        for &i in indices {
            let p = pos[i as usize];
            if self.scratch.last().is_some_and(|&l| pos[l as usize] == p) {
                continue;
            }
            self.scratch.push(i);
        }
        while self.scratch.len() > 1
            && pos[self.scratch[0] as usize] == pos[*self.scratch.last().unwrap() as usize]
        {
            self.scratch.pop();
        }
        self.points.clear();
        self.points
            .extend(self.scratch.iter().map(|&i| pos[i as usize]));
        let points = &self.points;
        if points.len() < 3 {
            self.report.degenerate_faces += 1;
            return FaceOutcome::Dropped;
        }
        // Every test below is scale-free: done on points scaled near 1 where their own
        // scale would overflow or underflow the products.
        if let Some(k) = normalizing_scale(points) {
            self.points.iter_mut().for_each(|p| *p *= k);
        }
        let points = &self.points;
        let normal = geom::newell_normal(points);
        let diameter = geom::Aabb::from_points(points.iter().copied())
            .extent()
            .length();
        if !(normal.length() * 0.5 > DEGENERACY_TOLERANCE * diameter * diameter) {
            // Zero area: collinear, or lobes of opposite turn that cancel (a bow-tie).
            if edges_cross(points) {
                self.report.self_intersecting_faces += 1;
            } else {
                self.report.degenerate_faces += 1;
            }
            return FaceOutcome::Dropped;
        }
        let scratch = std::mem::take(&mut self.scratch);
        let outcome = if points.len() == 3 {
            self.emit(&scratch, face);
            FaceOutcome::Kept
        } else {
            let planar = geom::max_plane_deviation(points) <= PLANARITY_TOLERANCE * diameter;
            if planar && geom::is_convex(points) {
                self.emit(&scratch, face);
                FaceOutcome::Kept
            } else if planar && edges_cross(points) {
                self.report.self_intersecting_faces += 1;
                FaceOutcome::Dropped
            } else {
                if planar {
                    self.report.concave_faces += 1;
                } else {
                    self.report.nonplanar_faces += 1;
                }
                let geom::Triangulation {
                    triangles: tris,
                    fanned,
                } = self.triangulate();
                if fanned {
                    self.report.messages.push(format!(
                        "face {face}: {} vertices, too many ear tests: its last part was \
                         fanned, and its triangles may overlap or leave it",
                        self.points.len()
                    ));
                }
                let mut kept = 0;
                for t in &tris {
                    let tri = [
                        scratch[t[0] as usize],
                        scratch[t[1] as usize],
                        scratch[t[2] as usize],
                    ];
                    let p = &self.points;
                    let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
                    // Skip slivers of zero area that ear clipping can leave on collinear runs.
                    if (b - a).cross(c - a).length() > DEGENERACY_TOLERANCE * diameter * diameter {
                        self.emit(&tri, face);
                        kept += 1;
                    }
                }
                FaceOutcome::Triangulated(kept)
            }
        };
        self.scratch = scratch;
        outcome
    }

    /// The triangulation of the face in `points` (see [`geom::triangulate_reporting`]).
    fn triangulate(&self) -> geom::Triangulation {
        #[cfg(test)]
        if let Some(budget) = self.ear_work_budget {
            return geom::triangulate_within(&self.points, budget);
        }
        geom::triangulate_reporting(&self.points)
    }

    fn emit(&mut self, indices: &[u32], face: u32) {
        self.mesh.polygon_indices.extend_from_slice(indices);
        self.mesh
            .polygon_starts
            .push(self.mesh.polygon_indices.len() as u32);
        self.mesh.polygon_face.push(face);
    }

    /// The mesh and what was fixed or dropped on the way.
    #[must_use]
    pub fn finish(mut self) -> (Mesh, LoadReport) {
        if !self.mesh.face_material.is_empty() {
            self.mesh
                .face_material
                .resize(self.mesh.face_count as usize, u32::MAX);
        }
        (self.mesh, self.report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn builder(points: &[(f64, f64, f64)]) -> MeshBuilder {
        let mut b = MeshBuilder::new();
        for &(x, y, z) in points {
            b.push_position(DVec3::new(x, y, z));
        }
        b
    }

    #[test]
    fn a_face_whose_triangulation_ran_out_of_work_is_named() {
        // A comb of 4 teeth (outline counter-clockwise): concave, triangulated.
        let mut outline = vec![(0., 0., 0.), (8., 0., 0.), (8., 1., 0.)];
        for t in (0..4).rev() {
            let x = f64::from(t) * 2.0;
            outline.extend([(x + 1.5, 1., 0.), (x + 1.5, 3., 0.), (x + 0.5, 3., 0.)]);
            outline.push((x + 0.5, 1., 0.));
        }
        outline.push((0., 1., 0.));
        let face: Vec<u32> = (0..outline.len() as u32).collect();
        let n = face.len();
        // The normal bound: ears to the end, no message.
        let mut b = builder(&outline);
        assert_eq!(
            b.push_face(&face, None),
            Ok(FaceOutcome::Triangulated(n - 2))
        );
        assert!(b.report.messages.is_empty(), "{:?}", b.report.messages);
        // A bound of a few units: the rest is fanned, and the report names the face.
        let mut b = builder(&outline);
        b.ear_work_budget = Some(3);
        b.push_face(&face, None).unwrap();
        b.push_face(&face, None).unwrap();
        assert_eq!(b.report.messages.len(), 2, "{:?}", b.report.messages);
        assert!(
            b.report.messages[1].starts_with(&format!("face 1: {n} vertices, too many ear tests")),
            "{}",
            b.report.messages[1]
        );
    }

    #[test]
    fn face_tests_do_not_depend_on_the_scale() {
        // The same faces at 1e-200, 1, 1e200 and 1e308: products of coordinates
        // (areas, squared diameters) underflowed or overflowed, so every face was
        // dropped as degenerate and a file of huge coordinates was reported empty
        // instead of out of range.
        for k in [
            1e-200, 1e-100, 1e-70, 1e-40, 1.0, 1e40, 1e70, 1e100, 1e200, 1e308,
        ] {
            let mut b = builder(&[
                (0., 0., 0.),
                (k, 0., 0.),
                (k, k, 0.),
                (0., k, 0.),
                (0.5 * k, 0.25 * k, 0.),
                (-k, 0., 0.),
            ]);
            assert_eq!(b.push_face(&[5, 1, 2], None), Ok(FaceOutcome::Kept), "{k}");
            // Non-convex: triangulated, both triangles kept.
            assert_eq!(
                b.push_face(&[0, 1, 2, 4, 3], None),
                Ok(FaceOutcome::Triangulated(3)),
                "{k}"
            );
            assert_eq!(
                b.push_face(&[0, 1, 2, 3], None),
                Ok(FaceOutcome::Kept),
                "{k}"
            );
            // Collinear: still degenerate at every scale.
            assert_eq!(
                b.push_face(&[5, 0, 1], None),
                Ok(FaceOutcome::Dropped),
                "{k}"
            );
            assert_eq!(
                b.push_face(&[5, 0, 1, 0], None),
                Ok(FaceOutcome::Dropped),
                "{k}"
            );
            let (m, r) = b.finish();
            assert_eq!(r.degenerate_faces, 2, "{k}");
            assert_eq!(m.polygon_count(), 5, "{k}");
        }
    }

    #[test]
    fn self_intersecting_faces_are_named_not_taken_for_zero_area() {
        for k in [1e-200, 1e-100, 1e-20, 1.0, 1e20, 1e200] {
            // 0..3: a bow-tie's corners (its Newell area is zero: two lobes of opposite
            // turn), 4: the tip of a pentagram with 0..3, 5..9: a pentagram.
            let star: Vec<(f64, f64, f64)> = (0..5)
                .map(|i| {
                    let a = std::f64::consts::TAU * f64::from(i * 2 % 5) / 5.0;
                    (a.cos() * k, a.sin() * k, 0.0)
                })
                .collect();
            let mut pts = vec![(0.0, 0.0, 0.0), (k, k, 0.0), (k, 0.0, 0.0), (0.0, k, 0.0)];
            pts.push((2.0 * k, 2.0 * k, 0.0));
            pts.extend(star);
            let mut b = builder(&pts);
            // Bow-tie with equal lobes: zero Newell area.
            assert_eq!(b.push_face(&[0, 1, 2, 3], None), Ok(FaceOutcome::Dropped));
            // Pentagram: non-zero Newell area, edges crossing.
            assert_eq!(
                b.push_face(&[5, 6, 7, 8, 9], None),
                Ok(FaceOutcome::Dropped),
                "{k}"
            );
            // The same corners in order: a square, kept.
            assert_eq!(b.push_face(&[0, 2, 1, 3], None), Ok(FaceOutcome::Kept));
            // Concave but simple (a dart): triangulated as before.
            assert_eq!(
                b.push_face(&[0, 2, 1, 4, 3], None),
                Ok(FaceOutcome::Triangulated(3)),
                "{k}"
            );
            // Collinear: degenerate, not self-intersecting.
            assert_eq!(b.push_face(&[0, 1, 4, 1], None), Ok(FaceOutcome::Dropped));
            let (m, r) = b.finish();
            assert_eq!(
                (r.self_intersecting_faces, r.degenerate_faces),
                (2, 1),
                "{k}"
            );
            assert_eq!(m.face_count(), 5);
            assert!(
                r.warnings()
                    .iter()
                    .any(|w| w.contains("2 self-intersecting")),
                "{:?}",
                r.warnings()
            );
        }
    }

    #[test]
    fn triangles_quads_and_ids() {
        let mut b = builder(&[
            (0., 0., 0.),
            (1., 0., 0.),
            (1., 1., 0.),
            (0., 1., 0.),
            (2., 2., 0.),
        ]);
        assert_eq!(b.push_face(&[0, 1, 2], None), Ok(FaceOutcome::Kept));
        assert_eq!(b.push_face(&[0, 1, 2, 3], None), Ok(FaceOutcome::Kept));
        // collinear: degenerate, dropped, but the id is consumed
        assert_eq!(b.push_face(&[0, 2, 4], None), Ok(FaceOutcome::Dropped));
        assert_eq!(b.push_face(&[0, 0, 1], None), Ok(FaceOutcome::Dropped));
        assert_eq!(b.push_face(&[1, 2, 3], None), Ok(FaceOutcome::Kept));
        assert_eq!(
            b.push_face(&[0, 9, 1], None),
            Err(FaceError::IndexOutOfRange { index: 9, count: 5 })
        );
        let (m, r) = b.finish();
        assert_eq!(m.polygon_count(), 3);
        assert_eq!(m.face_count(), 5);
        assert_eq!(
            (m.polygon_face(0), m.polygon_face(1), m.polygon_face(2)),
            (0, 1, 4)
        );
        assert_eq!(m.polygon(1), &[0, 1, 2, 3]);
        assert_eq!(r.degenerate_faces, 2);
        assert_eq!(m.polygons_of_face(2), 2..2);
        assert_eq!(m.polygons_of_face(4), 2..3);
    }

    #[test]
    fn nonplanar_and_concave_faces_are_triangulated_with_one_id() {
        let mut b = builder(&[(0., 0., 0.), (1., 0., 0.), (1., 1., 0.3), (0., 1., 0.)]);
        assert_eq!(
            b.push_face(&[0, 1, 2, 3], None),
            Ok(FaceOutcome::Triangulated(2))
        );
        let mut c = builder(&[
            (0., 0., 0.),
            (2., 0., 0.),
            (1., 0.5, 0.),
            (2., 2., 0.),
            (0., 2., 0.),
        ]);
        assert_eq!(
            c.push_face(&[0, 1, 2, 3, 4], None),
            Ok(FaceOutcome::Triangulated(3))
        );
        let (m, r) = b.finish();
        assert_eq!(r.nonplanar_faces, 1);
        assert_eq!(m.polygon_count(), 2);
        assert_eq!(m.polygons_of_face(0), 0..2);
        let (_, r) = c.finish();
        assert_eq!(r.concave_faces, 1);
        assert_eq!(r.nonplanar_faces, 0);
    }

    #[test]
    fn materials_per_face() {
        let mut b = builder(&[(0., 0., 0.), (1., 0., 0.), (1., 1., 0.)]);
        b.push_face(&[0, 1, 2], None).unwrap();
        let red = b.push_material(Material {
            name: "red".into(),
            color: [1., 0., 0.],
        });
        b.push_face(&[0, 1, 2], Some(red)).unwrap();
        b.push_face(&[0, 1, 2], None).unwrap();
        let (m, _) = b.finish();
        assert!(m.face_material(0).is_none());
        assert_eq!(m.face_material(1).unwrap().name, "red");
        assert!(m.face_material(2).is_none());
    }
}
