//! Closest-hit traversal of a [`Bvh`].
//!
//! # Box test in single precision, made conservative
//! The nodes' boxes are `f32`, rounded outwards from the `f64` triangles. The ray is
//! converted to `f32` too, so the slab distances carry rounding errors of a few ulp of
//! `|box| + |origin|`. To never miss a box the exact ray enters, every box is grown by a
//! margin `δ = 2^-17 (|origin|∞ + scale)` (`scale` = the largest coordinate of the
//! scene), about 20 times the worst error. The margin costs nothing per test: the lower
//! planes are met at `(min - (o + δ)) / d` and the upper ones at `(max - (o - δ)) / d`,
//! so two shifted origins are computed once per ray (Ize 2013 makes the same point for
//! `tmax *= 1 + 2γ`). Zero direction components get an inverse of `±10^30` (not
//! infinity), so no `0 · ∞` NaN can appear and plain comparisons suffice.
//!
//! # Order
//! At an interior node both children's boxes are tested (they share a cache line); the
//! nearer is visited first and the farther pushed with its entry distance, skipped when
//! popped if a hit nearer than that was found meanwhile. Triangles are tested with the
//! exact `f64` watertight test, so the result equals brute force's.

use glam::DVec3;

use super::{Bvh, BvhNode, MAX_DEPTH, f32_down, f32_up};
use crate::accel::triangles::{AxisOrder, ClosestHit, HitContext, WithAxisOrder};

/// What a traversal did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceCounters {
    /// Boxes tested.
    pub boxes: u64,
    /// Exact triangle tests run.
    pub triangles: u64,
}

impl std::ops::AddAssign for TraceCounters {
    fn add_assign(&mut self, o: Self) {
        self.boxes += o.boxes;
        self.triangles += o.triangles;
    }
}

/// A traversal stack, reusable from ray to ray (one per thread).
#[derive(Clone, Debug)]
pub struct TraversalStack {
    entries: [(u32, f32); MAX_DEPTH],
}

impl Default for TraversalStack {
    fn default() -> Self {
        TraversalStack {
            entries: [(0, 0.0); MAX_DEPTH],
        }
    }
}

/// The margin of the box test relative to the coordinates (see the module doc).
const MARGIN: f64 = 1.0 / 131_072.0;

/// A ray prepared for the single-precision slab test.
#[derive(Clone, Copy, Debug)]
pub struct BoxRay {
    lower_origin: [f32; 3],
    upper_origin: [f32; 3],
    inv: [f32; 3],
}

#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

impl BoxRay {
    /// Prepares a ray for boxes whose coordinates are at most `scale` in absolute value.
    #[must_use]
    pub fn new(origin: DVec3, direction: DVec3, scale: f64) -> Self {
        let delta = (origin.abs().max_element() + scale) * MARGIN;
        let inv = |d: f64| (1.0 / d).clamp(-1e30, 1e30) as f32;
        BoxRay {
            lower_origin: (origin + delta).to_array().map(|x| x as f32),
            upper_origin: (origin - delta).to_array().map(|x| x as f32),
            inv: [inv(direction.x), inv(direction.y), inv(direction.z)],
        }
    }

    /// The entry distance into the (grown) box if the ray meets it within
    /// `[t_min, t_max]`, else `+inf`.
    #[inline(always)]
    #[must_use]
    pub fn entry(&self, n: &BvhNode, t_min: f32, t_max: f32) -> f32 {
        let x0 = (n.min[0] - self.lower_origin[0]) * self.inv[0];
        let x1 = (n.max[0] - self.upper_origin[0]) * self.inv[0];
        let y0 = (n.min[1] - self.lower_origin[1]) * self.inv[1];
        let y1 = (n.max[1] - self.upper_origin[1]) * self.inv[1];
        let z0 = (n.min[2] - self.lower_origin[2]) * self.inv[2];
        let z1 = (n.max[2] - self.upper_origin[2]) * self.inv[2];
        let near = max(max(min(x0, x1), min(y0, y1)), max(min(z0, z1), t_min));
        let far = min(min(max(x0, x1), max(y0, y1)), min(max(z0, z1), t_max));
        if near <= far { near } else { f32::INFINITY }
    }
}

impl Bvh {
    /// The nearest hit with `ctx.t_min <= t <= t_max`, nearest child first.
    pub fn closest_hit(
        &self,
        ctx: &HitContext<'_>,
        t_max: f64,
        stack: &mut TraversalStack,
        counters: &mut TraceCounters,
    ) -> ClosestHit {
        struct Run<'a, 'b> {
            bvh: &'a Bvh,
            ctx: &'a HitContext<'b>,
            t_max: f64,
            stack: &'a mut TraversalStack,
            counters: &'a mut TraceCounters,
        }
        impl WithAxisOrder for Run<'_, '_> {
            type Output = ClosestHit;
            fn run<O: AxisOrder>(self) -> ClosestHit {
                self.bvh
                    .ordered::<O>(self.ctx, self.t_max, self.stack, self.counters)
            }
        }
        ctx.ray.dispatch(Run {
            bvh: self,
            ctx,
            t_max,
            stack,
            counters,
        })
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
        if self.is_empty() || !(ctx.t_min <= t_max) {
            return closest;
        }
        let ray = BoxRay::new(ctx.ray.origin, ctx.ray.direction, self.scale);
        let t_lo = f32_down(ctx.t_min);
        let mut t_hi = f32_up(t_max);
        let mut node = self.node(0);
        counters.boxes += 1;
        if ray.entry(node, t_lo, t_hi) == f32::INFINITY {
            return closest;
        }
        let stack = &mut stack.entries;
        let mut sp = 0usize;
        loop {
            if node.is_leaf() {
                let range = node.first as usize..(node.first + node.count) as usize;
                for (tri, &poly) in self.triangles[range.clone()]
                    .iter()
                    .zip(&self.polygons[range])
                {
                    counters.triangles +=
                        u64::from(ctx.test::<O>(tri, poly, f64::INFINITY, &mut closest));
                }
                t_hi = f32_up(closest.t);
            } else {
                let pair = &self.pairs[(node.first >> 1) as usize].0;
                counters.boxes += 2;
                let ta = ray.entry(&pair[0], t_lo, t_hi);
                let tb = ray.entry(&pair[1], t_lo, t_hi);
                let (near_node, t_near, t_far, far_index) = if ta <= tb {
                    (&pair[0], ta, tb, node.first + 1)
                } else {
                    (&pair[1], tb, ta, node.first)
                };
                if t_near != f32::INFINITY {
                    if t_far != f32::INFINITY {
                        debug_assert!(sp < stack.len());
                        stack[sp] = (far_index, t_far);
                        sp += 1;
                    }
                    node = near_node;
                    continue;
                }
            }
            // Pop the next subtree that may still hold a nearer hit.
            loop {
                if sp == 0 {
                    return closest;
                }
                sp -= 1;
                let (i, t) = stack[sp];
                if t <= t_hi {
                    node = self.node(i);
                    break;
                }
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
                if self.bvh.is_empty() || !(self.ctx.t_min <= self.t_max) {
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

    fn recurse<O: AxisOrder>(
        &self,
        i: u32,
        ray: &BoxRay,
        range: (f32, f32),
        ctx: &HitContext<'_>,
        closest: &mut ClosestHit,
        counters: &mut TraceCounters,
    ) {
        let n = self.node(i);
        if n.is_leaf() {
            for k in n.first as usize..(n.first + n.count) as usize {
                counters.triangles += u64::from(ctx.test::<O>(
                    &self.triangles[k],
                    self.polygons[k],
                    f64::INFINITY,
                    closest,
                ));
            }
            return;
        }
        counters.boxes += 1;
        if ray.entry(n, range.0, range.1) == f32::INFINITY {
            return;
        }
        self.recurse::<O>(n.first, ray, range, ctx, closest, counters);
        self.recurse::<O>(n.first + 1, ray, range, ctx, closest, counters);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::BvhOptions;
    use crate::accel::triangles::{PrimaryRays, SceneTriangles, WatertightRay};
    use crate::cull::backface::BackfaceMode;
    use crate::scene::{Viewport, demo};

    #[test]
    fn box_test_never_misses_a_box_the_exact_ray_crosses() {
        // Rays aimed at random points of a box's surface, from near and far origins:
        // the single-precision test must report a hit every time.
        let mut rng = demo::SplitMix64(4);
        for _ in 0..2000 {
            let lo = DVec3::new(
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
            );
            let hi = lo
                + DVec3::new(
                    rng.range(0.0, 2.0),
                    rng.range(0.0, 2.0),
                    rng.range(0.0, 2.0),
                );
            let node = BvhNode {
                min: [f32_down(lo.x), f32_down(lo.y), f32_down(lo.z)],
                first: 0,
                max: [f32_up(hi.x), f32_up(hi.y), f32_up(hi.z)],
                count: 1,
            };
            // A point on a face (one coordinate at its bound).
            let mut p = lo + (hi - lo) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            let k = (rng.next_u64() % 3) as usize;
            p[k] = if rng.next_f64() < 0.5 { lo[k] } else { hi[k] };
            let far = rng.next_f64() < 0.3;
            let o = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ) * if far { 1e4 } else { 20.0 };
            let d = p - o;
            let ray = BoxRay::new(o, d, 7.0);
            assert!(ray.entry(&node, 0.0, 2.0) <= 1.0, "missed {p:?} from {o:?}");
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
                let (o, d) = rays.ray(f64::from(i) + 0.5, f64::from(j) + 0.5);
                let ctx = HitContext {
                    ray: WatertightRay::new(o, d).unwrap(),
                    ignored: &ignored,
                    faces: tris.polygon_faces(),
                    t_min: rays.near,
                    tie: rays.tie_rule(),
                };
                let mut brute = ClosestHit::new(rays.far);
                for (t, &p) in tris.vertices().iter().zip(tris.triangle_polygons()) {
                    if !ignored[p as usize]
                        && let Some(tt) = ctx.ray.intersect_any(t, ctx.t_min, brute.t, &ctx.tie)
                    {
                        brute.offer(tt, tris.polygon_faces()[p as usize]);
                    }
                }
                let a = bvh.closest_hit(&ctx, rays.far, &mut stack, &mut ordered);
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
}
