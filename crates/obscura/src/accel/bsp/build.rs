//! Building the tree: the scene's polygons in the tree's frame, then node by node (an
//! explicit stack) a splitter chosen from sampled candidates (and an axis-aligned
//! plane for large sets), the set classified against it and the spanning polygons
//! split ([`crate::clip::split::split_polygon`]), within the memory budget.

use std::time::Instant;

use glam::DVec3;

use super::{BspBuildStats, BspNode, BspOptions, BspTree, BspVertex, Fragment, MADE_BY_SPLIT};
use crate::clip::split::{Split, split_polygon};
use crate::geom::{Aabb, Plane, PlaneSide};
use crate::rng::SplitMix64;
use crate::scene::Scene;
use crate::{Error, Result};

/// The centroid of the points and the largest distance from it.
fn bounding_sphere(points: &[DVec3]) -> [f64; 4] {
    let c = points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64;
    let r = points.iter().fold(0.0f64, |m, &p| m.max(p.distance(c)));
    [c.x, c.y, c.z, r]
}

/// Sets smaller than this get no axis-aligned candidate plane.
const AXIS_PLANE_MIN_SET: usize = 64;

/// A node's splitting plane: a polygon's (index in the node's set) or an
/// axis-aligned one.
enum Splitter {
    Polygon(usize),
    Axis(Plane),
}

impl BspTree {
    /// Builds the tree of every polygon of every object of the scene. An empty scene
    /// gives an empty tree. Fails only on invalid options.
    pub fn build(scene: &Scene, options: &BspOptions) -> Result<BspTree> {
        Self::build_until(scene, options, &crate::work::Deadline::default())
    }

    /// [`BspTree::build`] that stops with the deadline's error (see [`crate::work`])
    /// when it passes while the tree is built.
    pub fn build_until(
        scene: &Scene,
        options: &BspOptions,
        deadline: &crate::work::Deadline,
    ) -> Result<BspTree> {
        options.validate()?;
        let start = Instant::now();
        let mut tree = BspTree {
            nodes: Vec::new(),
            node_fragments: Vec::new(),
            fragments: Vec::new(),
            fragment_vertices: Vec::new(),
            vertices: Vec::new(),
            cuts: Vec::new(),
            local: Vec::new(),
            origin: DVec3::ZERO,
            vertex_base: Vec::with_capacity(scene.objects().len()),
            object_vertex_counts: Vec::with_capacity(scene.objects().len()),
            face_count: scene.face_count(),
            eps: 0.0,
            relative_tolerance: options.tolerance,
            rounding: 0.0,
            spheres: Vec::new(),
            slack: 0.0,
            subtree_bounds: Vec::new(),
            subtree_counts: Vec::new(),
            stats: BspBuildStats::default(),
        };
        let bounds = scene.bounds();
        if !bounds.is_empty() {
            tree.origin = bounds.center();
        }
        let mut scale = 0.0f64;
        for (k, o) in scene.objects().iter().enumerate() {
            tree.vertex_base.push(tree.vertices.len() as u32);
            tree.object_vertex_counts
                .push(o.mesh.positions().len() as u32);
            for (i, &p) in o.mesh.positions().iter().enumerate() {
                let world = o.transform.transform_point3(p);
                let local = world - tree.origin;
                scale = scale.max(local.abs().max_element());
                tree.vertices.push(BspVertex {
                    world,
                    object: k as u32,
                    local: i as u32,
                });
                tree.local.push(local);
            }
        }
        // World coordinates carry rounding of their own magnitude: points meant to be
        // on one plane are that far off it, whatever the tree's frame.
        let rounding = 16.0 * f64::EPSILON * tree.origin.abs().max_element();
        tree.eps = (options.tolerance * scale)
            .max(rounding)
            .max(f64::MIN_POSITIVE);
        tree.rounding = rounding.max(f64::MIN_POSITIVE);
        tree.slack = 1e-12 * scale.max(f64::MIN_POSITIVE);
        let mut points = Vec::new();
        for (k, o) in scene.objects().iter().enumerate() {
            let base = tree.vertex_base[k];
            for p in 0..o.mesh.polygon_count() {
                tree.stats.input_polygons += 1;
                let idx = o.mesh.polygon(p);
                points.clear();
                points.extend(idx.iter().map(|&i| tree.local[(base + i) as usize]));
                let Some(plane) = Plane::newell(&points) else {
                    tree.stats.degenerate += 1;
                    continue;
                };
                let thickness = points
                    .iter()
                    .fold(0.0f64, |m, &q| m.max(plane.evaluate(q).abs()));
                let start = tree.fragment_vertices.len() as u32;
                tree.fragment_vertices.extend(idx.iter().map(|&i| base + i));
                tree.spheres.push(bounding_sphere(&points));
                tree.fragments.push(Fragment {
                    face: o.first_face + o.mesh.polygon_face(p),
                    object: k as u32,
                    polygon: p as u32,
                    plane,
                    thickness,
                    start,
                    len: idx.len() as u32,
                    root: tree.fragments.len() as u32,
                    cut_start: 0,
                    cut_len: 0,
                });
            }
        }
        let all: Vec<u32> = (0..tree.fragments.len() as u32).collect();
        tree.build_nodes(all, options, deadline)?;
        tree.compute_subtree_bounds();
        tree.stats.nodes = tree.nodes.len() as u64;
        tree.stats.fragments = tree.node_fragments.len() as u64;
        tree.stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(tree)
    }

    fn build_nodes(
        &mut self,
        all: Vec<u32>,
        options: &BspOptions,
        deadline: &crate::work::Deadline,
    ) -> Result<()> {
        if all.is_empty() {
            return Ok(());
        }
        let mut rng = SplitMix64(options.seed);
        let placeholder = BspNode {
            plane: Plane {
                normal: DVec3::Z,
                d: 0.0,
            },
            front: None,
            back: None,
            eps: 0.0,
            first: 0,
            count: 0,
            depth: 0,
        };
        self.nodes.push(placeholder);
        let budget = crate::budget::MemoryBudget::from_option(options.memory_limit);
        // Bytes of the sets waiting on the stack.
        let mut waiting = all.capacity() as u64 * 4;
        let mut stack: Vec<(u32, Vec<u32>, u32)> = vec![(0, all, 1)];
        let mut points = Vec::new();
        while let Some((n, set, depth)) = stack.pop() {
            deadline.check("BSP construction")?;
            waiting -= set.capacity() as u64 * 4;
            let (plane, eps, splitter) = match self.choose_splitter(&set, options, &mut rng) {
                Splitter::Polygon(i) => {
                    let f = &self.fragments[set[i] as usize];
                    (f.plane, self.own_eps(set[i]) + f.thickness, Some(set[i]))
                }
                Splitter::Axis(plane) => (plane, self.eps, None),
            };
            // A polygon splitter stays in its node whatever its own vertices say (a
            // slightly non-planar quad must not be cut by its own plane).
            let mut on: Vec<u32> = splitter.into_iter().collect();
            let (mut front, mut back) = (Vec::new(), Vec::new());
            for &f in &set {
                if Some(f) == splitter {
                    continue;
                }
                match self.classify(f, &plane, eps) {
                    PlaneSide::Front => front.push(f),
                    PlaneSide::Back => back.push(f),
                    PlaneSide::On => on.push(f),
                    PlaneSide::Spanning => {
                        let (a, b) = self.split(f, n, &plane, eps, &mut points);
                        front.extend(a);
                        back.extend(b);
                    }
                }
            }
            on.sort_by_key(|&f| (std::cmp::Reverse(self.fragments[f as usize].face), f));
            let first = self.node_fragments.len() as u32;
            self.node_fragments.extend_from_slice(&on);
            self.stats.depth = self.stats.depth.max(u64::from(depth));
            let mut node = BspNode {
                plane,
                front: None,
                back: None,
                // An upper bound of the pairs' tolerances.
                eps: eps.max(self.eps),
                first,
                count: on.len() as u32,
                depth,
            };
            for (child, is_front) in [(back, false), (front, true)] {
                if child.is_empty() {
                    continue;
                }
                let idx = self.nodes.len() as u32;
                self.nodes.push(placeholder);
                if is_front {
                    node.front = Some(idx);
                } else {
                    node.back = Some(idx);
                }
                waiting += child.capacity() as u64 * 4;
                stack.push((idx, child, depth + 1));
            }
            self.nodes[n as usize] = node;
            let bytes = self.bytes() + waiting + stack.capacity() as u64 * 32;
            if bytes > budget.limit() {
                return Err(budget.exceeded("BSP fragments", self.fragments.len() as u64, bytes));
            }
            if self.fragments.len() > options.max_fragments {
                return Err(Error::option(
                    "bsp fragments",
                    format!(
                        "the tree of {} polygons passed {} fragments ({} splits so far): \
                         its polygons cut each other too much for a BSP tree (random or \
                         interpenetrating geometry); render with another algorithm, or \
                         raise BspOptions::max_fragments",
                        self.stats.input_polygons, options.max_fragments, self.stats.splits
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The bytes the tree's vectors hold (by capacity).
    fn bytes(&self) -> u64 {
        fn b<T>(v: &Vec<T>) -> u64 {
            (v.capacity() * size_of::<T>()) as u64
        }
        b(&self.nodes)
            + b(&self.node_fragments)
            + b(&self.fragments)
            + b(&self.fragment_vertices)
            + b(&self.vertices)
            + b(&self.cuts)
            + b(&self.local)
            + b(&self.spheres)
    }

    /// Children have larger indices than their parent: one pass from the end.
    fn compute_subtree_bounds(&mut self) {
        let n = self.nodes.len();
        self.subtree_bounds = vec![Aabb::EMPTY; n];
        self.subtree_counts = vec![0; n];
        for i in (0..n).rev() {
            let node = self.nodes[i];
            let mut b = Aabb::EMPTY;
            for &f in self.node_fragments(i as u32) {
                for &v in self.fragment_indices(&self.fragments[f as usize]) {
                    b = b.with_point(self.vertices[v as usize].world);
                }
            }
            let mut count = node.count;
            for c in [node.front, node.back].into_iter().flatten() {
                b = b.union(self.subtree_bounds[c as usize]);
                count += self.subtree_counts[c as usize];
            }
            self.subtree_bounds[i] = b;
            self.subtree_counts[i] = count;
        }
    }

    /// The chosen splitter (see the module doc for the score).
    fn choose_splitter(&self, set: &[u32], options: &BspOptions, rng: &mut SplitMix64) -> Splitter {
        let n = set.len();
        if n <= 2 {
            return Splitter::Polygon(0);
        }
        let k = options.candidates.max(1);
        let candidates: Vec<usize> = if n <= k {
            (0..n).collect()
        } else {
            (0..k)
                .map(|_| (rng.next_u64() % n as u64) as usize)
                .collect()
        };
        let axis = (options.axis_planes && n >= AXIS_PLANE_MIN_SET)
            .then(|| self.median_plane(set))
            .flatten();
        if candidates.len() == 1 && axis.is_none() {
            return Splitter::Polygon(candidates[0]);
        }
        let sample = if options.score_sample == 0 || n <= options.score_sample {
            n
        } else {
            options.score_sample
        };
        // (score, whether the plane leaves one side empty without splitting, splits)
        let score = |plane: &Plane, eps: f64, skip: usize| {
            let (mut front, mut back, mut spans) = (0u64, 0u64, 0u64);
            for s in 0..sample {
                // Evenly spaced over the set: s * n / sample, in integers.
                let i = (s as u64 * n as u64 / sample as u64) as usize;
                if i == skip {
                    continue;
                }
                match self.classify(set[i], plane, eps) {
                    PlaneSide::Front => front += 1,
                    PlaneSide::Back => back += 1,
                    PlaneSide::Spanning => spans += 1,
                    PlaneSide::On => {}
                }
            }
            let cost = options.split_weight * spans as f64
                + options.balance_weight * (front as f64 - back as f64).abs();
            (cost, spans == 0 && (front == 0 || back == 0), spans)
        };
        let mut best = (f64::INFINITY, 0usize, false);
        for &c in &candidates {
            let f = &self.fragments[set[c] as usize];
            let (cost, one_sided, _) = score(&f.plane, self.own_eps(set[c]) + f.thickness, c);
            if cost < best.0 {
                best = (cost, c, one_sided);
            }
        }
        if let Some(plane) = axis {
            let (cost, _, spans) = score(&plane, self.eps, usize::MAX);
            // A one-sided polygon plane only peels one polygon off: on a convex
            // surface every candidate is one, and a chain of m nodes costs O(m^2) to
            // build. The axis plane then wins if it cuts less than a quarter of the set.
            let better = cost < best.0 || (best.2 && 4 * spans < sample as u64);
            if better && self.divides(set, &plane) {
                return Splitter::Axis(plane);
            }
        }
        Splitter::Polygon(best.1)
    }

    /// The plane perpendicular to the longest side of the box of the polygons'
    /// first vertices, through their median along it.
    fn median_plane(&self, set: &[u32]) -> Option<Plane> {
        let first = |f: u32| {
            let v = self.fragment_vertices[self.fragments[f as usize].start as usize];
            self.local[v as usize]
        };
        let (lo, hi) = set
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &f| {
                (lo.min(first(f)), hi.max(first(f)))
            });
        let extent = hi - lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        if !(extent[axis] > 0.0) {
            return None;
        }
        let mut coords: Vec<f64> = set.iter().map(|&f| first(f)[axis]).collect();
        let mid = coords.len() / 2;
        let (_, &mut median, _) = coords.select_nth_unstable_by(mid, f64::total_cmp);
        let mut normal = DVec3::ZERO;
        normal[axis] = 1.0;
        Some(Plane { normal, d: -median })
    }

    /// Whether a plane without a polygon of its own leaves fewer polygons on each side
    /// than the set has (else the recursion would not end).
    fn divides(&self, set: &[u32], plane: &Plane) -> bool {
        let (mut front, mut back) = (0usize, 0usize);
        for &f in set {
            match self.classify(f, plane, self.eps) {
                PlaneSide::Front => front += 1,
                PlaneSide::Back => back += 1,
                PlaneSide::Spanning => {
                    front += 1;
                    back += 1;
                }
                PlaneSide::On => {}
            }
        }
        front < set.len() && back < set.len()
    }

    /// Splits fragment `f` by the plane of node `node`; returns the new front and back
    /// fragments.
    fn split(
        &mut self,
        f: u32,
        node: u32,
        plane: &Plane,
        eps: f64,
        points: &mut Vec<DVec3>,
    ) -> (Option<u32>, Option<u32>) {
        let frag = self.fragments[f as usize];
        let idx: Vec<u32> = self.fragment_indices(&frag).to_vec();
        points.clear();
        points.extend(idx.iter().map(|&v| self.local[v as usize]));
        match split_polygon(points, plane, self.pair_eps(f, eps)) {
            Split::Front | Split::Coplanar { .. } => (Some(f), None),
            Split::Back => (None, Some(f)),
            Split::Spanning { front, back } => {
                self.stats.splits += 1;
                let mut made = Vec::new();
                let a = self.push_piece(&frag, &idx, points, &front, &mut made, node << 1 | 1);
                let b = self.push_piece(&frag, &idx, points, &back, &mut made, node << 1);
                (Some(a), Some(b))
            }
        }
    }

    /// Adds a piece of `parent`: points equal to a parent vertex reuse its index (so
    /// pieces keep the exact projection of the original vertices), new points become
    /// new vertices, shared by both pieces through `made`. The piece's cuts are its
    /// parent's and `cut`.
    fn push_piece(
        &mut self,
        parent: &Fragment,
        idx: &[u32],
        parent_points: &[DVec3],
        piece: &[DVec3],
        made: &mut Vec<(DVec3, u32)>,
        cut: u32,
    ) -> u32 {
        let start = self.fragment_vertices.len() as u32;
        for &q in piece {
            let old = parent_points.iter().position(|&p| p == q).map(|j| idx[j]);
            let v = match old.or_else(|| made.iter().find(|m| m.0 == q).map(|m| m.1)) {
                Some(v) => v,
                None => {
                    self.vertices.push(BspVertex {
                        world: q + self.origin,
                        object: parent.object,
                        local: MADE_BY_SPLIT,
                    });
                    self.local.push(q);
                    let v = (self.vertices.len() - 1) as u32;
                    made.push((q, v));
                    v
                }
            };
            self.fragment_vertices.push(v);
        }
        self.spheres.push(bounding_sphere(piece));
        let cut_start = self.cuts.len() as u32;
        let inherited = parent.cut_start as usize..(parent.cut_start + parent.cut_len) as usize;
        self.cuts.extend_from_within(inherited);
        self.cuts.push(cut);
        self.fragments.push(Fragment {
            start,
            len: piece.len() as u32,
            cut_start,
            cut_len: parent.cut_len + 1,
            ..*parent
        });
        (self.fragments.len() - 1) as u32
    }
}
