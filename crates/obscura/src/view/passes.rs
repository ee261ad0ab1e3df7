//! The two passes of [`prepare`](super::prepare): vertices (transform, outcode, screen
//! position) and faces (the view's back faces skipped, or decided here by its rule
//! when not asked for before; outcode rejection, clipping, emission), each
//! serial or, with the `parallel` feature and more than one thread, on chunks in
//! parallel. Both orders of work give the same arrays: chunks are contiguous runs of
//! vertices or faces, concatenated in order.
//!
//! Each decision is computed by the expressions of the stage-per-pass pipeline it
//! replaced (kept as `prepare_reference` in the tests, which compare the two).
//!
//! The vertex pass runs compiled for AVX-512 (else AVX2) when the processor has it:
//! the same operations (the compiler never fuses a multiply and an add), 4.10 -> 3.90
//! ms for the whole preparation of the Sponza atrium view (minimum of 6x40 runs). It
//! takes the points eight at a time, lane by lane without branches
//! (`transform_vertices8`), so that they stay in vector lanes: 3.44-3.55 -> 2.99-3.10
//! ms (5 rounds of 40 alternated). On several threads each takes contiguous runs
//! through the same kernel, written in place into the output's capacity; the
//! parallel pass used to map vertex by vertex through the scalar transform and unzip
//! the results, and made the preparation slower on two threads than on one (Sponza,
//! warm, minimum of 20: 3.9-4.1 ms on two threads against 2.8 on one; now 1.9-3.0).

use std::mem::MaybeUninit;

use glam::{DVec3, DVec4};

use super::decisions::is_back_face;
use super::{ModelView, ViewTransform, ViewVertex};
use crate::clip::outcode_homogeneous;
use crate::clip::sutherland_hodgman::{ClipEyeVertex, clip_polygon_homogeneous_masked};
use crate::cull::backface::BackfaceMode;
use crate::scene::Scene;

/// Threads available: rayon's current pool with the `parallel` feature, else 1.
pub(super) fn thread_count() -> usize {
    #[cfg(feature = "parallel")]
    {
        rayon::current_num_threads()
    }
    #[cfg(not(feature = "parallel"))]
    {
        1
    }
}

/// Below this many vertices or faces a pass runs on one thread: splitting would cost
/// more than it saves.
#[cfg(feature = "parallel")]
const PARALLEL_MIN: usize = 20_000;

/// An empty vector with room for `n` elements, in huge pages when large (page faults
/// of fresh 4 KiB pages cost more than the transform of the vertices they hold).
fn huge_vec<T>(n: usize) -> Vec<T> {
    crate::memory::vec_with_capacity(n).unwrap_or_else(|_| Vec::with_capacity(n))
}

/// Room reserved for the vertices made by clipping, beyond `total` shared vertices: a
/// clipped polygon gains at most one vertex per plane it crosses, and few polygons
/// cross one. When more are made, the vector grows (correct, only slower).
fn clip_headroom(total: usize) -> usize {
    total / 16 + 1024
}

/// One vertex: eye position, clip position, outcode, and the screen position when
/// inside the view volume (NaN otherwise).
#[inline(always)]
fn transform_vertex(model_view: &ModelView, t: &ViewTransform, p: DVec3) -> (ViewVertex, u8) {
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
    (v, code)
}

/// [`transform_vertex`] for eight points: the same operations in the same order, so
/// the same bits, written lane by lane without a branch (the screen position is
/// computed for every lane and replaced by NaN outside the view volume) so that the
/// compiler keeps the eight points in vector lanes.
#[inline(always)]
fn transform_vertices8(
    mv: &ModelView,
    t: &ViewTransform,
    p: &[DVec3; 8],
) -> ([ViewVertex; 8], [u8; 8]) {
    let px: [f64; 8] = std::array::from_fn(|l| p[l].x);
    let py: [f64; 8] = std::array::from_fn(|l| p[l].y);
    let pz: [f64; 8] = std::array::from_fn(|l| p[l].z);
    // `ModelView::apply`: per coordinate, shift + (z pz + (y py + x px)) with the
    // columns of `linear`, then z qz + (y qy + x qx) with those of `rotation`.
    let (lin, r) = (&mv.linear, &mv.rotation);
    let shifted = |k: usize| -> [f64; 8] {
        let (ax, ay, az, aw) = (lin.x_axis[k], lin.y_axis[k], lin.z_axis[k], mv.shift[k]);
        std::array::from_fn(|j| aw + (az * pz[j] + (ay * py[j] + ax * px[j])))
    };
    let (qx, qy, qz) = (shifted(0), shifted(1), shifted(2));
    let point = |k: usize| -> [f64; 8] {
        let (ax, ay, az) = (r.x_axis[k], r.y_axis[k], r.z_axis[k]);
        std::array::from_fn(|j| az * qz[j] + (ay * qy[j] + ax * qx[j]))
    };
    let (ex, ey, ez) = (point(0), point(1), point(2));
    // `DMat4::mul_vec4` of (eye, 1): x_axis ex, plus y_axis ey, plus z_axis ez, plus
    // w_axis 1.
    let m = &t.projection;
    let clip = |k: usize| -> [f64; 8] {
        let (ax, ay, az, aw) = (m.x_axis[k], m.y_axis[k], m.z_axis[k], m.w_axis[k]);
        std::array::from_fn(|l| ax * ex[l] + ay * ey[l] + az * ez[l] + aw * 1.0)
    };
    let (cx, cy, cw) = (clip(0), clip(1), clip(3));
    // `ViewTransform::eye_to_clip`'s `z`, from the depth.
    let cz: [f64; 8] = std::array::from_fn(|l| t.near_z(cw[l], -ez[l]));
    let mut codes = [0u8; 8];
    let mut vertices = [ViewVertex {
        x: 0.0,
        y: 0.0,
        zq: 0.0,
        eye: DVec3::ZERO,
    }; 8];
    for l in 0..8 {
        let c = DVec4::new(cx[l], cy[l], cz[l], cw[l]);
        let eye = DVec3::new(ex[l], ey[l], ez[l]);
        codes[l] = outcode_homogeneous(c);
        // Computed for every lane, NaN outside the view volume (a select, no branch).
        let v = t.to_screen(c, eye);
        let inside = codes[l] == 0;
        let keep = |a: f64| if inside { a } else { f64::NAN };
        vertices[l] = ViewVertex {
            x: keep(v.x),
            y: keep(v.y),
            zq: keep(v.zq),
            eye,
        };
    }
    (vertices, codes)
}

/// Transforms the vertices of the visible objects (`bases[slot]` is the first vertex of
/// object slot `slot`, `bases[visible.len()]` the total): the vertices and their outcodes.
pub(super) fn transform_vertices(
    scene: &Scene,
    visible: &[(usize, bool)],
    bases: &[u32],
    t: &ViewTransform,
    threads: usize,
) -> (Vec<ViewVertex>, Vec<u8>) {
    let total = bases.last().map_or(0, |&b| b as usize);
    let model_views: Vec<ModelView> = visible
        .iter()
        .map(|&(k, _)| t.model_view(&scene.objects()[k].transform))
        .collect();
    // Room for the vertices clipping makes, appended after these by `prepare`: growing
    // the vector would copy it all into fresh pages (Sponza's atrium view: 8.8 MB,
    // 2,700 page faults, 4 ms). Untouched capacity costs address space only.
    let mut vertices = huge_vec(total + clip_headroom(total));
    let mut codes = huge_vec(total);
    let pass = VertexPass {
        scene,
        visible,
        bases,
        model_views: &model_views,
        t,
    };
    let (out_v, out_c) = (
        &mut vertices.spare_capacity_mut()[..total],
        &mut codes.spare_capacity_mut()[..total],
    );
    #[cfg(feature = "parallel")]
    if threads > 1 && total >= PARALLEL_MIN {
        use rayon::prelude::*;
        // A few contiguous runs per thread, each through the vector kernel.
        let run = total.div_ceil(threads * 4).next_multiple_of(8);
        out_v
            .par_chunks_mut(run)
            .zip(out_c.par_chunks_mut(run))
            .enumerate()
            .for_each(|(k, (v, c))| pass.run_fastest(k * run, v, c));
    } else {
        pass.run_fastest(0, out_v, out_c);
    }
    #[cfg(not(feature = "parallel"))]
    {
        let _ = threads;
        pass.run_fastest(0, out_v, out_c);
    }
    // SAFETY: the runs above cover `0..total` and `VertexPass::run` writes every
    // element of the slices it is given (it checks so before returning; a run that
    // panicked never gets here).
    unsafe {
        vertices.set_len(total);
        codes.set_len(total);
    }
    (vertices, codes)
}

/// What the vertex pass reads: the visible objects, the first vertex of each
/// (`bases`), their model-view transforms.
struct VertexPass<'a> {
    scene: &'a Scene,
    visible: &'a [(usize, bool)],
    bases: &'a [u32],
    model_views: &'a [ModelView],
    t: &'a ViewTransform,
}

impl VertexPass<'_> {
    /// Transforms the vertices `first..first + v.len()` (numbered across the visible
    /// objects) into `v` and their outcodes into `c`, eight at a time within each
    /// object (`transform_vertices8`), writing every element.
    #[inline(always)]
    fn run(&self, first: usize, v: &mut [MaybeUninit<ViewVertex>], c: &mut [MaybeUninit<u8>]) {
        let end = first + v.len();
        assert_eq!(v.len(), c.len(), "one outcode per vertex");
        let mut written = 0;
        let slot0 = self
            .bases
            .partition_point(|&b| b as usize <= first)
            .saturating_sub(1);
        for slot in slot0..self.visible.len() {
            let (b0, b1) = (self.bases[slot] as usize, self.bases[slot + 1] as usize);
            let (lo, hi) = (first.max(b0), end.min(b1));
            if lo >= hi {
                if b0 >= end {
                    break;
                }
                continue;
            }
            let mv = &self.model_views[slot];
            let positions =
                &self.scene.objects()[self.visible[slot].0].mesh.positions()[lo - b0..hi - b0];
            let (vs, cs) = (
                &mut v[lo - first..hi - first],
                &mut c[lo - first..hi - first],
            );
            let mut eights = positions.chunks_exact(8);
            let mut vs8 = vs.chunks_exact_mut(8);
            let mut cs8 = cs.chunks_exact_mut(8);
            for ((p, vo), co) in (&mut eights).zip(&mut vs8).zip(&mut cs8) {
                let p: &[DVec3; 8] = p.try_into().expect("chunks of eight");
                let (tv, tc) = transform_vertices8(mv, self.t, p);
                for ((vo, co), (tv, tc)) in vo.iter_mut().zip(co).zip(tv.into_iter().zip(tc)) {
                    vo.write(tv);
                    co.write(tc);
                }
                written += 8;
            }
            let rest = eights.remainder();
            for ((&p, vo), co) in rest
                .iter()
                .zip(vs8.into_remainder())
                .zip(cs8.into_remainder())
            {
                let (tv, tc) = transform_vertex(mv, self.t, p);
                vo.write(tv);
                co.write(tc);
                written += 1;
            }
        }
        assert_eq!(written, v.len(), "every vertex of the run transformed");
    }

    /// [`VertexPass::run`] compiled for the fastest instructions this processor has
    /// (the same operations, so the same bits: the compiler fuses no multiply and add).
    fn run_fastest(
        &self,
        first: usize,
        v: &mut [MaybeUninit<ViewVertex>],
        c: &mut [MaybeUninit<u8>],
    ) {
        #[cfg(target_arch = "x86_64")]
        if let Some(cpu) = crate::cpu::Avx512::new() {
            // SAFETY: `Avx512::new` checked every feature `run_avx512` enables.
            unsafe { self.run_avx512(cpu, first, v, c) };
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(cpu) = crate::cpu::Avx2::new() {
            // SAFETY: `Avx2::new` checked every feature `run_avx2` enables.
            unsafe { self.run_avx2(cpu, first, v, c) };
            return;
        }
        self.run(first, v, c);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn run_avx2(
        &self,
        _: crate::cpu::Avx2,
        first: usize,
        v: &mut [MaybeUninit<ViewVertex>],
        c: &mut [MaybeUninit<u8>],
    ) {
        self.run(first, v, c);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
    fn run_avx512(
        &self,
        _: crate::cpu::Avx512,
        first: usize,
        v: &mut [MaybeUninit<ViewVertex>],
        c: &mut [MaybeUninit<u8>],
    ) {
        self.run(first, v, c);
    }
}

/// What the face pass reads.
pub(super) struct FaceContext<'a> {
    pub scene: &'a Scene,
    pub visible: &'a [(usize, bool)],
    pub bases: &'a [u32],
    pub vertices: &'a [ViewVertex],
    pub codes: &'a [u8],
    pub t: &'a ViewTransform,
    /// Per scene object, its first scene polygon.
    pub polygon_base: &'a [u32],
    /// The faces to skip, per scene polygon, when the view has decided them already
    /// (its back faces, with any faces the occlusion stage culled); `None`: the pass
    /// decides the back faces itself, by the view's rule (`decisions::is_back_face`).
    pub skip: Option<&'a [bool]>,
    /// The view's back-face mode, for a pass that decides.
    pub backface: BackfaceMode,
}

/// The polygons the face pass emits, and its counts per stage.
#[derive(Default)]
pub(super) struct FaceOutput {
    /// Polygon starts: with the leading 0 in the final output, without it in a chunk's.
    pub starts: Vec<u32>,
    pub indices: Vec<u32>,
    pub faces: Vec<u32>,
    pub objects: Vec<u32>,
    /// Vertices made by clipping, to append after the shared ones.
    pub clipped_vertices: Vec<ViewVertex>,
    /// Faces kept by the back-face test.
    pub front: u64,
    /// Faces kept by the outcode test.
    pub kept: u64,
    /// Faces that crossed a plane and were clipped.
    pub to_clip: u64,
    /// Clipped faces with something left.
    pub clipped: u64,
}

/// Scratch vectors of the clipper.
#[derive(Default)]
struct Scratch {
    /// Eye positions of a polygon of more than 3 vertices, for its normal.
    eye: Vec<DVec3>,
    input: Vec<ClipEyeVertex>,
    out: Vec<ClipEyeVertex>,
    scratch: Vec<ClipEyeVertex>,
}

/// Polygons `p0..p1` of visible object `slot`, appended to `out`. A vertex made by
/// clipping gets index `new_base + ` its position in `out.clipped_vertices`.
#[inline(always)]
fn faces_of(
    ctx: &FaceContext<'_>,
    slot: usize,
    polygons: std::ops::Range<usize>,
    new_base: u32,
    out: &mut FaceOutput,
    s: &mut Scratch,
) {
    let (k, inside) = ctx.visible[slot];
    let o = &ctx.scene.objects()[k];
    let base = ctx.bases[slot];
    let skip = ctx.skip.map(|s| &s[ctx.polygon_base[k] as usize..]);
    let cull = ctx.backface.applies_to(o.closed);
    let (mstarts, mindices, mfaces) = o.mesh.polygon_arrays();
    let (vertices, codes, t) = (ctx.vertices, ctx.codes, ctx.t);
    let eye = |i: u32| vertices[(base + i) as usize].eye;
    for p in polygons {
        let poly = &mindices[mstarts[p] as usize..mstarts[p + 1] as usize];
        // The view's decision (`View::back_facing`): read if made, else made here by
        // the same function, fused with this pass so the faces are traversed once.
        let skipped = match skip {
            Some(skip) => skip[p],
            None => cull && is_back_face(o.mirrored, poly, eye, t, &mut s.eye),
        };
        if skipped {
            continue;
        }
        out.front += 1;
        let or = if inside {
            0
        } else {
            let code = |i: u32| codes[(base + i) as usize];
            let (and, or) = if let &[a, b, c] = poly {
                // Triangles, most faces: three independent loads, no loop.
                let (a, b, c) = (code(a), code(b), code(c));
                (a & b & c, a | b | c)
            } else {
                poly.iter()
                    .fold((0x3f, 0), |(and, or), &i| (and & code(i), or | code(i)))
            };
            if and != 0 {
                continue;
            }
            or
        };
        out.kept += 1;
        if or == 0 {
            if let &[a, b, c] = poly {
                out.indices.extend([base + a, base + b, base + c]);
            } else {
                out.indices.extend(poly.iter().map(|&i| base + i));
            }
        } else {
            out.to_clip += 1;
            s.input.clear();
            s.input.extend(poly.iter().map(|&i| {
                // The vertex pass's clip position, recomputed from the same eye position
                // by the same function: the same bits.
                let eye = vertices[(base + i) as usize].eye;
                ClipEyeVertex {
                    clip: t.eye_to_clip(eye),
                    eye,
                }
            }));
            clip_polygon_homogeneous_masked(&s.input, or, &mut s.out, &mut s.scratch);
            let first = new_base + out.clipped_vertices.len() as u32;
            let n = t.project_clipped(&s.out, &mut out.clipped_vertices) as u32;
            if n == 0 {
                continue;
            }
            out.clipped += 1;
            out.indices.extend(first..first + n);
        }
        out.starts.push(out.indices.len() as u32);
        out.faces.push(o.first_face + mfaces[p]);
        out.objects.push(k as u32);
    }
}

/// Marks a chunk-local index of a vertex made by clipping, until the chunks are joined.
#[cfg(feature = "parallel")]
const LOCAL: u32 = 1 << 31;

/// Runs the face pass over all visible objects.
pub(super) fn process_faces(
    ctx: &FaceContext<'_>,
    face_total: usize,
    threads: usize,
) -> FaceOutput {
    let vertex_total = ctx.vertices.len();
    #[cfg(feature = "parallel")]
    if threads > 1 && face_total >= PARALLEL_MIN && vertex_total < LOCAL as usize {
        return process_faces_parallel(ctx, face_total, threads);
    }
    let _ = threads;
    let mut out = FaceOutput {
        starts: huge_vec(face_total + 1),
        indices: huge_vec(face_total * 3),
        faces: huge_vec(face_total),
        objects: huge_vec(face_total),
        ..FaceOutput::default()
    };
    out.starts.push(0);
    let mut scratch = Scratch::default();
    for (slot, &(k, _)) in ctx.visible.iter().enumerate() {
        let n = ctx.scene.objects()[k].mesh.polygon_count();
        faces_of(ctx, slot, 0..n, vertex_total as u32, &mut out, &mut scratch);
    }
    out
}

#[cfg(feature = "parallel")]
fn process_faces_parallel(ctx: &FaceContext<'_>, face_total: usize, threads: usize) -> FaceOutput {
    use rayon::prelude::*;
    // Chunks of about equal face counts, each a list of (slot, polygon range).
    let target = face_total.div_ceil(threads * 8).max(4096);
    let mut chunks: Vec<Vec<(usize, std::ops::Range<usize>)>> = vec![Vec::new()];
    let mut filled = 0;
    for (slot, &(k, _)) in ctx.visible.iter().enumerate() {
        let n = ctx.scene.objects()[k].mesh.polygon_count();
        let mut p = 0;
        while p < n {
            let take = (n - p).min(target - filled);
            chunks
                .last_mut()
                .expect("never empty")
                .push((slot, p..p + take));
            p += take;
            filled += take;
            if filled == target {
                chunks.push(Vec::new());
                filled = 0;
            }
        }
    }
    let parts: Vec<FaceOutput> = chunks
        .par_iter()
        .map(|segments| {
            let size: usize = segments.iter().map(|(_, r)| r.len()).sum();
            let mut out = FaceOutput {
                starts: Vec::with_capacity(size),
                indices: Vec::with_capacity(size * 3),
                faces: Vec::with_capacity(size),
                objects: Vec::with_capacity(size),
                ..FaceOutput::default()
            };
            let mut scratch = Scratch::default();
            for (slot, range) in segments {
                faces_of(ctx, *slot, range.clone(), LOCAL, &mut out, &mut scratch);
            }
            out
        })
        .collect();
    let polygons: usize = parts.iter().map(|p| p.faces.len()).sum();
    let index_count: usize = parts.iter().map(|p| p.indices.len()).sum();
    let mut out = FaceOutput {
        starts: huge_vec(polygons + 1),
        indices: huge_vec(index_count),
        faces: huge_vec(polygons),
        objects: huge_vec(polygons),
        ..FaceOutput::default()
    };
    out.starts.push(0);
    for part in parts {
        let offset = out.indices.len() as u32;
        out.starts.extend(part.starts.iter().map(|&s| s + offset));
        if part.clipped_vertices.is_empty() {
            out.indices.extend_from_slice(&part.indices);
        } else {
            let new_base = (ctx.vertices.len() + out.clipped_vertices.len()) as u32;
            out.indices.extend(
                part.indices
                    .iter()
                    .map(|&i| if i >= LOCAL { i - LOCAL + new_base } else { i }),
            );
        }
        out.clipped_vertices
            .extend_from_slice(&part.clipped_vertices);
        out.faces.extend_from_slice(&part.faces);
        out.objects.extend_from_slice(&part.objects);
        out.front += part.front;
        out.kept += part.kept;
        out.to_clip += part.to_clip;
        out.clipped += part.clipped;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Camera, Viewport};

    /// Runs the vertex pass over `0..total` in runs of `run` vertices with `f`.
    fn in_runs(
        pass: &VertexPass<'_>,
        total: usize,
        run: usize,
        f: impl Fn(&VertexPass<'_>, usize, &mut [MaybeUninit<ViewVertex>], &mut [MaybeUninit<u8>]),
    ) -> (Vec<ViewVertex>, Vec<u8>) {
        let blank = ViewVertex {
            x: 0.0,
            y: 0.0,
            zq: 0.0,
            eye: DVec3::ZERO,
        };
        let mut v = vec![MaybeUninit::new(blank); total];
        let mut c = vec![MaybeUninit::new(0xffu8); total];
        for (k, (v, c)) in v.chunks_mut(run).zip(c.chunks_mut(run)).enumerate() {
            f(pass, k * run, v, c);
        }
        // SAFETY: every element was initialised above (and overwritten by the pass).
        let v = v.into_iter().map(|m| unsafe { m.assume_init() }).collect();
        let c = c.into_iter().map(|m| unsafe { m.assume_init() }).collect();
        (v, c)
    }

    #[test]
    fn the_vertex_pass_equals_one_vertex_at_a_time_in_any_runs_and_kernels() {
        // The default demo from a camera that sees some vertices and not others
        // (outcodes, NaN screen positions), and every object in the pass.
        let scene = crate::scene::demo::default_scene();
        let cam = Camera::perspective(
            DVec3::new(0.7, 1.3, 2.2),
            DVec3::new(0.2, 0.0, -0.4),
            DVec3::Y,
            50.0,
            0.1,
            30.0,
        );
        let t = ViewTransform::new(&cam, Viewport::new(160, 90).unwrap());
        let visible: Vec<(usize, bool)> = (0..scene.objects().len()).map(|k| (k, true)).collect();
        let model_views: Vec<ModelView> = visible
            .iter()
            .map(|&(k, _)| t.model_view(&scene.objects()[k].transform))
            .collect();
        let mut bases = vec![0u32];
        for &(k, _) in &visible {
            bases.push(bases.last().unwrap() + scene.objects()[k].mesh.positions().len() as u32);
        }
        let total = *bases.last().unwrap() as usize;
        // The reference: one vertex at a time.
        let (mut v0, mut c0) = (Vec::new(), Vec::new());
        for (slot, &(k, _)) in visible.iter().enumerate() {
            for &p in scene.objects()[k].mesh.positions() {
                let (v, c) = transform_vertex(&model_views[slot], &t, p);
                v0.push(v);
                c0.push(c);
            }
        }
        assert!(visible.len() > 2 && total > 100 && c0.iter().any(|&c| c != 0) && c0.contains(&0));
        let pass = VertexPass {
            scene: &scene,
            visible: &visible,
            bases: &bases,
            model_views: &model_views,
            t: &t,
        };
        // Runs that start inside objects and span several, as the parallel pass cuts
        // them, with every kernel.
        for run in [total, 8, 24, 1000, 3] {
            let (v, c) = in_runs(&pass, total, run, |p, first, v, c| p.run(first, v, c));
            assert_eq!((bits(&v), &c), (bits(&v0), &c0), "portable, runs of {run}");
            let (v, c) = in_runs(&pass, total, run, |p, first, v, c| {
                p.run_fastest(first, v, c)
            });
            assert_eq!((bits(&v), &c), (bits(&v0), &c0), "fastest, runs of {run}");
            #[cfg(target_arch = "x86_64")]
            if let Some(cpu) = crate::cpu::Avx2::new() {
                // SAFETY: `Avx2::new` checked every feature `run_avx2` enables.
                let (v, c) = in_runs(&pass, total, run, |p, first, v, c| unsafe {
                    p.run_avx2(cpu, first, v, c)
                });
                assert_eq!((bits(&v), &c), (bits(&v0), &c0), "AVX2, runs of {run}");
            } else {
                crate::cpu::simd_test_skipped(
                    "AVX2",
                    "the AVX2 vertex pass against the portable one",
                );
            }
            #[cfg(target_arch = "x86_64")]
            if let Some(cpu) = crate::cpu::Avx512::new() {
                // SAFETY: `Avx512::new` checked every feature `run_avx512` enables.
                let (v, c) = in_runs(&pass, total, run, |p, first, v, c| unsafe {
                    p.run_avx512(cpu, first, v, c)
                });
                assert_eq!((bits(&v), &c), (bits(&v0), &c0), "AVX-512, runs of {run}");
            } else {
                crate::cpu::simd_test_skipped(
                    "AVX-512",
                    "the AVX-512 vertex pass against the portable one",
                );
            }
        }
    }

    #[cfg(feature = "parallel")]
    #[test]
    fn the_parallel_vertex_pass_equals_the_serial_one() {
        let scene = crate::scene::demo::sphere(300, 150);
        let cam = scene.default_camera(1.5);
        let t = ViewTransform::new(&cam, Viewport::new(160, 90).unwrap());
        let visible = [(0, false)];
        let total = scene.objects()[0].mesh.positions().len();
        assert!(
            total >= PARALLEL_MIN,
            "{total} vertices take the parallel pass"
        );
        let bases = [0, total as u32];
        let serial = transform_vertices(&scene, &visible, &bases, &t, 1);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let parallel = pool.install(|| transform_vertices(&scene, &visible, &bases, &t, 3));
        assert_eq!(bits(&serial.0), bits(&parallel.0));
        assert_eq!(serial.1, parallel.1);
    }

    fn bits(v: &[ViewVertex]) -> Vec<[u64; 6]> {
        v.iter()
            .map(|v| [v.x, v.y, v.zq, v.eye.x, v.eye.y, v.eye.z].map(f64::to_bits))
            .collect()
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
    fn vertices8_avx512(
        _: crate::cpu::Avx512,
        mv: &ModelView,
        t: &ViewTransform,
        p: &[DVec3; 8],
    ) -> ([ViewVertex; 8], [u8; 8]) {
        transform_vertices8(mv, t, p)
    }

    #[test]
    fn eight_vertices_at_once_are_one_at_a_time_bit_for_bit() {
        // Points in, out of and behind the view volume, on its planes, and not finite,
        // through a perspective and an orthographic camera.
        let mut rng = crate::rng::SplitMix64(41);
        let specials = [
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            0.0,
            -0.0,
            1e300,
            -1e-300,
        ];
        let eye = DVec3::new(0.3, -0.2, 4.0);
        let cameras = [
            Camera::perspective(eye, DVec3::ZERO, DVec3::Y, 60.0, 0.5, 20.0),
            Camera::orthographic(eye, DVec3::ZERO, DVec3::Y, 3.0, 0.5, 20.0),
        ];
        let model = glam::DMat4::from_rotation_y(0.3)
            * glam::DMat4::from_translation(DVec3::new(0.1, 0.2, -0.3));
        let mut outside = 0;
        for cam in cameras {
            let t = ViewTransform::new(&cam, Viewport::new(320, 200).unwrap());
            let mv = t.model_view(&model);
            for round in 0..400 {
                let p: [DVec3; 8] = std::array::from_fn(|_| {
                    let mut c = [0.0; 3].map(|_| rng.range(-6.0, 6.0));
                    if round % 4 == 0 {
                        let k = (rng.next_u64() % 3) as usize;
                        c[k] = specials[(rng.next_u64() % specials.len() as u64) as usize];
                    }
                    DVec3::from_array(c)
                });
                let (v, c) = transform_vertices8(&mv, &t, &p);
                #[cfg(target_arch = "x86_64")]
                if let Some(cpu) = crate::cpu::Avx512::new() {
                    // SAFETY: `Avx512::new` checked every feature `vertices8_avx512` enables.
                    let (v2, c2) = unsafe { vertices8_avx512(cpu, &mv, &t, &p) };
                    assert_eq!((bits(&v), c), (bits(&v2), c2), "{p:?}");
                } else if round == 0 {
                    crate::cpu::simd_test_skipped(
                        "AVX-512",
                        "eight vertices with AVX-512 against one at a time",
                    );
                }
                for l in 0..8 {
                    let (w, d) = transform_vertex(&mv, &t, p[l]);
                    assert_eq!(c[l], d, "{:?}", p[l]);
                    assert_eq!(bits(&v[l..=l]), bits(&[w]), "{:?}", p[l]);
                    outside += usize::from(d != 0);
                }
            }
        }
        assert!(outside > 1000 && outside < 6000, "{outside} outside");
    }
}
