//! Feature edges of a mesh, after welding coincident vertices: silhouettes, boundaries,
//! borders, creases, intersection lines and (on request) every other edge.
//!
//! # Input and output
//! [`feature_edges`] takes the scene index and a view and returns, for the objects the
//! view keeps, the edges of the kinds [`EdgeOptions::kinds`] asks for, in world space
//! ([`DrawnEdge`]): mesh edges object by object in the order of their welded adjacency
//! ([`crate::scene::EdgeAdjacency`], vertices welded by exact position, so a triangle
//! soup as STL stores it gives the same edges as the indexed mesh), then intersection
//! lines by polygon pair. Vertex ids are in load order across the scene, polygon
//! numbers as [`View::polygon_base`] counts them.
//!
//! # The kinds (one per edge, by priority)
//! 1. **Silhouette**: between a polygon that faces the eye and one that does not. The
//!    facing of each polygon is decided once, exactly: `orient3d` of a triangle of the
//!    polygon (the fan triangle with the largest area) and the eye (perspective), or
//!    the polygon's first vertex moved back along the view direction (orthographic:
//!    the direction as rounded to that point). Edge-on polygons count as back-facing,
//!    the pipeline's rule (`cull::backface`). [`View::back_facing`] is not used: it is
//!    only set for the closed objects the view culls.
//! 2. **Boundary**: used by one polygon. Edges used by three or more polygons
//!    (non-manifold), or by two polygons that disagree on its direction (inconsistent
//!    orientation, where facing cannot be compared), count as boundaries too.
//! 3. **Border**: between polygons of different colours (materials) of one object, or
//!    between objects: a boundary edge of one object whose ends coincide bitwise in
//!    world space with a boundary edge of another kept object becomes one edge with a
//!    polygon of each (a silhouette if their facing differs, a border otherwise).
//! 4. **Crease**: the angle between the two polygons' normals exceeds
//!    [`EdgeOptions::crease_degrees`] (default 30; a cube's edges are 90). Below
//!    [`MIN_CREASE_DEGREES`] (rounding of coplanar neighbours) an edge is never a crease.
//! 5. **Other**: any remaining edge between two polygons of different faces.
//!
//! Edges between two polygons of one face (the diagonals of a triangulated planar
//! face) are never drawn, unless the face is folded so that their facing differs
//! (a silhouette). **Intersection** lines are not mesh edges: where two polygons pass
//! through each other ([`intersect`]), computed once per scene and kept by the index
//! ([`SceneIndex::intersection_lines`]); their [`DrawnEdge::faces`] are the two
//! polygons, and they are kept when either polygon's object is.
//!
//! # Complexity
//! `O(V + P + E)` per view for `V` vertices, `P` polygons and `E` edges of the kept
//! objects (the adjacency is built once per scene), polygons in parallel; intersection
//! lines `O(T log T)` once per scene for `T` triangles.
//!
//! Sources: seed 004 (hidden lines: which edges a drawing shows); Appel 1967 (contour
//! edges between front and back faces); Shewchuk 1997, "Adaptive precision
//! floating-point arithmetic and fast robust geometric predicates" (`orient3d`).

pub mod intersect;

use std::collections::HashMap;

use glam::DVec3;

use super::{DrawnEdge, EdgeKind, EdgeKinds};
use crate::geom::newell_normal;
use crate::scene::{Object, Projection};
use crate::{Error, Result, SceneIndex, View};

pub use intersect::IntersectionSegment;

/// Below this angle between normals (degrees) an edge is never a crease: neighbours
/// that are coplanar but for rounding.
pub const MIN_CREASE_DEGREES: f64 = 1e-6;

/// Which edges to find.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct EdgeOptions {
    /// The kinds to keep.
    pub kinds: EdgeKinds,
    /// Angle in degrees between the normals of two polygons above which their edge is
    /// a crease (0..=180).
    pub crease_degrees: f64,
}

impl Default for EdgeOptions {
    fn default() -> Self {
        EdgeOptions {
            kinds: EdgeKinds::default(),
            crease_degrees: 30.0,
        }
    }
}

impl EdgeOptions {
    /// These options with other kinds.
    #[must_use]
    pub fn with_kinds(mut self, kinds: EdgeKinds) -> Self {
        self.kinds = kinds;
        self
    }

    /// These options with another crease threshold in degrees.
    #[must_use]
    pub fn with_crease_degrees(mut self, degrees: f64) -> Self {
        self.crease_degrees = degrees;
        self
    }

    /// Refuses a crease threshold that is not a number of degrees in `0..=180`.
    pub fn validate(&self) -> Result<()> {
        if !(0.0..=180.0).contains(&self.crease_degrees) {
            return Err(Error::option(
                "crease",
                format!(
                    "{} is not an angle in degrees between 0 and 180",
                    self.crease_degrees
                ),
            ));
        }
        Ok(())
    }
}

/// What the edge classification needs of one polygon, in world space.
#[derive(Clone, Copy, Debug)]
struct PolygonInfo {
    /// Faces the eye.
    front: bool,
    /// Unit normal (oriented as the mesh's front, mirroring undone); zero if degenerate.
    normal: DVec3,
}

/// How polygons face the camera.
#[derive(Clone, Copy)]
enum Facing {
    Eye(DVec3),
    Direction(DVec3),
}

/// The facing and unit normal of polygon `p` of `object`, whose world vertices are
/// `world`.
fn polygon_info(object: &Object, world: &[DVec3], p: usize, facing: Facing) -> PolygonInfo {
    let poly = object.mesh.polygon(p);
    let a = world[poly[0] as usize];
    let (mut b, mut c, mut best) = (a, a, -1.0);
    for w in poly[1..].windows(2) {
        let (q, r) = (world[w[0] as usize], world[w[1] as usize]);
        let area = (q - a).cross(r - a).length_squared();
        if area > best {
            (b, c, best) = (q, r, area);
        }
    }
    let normal = if poly.len() == 3 {
        (b - a).cross(c - a)
    } else {
        let pts: Vec<DVec3> = poly.iter().map(|&i| world[i as usize]).collect();
        newell_normal(&pts)
    };
    let normal = normal.normalize_or_zero();
    let d = match facing {
        Facing::Eye(eye) => eye,
        Facing::Direction(f) => a - f,
    };
    // orient3d < 0: `d` on the side from which a, b, c turn counter-clockwise.
    let o = crate::geom::orient3d(a, b, c, d);
    let front = if object.mirrored { o > 0.0 } else { o < 0.0 };
    PolygonInfo {
        front,
        normal: if object.mirrored { -normal } else { normal },
    }
}

/// The angle in degrees between two unit normals.
fn normal_angle(n: DVec3, m: DVec3) -> f64 {
    n.cross(m).length().atan2(n.dot(m)).to_degrees()
}

/// A boundary edge waiting to be matched with another object's.
struct Loose {
    object: usize,
    vertices: [u32; 2],
    polygon: u32,
    /// Whether its polygon faces the eye.
    front: bool,
    world: [DVec3; 2],
}

/// The edges of the objects `view` keeps, of the kinds `options` asks for (see the
/// [module documentation](self)). Errors: a crease threshold out of range.
pub fn feature_edges(
    index: &SceneIndex,
    view: &View,
    options: &EdgeOptions,
) -> Result<Vec<DrawnEdge>> {
    options.validate()?;
    let kinds = options.kinds;
    let scene = index.scene();
    let camera = view.camera();
    let facing = match camera.projection {
        Projection::Perspective { .. } => Facing::Eye(camera.eye),
        Projection::Orthographic { .. } => Facing::Direction(camera.basis().2),
    };
    let crease = options.crease_degrees.max(MIN_CREASE_DEGREES);
    let mesh_kinds = [
        EdgeKind::Silhouette,
        EdgeKind::Boundary,
        EdgeKind::Border,
        EdgeKind::Crease,
        EdgeKind::Other,
    ];
    let wants_mesh_edges = mesh_kinds.iter().any(|&k| kinds.contains(k));
    let mut out = Vec::new();
    let mut loose: Vec<Loose> = Vec::new();
    let mut vertex_base = 0u32;
    let adjacency = if wants_mesh_edges {
        index.edge_adjacency()
    } else {
        &[]
    };
    for (k, object) in scene.objects().iter().enumerate() {
        let base = vertex_base;
        vertex_base += object.mesh.positions().len() as u32;
        if !view.kept_objects()[k] || !wants_mesh_edges {
            continue;
        }
        let adj = &adjacency[k];
        let world = object.world_positions();
        let info = polygons_info(object, &world, facing);
        let global = |p: u32| view.polygon_base()[k] + p;
        let mesh = &object.mesh;
        for e in &adj.edges {
            let ends = [world[e.a as usize], world[e.b as usize]];
            let vertices = [base + e.a, base + e.b];
            let (kind, faces) = match (e.uses, e.forward, e.backward) {
                (2, Some(f), Some(g)) => {
                    let (pf, pg) = (info[f as usize], info[g as usize]);
                    let kind = if pf.front != pg.front {
                        EdgeKind::Silhouette
                    } else if mesh.polygon_face(f as usize) == mesh.polygon_face(g as usize) {
                        continue;
                    } else if object.face_color(mesh.polygon_face(f as usize))
                        != object.face_color(mesh.polygon_face(g as usize))
                    {
                        EdgeKind::Border
                    } else if normal_angle(pf.normal, pg.normal) > crease {
                        EdgeKind::Crease
                    } else {
                        EdgeKind::Other
                    };
                    (kind, [Some(global(f)), Some(global(g))])
                }
                (1, f, g) => {
                    let p = f.or(g).expect("an edge used once has a polygon");
                    loose.push(Loose {
                        object: k,
                        vertices,
                        polygon: global(p),
                        front: info[p as usize].front,
                        world: ends,
                    });
                    continue;
                }
                (_, f, g) => (EdgeKind::Boundary, [f.map(global), g.map(global)]),
            };
            if kinds.contains(kind) {
                out.push(DrawnEdge {
                    vertices: Some(vertices),
                    object: Some(k as u32),
                    kind,
                    faces,
                    world: ends,
                });
            }
        }
    }
    out.extend(match_loose(loose, kinds));
    if kinds.contains(EdgeKind::Intersection) {
        let objects = index.triangles().polygon_objects();
        let kept = view.kept_objects();
        for s in index.intersection_lines() {
            let [a, b] = s.polygons.map(|p| objects[p as usize]);
            if !(kept[a as usize] || kept[b as usize]) {
                continue;
            }
            out.push(DrawnEdge {
                vertices: None,
                object: Some(a),
                kind: EdgeKind::Intersection,
                faces: s.polygons.map(Some),
                world: s.world,
            });
        }
    }
    Ok(out)
}

/// [`polygon_info`] of every polygon of `object` (in parallel when there are many).
fn polygons_info(object: &Object, world: &[DVec3], facing: Facing) -> Vec<PolygonInfo> {
    let n = object.mesh.polygon_count();
    #[cfg(feature = "parallel")]
    if n >= 20_000 {
        use rayon::prelude::*;
        return (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|p| polygon_info(object, world, p, facing))
            .collect();
    }
    (0..n)
        .map(|p| polygon_info(object, world, p, facing))
        .collect()
}

/// The boundary edges of the kept objects: those whose ends coincide (bitwise, in world
/// space) with another object's boundary edge become one edge of both objects.
fn match_loose(loose: Vec<Loose>, kinds: EdgeKinds) -> Vec<DrawnEdge> {
    type Key = [u64; 6];
    let bits = |p: DVec3| {
        [
            (p.x + 0.0).to_bits(),
            (p.y + 0.0).to_bits(),
            (p.z + 0.0).to_bits(),
        ]
    };
    let key = |w: &[DVec3; 2]| -> Key {
        let (a, b) = (bits(w[0]), bits(w[1]));
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        [a[0], a[1], a[2], b[0], b[1], b[2]]
    };
    let several_objects = loose.windows(2).any(|w| w[0].object != w[1].object);
    let mut groups: HashMap<Key, Vec<usize>> = HashMap::new();
    if several_objects {
        for (i, l) in loose.iter().enumerate() {
            groups.entry(key(&l.world)).or_default().push(i);
        }
    }
    let mut out = Vec::new();
    for (i, l) in loose.iter().enumerate() {
        let group = groups.get(&key(&l.world)).map_or(&[][..], Vec::as_slice);
        let (kind, faces) = match group {
            [a, b] if loose[*a].object != loose[*b].object => {
                if *a != i {
                    continue; // drawn with the first of the pair
                }
                let other = &loose[*b];
                let kind = if l.front != other.front {
                    EdgeKind::Silhouette
                } else {
                    EdgeKind::Border
                };
                (kind, [Some(l.polygon), Some(other.polygon)])
            }
            [a, ..] if group.len() > 2 => {
                if *a != i {
                    continue;
                }
                (
                    EdgeKind::Boundary,
                    [Some(l.polygon), Some(loose[group[1]].polygon)],
                )
            }
            _ => (EdgeKind::Boundary, [Some(l.polygon), None]),
        };
        if kinds.contains(kind) {
            out.push(DrawnEdge {
                vertices: Some(l.vertices),
                object: Some(l.object as u32),
                kind,
                faces,
                world: l.world,
            });
        }
    }
    out
}
