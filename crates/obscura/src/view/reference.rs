//! The front end as first written, one pass per stage: the tests compare [`prepare`]
//! with it bit for bit.

use std::time::Instant;

use glam::{DVec3, DVec4};

use super::prepare::{checked_transform, visible_objects};
use super::*;
use crate::Result;
use crate::clip::outcode_homogeneous;
use crate::clip::sutherland_hodgman::{ClipEyeVertex, clip_polygon_homogeneous_masked};
use crate::geom::newell_normal;
use crate::scene::{Camera, Scene, Viewport};

/// The front end as first written: one pass per stage, intermediate lists, a clip-space
/// copy of every vertex. [`prepare`] must give the same view.
pub(super) fn prepare_reference<'s>(
    scene: &'s Scene,
    camera: &Camera,
    viewport: Viewport,
    options: &PrepareOptions,
) -> Result<PreparedView<'s>> {
    let t = checked_transform(scene, camera, viewport)?;
    let mut stats = PipelineStats::default();

    let mut visible = visible_objects(scene, &t, options, None, &mut stats);

    // Vertices: world -> eye -> clip, outcodes, screen positions.
    let start = Instant::now();
    let vertex_total: usize = visible
        .iter()
        .map(|&(k, _)| scene.objects()[k].mesh.positions().len())
        .sum();
    let mut vertices: Vec<ViewVertex> = Vec::with_capacity(vertex_total);
    let mut clip: Vec<DVec4> = Vec::with_capacity(vertex_total);
    let mut codes: Vec<u8> = Vec::with_capacity(vertex_total);
    let mut bases: Vec<u32> = Vec::with_capacity(visible.len());
    for &(k, _) in &visible {
        let o = &scene.objects()[k];
        bases.push(vertices.len() as u32);
        let model_view = t.model_view(&o.transform);
        for &p in o.mesh.positions() {
            let eye = model_view.apply(p);
            let c = t.eye_to_clip(eye);
            let code = outcode_homogeneous(c);
            let v = if code == 0 {
                t.to_screen(c, eye)
            } else {
                ViewVertex {
                    x: f64::NAN,
                    y: f64::NAN,
                    zq: f64::NAN,
                    eye,
                }
            };
            vertices.push(v);
            clip.push(c);
            codes.push(code);
        }
    }
    stats.push(
        "vertices: world -> eye -> clip",
        "vertices",
        vertex_total as u64,
        vertex_total as u64,
        start,
    );
    super::prepare::confirm_inside(scene, &mut visible, &bases, &codes);

    // Back faces, then trivial rejection by outcodes.
    let start = Instant::now();
    let face_total: usize = visible
        .iter()
        .map(|&(k, _)| scene.objects()[k].mesh.polygon_count())
        .sum();
    let mut front: Vec<(u32, u32)> = Vec::with_capacity(face_total);
    let mut polygon_base: Vec<u32> = Vec::with_capacity(scene.objects().len() + 1);
    let mut polygon_total = 0u32;
    for o in scene.objects() {
        polygon_base.push(polygon_total);
        polygon_total += o.mesh.polygon_count() as u32;
    }
    polygon_base.push(polygon_total);
    let mut back_facing = vec![false; polygon_total as usize];
    let mut eye_pts: Vec<DVec3> = Vec::new();
    for (slot, &(k, _)) in visible.iter().enumerate() {
        let o = &scene.objects()[k];
        let base = bases[slot] as usize;
        let cull = options.backface.applies_to(o.closed);
        for p in 0..o.mesh.polygon_count() {
            if cull {
                let poly = o.mesh.polygon(p);
                let normal = if poly.len() == 3 {
                    let (a, b, c) = (
                        vertices[base + poly[0] as usize].eye,
                        vertices[base + poly[1] as usize].eye,
                        vertices[base + poly[2] as usize].eye,
                    );
                    (b - a).cross(c - a)
                } else {
                    eye_pts.clear();
                    eye_pts.extend(poly.iter().map(|&i| vertices[base + i as usize].eye));
                    newell_normal(&eye_pts)
                };
                let normal = if o.mirrored { -normal } else { normal };
                if t.is_back_facing_eye(normal, vertices[base + poly[0] as usize].eye) {
                    back_facing[polygon_base[k] as usize + p] = true;
                    continue;
                }
            }
            front.push((slot as u32, p as u32));
        }
    }
    stats.push(
        "faces: back-face culling",
        "faces",
        face_total as u64,
        front.len() as u64,
        start,
    );

    let start = Instant::now();
    let mut kept: Vec<(u32, u32, u8)> = Vec::with_capacity(front.len());
    for &(slot, p) in &front {
        let (k, inside) = visible[slot as usize];
        let base = bases[slot as usize] as usize;
        if inside {
            kept.push((slot, p, 0));
            continue;
        }
        let (mut and, mut or) = (0x3f, 0);
        for &i in scene.objects()[k].mesh.polygon(p as usize) {
            let c = codes[base + i as usize];
            and &= c;
            or |= c;
        }
        if and == 0 {
            kept.push((slot, p, or));
        }
    }
    stats.push(
        "faces: frustum (outcodes)",
        "faces",
        front.len() as u64,
        kept.len() as u64,
        start,
    );

    // Clip faces that cross a plane; emit polygons.
    let start = Instant::now();
    let mut starts: Vec<u32> = Vec::with_capacity(kept.len() + 1);
    let mut indices: Vec<u32> = Vec::with_capacity(kept.len() * 3);
    let mut faces: Vec<u32> = Vec::with_capacity(kept.len());
    let mut objects: Vec<u32> = Vec::with_capacity(kept.len());
    starts.push(0);
    let (mut to_clip, mut clipped_out) = (0u64, 0u64);
    let (mut input, mut out, mut scratch): (
        Vec<ClipEyeVertex>,
        Vec<ClipEyeVertex>,
        Vec<ClipEyeVertex>,
    ) = (Vec::new(), Vec::new(), Vec::new());
    for &(slot, p, or) in &kept {
        let (k, _) = visible[slot as usize];
        let o = &scene.objects()[k];
        let base = bases[slot as usize];
        let poly = o.mesh.polygon(p as usize);
        if or == 0 {
            indices.extend(poly.iter().map(|&i| base + i));
        } else {
            to_clip += 1;
            input.clear();
            input.extend(poly.iter().map(|&i| {
                let g = (base + i) as usize;
                ClipEyeVertex {
                    clip: clip[g],
                    eye: vertices[g].eye,
                }
            }));
            clip_polygon_homogeneous_masked(&input, or, &mut out, &mut scratch);
            let first = vertices.len() as u32;
            let n = t.project_clipped(&out, &mut vertices) as u32;
            if n == 0 {
                continue;
            }
            clipped_out += 1;
            indices.extend(first..first + n);
        }
        starts.push(indices.len() as u32);
        faces.push(o.first_face + o.mesh.polygon_face(p as usize));
        objects.push(k as u32);
    }
    stats.push(
        "faces: clip (Sutherland-Hodgman, homogeneous)",
        "faces",
        to_clip,
        clipped_out,
        start,
    );

    let mut kept = vec![false; scene.objects().len()];
    for &(k, _) in &visible {
        kept[k] = true;
    }
    let view = View {
        scene,
        camera: *camera,
        viewport,
        transform: t,
        options: *options,
        visible,
        kept,
        bases,
        vertices,
        codes: Vec::new(),
        polygon_base,
        back_facing: std::sync::OnceLock::from(back_facing),
        skip: None,
        culling: None,
        back_face_ms: 0.0,
        stats,
    };
    Ok(PreparedView::from_parts(
        view, starts, indices, faces, objects,
    ))
}
