//! Candidate occluders, found once per scene, and their per-view ranking by the
//! Coorg-Teller metric.
//!
//! A candidate is a convex planar polygon of the scene: a face with more than three
//! vertices, or a pair of triangles of one object that share an edge, lie in one plane
//! and make a convex quadrilateral together (the two triangles of a wall). Faces are
//! oriented as back-face culling orients them (counter-clockwise seen from outside, the
//! order reversed in a mirrored object), so a candidate's normal points to the side the
//! face is seen from. Non-convex and non-planar faces are never candidates (their
//! shadow volume is not the convex one of [`super::shadow`]). At most
//! [`MAX_CANDIDATES`] of the largest are kept, and none smaller than
//! [`MIN_RELATIVE_AREA`] of the square of the scene's diagonal.
//!
//! # The metric and its sign
//! Coorg and Teller rank an occluder by `f = -A (n̂ · v̂) / |v|²`: `A` its area, `n̂` its
//! unit normal, `v` the vector from the eye to its centre ([`coorg_teller_metric`]).
//! `-(n̂ · v̂)` is the cosine between the normal and the direction back to the eye, so
//! **`f > 0` means the occluder faces the viewer**, and `f` approximates the solid
//! angle the occluder subtends: a unit square two units in front of the eye, facing it,
//! scores `1/4`. Occluders seen from behind (`f <= 0`) are never used: their faces may
//! be removed by back-face culling, so they would not be drawn to hide anything.
//! For a parallel projection the eye is at infinity; the metric becomes the projected
//! area `-A (n̂ · d̂)` (`d̂` the view direction, [`parallel_metric`]).

use std::collections::HashMap;

use glam::DVec3;

use crate::geom::Aabb;
use crate::geom::newell_normal;
use crate::scene::{Mesh, Scene};
use crate::view::ViewTransform;

/// The most candidates kept per scene (the largest by area).
pub const MAX_CANDIDATES: usize = 4096;

/// Candidates smaller than this fraction of the squared scene diagonal are dropped.
pub const MIN_RELATIVE_AREA: f64 = 1e-7;

/// A polygon is planar enough when no vertex is farther from its plane than this
/// fraction of its size.
const FLATNESS: f64 = 1e-7;

/// One candidate occluder: a convex planar polygon in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    /// The scene polygon it came from (the first of a merged pair); `u32::MAX` for a
    /// face of an occluder mesh.
    pub polygon: u32,
    /// The second triangle of a merged pair.
    pub merged: Option<u32>,
    /// Its object.
    pub object: u32,
    /// World-space vertices, counter-clockwise seen from the side [`Self::normal`]
    /// points to, no two consecutive ones equal.
    pub vertices: Vec<DVec3>,
    /// Unit normal, towards the side the face is seen from.
    pub normal: DVec3,
    /// Area.
    pub area: f64,
    /// The average of the vertices.
    pub centre: DVec3,
    /// The farthest any vertex lies from the plane through [`Self::centre`].
    pub flatness: f64,
    /// For a face of an object's occluder mesh (never drawn), the object's world box:
    /// the candidate is used only in views that have the whole box beyond the near
    /// plane ([`Self::usable`]). `None` for a face of the scene.
    pub stands_for: Option<Aabb>,
}

impl Candidate {
    /// A candidate from world-space vertices ordered counter-clockwise seen from the
    /// front; `None` if the polygon is degenerate (fewer than three distinct vertices,
    /// zero or non-finite area, all vertices on a line), not planar or not convex.
    #[must_use]
    pub fn from_polygon(polygon: u32, object: u32, points: &[DVec3]) -> Option<Candidate> {
        let mut v: Vec<DVec3> = Vec::with_capacity(points.len());
        for &p in points {
            if !p.is_finite() {
                return None;
            }
            if v.last() != Some(&p) {
                v.push(p);
            }
        }
        while v.len() > 1 && v.first() == v.last() {
            v.pop();
        }
        if v.len() < 3 {
            return None;
        }
        let size = v
            .iter()
            .map(|&p| (p - v[0]).length())
            .fold(0.0f64, f64::max);
        let n = newell_normal(&v);
        let len = n.length();
        let area = 0.5 * len;
        // Collinear or tiny against its own size: its plane is not defined.
        if !(area > 1e-9 * size * size) || !area.is_finite() {
            return None;
        }
        let normal = n / len;
        let centre = v.iter().copied().sum::<DVec3>() / v.len() as f64;
        let flatness = v
            .iter()
            .map(|&p| normal.dot(p - centre).abs())
            .fold(0.0f64, f64::max);
        if flatness > FLATNESS * size {
            return None;
        }
        let k = v.len();
        for i in 0..k {
            let a = v[(i + 1) % k] - v[i];
            let b = v[(i + 2) % k] - v[(i + 1) % k];
            // A reflex turn (beyond rounding) makes it non-convex.
            if a.cross(b).dot(normal) < -1e-9 * a.length() * b.length() {
                return None;
            }
        }
        Some(Candidate {
            polygon,
            merged: None,
            object,
            vertices: v,
            normal,
            area,
            centre,
            flatness,
            stands_for: None,
        })
    }

    /// Whether the candidate may be used in view `t`: always for a face of the scene;
    /// for a face of an occluder mesh, when its object's whole box lies beyond the near
    /// plane (see [`crate::scene::occluder`]).
    #[must_use]
    pub fn usable(&self, t: &ViewTransform) -> bool {
        self.stands_for
            .is_none_or(|b| crate::scene::occluder::box_beyond_near(&b, t))
    }
}

/// The candidate occluders of a scene, largest first (see the
/// [module documentation](self)). Built once per scene
/// ([`crate::SceneIndex::occluder_candidates`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OccluderCandidates {
    candidates: Vec<Candidate>,
    /// Faces and merged pairs that qualified before the size cut.
    found: usize,
}

impl OccluderCandidates {
    /// The candidates of a scene: of each object, its own faces, or the faces of its
    /// occluder mesh when it has one ([`crate::scene::Object::occluder`]).
    #[must_use]
    pub fn new(scene: &Scene) -> OccluderCandidates {
        let mut all = Vec::new();
        let mut base = 0u32;
        for (k, o) in scene.objects().iter().enumerate() {
            let n = o.mesh.polygon_count();
            if let Some(occ) = &o.occluder {
                // Already in world space, faces counter-clockwise from outside.
                let from = all.len();
                faces_of(occ, occ.positions(), false, k as u32, None, &mut all);
                for c in &mut all[from..] {
                    c.stands_for = Some(o.bounds);
                }
            } else {
                let world = o.world_positions();
                faces_of(&o.mesh, &world, o.mirrored, k as u32, Some(base), &mut all);
            }
            base += n as u32;
        }
        let found = all.len();
        let diagonal = scene.bounds().extent().length();
        let min_area = MIN_RELATIVE_AREA * diagonal * diagonal;
        all.retain(|c| c.area >= min_area);
        all.sort_by(|a, b| b.area.total_cmp(&a.area).then(a.polygon.cmp(&b.polygon)));
        all.truncate(MAX_CANDIDATES);
        OccluderCandidates {
            candidates: all,
            found,
        }
    }

    /// The candidates, largest first.
    #[must_use]
    pub fn candidates(&self) -> &[Candidate] {
        &self.candidates
    }

    /// How many convex planar faces and merged pairs were found before the cut to the
    /// largest.
    #[must_use]
    pub fn found(&self) -> usize {
        self.found
    }

    /// The number of candidates kept.
    #[must_use]
    pub fn len(&self) -> usize {
        self.candidates.len()
    }

    /// Whether there are none.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.candidates.is_empty()
    }
}

/// Appends the candidates of one mesh: its convex planar faces of more than three
/// vertices and its coplanar triangle pairs, from the world positions `world`
/// (reversed when `mirrored`); `base` is the scene id of its first polygon, `None` for
/// an occluder mesh (whose candidates carry `polygon == u32::MAX`).
fn faces_of(
    mesh: &Mesh,
    world: &[DVec3],
    mirrored: bool,
    object: u32,
    base: Option<u32>,
    all: &mut Vec<Candidate>,
) {
    let n = mesh.polygon_count();
    let id = |p: usize| base.map_or(u32::MAX, |b| b + p as u32);
    let ordered = |poly: &[u32]| -> Vec<DVec3> {
        let mut pts: Vec<DVec3> = poly.iter().map(|&i| world[i as usize]).collect();
        if mirrored {
            pts.reverse();
        }
        pts
    };
    // Triangles by their directed edges (by position, so split vertices still
    // meet), for merging pairs.
    let key = |i: u32| world[i as usize].to_array().map(f64::to_bits);
    let mut edges: HashMap<([u64; 3], [u64; 3]), u32> = HashMap::new();
    for p in 0..n {
        let poly = mesh.polygon(p);
        if poly.len() == 3 {
            for e in 0..3 {
                edges.insert((key(poly[e]), key(poly[(e + 1) % 3])), p as u32);
            }
        }
    }
    let mut used = vec![false; n];
    for p in 0..n {
        let poly = mesh.polygon(p);
        if poly.len() != 3 {
            if let Some(c) = Candidate::from_polygon(id(p), object, &ordered(poly)) {
                all.push(c);
            }
            continue;
        }
        if used[p] {
            continue;
        }
        used[p] = true;
        let mut best: Option<(Candidate, usize)> = None;
        for e in 0..3 {
            let (a, b, c) = (poly[e], poly[(e + 1) % 3], poly[(e + 2) % 3]);
            let Some(&q) = edges.get(&(key(b), key(a))) else {
                continue;
            };
            let q = q as usize;
            if q == p || used[q] {
                continue;
            }
            let other = mesh.polygon(q);
            let Some(d) = other
                .iter()
                .copied()
                .find(|&i| key(i) != key(a) && key(i) != key(b))
            else {
                continue;
            };
            // The pair's outline: a, d, b, c (the shared edge a-b dropped).
            if let Some(mut m) = Candidate::from_polygon(id(p), object, &ordered(&[a, d, b, c])) {
                let single = newell_normal(&ordered(poly)).normalize_or_zero();
                if single.dot(m.normal) > 1.0 - 1e-9 {
                    m.merged = base.map(|_| id(q));
                    best = Some((m, q));
                    break;
                }
            }
        }
        match best {
            Some((m, q)) => {
                used[q] = true;
                all.push(m);
            }
            None => {
                if let Some(c) = Candidate::from_polygon(id(p), object, &ordered(poly)) {
                    all.push(c);
                }
            }
        }
    }
}

/// The Coorg-Teller metric `-A (n̂ · v̂) / |v|²` of an occluder of area `area`, unit
/// normal `normal` and centre `centre` seen from `eye`: positive when it faces the
/// eye (see the [module documentation](self)); zero for an eye at the centre.
#[must_use]
pub fn coorg_teller_metric(area: f64, normal: DVec3, centre: DVec3, eye: DVec3) -> f64 {
    let v = centre - eye;
    let d2 = v.length_squared();
    if !(d2 > 0.0) {
        return 0.0;
    }
    -area * normal.dot(v) / (d2 * d2.sqrt())
}

/// The metric of a parallel projection along `direction`: the projected area
/// `-A (n̂ · d̂)`, positive when the occluder faces the viewer.
#[must_use]
pub fn parallel_metric(area: f64, normal: DVec3, direction: DVec3) -> f64 {
    -area * normal.dot(direction.normalize_or_zero())
}
