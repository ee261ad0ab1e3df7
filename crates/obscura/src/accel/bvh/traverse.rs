//! Closest-hit traversal of a [`Bvh`].
//!
//! Source: Kay and Kajiya, *Ray tracing complex scenes* (SIGGRAPH 1986), the slab test;
//! Ize, *Robust BVH ray traversal* (JCGT, 2013), its rounding.
//!
//! # Box test in single precision, made conservative
//! The nodes' boxes are `f32`, rounded outwards from the `f64` triangles. The ray is
//! converted to `f32` too, and a slab distance `(plane - origin) / direction` carries
//! two kinds of rounding error: the origin's conversion, a few ulp of `|origin|` in
//! space, and a relative error of at most three roundings of the distance itself (the
//! subtraction, the inverse direction and the product). The test covers both, so it
//! never misses a box the exact ray meets:
//! - every box is grown by a margin `δ = 2^-17 (|origin|∞ + 2^-30 scale)` (`scale` =
//!   the largest coordinate of the scene), over 100 times the origin's rounding. It
//!   costs nothing per test: the lower planes are met at `(min - (o + δ)) / d` and the
//!   upper ones at `(max - (o - δ)) / d`, so two shifted origins are computed once per
//!   ray. (The `2^-30 scale` floor only matters for directions with a component under
//!   `10^-30`, whose inverse is clamped: see below.)
//! - the entry and exit distances are widened by their relative error bound: the box
//!   is entered when `near - γ |near| <= far + γ |far|`, `γ = 2^-18` (about 20 times
//!   the three roundings), and the widened entry is what is returned. Both sides
//!   widened keep the test valid whatever the signs (a negative near limit, as an
//!   orthographic camera's near plane behind the eye gives).
//!
//! Why not one margin for both: a margin in space must cover the relative error at the
//! largest distance a box can be, so it grows with the scene (`2^-17 (|origin| +
//! scale)` was the rule before). With a ground quad 10^7 wide it grew every box near
//! the camera by 76 units, and ray casting a sphere on it was 145 times slower. A
//! relative widening costs a few operations per node and grows each box only in
//! proportion to its own distance (Ize 2013 makes the same point: `tmax *= 1 + 2γ`).
//! Zero direction components get an inverse of `±10^30` (not
//! infinity), so no `0 · ∞` NaN can appear and plain comparisons suffice.
//!
//! # Order
//! At a node the eight children's boxes are tested at once (an 8-lane computation the
//! compiler vectorizes); the children entered are sorted by entry distance, the
//! nearest visited next and the others pushed farthest first, each with its entry
//! distance, and skipped when popped if a hit nearer than that was found meanwhile.
//! Leaves are tested when reached in that order. Triangles are tested with the exact
//! `f64` watertight test, so the result equals brute force's.
//!
//! # Kernels
//! The traversal is plain (safe) Rust written so that the compiler vectorizes the box
//! test. On x86-64 it is compiled twice: for the baseline (SSE2: two 4-lane halves per
//! node) and for AVX2 (one 8-lane pass), chosen at run time by CPU detection; the AVX2
//! call is the only `unsafe` (the CPU check is its precondition). Both run the same
//! operations in the same order on IEEE floats (no fused multiply-add is enabled), so
//! they return the same hits; [`Kernel`] lets tests and benchmarks force either.
//! Measured on Sponza's atrium view at 1920x1080, one thread: about 2.8 (SSE2) and
//! 3.2 (AVX2) million rays per second.

use glam::DVec3;

use super::{Bvh, BvhNode, MAX_DEPTH, Slot, WIDTH, f32_down, f32_up};
use crate::accel::triangles::{AxisOrder, ClosestHit, HitContext, WithAxisOrder};

/// What a traversal did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceCounters {
    /// Nodes visited (eight boxes each).
    pub nodes: u64,
    /// Exact triangle tests run.
    pub triangles: u64,
    /// Nodes visited by packets ([`super::packet`]; `nodes` counts each ray of a
    /// packet that visits a node).
    pub packet_nodes: u64,
}

impl std::ops::AddAssign for TraceCounters {
    fn add_assign(&mut self, o: Self) {
        self.nodes += o.nodes;
        self.triangles += o.triangles;
        self.packet_nodes += o.packet_nodes;
    }
}

/// Up to three siblings are pushed per level.
const STACK_SIZE: usize = (WIDTH - 1) * MAX_DEPTH + WIDTH;

/// Marks a stack entry that is a leaf: the rest is `WIDTH * node + slot`.
const LEAF_BIT: u32 = 1 << 31;

/// A traversal stack, reusable from ray to ray (one per thread).
#[derive(Clone, Debug)]
pub struct TraversalStack {
    entries: Box<[(u32, f32); STACK_SIZE]>,
}

impl Default for TraversalStack {
    fn default() -> Self {
        TraversalStack {
            entries: Box::new([(0, 0.0); STACK_SIZE]),
        }
    }
}

/// The margin of the box test relative to the origin's coordinates (see the module
/// doc).
const MARGIN: f64 = 1.0 / 131_072.0;

/// The part of the scene's largest coordinate in the margin (see the module doc).
const SCALE_FLOOR: f64 = 1.0 / 1_073_741_824.0;

/// The relative widening `γ` of the box test's entry and exit distances (see the
/// module doc).
pub(super) const WIDEN: f32 = 1.0 / 262_144.0;

/// The margin `δ` of the box test for a ray whose origin's largest absolute coordinate
/// is `origin_max`, through boxes whose coordinates are at most `scale`.
#[inline(always)]
pub(super) fn margin(origin_max: f64, scale: f64) -> f64 {
    (origin_max + scale * SCALE_FLOOR) * MARGIN
}

/// `x` moved down by its relative error bound: `x - γ |x|` (see the module doc).
#[inline(always)]
pub(super) fn widen_down(x: f32) -> f32 {
    x - x.abs() * WIDEN
}

/// `x` moved up by its relative error bound: `x + γ |x|`.
#[inline(always)]
pub(super) fn widen_up(x: f32) -> f32 {
    x + x.abs() * WIDEN
}

/// A ray prepared for the single-precision slab test.
///
/// Per axis, which of a box's planes the ray meets first is fixed by the sign of its
/// direction, so the planes are picked once per ray (`swap`) and the test needs no
/// per-box min/max of the two slab distances.
#[derive(Clone, Copy, Debug)]
pub struct BoxRay {
    /// Origin shifted for the entry planes (`o + δ` for lower planes, `o - δ` for upper).
    near_origin: [f32; 3],
    /// Origin shifted for the exit planes.
    far_origin: [f32; 3],
    inv: [f32; 3],
    /// Whether the ray goes down this axis (enters through the upper plane).
    swap: [bool; 3],
}

/// The ray origin shifted by the margin `δ` for boxes of coordinates up to `scale`:
/// `(o + δ, o - δ)` in `f32`. A box's lower planes are measured from the first, its
/// upper planes from the second, which grows every box by `δ` on each side.
#[inline]
pub(super) fn shifted_origins(origin: DVec3, scale: f64) -> ([f32; 3], [f32; 3]) {
    let delta = margin(origin.abs().max_element(), scale);
    let lower = (origin + delta).to_array().map(|x| x as f32);
    let upper = (origin - delta).to_array().map(|x| x as f32);
    (lower, upper)
}

/// `1 / d` per axis in `f32`; 1 / ±0 gives ±inf, clamped to ±10^30 so it keeps the
/// sign that picks the planes and no `0 · ∞` NaN can appear.
#[inline]
pub(super) fn inverse_direction(direction: DVec3) -> [f32; 3] {
    direction
        .to_array()
        .map(|d| (1.0 / d).clamp(-1e30, 1e30) as f32)
}

#[inline(always)]
pub(super) fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

#[inline(always)]
pub(super) fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

impl BoxRay {
    /// Prepares a ray for boxes whose coordinates are at most `scale` in absolute value.
    #[must_use]
    pub fn new(origin: DVec3, direction: DVec3, scale: f64) -> Self {
        let (lower, upper) = shifted_origins(origin, scale);
        let inv = inverse_direction(direction);
        let swap = inv.map(|i| i < 0.0);
        BoxRay {
            near_origin: std::array::from_fn(|k| if swap[k] { upper[k] } else { lower[k] }),
            far_origin: std::array::from_fn(|k| if swap[k] { lower[k] } else { upper[k] }),
            inv,
            swap,
        }
    }

    /// The entry distances into the eight (grown) boxes of a node where the ray meets
    /// them within `[t_min, t_max]`, `+inf` where it does not (both widened by the
    /// relative error bound: see the module doc).
    // The shape of this function is what lets the compiler turn it into a few 8-lane
    // instructions. Seemingly neutral rewrites (a tree-shaped min/max reduction, arrays
    // built with `from_fn`) were measured to halve the traversal speed by breaking the
    // vectorization: benchmark before changing it.
    #[inline(always)]
    #[must_use]
    pub fn entries(&self, n: &BvhNode, t_min: f32, t_max: f32) -> [f32; WIDTH] {
        let mut near = [t_min; WIDTH];
        let mut far = [t_max; WIDTH];
        for axis in 0..3 {
            let (entry, exit) = if self.swap[axis] {
                (&n.max[axis], &n.min[axis])
            } else {
                (&n.min[axis], &n.max[axis])
            };
            let (o_near, o_far, inv) = (
                self.near_origin[axis],
                self.far_origin[axis],
                self.inv[axis],
            );
            for k in 0..WIDTH {
                near[k] = max(near[k], (entry[k] - o_near) * inv);
                far[k] = min(far[k], (exit[k] - o_far) * inv);
            }
        }
        let mut out = [f32::INFINITY; WIDTH];
        for k in 0..WIDTH {
            let (lo, hi) = (widen_down(near[k]), widen_up(far[k]));
            if lo <= hi {
                out[k] = lo;
            }
        }
        out
    }
}

/// Which compiled version of the traversal runs (see the module doc): the crate's one
/// kernel choice. [`Kernel::Avx512`] gives packets ([`super::packet`]) AVX-512 lanes;
/// single rays have no such lanes and run the AVX2 build.
pub use crate::cpu::Kernel;

impl Bvh {
    /// The nearest hit with `ctx.t_min <= t <= t_max`, nearest child first.
    pub fn closest_hit(
        &self,
        ctx: &HitContext<'_>,
        t_max: f64,
        stack: &mut TraversalStack,
        counters: &mut TraceCounters,
    ) -> ClosestHit {
        self.closest_hit_with(Kernel::Auto, ctx, t_max, stack, counters)
    }

    /// [`Bvh::closest_hit`] with a chosen kernel.
    pub fn closest_hit_with(
        &self,
        kernel: Kernel,
        ctx: &HitContext<'_>,
        t_max: f64,
        stack: &mut TraversalStack,
        counters: &mut TraceCounters,
    ) -> ClosestHit {
        struct Run<'a, 'b> {
            bvh: &'a Bvh,
            kernel: Kernel,
            ctx: &'a HitContext<'b>,
            t_max: f64,
            stack: &'a mut TraversalStack,
            counters: &'a mut TraceCounters,
        }
        impl WithAxisOrder for Run<'_, '_> {
            type Output = ClosestHit;
            fn run<O: AxisOrder>(self) -> ClosestHit {
                #[cfg(target_arch = "x86_64")]
                if let Some(cpu) = self.kernel.avx2() {
                    // SAFETY: `Avx2::new` checked every feature this function enables;
                    // its body is safe code.
                    return unsafe {
                        self.bvh.ordered_avx2::<O>(
                            cpu,
                            self.ctx,
                            self.t_max,
                            self.stack,
                            self.counters,
                        )
                    };
                }
                self.bvh
                    .ordered::<O>(self.ctx, self.t_max, self.stack, self.counters)
            }
        }
        ctx.ray.dispatch(Run {
            bvh: self,
            kernel,
            ctx,
            t_max,
            stack,
            counters,
        })
    }

    /// [`Bvh::ordered`] compiled for AVX2, so the node test runs 8 lanes wide.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn ordered_avx2<O: AxisOrder>(
        &self,
        _: crate::cpu::Avx2,
        ctx: &HitContext<'_>,
        t_max: f64,
        stack: &mut TraversalStack,
        counters: &mut TraceCounters,
    ) -> ClosestHit {
        self.ordered::<O>(ctx, t_max, stack, counters)
    }

    #[inline(always)]
    fn ordered<O: AxisOrder>(
        &self,
        ctx: &HitContext<'_>,
        t_max: f64,
        stack: &mut TraversalStack,
        counters: &mut TraceCounters,
    ) -> ClosestHit {
        let mut closest = ClosestHit::new(t_max);
        if self.nodes.is_empty() || !(ctx.t_min <= t_max) {
            return closest;
        }
        let ray = BoxRay::new(ctx.ray.origin, ctx.ray.direction, self.scale);
        let t_lo = f32_down(ctx.t_min);
        let mut t_hi = f32_up(t_max);
        let stack = &mut stack.entries;
        let mut sp = 0usize;
        let mut node = 0u32;
        let mut leaf = |first: u32, count: u32, closest: &mut ClosestHit| {
            let range = first as usize..(first + count) as usize;
            for (tri, &poly) in self.triangles[range.clone()]
                .iter()
                .zip(&self.polygons[range])
            {
                counters.triangles += u64::from(ctx.test::<O>(tri, poly, f64::INFINITY, closest));
            }
        };
        loop {
            let n = &self.nodes[node as usize];
            counters.nodes += 1;
            let t = ray.entries(n, t_lo, t_hi);
            // The children entered, nearest first (insertion sort of at most eight).
            let mut hits = [(0.0f32, 0usize); WIDTH];
            let mut m = 0;
            let occupied = n.occupied();
            for (k, &tk) in t.iter().enumerate() {
                if tk != f32::INFINITY && occupied >> k & 1 != 0 {
                    let mut p = m;
                    while p > 0 && hits[p - 1].0 > tk {
                        hits[p] = hits[p - 1];
                        p -= 1;
                    }
                    hits[p] = (tk, k);
                    m += 1;
                }
            }
            let mut next = None;
            // Push the farther ones (farthest first, so they pop nearest first).
            for &(tk, k) in hits[..m].iter().rev() {
                let entry = if n.count[k] == 0 {
                    n.child[k]
                } else {
                    LEAF_BIT | (node * WIDTH as u32 + k as u32)
                };
                if let Some(prev) = next.replace((entry, tk)) {
                    debug_assert!(sp < stack.len());
                    stack[sp] = prev;
                    sp += 1;
                }
            }
            // Visit the nearest now, then pop until an interior node comes up.
            let mut current = next;
            loop {
                let Some((entry, t_entry)) = current.take() else {
                    if sp == 0 {
                        return closest;
                    }
                    sp -= 1;
                    current = Some(stack[sp]);
                    continue;
                };
                if t_entry > t_hi {
                    continue;
                }
                if entry & LEAF_BIT == 0 {
                    node = entry;
                    break;
                }
                let slot = entry & !LEAF_BIT;
                let owner = &self.nodes[slot as usize / WIDTH];
                let k = slot as usize % WIDTH;
                leaf(owner.child[k], owner.count[k], &mut closest);
                t_hi = f32_up(closest.t);
            }
        }
    }

    /// The seeds' hierarchical test, verbatim (seed 000, "Περιβάλλοντες Όγκοι (7)"):
    ///
    /// ```text
    /// IntersectionTest(M):
    ///   if BottomLevel(M): return LLIntersectionTest(M)      // every triangle
    ///   else if LLIntersectionTest(BoundingVolume(M)):
    ///     for each part C of M: IntersectionTest(C)
    /// ```
    ///
    /// Children in stored order, no pruning by the nearest hit: it visits every box the
    /// ray pierces. Same result as [`Bvh::closest_hit`], for comparison.
    pub fn closest_hit_recursive(
        &self,
        ctx: &HitContext<'_>,
        t_max: f64,
        counters: &mut TraceCounters,
    ) -> ClosestHit {
        struct Run<'a, 'b> {
            bvh: &'a Bvh,
            ctx: &'a HitContext<'b>,
            t_max: f64,
            counters: &'a mut TraceCounters,
        }
        impl WithAxisOrder for Run<'_, '_> {
            type Output = ClosestHit;
            fn run<O: AxisOrder>(self) -> ClosestHit {
                let mut closest = ClosestHit::new(self.t_max);
                if self.bvh.nodes.is_empty() || !(self.ctx.t_min <= self.t_max) {
                    return closest;
                }
                let ray = BoxRay::new(self.ctx.ray.origin, self.ctx.ray.direction, self.bvh.scale);
                let range = (f32_down(self.ctx.t_min), f32_up(self.t_max));
                self.bvh
                    .recurse::<O>(0, &ray, range, self.ctx, &mut closest, self.counters);
                closest
            }
        }
        ctx.ray.dispatch(Run {
            bvh: self,
            ctx,
            t_max,
            counters,
        })
    }

    /// `IntersectionTest` of the parts of node `i` (its bounding volume was met, or it
    /// is the root): for each part, test its volume, then a leaf's triangles
    /// (`LLIntersectionTest`) or the node's own parts.
    fn recurse<O: AxisOrder>(
        &self,
        i: u32,
        ray: &BoxRay,
        range: (f32, f32),
        ctx: &HitContext<'_>,
        closest: &mut ClosestHit,
        counters: &mut TraceCounters,
    ) {
        let n = &self.nodes[i as usize];
        counters.nodes += 1;
        let t = ray.entries(n, range.0, range.1);
        for k in 0..WIDTH {
            if t[k] == f32::INFINITY {
                continue;
            }
            match n.slot(k) {
                Slot::Empty => {}
                Slot::Node(c) => self.recurse::<O>(c, ray, range, ctx, closest, counters),
                Slot::Leaf { first, count } => {
                    for t in first as usize..(first + count) as usize {
                        counters.triangles += u64::from(ctx.test::<O>(
                            &self.triangles[t],
                            self.polygons[t],
                            f64::INFINITY,
                            closest,
                        ));
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::BvhOptions;
    use crate::accel::triangles::{PrimaryRays, SceneTriangles};
    use crate::cull::backface::BackfaceMode;
    use crate::scene::{Viewport, demo};

    #[test]
    fn box_test_never_misses_a_box_the_exact_ray_crosses() {
        // Rays aimed at random points of a box's faces, edges and corners (grazing
        // rays), from near and far origins (and from near the origin of coordinates,
        // where the margin in space is nearly zero and the relative widening does the
        // work), with boxes from 1e-4 to 1e4 across placed up to 1e6 from the origin
        // of coordinates, directions of any length, and boxes ahead of the origin or
        // behind it (a negative near limit). The single-precision test must report
        // every box, entered no later than the exact ray enters it.
        let mut rng = crate::rng::SplitMix64(4);
        let f32_exact = |v: f64| f64::from(v as f32);
        for case in 0..20_000 {
            let size: f64 = [1e-4, 1.0, 1e4][case % 3];
            let offset = [0.0, 1.0, 1e3, 1e6][(case / 3) % 4] * size.max(1.0);
            let centre = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0) * offset;
            let v = |rng: &mut crate::rng::SplitMix64, a: f64, b: f64| {
                DVec3::new(rng.range(a, b), rng.range(a, b), rng.range(a, b))
            };
            // Box corners that are `f32` values, so the node holds the box exactly.
            let lo = (centre + v(&mut rng, -5.0, 5.0) * size).map(f32_exact);
            let hi = (lo + v(&mut rng, 0.0, 2.0) * size).map(f32_exact);
            let mut node = BvhNode::default();
            for axis in 0..3 {
                node.min[axis][2] = lo[axis] as f32;
                node.max[axis][2] = hi[axis] as f32;
            }
            // A point on a face, an edge or a corner (one to three coordinates at
            // their bounds).
            let mut p = lo + (hi - lo) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            let pinned = 1 + case % 3;
            let first = (rng.next_u64() % 3) as usize;
            for j in 0..pinned {
                let k = (first + j) % 3;
                p[k] = if rng.next_f64() < 0.5 { lo[k] } else { hi[k] };
            }
            let far = rng.next_f64() < 0.3;
            // From near the origin of coordinates (the margin is then nearly all
            // reach), or from around the box.
            let o = if case % 4 == 0 {
                v(&mut rng, -1.0, 1.0) * size * 1e-6
            } else {
                p + v(&mut rng, -1.0, 1.0) * size * if far { 1e4 } else { 20.0 }
            };
            // The ray reaches `p` at `t_p`, within its limits.
            let length = [1e-3, 1.0, 1e3][(case / 12) % 3];
            let behind = case % 5 == 0;
            let (d, t_p) = if behind {
                ((o - p) * length, -1.0 / length)
            } else {
                ((p - o) * length, 1.0 / length)
            };
            let (t_min, t_max) = if behind {
                (1.5 * t_p, 0.5 * t_p)
            } else {
                (0.0, 1.5 * t_p)
            };
            let ray = BoxRay::new(o, d, 1e4);
            let t = ray.entries(&node, f32_down(t_min), f32_up(t_max));
            assert!(
                f64::from(t[2]) <= t_p,
                "case {case}: missed {p:?} from {o:?} (entry {})",
                t[2]
            );
            // Empty slots are never entered.
            assert_eq!([t[0], t[1], t[3]], [f32::INFINITY; 3]);
        }
    }

    #[test]
    fn ordered_and_recursive_traversals_equal_brute_force() {
        let scene = demo::default_scene();
        let tris = SceneTriangles::new(&scene);
        let bvh = Bvh::build(&tris, &BvhOptions::default());
        let vp = Viewport::new(48, 36).unwrap();
        let cam = scene.default_camera(vp.aspect());
        let rays = PrimaryRays::new(&cam, vp);
        let ignored = tris.ignored_polygons(&scene, &cam, BackfaceMode::Closed);
        let mut stack = TraversalStack::default();
        let (mut ordered, mut recursive) = (TraceCounters::default(), TraceCounters::default());
        let mut hits = 0;
        for j in 0..vp.height {
            for i in 0..vp.width {
                let ctx = rays
                    .context(
                        f64::from(i) + 0.5,
                        f64::from(j) + 0.5,
                        &ignored,
                        tris.polygon_faces(),
                    )
                    .unwrap();
                let mut brute = ClosestHit::new(rays.far);
                for (t, &p) in tris.vertices().iter().zip(tris.triangle_polygons()) {
                    if !ignored[p as usize]
                        && let Some(tt) = ctx.ray.intersect_any(t, ctx.t_min, brute.t, &ctx.tie)
                    {
                        brute.offer(tt, tris.polygon_faces()[p as usize]);
                    }
                }
                let a = bvh.closest_hit(&ctx, rays.far, &mut stack, &mut ordered);
                let portable = bvh.closest_hit_with(
                    Kernel::Portable,
                    &ctx,
                    rays.far,
                    &mut stack,
                    &mut TraceCounters::default(),
                );
                assert_eq!(a, portable, "pixel {i},{j}: kernels differ");
                let b = bvh.closest_hit_recursive(&ctx, rays.far, &mut recursive);
                assert_eq!(a, brute, "pixel {i},{j}");
                assert_eq!(b, brute, "pixel {i},{j}");
                hits += usize::from(brute.is_hit());
            }
        }
        assert!(hits > 500, "{hits}");
        // Ordering and pruning must save work over the unordered recursion.
        assert!(
            ordered.triangles < recursive.triangles,
            "{ordered:?} {recursive:?}"
        );
    }

    /// Rays whose numbers overflow `f32` (origins spread over an orthographic view 1e39
    /// wide and more, which `Camera::validate` refuses but the traversals must survive): no slot that holds
    /// nothing is entered. Before the traversals checked occupied slots, an empty slot's
    /// sentinel child was taken for a leaf and indexed out of bounds.
    #[test]
    fn rays_beyond_single_precision_enter_no_empty_slot() {
        use crate::accel::bvh::packet::{PacketContext, PacketStack, RayPacket};
        // A cube: its BVH's root has empty slots.
        let mut scene = crate::Scene::new();
        scene
            .add(crate::scene::ObjectDesc::new(
                "cube",
                demo::box_mesh(DVec3::splat(-1.0), DVec3::ONE),
            ))
            .unwrap();
        let tris = SceneTriangles::new(&scene);
        let bvh = Bvh::build(&tris, &BvhOptions::default());
        let vp = Viewport::new(24, 24).unwrap();
        let base = crate::scene::Camera::perspective(
            DVec3::new(2.0, 1.5, 4.0),
            DVec3::ZERO,
            DVec3::Y,
            60.0,
            0.1,
            100.0,
        );
        let mut traced = 0;
        for height in [1e39, 1e60, 1e300] {
            // An orthographic view that wide puts the rays' origins beyond `f32`.
            let cam = crate::scene::Camera {
                projection: crate::scene::Projection::Orthographic { height },
                ..base
            };
            let rays = PrimaryRays::new(&cam, vp);
            let ignored = tris.ignored_polygons(&scene, &cam, BackfaceMode::Off);
            let ctx = PacketContext {
                ignored: &ignored,
                faces: tris.polygon_faces(),
                t_min: rays.near,
                tie: rays.tie_rule(),
            };
            let (mut stack, mut packets) = (TraversalStack::default(), PacketStack::default());
            for j in (0..vp.height).step_by(4) {
                for i in (0..vp.width).step_by(4) {
                    let list: Vec<(DVec3, DVec3)> = (0..16)
                        .map(|k| rays.ray(f64::from(i + k % 4) + 0.5, f64::from(j + k / 4) + 0.5))
                        .collect();
                    for &(o, d) in &list {
                        let Some(ray) = crate::accel::triangles::WatertightRay::new(o, d) else {
                            continue;
                        };
                        let hit = bvh.closest_hit(
                            &ctx.with_ray(ray),
                            rays.far,
                            &mut stack,
                            &mut TraceCounters::default(),
                        );
                        assert!(!hit.is_hit() || hit.t.is_finite());
                        traced += 1;
                    }
                    let packet = RayPacket::new(&list, bvh.scale());
                    for kernel in [Kernel::Portable, Kernel::Auto] {
                        let hits = bvh.closest_hits_with(
                            kernel,
                            &packet,
                            &ctx,
                            rays.far,
                            &mut packets,
                            &mut TraceCounters::default(),
                        );
                        assert!(hits.iter().all(|h| !h.is_hit() || h.t.is_finite()));
                    }
                }
            }
        }
        assert!(traced > 0);
    }
}
