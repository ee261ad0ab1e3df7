//! Per-object occluder meshes: a simplified mesh that lies inside its object, as the
//! occluder or LOD meshes of game engines, used by the occluders and occlusion-buffer
//! culling methods in place of the object's own faces, and never drawn.
//!
//! # Why it may stand for the object
//! Every point of an occluder mesh lies inside its object's closed, outward-oriented
//! surface. A line of sight from an eye outside the object to a point of the occluder
//! mesh therefore crosses the object's surface first, entering it through a face that
//! faces the eye: that face is drawn (back-face culling keeps it), nearer than the
//! occluder point, so whatever the occluder mesh hides the object's own surface hides.
//! The methods use an occluder mesh only in a view where its object's whole bounding
//! box lies beyond the near plane ([`occluder_usable`]): the eye is then outside the
//! object, and the crossing is not clipped away. An open object has no inside, so only
//! a closed object may have an occluder mesh.
//!
//! # The check ([`Scene::set_occluder`])
//! The occluder mesh's vertices must lie in the object's world box, the object's mesh
//! must be closed (every edge used twice, once each way) and oriented outward (positive
//! signed volume), and every vertex and edge midpoint of the occluder mesh must be inside
//! it by the parity of the crossings of a ray (Jordan's theorem; a ray that grazes an edge
//! is cast again in another direction; a point on the surface counts as inside). Points
//! between the ones tested are not checked: an occluder mesh whose faces bulge out of a
//! concave object between its tested points is the author's error.
//!
//! Complexity: the check is O((v + e) f) for an occluder mesh of v vertices and e edges
//! and an object of f triangles.

use std::sync::Arc;

use glam::{DMat4, DVec3};

use super::{EdgeAdjacency, Mesh, MeshBuilder, Object, Scene};
use crate::view::ViewTransform;
use crate::{Error, Result};

/// Directions the parity ray is cast in (irregular, so that grid-aligned meshes are
/// rarely grazed; the next one is tried when a ray grazes an edge).
const RAY_DIRECTIONS: [[f64; 3]; 4] = [
    [0.577_2, 0.618_1, 0.533_7],
    [-0.301_7, 0.887_3, -0.350_9],
    [0.141_9, -0.523_1, 0.840_3],
    [-0.693_9, -0.412_7, 0.590_1],
];

impl Scene {
    /// Gives object `object` an occluder mesh: `mesh`, placed in the world by
    /// `transform` (pass the object's own [`Object::transform`] for a mesh given in the
    /// object's coordinates), checked as the [module documentation](self) says and
    /// kept in world space ([`Object::occluder`]). Replaces any occluder mesh it had.
    ///
    /// # Errors
    /// [`Error::InvalidObject`] naming the object: an index out of range, an empty mesh
    /// or one with non-finite vertices, an object that is not closed or is inside out, a
    /// vertex outside the object's box, a vertex or edge midpoint outside its mesh.
    pub fn set_occluder(&mut self, object: usize, mesh: &Mesh, transform: DMat4) -> Result<()> {
        let Some(o) = self.objects.get(object) else {
            return Err(Error::option(
                "occluder object",
                format!("object {object} of {}", self.objects.len()),
            ));
        };
        let invalid = |message: String| Error::InvalidObject {
            object: o.name.clone(),
            message: format!("occluder mesh: {message}"),
        };
        let world = bake(mesh, transform).map_err(&invalid)?;
        check_inside(o, &world).map_err(invalid)?;
        self.objects[object].occluder = Some(Arc::new(world));
        Ok(())
    }
}

/// `mesh` in world space (faces reversed when `transform` mirrors, so fronts stay
/// fronts).
fn bake(mesh: &Mesh, transform: DMat4) -> std::result::Result<Mesh, String> {
    if mesh.polygon_count() == 0 {
        return Err("it has no faces".into());
    }
    if !transform.is_finite() || transform.row(3) != glam::DVec4::W {
        return Err("its transform is not a finite affine transform".into());
    }
    let det = transform.determinant();
    if !(det.abs() > 0.0) {
        return Err("its transform is singular".into());
    }
    let mut b = MeshBuilder::new();
    for (i, &p) in mesh.positions().iter().enumerate() {
        let w = transform.transform_point3(p);
        if !w.is_finite() {
            return Err(format!("vertex {i} is not finite"));
        }
        b.push_position(w);
    }
    let mut idx = Vec::new();
    for p in 0..mesh.polygon_count() {
        idx.clear();
        idx.extend_from_slice(mesh.polygon(p));
        if det < 0.0 {
            idx.reverse();
        }
        b.push_face(&idx, None)
            .map_err(|e| format!("face {p}: {e}"))?;
    }
    Ok(b.finish().0)
}

/// Checks that the world-space occluder mesh `occ` lies inside object `o`.
fn check_inside(o: &Object, occ: &Mesh) -> std::result::Result<(), String> {
    if !EdgeAdjacency::new(&o.mesh).is_closed() {
        return Err(
            "the object is not closed (an edge not used twice, once each way): \
             an occluder mesh stands only for a closed object, whose inside no line of \
             sight reaches without crossing its surface"
                .into(),
        );
    }
    let b = &o.bounds;
    let scale = b.min.abs().max(b.max.abs()).max_element().max(1e-300);
    let eps = 1e-9 * scale;
    for (i, &p) in occ.positions().iter().enumerate() {
        if (p.cmplt(b.min - eps) | p.cmpgt(b.max + eps)).any() {
            return Err(format!(
                "vertex {i} ({}, {}, {}) lies outside the object's bounding box \
                 ({:?} to {:?})",
                p.x,
                p.y,
                p.z,
                b.min.to_array(),
                b.max.to_array()
            ));
        }
    }
    // World-space triangles of the object, counter-clockwise seen from outside.
    let world = o.world_positions();
    let mut tris: Vec<[DVec3; 3]> = Vec::new();
    for p in 0..o.mesh.polygon_count() {
        let poly = o.mesh.polygon(p);
        for k in 1..poly.len().saturating_sub(1) {
            let (a, mut bb, mut c) = (
                world[poly[0] as usize],
                world[poly[k] as usize],
                world[poly[k + 1] as usize],
            );
            if o.mirrored {
                std::mem::swap(&mut bb, &mut c);
            }
            tris.push([a, bb, c]);
        }
    }
    let volume: f64 = tris.iter().map(|t| t[0].dot(t[1].cross(t[2]))).sum::<f64>() / 6.0;
    if !(volume > 0.0) {
        return Err(format!(
            "the object is inside out (its signed volume is {volume:e}, not positive): \
             its faces do not face outward"
        ));
    }
    let inside = |q: DVec3| inside_by_parity(&tris, q, eps);
    for (i, &p) in occ.positions().iter().enumerate() {
        if !inside(p) {
            return Err(format!(
                "vertex {i} ({}, {}, {}) lies outside the object's mesh",
                p.x, p.y, p.z
            ));
        }
    }
    let pos = occ.positions();
    for f in 0..occ.polygon_count() {
        let poly = occ.polygon(f);
        for k in 0..poly.len() {
            let (a, c) = (poly[k], poly[(k + 1) % poly.len()]);
            let m = (pos[a as usize] + pos[c as usize]) * 0.5;
            if !inside(m) {
                return Err(format!(
                    "the midpoint ({}, {}, {}) of the edge from vertex {a} to vertex {c} \
                     lies outside the object's mesh",
                    m.x, m.y, m.z
                ));
            }
        }
    }
    Ok(())
}

/// Whether `q` is inside the closed surface `tris` (or on it, within `eps`): the parity
/// of a ray's crossings, cast again in another direction when it grazes an edge or a
/// vertex. After every direction grazes, the point counts as outside (refused).
fn inside_by_parity(tris: &[[DVec3; 3]], q: DVec3, eps: f64) -> bool {
    'directions: for d in RAY_DIRECTIONS {
        let d = DVec3::from_array(d).normalize();
        let mut crossings = 0usize;
        for t in tris {
            let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
            let n = e1.cross(e2);
            let len = n.length();
            if !(len > 0.0) {
                continue;
            }
            // On the triangle's plane and within it: on the surface.
            let dist = n.dot(q - t[0]) / len;
            let pvec = d.cross(e2);
            let det = e1.dot(pvec);
            if dist.abs() <= eps && on_triangle(t, q - n / len * dist, eps) {
                return true;
            }
            // Möller and Trumbore's ray-triangle test.
            if det.abs() <= 1e-12 * e1.length() * e2.length() {
                // The ray runs along the plane: grazing if the plane holds the point.
                if dist.abs() <= eps {
                    continue 'directions;
                }
                continue;
            }
            let inv = 1.0 / det;
            let s = q - t[0];
            let u = s.dot(pvec) * inv;
            let qvec = s.cross(e1);
            let v = d.dot(qvec) * inv;
            let along = e2.dot(qvec) * inv;
            if along <= 0.0 {
                continue;
            }
            const EDGE: f64 = 1e-9;
            let w = 1.0 - u - v;
            if u < -EDGE || v < -EDGE || w < -EDGE {
                continue;
            }
            if u <= EDGE || v <= EDGE || w <= EDGE {
                continue 'directions;
            }
            crossings += 1;
        }
        return crossings % 2 == 1;
    }
    false
}

/// Whether `p` (on the triangle's plane) lies in the triangle, within `eps`.
fn on_triangle(t: &[DVec3; 3], p: DVec3, eps: f64) -> bool {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    (0..3).all(|k| {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        let e = b - a;
        let el = e.length();
        el > 0.0 && n.dot(e.cross(p - a)) / (n.length() * el) >= -eps
    })
}

/// Whether object `o`'s occluder mesh may stand for it in the view `t`: it has one,
/// and its whole world box lies beyond the near plane ([`box_beyond_near`]). The
/// occluders and buffer methods call it per view.
#[must_use]
pub fn occluder_usable(o: &Object, t: &ViewTransform) -> bool {
    o.occluder.is_some() && box_beyond_near(&o.bounds, t)
}

/// Whether every corner of box `b` lies beyond the near plane of view `t` (a hair
/// beyond it): then the eye is outside the box, and no line of sight to a point of
/// the box is clipped before it reaches the box.
#[must_use]
pub fn box_beyond_near(b: &crate::geom::Aabb, t: &ViewTransform) -> bool {
    let near = t.near.max(t.near_limit);
    let near = near + near.abs() * 1e-6;
    b.corners().iter().all(|&c| -t.world_to_eye(c).z > near)
}
