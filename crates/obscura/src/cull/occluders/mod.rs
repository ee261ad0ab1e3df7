//! Occluders, from a point (seed 000 "από-Σημείο (2)-(6)"): candidate planar occluders
//! ranked by the Coorg-Teller metric `-A (n · v) / |v|^2`, their shadow (occlusion)
//! volumes, and the scene's bounds hierarchy walked against them: a node inside a
//! shadow volume is culled, outside kept, straddling opened.
//!
//! Paper: S. Coorg and S. Teller, "Real-time occlusion culling for models with large
//! occluders", Symposium on Interactive 3D Graphics, 1997.
//!
//! | part | module |
//! | --- | --- |
//! | candidates (large convex planar faces, coplanar triangle pairs), once per scene; the metric and its sign | [`select`](mod@select) |
//! | the shadow volume of one convex occluder, box inside / outside / straddling, margins | [`shadow`] |
//! | the binary hierarchy over the clusters' boxes, once per scene, and its walk | [`walk`] |
//!
//! Per view ([`CullMethod::Occluders`](super::occlusion::CullMethod::Occluders)): every
//! candidate that faces the viewer (`f > 0`), lies wholly beyond the near plane (a
//! part in front of it would be clipped away and hide nothing) and is not wholly
//! outside the view volume is ranked by the metric; the best
//! [`CullOptions::max_occluders`] whose shadow volumes are well defined are used, best
//! first, and listed in [`Culling::occluders`] as their scene polygons. The walk culls
//! clusters inside a volume with [`CullReason::Occluder`] (the volume's rank); an
//! object all of whose clusters are culled is culled whole, with its first cluster's
//! reason. With [`CullOptions::clusters`] off only whole objects are culled.
//!
//! Why an occluder that is used is always drawn: it faces the viewer clearly (so
//! back-face culling keeps it), it is wholly beyond the near plane, and what it hides
//! lies on lines of sight that cross it first, so the frustum cannot remove it without
//! removing what it hides, and another occluder can only hide it together with what it
//! hides (shadow volumes nest).
//!
//! An object's occluder mesh ([`crate::scene::Object::occluder`], never drawn) gives
//! the candidates in place of its faces. It lies inside the object's closed,
//! outward-facing surface, so a line of sight through it crosses a drawn face of the
//! object first; it is used only in views that have the object's whole box beyond the
//! near plane ([`select::Candidate::usable`]), where that face is not clipped away
//! (see [`crate::scene::occluder`]). Such an occluder is listed in
//! [`Culling::occluders`] as `u32::MAX`.
//!
//! # Limits: partial occlusion and fusion
//! One occluder at a time is tested: a box that two walls hide together, neither
//! alone, is kept. This is the partial-occlusion problem the notes raise (after
//! Papaioannou: each occluder must hide the box on its own, as a solid occluder would);
//! fusing occluders is the occlusion buffer's job ([`super::buffer`]).

pub mod select;
pub mod shadow;
pub mod walk;

use std::time::Instant;

use glam::DVec3;

use self::select::{OccluderCandidates, coorg_teller_metric, parallel_metric};
use self::shadow::ShadowVolume;
use super::frustum::{Containment, classify_clip_points};
use super::occlusion::{CullOptions, CullReason, Culling};
use crate::Result;
use crate::index::SceneIndex;
use crate::view::ViewTransform;

/// The margin of the shadow volumes' edge planes, in pixels (see [`shadow`]).
pub const PIXEL_MARGIN: f64 = 0.05;

/// The occluders of one view, best first: each candidate's number in
/// [`OccluderCandidates::candidates`] and its shadow volume (see the
/// [module documentation](self) for which qualify).
#[must_use]
pub fn select(
    candidates: &OccluderCandidates,
    t: &ViewTransform,
    max_occluders: usize,
) -> Vec<(usize, ShadowVolume)> {
    if max_occluders == 0 {
        return Vec::new();
    }
    // The view direction in world space (the camera looks down eye -z).
    let direction = t.rotation.transpose() * DVec3::NEG_Z;
    let p = &t.projection;
    let (sx, sy) = (p.x_axis.x.abs(), p.y_axis.y.abs());
    // One pixel: in tangent units (perspective) or world units (parallel).
    let pixel = (2.0 / (sx * t.width)).max(2.0 / (sy * t.height));
    let margin = PIXEL_MARGIN * pixel;
    let near = t.near.max(t.near_limit);
    let near = near + near.abs() * 1e-6;
    let mut ranked: Vec<(f64, usize)> = Vec::new();
    for (i, c) in candidates.candidates().iter().enumerate() {
        let f = if t.orthographic {
            parallel_metric(c.area, c.normal, direction)
        } else {
            coorg_teller_metric(c.area, c.normal, c.centre, t.eye)
        };
        if !(f > 0.0) || !c.usable(t) {
            continue;
        }
        if c.vertices.iter().any(|&v| !(-t.world_to_eye(v).z > near)) {
            continue;
        }
        if classify_clip_points(c.vertices.iter().map(|&v| t.world_to_clip(v)))
            == Containment::Outside
        {
            continue;
        }
        ranked.push((f, i));
    }
    ranked.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut out = Vec::new();
    for &(_, i) in &ranked {
        if out.len() >= max_occluders {
            break;
        }
        let c = &candidates.candidates()[i];
        let v = if t.orthographic {
            ShadowVolume::parallel(c, direction, margin, t.far - t.near)
        } else {
            ShadowVolume::perspective(c, t.eye, margin)
        };
        if let Some(v) = v {
            out.push((i, v));
        }
    }
    out
}

/// Culls, among what the frustum left, the objects and clusters inside the shadow
/// volume of one of the best-ranked occluders.
pub(crate) fn cull(
    index: &SceneIndex<'_>,
    t: &ViewTransform,
    options: &CullOptions,
    c: &mut Culling,
) -> Result<()> {
    let s = Instant::now();
    let candidates = index.occluder_candidates();
    let bvh = index.cluster_bvh();
    c.stage("occluder candidates", s);
    let s = Instant::now();
    let selected = select(candidates, t, options.max_occluders);
    c.occluders = selected
        .iter()
        .map(|&(i, _)| candidates.candidates()[i].polygon)
        .collect();
    c.stage("rank occluders", s);
    if selected.is_empty() {
        c.notes.push(format!(
            "occluders: none of the {} candidates faces the viewer wholly beyond the near plane: nothing culled by occluders",
            candidates.len()
        ));
        return Ok(());
    }
    let s = Instant::now();
    let clusters = index.clusters();
    let volumes: Vec<ShadowVolume> = selected.into_iter().map(|(_, v)| v).collect();
    let mut decisions = c.clusters.clone();
    // Clusters of objects culled whole are not looked at again.
    for (cl, d) in decisions.iter_mut().enumerate() {
        if d.is_none() {
            *d = c.objects[clusters.object(cl) as usize];
        }
    }
    bvh.walk(&volumes, &mut decisions);
    for k in 0..c.objects.len() {
        let range = clusters.of_object(k);
        if c.objects[k].is_some() || range.is_empty() {
            continue;
        }
        if range.clone().all(|cl| decisions[cl].is_some()) {
            if let Some(r) = decisions[range.start] {
                c.cull_object(k, r);
            }
        } else if options.clusters {
            for cl in range {
                if let Some(r @ CullReason::Occluder(_)) = decisions[cl] {
                    c.cull_cluster(cl, r);
                }
            }
        }
    }
    c.stage("occluder walk", s);
    Ok(())
}
