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
//! The traversal is written once over a lane backend (`lanes.rs`): portable Rust,
//! compiled for the baseline and for AVX2 (vectorized by the compiler), or AVX-512
//! intrinsics (sixteen rays per register, comparisons giving the ray masks directly),
//! chosen at run time by CPU detection; [`Kernel`] lets tests and benchmarks force
//! one. All run the same IEEE operations in the same order (no fused multiply-add), so
//! they return the same hits. On Sponza's atrium view at 1920x1080, one thread:
//! about 4.2 million rays per second with AVX2, 8 with AVX-512 (single rays: 2.9).
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

use glam::DVec3;

#[cfg(target_arch = "x86_64")]
use super::lanes::Avx512;
use super::lanes::{Lanes, Portable};
use super::traverse::{Kernel, TraceCounters, TraversalStack, inverse_direction, shifted_origins};
use super::{Bvh, MAX_DEPTH, WIDTH, f32_down, f32_up};
use crate::accel::triangles::{
    AxisOrder, ClosestHit, HitContext, TieRule, WatertightRay, WithAxisOrder, dispatch_order,
};

/// The side of a packet's block of pixels.
pub const PACKET_SIDE: usize = 4;

/// Rays per packet.
pub const PACKET: usize = PACKET_SIDE * PACKET_SIDE;

/// Lanes of one `f64` pass of the triangle test.
pub(super) const CHUNK: usize = 8;

/// One bit per ray of a packet.
pub(super) type Mask = u32;

/// The rays of a packet prepared for the box test (per ray, as [`super::traverse`]
/// prepares one) and for the watertight triangle test.
#[derive(Clone, Debug)]
pub struct RayPacket {
    rays: [Option<WatertightRay>; PACKET],
    /// Lanes holding a ray.
    valid: Mask,
    /// The axis order all rays share, `None` when they do not (or there is no ray).
    order: Option<u8>,
    /// Origins (`origin[axis][ray]`), for the triangle test.
    pub(super) origin: [[f64; PACKET]; 3],
    /// The shear of each ray's frame (`shear[k][ray]`, k = x, y, z of its order).
    pub(super) shear: [[f64; PACKET]; 3],
    /// Origins shifted for the lower planes of boxes (`o + δ`).
    pub(super) lower: [[f32; PACKET]; 3],
    /// Origins shifted for the upper planes of boxes (`o - δ`).
    pub(super) upper: [[f32; PACKET]; 3],
    /// `1 / direction`, clamped.
    pub(super) inv: [[f32; PACKET]; 3],
}

impl RayPacket {
    /// Prepares up to [`PACKET`] rays `(origin, direction)` for boxes whose coordinates
    /// are at most `scale` (the [`Bvh::scale`]). A ray that is not a ray (zero or not
    /// finite direction) gets no lane; rays beyond [`PACKET`] are ignored.
    #[must_use]
    pub fn new(rays: &[(DVec3, DVec3)], scale: f64) -> Self {
        let mut p = RayPacket {
            rays: [None; PACKET],
            valid: 0,
            order: None,
            origin: [[0.0; PACKET]; 3],
            shear: [[0.0; PACKET]; 3],
            lower: [[0.0; PACKET]; 3],
            upper: [[0.0; PACKET]; 3],
            inv: [[0.0; PACKET]; 3],
        };
        let mut orders = 0u8;
        for (r, &(origin, direction)) in rays.iter().take(PACKET).enumerate() {
            let Some(ray) = WatertightRay::new(origin, direction) else {
                continue;
            };
            p.rays[r] = Some(ray);
            p.valid |= 1 << r;
            orders |= 1 << ray.order_index();
            let (lower, upper) = shifted_origins(origin, scale);
            let inv = inverse_direction(direction);
            let shear = ray.shear();
            for k in 0..3 {
                p.origin[k][r] = origin[k];
                p.shear[k][r] = shear[k];
                p.lower[k][r] = lower[k];
                p.upper[k][r] = upper[k];
                p.inv[k][r] = inv[k];
            }
        }
        if orders.count_ones() == 1 {
            p.order = Some(orders.trailing_zeros() as u8);
        }
        p
    }

    /// The prepared ray of lane `r`, if there is one.
    #[must_use]
    pub fn ray(&self, r: usize) -> Option<&WatertightRay> {
        self.rays.get(r).and_then(Option::as_ref)
    }

    /// Whether all rays share one axis order (the packet is traced as a packet).
    #[must_use]
    pub fn is_coherent(&self) -> bool {
        self.order.is_some()
    }
}

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
                if let Some(&ray) = packet.ray(r) {
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
                    if matches!(kernel, Kernel::Auto | Kernel::Avx512)
                        && let Some(lanes) = Avx512::new()
                    {
                        // SAFETY: `Avx512::new` checked the features this function
                        // enables; its body is safe code.
                        return unsafe {
                            bvh.packet_avx512::<O>(lanes, packet, ctx, t_max, stack, counters)
                        };
                    }
                    if kernel != Kernel::Portable && std::arch::is_x86_feature_detected!("avx2") {
                        // SAFETY: the CPU has AVX2 (checked just above), the only
                        // requirement of this function; its body is safe code.
                        return unsafe {
                            bvh.packet_avx2::<O>(packet, ctx, t_max, stack, counters)
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
    #[target_feature(enable = "avx512f,avx2")]
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
        packet: &RayPacket,
        ctx: &PacketContext<'_>,
        t_max: f64,
        stack: &mut PacketStack,
        counters: &mut TraceCounters,
    ) -> [ClosestHit; PACKET] {
        self.packet::<O, Portable>(Portable, packet, ctx, t_max, stack, counters)
    }

    #[inline(always)]
    fn packet<O: AxisOrder, L: Lanes>(
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
            // The children entered by some ray, nearest first (insertion sort).
            let mut entered = [Entry::default(); WIDTH];
            let mut m = 0;
            for k in 0..WIDTH {
                if n.child[k] == super::EMPTY_CHILD && n.count[k] == 0 {
                    continue;
                }
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
                    let mask = e.mask & not_before(&hits.t_hi, e.near);
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
    fn packet_leaf<O: AxisOrder, L: Lanes>(
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

/// The rays whose far limit is not before `t`.
#[inline(always)]
fn not_before(t_hi: &[f32; PACKET], t: f32) -> Mask {
    let mut mask = 0;
    for (r, &hi) in t_hi.iter().enumerate() {
        mask |= Mask::from(hi >= t) << r;
    }
    mask
}
