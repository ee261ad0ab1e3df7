//! Packets of coherent rays traced through a [`Bvh`] together.
//!
//! Primary rays through neighbouring pixels visit nearly the same nodes and
//! triangles. A [`RayPacket`] holds [`PACKET`] of them (a 4x4 block of pixels) and
//! walks the tree once for all: each node is loaded and each decision taken once per
//! packet instead of once per ray, and the arithmetic runs across the rays (one lane
//! per ray) instead of across a node's children.
//!
//! # Per-ray masks: the same hits as single rays
//! Every stack entry carries the set of rays (a bit mask) that entered its box. At a
//! node, each child's box is tested against every ray of the mask with exactly the
//! single-ray box test of [`super::traverse`] (the same grown boxes, the same `f32`
//! slab distances, only selected by a min/max instead of by the direction's sign), and
//! only the rays that enter it go down. Leaves test their triangles against the rays
//! of their mask with the exact `f64` watertight test of
//! [`crate::accel::triangles`], one lane per ray, with the very operations of the
//! scalar test in the same order (so the same `t` to the last bit); rays exactly on an
//! edge of a triangle are finished by the scalar test (the tie rule). Each ray keeps
//! its own nearest hit and prunes with it, so a packet returns, ray by ray, what
//! [`Bvh::closest_hit`] returns: the nearest hit, the lower face id on an exact tie.
//!
//! # The packet as a whole: an interval test
//! Most children of a node are missed by every ray of a packet. When each direction
//! component keeps its sign across the packet, the rays' slab distances into a box are
//! bounded by products of intervals: the smallest entry by the entry plane measured
//! from the extreme shifted origin times the range of `1 / d`, the largest exit
//! likewise (Boulos et al., "Geometric and Arithmetic Culling Methods for Entire Ray
//! Packets", 2006). Rounding is monotone, so each ray's own `f32` distances lie within
//! these `f32` bounds, and so do their widened values (`x ∓ γ |x|` is monotone): a
//! child whose widened bounds do not overlap is entered by no ray, and the eight
//! children are culled so in one 8-lane test before any per-ray test.
//!
//! # Order
//! The children a packet enters are visited nearest first by the smallest entry
//! distance of their rays; the others are pushed with it. When an entry is popped, the
//! rays whose nearest hit is nearer than that distance are dropped from its mask (they
//! cannot enter the box), and the entry is skipped when no ray is left.
//!
//! # When packets are not used
//! The triangle test is compiled per axis order (the ray's dominant direction axis and
//! its sign); a packet whose rays do not share one (rays on both sides of a 45°
//! diagonal) is traced ray by ray with [`Bvh::closest_hit_with`].
//!
//! # Kernels
//! The traversal is written once over a lane backend (`packet_lanes.rs`, one lane per ray): portable Rust,
//! compiled for the baseline and for AVX2 (vectorized by the compiler), or AVX-512
//! intrinsics (sixteen rays per register, comparisons giving the ray masks directly),
//! chosen at run time by CPU detection; [`Kernel`] lets tests and benchmarks force
//! one. All run the same IEEE operations in the same order (no fused multiply-add), so
//! they return the same hits. The rays' preparation ([`RayPacket::prepare`]) is
//! likewise written lane by lane and compiled for AVX-512 where the CPU has it.
//! On Sponza's atrium view at 1920x1080, one thread: about 4.2 million rays per second
//! with AVX2, 10 with AVX-512 (single rays: 2.9).
//!
//! - Input: up to [`PACKET`] rays, the polygons to ignore, face ids, the near limit,
//!   the tie rule. Output: per ray, its [`ClosestHit`].
//! - Complexity: per packet, the union of the rays' paths through the tree; per ray,
//!   the same box and triangle tests as alone, minus those a packet makes redundant.
//! - Limitations: packets pay for rays that diverge (a silhouette in the block sends
//!   lanes down different subtrees, and inactive lanes are computed and masked).
//! - Source: Wald, Slusallek, Benthin and Wagner, "Interactive Rendering with Coherent
//!   Ray Tracing" (2001), packets of coherent rays; Wald, Benthin and Boulos, "Getting
//!   Rid of Packets" (2008) and Embree's packet kernels, per-ray masks in wide BVHs.

use super::packet_lanes::{PacketLanes, Portable};
use super::ray_packet::{CHUNK, Mask};
pub use super::ray_packet::{PACKET, PACKET_SIDE, RayPacket};
use super::traverse::{TraceCounters, TraversalStack};
use super::{Bvh, MAX_DEPTH, WIDTH, f32_down, f32_up};
use crate::accel::triangles::{
    AxisOrder, ClosestHit, HitContext, TieRule, WatertightRay, WithAxisOrder, dispatch_order,
};
#[cfg(target_arch = "x86_64")]
use crate::cpu::Avx512;
use crate::cpu::Kernel;

/// What the rays of a packet share: the polygons to ignore (back faces), face ids, the
/// near limit and the tie rule (a [`HitContext`] without its ray).
#[derive(Clone, Copy, Debug)]
pub struct PacketContext<'a> {
    /// Per polygon: whether hits on it are ignored.
    pub ignored: &'a [bool],
    /// Per polygon: its face id.
    pub faces: &'a [u32],
    /// The smallest accepted parameter (the near plane).
    pub t_min: f64,
    /// Rays exactly on edges.
    pub tie: TieRule,
}

impl<'a> PacketContext<'a> {
    /// The single-ray context of `ray`.
    #[must_use]
    pub fn with_ray(&self, ray: WatertightRay) -> HitContext<'a> {
        HitContext {
            ray,
            ignored: self.ignored,
            faces: self.faces,
            t_min: self.t_min,
            tie: self.tie,
        }
    }
}

/// A stack entry: a node (or, with [`LEAF_BIT`], a leaf slot `WIDTH * node + slot`),
/// the rays that entered it and the smallest of their entry distances.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    item: u32,
    mask: Mask,
    near: f32,
}

const LEAF_BIT: u32 = 1 << 31;

const STACK_SIZE: usize = (WIDTH - 1) * MAX_DEPTH + WIDTH;

/// The stacks of a packet traversal (and of single rays, for packets that are not
/// coherent), reusable from packet to packet (one per thread).
#[derive(Clone, Debug)]
pub struct PacketStack {
    entries: Box<[Entry; STACK_SIZE]>,
    single: TraversalStack,
}

impl Default for PacketStack {
    fn default() -> Self {
        PacketStack {
            entries: Box::new([Entry::default(); STACK_SIZE]),
            single: TraversalStack::default(),
        }
    }
}

/// The nearest hits of a packet's rays, lane by lane.
struct Hits {
    t: [f64; PACKET],
    face: [u32; PACKET],
    /// `t` rounded up to `f32`: the far limit of the box tests.
    t_hi: [f32; PACKET],
}

impl Bvh {
    /// The nearest hit of every ray of the packet with `ctx.t_min <= t <= t_max`
    /// (lanes without a ray: no hit), each equal to [`Bvh::closest_hit`]'s.
    pub fn closest_hits(
        &self,
        packet: &RayPacket,
        ctx: &PacketContext<'_>,
        t_max: f64,
        stack: &mut PacketStack,
        counters: &mut TraceCounters,
    ) -> [ClosestHit; PACKET] {
        self.closest_hits_with(Kernel::Auto, packet, ctx, t_max, stack, counters)
    }

    /// [`Bvh::closest_hits`] with a chosen kernel.
    pub fn closest_hits_with(
        &self,
        kernel: Kernel,
        packet: &RayPacket,
        ctx: &PacketContext<'_>,
        t_max: f64,
        stack: &mut PacketStack,
        counters: &mut TraceCounters,
    ) -> [ClosestHit; PACKET] {
        let Some(order) = packet.order else {
            let mut out = [ClosestHit::new(t_max); PACKET];
            for (r, hit) in out.iter_mut().enumerate() {
                if let Some(ray) = packet.ray(r) {
                    let single = ctx.with_ray(ray);
                    *hit =
                        self.closest_hit_with(kernel, &single, t_max, &mut stack.single, counters);
                }
            }
            return out;
        };
        struct Run<'a, 'b> {
            bvh: &'a Bvh,
            kernel: Kernel,
            packet: &'a RayPacket,
            ctx: &'a PacketContext<'b>,
            t_max: f64,
            stack: &'a mut PacketStack,
            counters: &'a mut TraceCounters,
        }
        impl WithAxisOrder for Run<'_, '_> {
            type Output = [ClosestHit; PACKET];
            fn run<O: AxisOrder>(self) -> [ClosestHit; PACKET] {
                let Run {
                    bvh,
                    kernel,
                    packet,
                    ctx,
                    t_max,
                    stack,
                    counters,
                } = self;
                #[cfg(target_arch = "x86_64")]
                {
                    if let Some(lanes) = kernel.avx512() {
                        // SAFETY: `Avx512::new` checked the features this function
                        // enables; its body is safe code.
                        return unsafe {
                            bvh.packet_avx512::<O>(lanes, packet, ctx, t_max, stack, counters)
                        };
                    }
                    if let Some(cpu) = kernel.avx2() {
                        // SAFETY: `Avx2::new` checked every feature this function
                        // enables; its body is safe code.
                        return unsafe {
                            bvh.packet_avx2::<O>(cpu, packet, ctx, t_max, stack, counters)
                        };
                    }
                }
                bvh.packet::<O, Portable>(Portable, packet, ctx, t_max, stack, counters)
            }
        }
        dispatch_order(
            order,
            Run {
                bvh: self,
                kernel,
                packet,
                ctx,
                t_max,
                stack,
                counters,
            },
        )
    }

    /// [`Bvh::packet`] with AVX-512 lanes.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
    fn packet_avx512<O: AxisOrder>(
        &self,
        lanes: Avx512,
        packet: &RayPacket,
        ctx: &PacketContext<'_>,
        t_max: f64,
        stack: &mut PacketStack,
        counters: &mut TraceCounters,
    ) -> [ClosestHit; PACKET] {
        self.packet::<O, Avx512>(lanes, packet, ctx, t_max, stack, counters)
    }

    /// [`Bvh::packet`] with portable lanes compiled for AVX2 (vectorized by the
    /// compiler).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn packet_avx2<O: AxisOrder>(
        &self,
        _: crate::cpu::Avx2,
        packet: &RayPacket,
        ctx: &PacketContext<'_>,
        t_max: f64,
        stack: &mut PacketStack,
        counters: &mut TraceCounters,
    ) -> [ClosestHit; PACKET] {
        self.packet::<O, Portable>(Portable, packet, ctx, t_max, stack, counters)
    }

    #[inline(always)]
    fn packet<O: AxisOrder, L: PacketLanes>(
        &self,
        lanes: L,
        packet: &RayPacket,
        ctx: &PacketContext<'_>,
        t_max: f64,
        stack: &mut PacketStack,
        counters: &mut TraceCounters,
    ) -> [ClosestHit; PACKET] {
        let mut hits = Hits {
            t: [t_max; PACKET],
            face: [crate::BACKGROUND; PACKET],
            t_hi: [f32_up(t_max); PACKET],
        };
        let done = |hits: &Hits| -> [ClosestHit; PACKET] {
            std::array::from_fn(|r| ClosestHit {
                t: hits.t[r],
                face: hits.face[r],
            })
        };
        if self.nodes.is_empty() || !(ctx.t_min <= t_max) || packet.valid == 0 {
            return done(&hits);
        }
        let t_lo = f32_down(ctx.t_min);
        let stack = &mut stack.entries;
        let mut sp = 0usize;
        let mut node = 0u32;
        let mut mask = packet.valid;
        loop {
            let n = &self.nodes[node as usize];
            counters.nodes += u64::from(mask.count_ones());
            counters.packet_nodes += 1;
            // The children some ray may enter: by the interval test of the whole
            // packet when it has one, else those that exist.
            let candidates = match &packet.frustum {
                Some(f) => {
                    lanes.children(f, n, t_lo, lanes.far_limit(&hits.t_hi, mask)) & n.occupied()
                }
                None => n.occupied(),
            };
            // The children entered by some ray, nearest first (insertion sort).
            let mut entered = [Entry::default(); WIDTH];
            let mut m = 0;
            let mut rest = candidates;
            while rest != 0 {
                let k = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                let (enter, first) = lanes.enter(packet, n, k, t_lo, &hits.t_hi, mask);
                if enter == 0 {
                    continue;
                }
                let item = if n.count[k] == 0 {
                    n.child[k]
                } else {
                    LEAF_BIT | (node * WIDTH as u32 + k as u32)
                };
                let mut p = m;
                while p > 0 && entered[p - 1].near > first {
                    entered[p] = entered[p - 1];
                    p -= 1;
                }
                entered[p] = Entry {
                    item,
                    mask: enter,
                    near: first,
                };
                m += 1;
            }
            // Push the farther ones (farthest first, so they pop nearest first).
            for e in entered[1..m.max(1)].iter().rev() {
                debug_assert!(sp < stack.len());
                stack[sp] = *e;
                sp += 1;
            }
            let mut current = (m > 0).then_some(entered[0]);
            loop {
                let Some(e) = current.take() else {
                    if sp == 0 {
                        return done(&hits);
                    }
                    sp -= 1;
                    // A ray whose nearest hit is nearer than every ray's entry into the
                    // box cannot enter it.
                    let e = stack[sp];
                    let mask = lanes.not_before(&hits.t_hi, e.near, e.mask);
                    if mask != 0 {
                        current = Some(Entry { mask, ..e });
                    }
                    continue;
                };
                if e.item & LEAF_BIT == 0 {
                    node = e.item;
                    mask = e.mask;
                    break;
                }
                let slot = e.item & !LEAF_BIT;
                let owner = &self.nodes[slot as usize / WIDTH];
                let k = slot as usize % WIDTH;
                self.packet_leaf::<O, L>(
                    lanes,
                    owner.child[k],
                    owner.count[k],
                    packet,
                    ctx,
                    e.mask,
                    &mut hits,
                    counters,
                );
            }
        }
    }

    /// Tests the rays of `mask` against the triangles of a leaf.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn packet_leaf<O: AxisOrder, L: PacketLanes>(
        &self,
        lanes: L,
        first: u32,
        count: u32,
        packet: &RayPacket,
        ctx: &PacketContext<'_>,
        mask: Mask,
        hits: &mut Hits,
        counters: &mut TraceCounters,
    ) {
        let mut changed: Mask = 0;
        let range = first as usize..(first + count) as usize;
        for (tri, &poly) in self.triangles[range.clone()]
            .iter()
            .zip(&self.polygons[range])
        {
            if ctx.ignored[poly as usize] {
                continue;
            }
            counters.triangles += u64::from(mask.count_ones());
            let face = ctx.faces[poly as usize];
            for c in 0..PACKET / CHUNK {
                if (mask >> (c * CHUNK)) & ((1 << CHUNK) - 1) == 0 {
                    continue;
                }
                let (hit, edge, t) = lanes.triangle::<O>(packet, tri, c, ctx.t_min, &hits.t);
                let mut take = hit & mask;
                while take != 0 {
                    let r = take.trailing_zeros() as usize;
                    take &= take - 1;
                    let tt = t[r - c * CHUNK];
                    if tt < hits.t[r] || face < hits.face[r] {
                        hits.t[r] = tt;
                        hits.face[r] = face;
                        changed |= 1 << r;
                    }
                }
                let mut edge = edge & mask;
                while edge != 0 {
                    let r = edge.trailing_zeros() as usize;
                    edge &= edge - 1;
                    let Some(ray) = packet.ray(r) else { continue };
                    if let Some(tt) = ray.intersect::<O>(tri, ctx.t_min, hits.t[r], &ctx.tie)
                        && (tt < hits.t[r] || face < hits.face[r])
                    {
                        hits.t[r] = tt;
                        hits.face[r] = face;
                        changed |= 1 << r;
                    }
                }
            }
        }
        while changed != 0 {
            let r = changed.trailing_zeros() as usize;
            changed &= changed - 1;
            hits.t_hi[r] = f32_up(hits.t[r]);
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::accel::bvh::BvhNode;
    use crate::accel::bvh::packet_lanes::PacketLanes;
    use crate::accel::bvh::traverse::BoxRay;
    use crate::rng::SplitMix64;

    /// The lane-by-lane preparation (compiled for the baseline here, and for AVX-512
    /// where `prepare` picks it) gives every ray exactly what the single-ray
    /// constructors give.
    #[test]
    fn prepared_lanes_equal_single_rays() {
        let mut rng = SplitMix64(5);
        for case in 0..400 {
            let n = if case % 5 == 0 {
                1 + case % PACKET
            } else {
                PACKET
            };
            let narrow = case % 2 == 0;
            let rays: Vec<(DVec3, DVec3)> = (0..n)
                .map(|r| {
                    let o = DVec3::new(
                        rng.range(-50.0, 50.0),
                        rng.range(-5.0, 5.0),
                        rng.range(-1.0, 1.0),
                    );
                    let mut d = DVec3::new(
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                    );
                    if narrow {
                        d = DVec3::new(0.1, -1.0, 0.2) + d * 0.05;
                    }
                    if r == 3 && case % 3 == 0 {
                        d = DVec3::ZERO;
                    }
                    if r == 4 && case % 7 == 0 {
                        d.y = f64::INFINITY;
                    }
                    (o, d)
                })
                .collect();
            let fast = RayPacket::new(&rays, 30.0);
            let mut plain = RayPacket::default();
            plain.prepare_lanes(&rays, 30.0);
            assert_eq!((fast.valid, fast.order), (plain.valid, plain.order));
            let bits = |p: &RayPacket, r: usize| {
                let f = |a: &[[f32; PACKET]; 3]| a.map(|x| x[r].to_bits());
                let d = |a: &[[f64; PACKET]; 3]| a.map(|x| x[r].to_bits());
                (
                    d(&p.origin),
                    d(&p.shear),
                    f(&p.lower),
                    f(&p.upper),
                    f(&p.inv),
                )
            };
            let mut orders = Vec::new();
            for (r, &(o, d)) in rays.iter().enumerate() {
                let Some(ray) = WatertightRay::new(o, d) else {
                    assert_eq!(fast.valid >> r & 1, 0);
                    continue;
                };
                assert_eq!(fast.valid >> r & 1, 1);
                orders.push(ray.order_index());
                assert_eq!(bits(&fast, r), bits(&plain, r), "case {case} lane {r}");
                if fast.order.is_some() {
                    assert_eq!(ray.shear().to_array(), [0, 1, 2].map(|k| fast.shear[k][r]));
                }
                // The box test's data: entries into a box equal the single ray's.
                let mut node = BvhNode::default();
                for axis in 0..3 {
                    node.min[axis][0] = -1.0;
                    node.max[axis][0] = 2.0;
                }
                let single = BoxRay::new(o, d, 30.0).entries(&node, 0.0, f32::INFINITY)[0];
                let t_hi = [f32::INFINITY; PACKET];
                let (entered, first) = Portable.enter(&fast, &node, 0, 0.0, &t_hi, 1 << r);
                assert_eq!(entered != 0, single != f32::INFINITY);
                if entered != 0 {
                    assert_eq!(first, single);
                }
            }
            orders.sort_unstable();
            orders.dedup();
            assert_eq!(fast.is_coherent(), orders.len() == 1);
            assert_eq!(plain.frustum.is_some(), fast.frustum.is_some());
        }
    }
}
