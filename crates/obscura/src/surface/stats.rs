//! Typed statistics: one struct per algorithm, with a named, documented field per
//! figure.
//!
//! Each algorithm reports what it did in its own struct ([`ZBufferStats`],
//! [`ScanlineStats`], [`DepthSortStats`], ...). [`AlgorithmStats`] holds one of them,
//! and [`Stats`] adds the time [`crate::surface::render`] measured around the
//! algorithm. Code reads fields (`stats.pixels_tested`); a removed figure is a compile
//! error, not a `None` a test may let through.
//!
//! Listing: every struct has `entries()`, its figures as `(key, value)` pairs in a
//! fixed order, the key being the field's name (the macro below writes both from the
//! one declaration, so they cannot drift apart). Counts become `f64`, flags 1 or 0, and
//! an absent optional group (the reference z-buffer has no phases, a paint order no
//! painting counts) lists nothing. The structs serialize as a JSON object of those
//! entries: these are the keys the CLI prints (`--stats`, `--stats-json`, `compare`).

use serde::ser::{Serialize, SerializeMap, Serializer};

use crate::surface::Algorithm;

/// A field of a stats struct: how it lists itself under its key.
pub(crate) trait StatField {
    /// Appends this field's entries (`key` for a plain value; the nested struct's own
    /// keys for a group; nothing for an absent option).
    fn push_to(&self, key: &'static str, out: &mut Vec<(&'static str, f64)>);
}

macro_rules! plain_stat {
    ($($t:ty),*) => {$(
        impl StatField for $t {
            #[allow(clippy::cast_precision_loss, clippy::cast_lossless)]
            fn push_to(&self, key: &'static str, out: &mut Vec<(&'static str, f64)>) {
                out.push((key, *self as f64));
            }
        }
    )*};
}
plain_stat!(u64, u32, usize, f64);

impl StatField for bool {
    fn push_to(&self, key: &'static str, out: &mut Vec<(&'static str, f64)>) {
        out.push((key, f64::from(u8::from(*self))));
    }
}

impl<T: StatField> StatField for Option<T> {
    fn push_to(&self, key: &'static str, out: &mut Vec<(&'static str, f64)>) {
        if let Some(v) = self {
            v.push_to(key, out);
        }
    }
}

fn serialize_entries<S: Serializer>(
    entries: &[(&'static str, f64)],
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    let mut m = s.serialize_map(Some(entries.len()))?;
    for (k, v) in entries {
        m.serialize_entry(k, v)?;
    }
    m.end()
}

/// Declares a stats struct whose `entries()` lists its fields under their own names,
/// in declaration order.
macro_rules! stats_struct {
    ($(#[$meta:meta])* pub struct $name:ident {
        $($(#[$fmeta:meta])* pub $field:ident : $ty:ty,)*
    }) => {
        $(#[$meta])*
        #[derive(Clone, Debug, Default, PartialEq)]
        #[non_exhaustive]
        pub struct $name {
            $($(#[$fmeta])* pub $field: $ty,)*
        }

        impl $name {
            /// The figures as `(key, value)` pairs, keys being the field names, in the
            /// order of the fields (the order the CLI prints them).
            #[must_use]
            pub fn entries(&self) -> Vec<(&'static str, f64)> {
                let mut out = Vec::new();
                $(StatField::push_to(&self.$field, stringify!($field), &mut out);)*
                out
            }
        }

        impl StatField for $name {
            fn push_to(&self, _key: &'static str, out: &mut Vec<(&'static str, f64)>) {
                $(StatField::push_to(&self.$field, stringify!($field), out);)*
            }
        }

        impl Serialize for $name {
            fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
                serialize_entries(&self.entries(), s)
            }
        }
    };
}

stats_struct! {
    /// What the z-buffer did ([`crate::surface::zbuffer`]).
    pub struct ZBufferStats {
        /// Polygons of the view.
        pub polygons: u64,
        /// Polygons covering at least one pixel sample.
        pub polygons_drawn: u64,
        /// Pixels whose depth was compared.
        pub pixels_tested: u64,
        /// Pixels written (overwrites counted).
        pub pixels_written: u64,
        /// The fast path's own figures; `None` for the reference z-buffer.
        pub fast: Option<ZBufferFastStats>,
    }
}

stats_struct! {
    /// The fast z-buffer's own figures (milliseconds summed over the bands, so thread
    /// time when several threads draw; rounded to 0.01 ms).
    pub struct ZBufferFastStats {
        /// Polygons drawn tile by tile (wider or taller than the small ones).
        pub big_polygons: u64,
        /// Every polygon set up and the small ones drawn.
        pub setup_and_small_ms: f64,
        /// The big polygons sorted and binned.
        pub binning_ms: f64,
        /// The tiles drawn and the frame resolved.
        pub tiles_ms: f64,
    }
}

stats_struct! {
    /// What the scanline algorithm did ([`crate::surface::scanline`]; the module doc
    /// explains each figure). Milliseconds are rounded to 0.01 ms.
    pub struct ScanlineStats {
        /// Polygons of the view.
        pub polygons: u64,
        /// Edges placed in the table (of the faces set up, meeting a sample line).
        pub edges: u64,
        /// Most edges active on one row.
        pub max_active_edges: u64,
        /// Most faces active on one row.
        pub max_active_faces: u64,
        /// Spans between consecutive crossings.
        pub spans: u64,
        /// Spans with one face or none (nothing to compare).
        pub spans_without_comparison: u64,
        /// Spans decided by comparing depths at their ends.
        pub spans_decided_at_ends: u64,
        /// Spans whose nearest face was kept from the span before.
        pub spans_by_kept_nearest: u64,
        /// Faces found hidden when they entered a span.
        pub faces_hidden_on_entering: u64,
        /// Spans decided by a proven order (row-to-row coherence).
        pub spans_by_coherence: u64,
        /// Spans decided pixel by pixel.
        pub spans_per_pixel: u64,
        /// Depth comparisons.
        pub depth_comparisons: u64,
        /// Comparisons skipped by coherence.
        pub comparisons_skipped_by_coherence: u64,
        /// Checks that an order holds over a whole overlap.
        pub order_checks: u64,
        /// Checks that proved the order.
        pub orders_proven: u64,
        /// Pixels the incremental `x` of a crossing was off.
        pub crossing_corrections: u64,
        /// Spans that fell back to the per-pixel decision.
        pub span_fallbacks: u64,
        /// Bucketing the polygons.
        pub table_ms: f64,
        /// Setting up new faces, placing their edges.
        pub enter_ms: f64,
        /// Settling crossings, making spans.
        pub sweep_ms: f64,
        /// Sorting crossings.
        pub sort_ms: f64,
        /// Spans to pixels.
        pub walk_ms: f64,
    }
}

stats_struct! {
    /// Depth sort's painting counts (absent from a [`crate::surface::depth_sort::PaintOrder`]).
    pub struct PaintStats {
        /// Polygons (or pieces) painted.
        pub polygons_painted: u64,
        /// Pixels written.
        pub pixels_written: u64,
    }
}

stats_struct! {
    /// What depth sort with the five Newell tests did ([`crate::surface::depth_sort`];
    /// the module doc explains each figure).
    pub struct DepthSortStats {
        /// Polygons of the view.
        pub polygons: u64,
        /// Polygons covering a sample (those sorted).
        pub polygons_sorted: u64,
        /// Pairs compared.
        pub comparisons: u64,
        /// Decided by depth alone (candidates met before a tile's scan stops).
        pub decided_depth: u64,
        /// Decided as pieces of one face.
        pub decided_same_face: u64,
        /// Decided by test 1 (x extents).
        pub decided_test1_x: u64,
        /// Decided by test 2 (y extents).
        pub decided_test2_y: u64,
        /// Decided by test 3 (wholly behind the other's plane).
        pub decided_test3: u64,
        /// Decided by test 4 (the other wholly in front of this plane).
        pub decided_test4: u64,
        /// Decided by test 5 (projections disjoint).
        pub decided_test5: u64,
        /// Decided as coplanar.
        pub decided_coplanar: u64,
        /// Decided by depth over the overlap.
        pub decided_overlap_depth: u64,
        /// Swaps of the order.
        pub swaps: u64,
        /// Swaps justified by test 3.
        pub swap_test3: u64,
        /// Swaps justified by test 4.
        pub swap_test4: u64,
        /// Swaps justified by depth over the overlap.
        pub swap_overlap_depth: u64,
        /// Cycles met.
        pub cycles: u64,
        /// Polygons split.
        pub splits: u64,
        /// Pairs left unresolved.
        pub unresolved: u64,
        /// Polygons painted unsorted, depth-tested (over the comparison budget).
        pub unsorted: u64,
        /// Painting counts (`None` in a paint order).
        pub paint: Option<PaintStats>,
    }
}

stats_struct! {
    /// What depth sort by covering matrix did ([`crate::surface::depth_sort`]).
    pub struct DepthSortMatrixStats {
        /// Polygons of the view.
        pub polygons: u64,
        /// Polygons covering a sample (those sorted).
        pub polygons_sorted: u64,
        /// Pairs compared.
        pub comparisons: u64,
        /// Decided as pieces of one face.
        pub decided_same_face: u64,
        /// Decided by test 1 (x extents).
        pub decided_test1_x: u64,
        /// Decided by test 2 (y extents).
        pub decided_test2_y: u64,
        /// Decided by the planes, both orders tried.
        pub decided_planes_both_orders: u64,
        /// Decided by test 5 (projections disjoint).
        pub decided_test5: u64,
        /// Decided as coplanar.
        pub decided_coplanar: u64,
        /// Decided by depth over the overlap.
        pub decided_overlap_depth: u64,
        /// Edges of the covering matrix.
        pub relations: u64,
        /// Cycles broken.
        pub cycles_broken: u64,
        /// Polygons split.
        pub splits: u64,
        /// Pairs left unresolved.
        pub unresolved: u64,
        /// Polygons painted unsorted, depth-tested (over the comparison budget).
        pub unsorted: u64,
        /// Painting counts (`None` in a paint order).
        pub paint: Option<PaintStats>,
    }
}

stats_struct! {
    /// What the BSP tree and its traversal did ([`crate::surface::bsp`]).
    pub struct BspStats {
        /// Nodes of the tree.
        pub bsp_nodes: u64,
        /// Fragments stored in the tree.
        pub bsp_fragments: u64,
        /// Polygons split during the build.
        pub bsp_splits: u64,
        /// Depth of the tree.
        pub bsp_depth: u64,
        /// The build's milliseconds.
        pub build_ms: f64,
        /// Whether the traversal ran front to back.
        pub front_to_back: bool,
        /// The traversal's milliseconds.
        pub view_ms: f64,
        /// Fragments visited.
        pub fragments_visited: u64,
        /// Fragments culled (back faces).
        pub fragments_culled: u64,
        /// Fragments outside the view.
        pub fragments_outside: u64,
        /// Subtrees skipped as hidden.
        pub subtrees_hidden: u64,
        /// Subtrees skipped as outside the view.
        pub subtrees_outside: u64,
        /// Fragments painted.
        pub fragments_painted: u64,
        /// Pixels written.
        pub pixels_written: u64,
        /// Whether the traversal stopped early (every pixel decided).
        pub early_exit: bool,
        /// Fragments visited over fragments stored (1 for an empty tree).
        pub visited_fraction: f64,
    }
}

stats_struct! {
    /// What Warnock's area subdivision did ([`crate::surface::warnock`]).
    pub struct WarnockStats {
        /// Polygons of the view.
        pub polygons: u64,
        /// Windows examined.
        pub windows: u64,
        /// Windows decided by rule 1 (no face).
        pub rule1: u64,
        /// Windows decided by rule 2.
        pub rule2: u64,
        /// Windows decided by rule 3.
        pub rule3: u64,
        /// Windows decided by rule 4.
        pub rule4: u64,
        /// Windows subdivided (rule 5).
        pub rule5: u64,
        /// 1x1 windows decided by comparing the faces at the pixel centre.
        pub pixel_decisions: u64,
        /// Face-window classifications.
        pub classifications: u64,
        /// Depth comparisons.
        pub depth_comparisons: u64,
        /// Deepest subdivision level.
        pub max_depth: u32,
    }
}

stats_struct! {
    /// The figures every ray caster reports ([`crate::surface::raycast`]).
    pub struct RayStats {
        /// Triangles of the scene.
        pub triangles: u64,
        /// Triangles facing the camera (or all, without back-face culling).
        pub front_triangles: u64,
        /// Rays cast.
        pub rays: u64,
        /// Rays that hit.
        pub hits: u64,
        /// Ray-triangle tests.
        pub triangle_tests: u64,
        /// Tracing milliseconds.
        pub trace_ms: f64,
        /// Millions of rays per second of tracing.
        pub mrays_per_s: f64,
    }
}

stats_struct! {
    /// What brute-force ray casting did.
    pub struct RaycastStats {
        /// The common figures.
        pub ray: RayStats,
        /// Triangle tests per ray.
        pub triangle_tests_per_ray: f64,
        /// Milliseconds gathering the scene's triangles (`None` when the caller gave
        /// them).
        pub triangles_ms: Option<f64>,
    }
}

stats_struct! {
    /// What ray casting with per-object bounding volumes did.
    pub struct RaycastBoundsStats {
        /// The common figures.
        pub ray: RayStats,
        /// Milliseconds building the bounding volumes.
        pub bounds_build_ms: f64,
        /// Objects (bounding volumes).
        pub objects: u64,
        /// Ray-volume tests.
        pub bound_tests: u64,
        /// Ray-volume tests that hit.
        pub bound_hits: u64,
        /// Triangle tests brute force would make (rays x front triangles).
        pub triangle_tests_brute_force: u64,
        /// Triangle tests saved against brute force.
        pub triangle_tests_saved: u64,
        /// Fraction of brute force's tests saved.
        pub saved_fraction: f64,
        /// Milliseconds gathering the scene's triangles (`None` when the caller gave
        /// them).
        pub triangles_ms: Option<f64>,
    }
}

stats_struct! {
    /// What ray casting through a bounding-volume hierarchy did.
    pub struct RaycastBvhStats {
        /// The common figures.
        pub ray: RayStats,
        /// Packet-node visits per ray.
        pub packet_node_visits_per_ray: f64,
        /// Milliseconds building the hierarchy.
        pub build_ms: f64,
        /// Nodes of the binary hierarchy.
        pub binary_nodes: u64,
        /// Depth of the binary hierarchy.
        pub binary_depth: u64,
        /// Nodes of the wide hierarchy traced.
        pub nodes: u64,
        /// Leaves.
        pub leaves: u64,
        /// Depth of the wide hierarchy.
        pub depth: u64,
        /// Surface-area-heuristic cost of the hierarchy.
        pub sah_cost: f64,
        /// Node visits per ray.
        pub node_visits_per_ray: f64,
        /// Triangle tests per ray.
        pub triangle_tests_per_ray: f64,
        /// Milliseconds gathering the scene's triangles (`None` when the caller gave
        /// them).
        pub triangles_ms: Option<f64>,
    }
}

stats_struct! {
    /// What ray casting through a uniform grid did.
    pub struct RaycastGridStats {
        /// The common figures.
        pub ray: RayStats,
        /// Milliseconds building the grid.
        pub build_ms: f64,
        /// Cells of the grid.
        pub cells: u64,
        /// Cells along x.
        pub resolution_x: u32,
        /// Cells along y.
        pub resolution_y: u32,
        /// Cells along z.
        pub resolution_z: u32,
        /// Triangle references in the cells.
        pub refs: u64,
        /// References per cell.
        pub refs_per_cell: f64,
        /// Empty cells.
        pub empty_cells: u64,
        /// References in the fullest cell.
        pub largest_cell: u64,
        /// Cells crossed per ray.
        pub cells_per_ray: f64,
        /// Triangle tests per ray.
        pub triangle_tests_per_ray: f64,
        /// Tests skipped by the mailbox (a triangle met again in a later cell).
        pub mailbox_hits: u64,
        /// Accepted hits found outside their cell (0 when the traversal is right).
        pub hits_outside_cell: u64,
        /// Rays that left the grid's far bound.
        pub far_rays: u64,
        /// Milliseconds gathering the scene's triangles (`None` when the caller gave
        /// them).
        pub triangles_ms: Option<f64>,
    }
}

stats_struct! {
    /// What the octree's build and front-to-back tracing did ([`crate::surface::octree`]).
    pub struct OctreeStats {
        /// Depth of the tree.
        pub depth: u32,
        /// Voxels on a side (`2^depth`).
        pub voxels_per_side: u32,
        /// Triangles voxelized.
        pub triangles: u64,
        /// Nodes after merging.
        pub nodes: u64,
        /// Nodes before merging.
        pub nodes_before_merge: u64,
        /// Empty leaves.
        pub leaves_empty: u64,
        /// Full leaves.
        pub leaves_full: u64,
        /// Partial (surface) leaves.
        pub leaves_partial: u64,
        /// Bytes of one node.
        pub bytes_per_node: u64,
        /// Bytes of the tree.
        pub memory_bytes: u64,
        /// Triangle-box separating-axis tests.
        pub sat_tests: u64,
        /// Connected components of empty space classified.
        pub components: u64,
        /// Inside/outside queries.
        pub inside_queries: u64,
        /// Milliseconds gathering triangles.
        pub triangles_ms: f64,
        /// Milliseconds subdividing.
        pub subdivide_ms: f64,
        /// Milliseconds classifying.
        pub classify_ms: f64,
        /// Milliseconds merging.
        pub merge_ms: f64,
        /// Milliseconds of the whole build.
        pub build_ms: f64,
        /// Milliseconds tracing.
        pub trace_ms: f64,
        /// Rays cast (one per pixel).
        pub rays: u64,
        /// Nodes visited.
        pub nodes_visited: u64,
        /// Nodes visited per ray.
        pub nodes_visited_per_ray: f64,
        /// Pixels covered.
        pub pixels_covered: u64,
        /// Scene triangles near the near plane's window (see the module doc).
        pub near_faces: u64,
    }
}

/// The stats of one algorithm: one variant per [`Algorithm`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum AlgorithmStats {
    /// [`Algorithm::ZBuffer`].
    ZBuffer(ZBufferStats),
    /// [`Algorithm::Scanline`].
    Scanline(ScanlineStats),
    /// [`Algorithm::DepthSort`].
    DepthSort(DepthSortStats),
    /// [`Algorithm::DepthSortMatrix`].
    DepthSortMatrix(DepthSortMatrixStats),
    /// [`Algorithm::Bsp`].
    Bsp(BspStats),
    /// [`Algorithm::Warnock`].
    Warnock(WarnockStats),
    /// [`Algorithm::Raycast`].
    Raycast(RaycastStats),
    /// [`Algorithm::RaycastBounds`].
    RaycastBounds(RaycastBoundsStats),
    /// [`Algorithm::RaycastBvh`].
    RaycastBvh(RaycastBvhStats),
    /// [`Algorithm::RaycastGrid`].
    RaycastGrid(RaycastGridStats),
    /// [`Algorithm::Octree`].
    Octree(OctreeStats),
}

impl AlgorithmStats {
    /// The algorithm these stats are of.
    #[must_use]
    pub fn algorithm(&self) -> Algorithm {
        match self {
            AlgorithmStats::ZBuffer(_) => Algorithm::ZBuffer,
            AlgorithmStats::Scanline(_) => Algorithm::Scanline,
            AlgorithmStats::DepthSort(_) => Algorithm::DepthSort,
            AlgorithmStats::DepthSortMatrix(_) => Algorithm::DepthSortMatrix,
            AlgorithmStats::Bsp(_) => Algorithm::Bsp,
            AlgorithmStats::Warnock(_) => Algorithm::Warnock,
            AlgorithmStats::Raycast(_) => Algorithm::Raycast,
            AlgorithmStats::RaycastBounds(_) => Algorithm::RaycastBounds,
            AlgorithmStats::RaycastBvh(_) => Algorithm::RaycastBvh,
            AlgorithmStats::RaycastGrid(_) => Algorithm::RaycastGrid,
            AlgorithmStats::Octree(_) => Algorithm::Octree,
        }
    }

    /// The figures as `(key, value)` pairs (see the module doc).
    #[must_use]
    pub fn entries(&self) -> Vec<(&'static str, f64)> {
        match self {
            AlgorithmStats::ZBuffer(s) => s.entries(),
            AlgorithmStats::Scanline(s) => s.entries(),
            AlgorithmStats::DepthSort(s) => s.entries(),
            AlgorithmStats::DepthSortMatrix(s) => s.entries(),
            AlgorithmStats::Bsp(s) => s.entries(),
            AlgorithmStats::Warnock(s) => s.entries(),
            AlgorithmStats::Raycast(s) => s.entries(),
            AlgorithmStats::RaycastBounds(s) => s.entries(),
            AlgorithmStats::RaycastBvh(s) => s.entries(),
            AlgorithmStats::RaycastGrid(s) => s.entries(),
            AlgorithmStats::Octree(s) => s.entries(),
        }
    }

    /// The ray casters' common figures; `None` for the other algorithms.
    #[must_use]
    pub fn ray(&self) -> Option<&RayStats> {
        match self {
            AlgorithmStats::Raycast(s) => Some(&s.ray),
            AlgorithmStats::RaycastBounds(s) => Some(&s.ray),
            AlgorithmStats::RaycastBvh(s) => Some(&s.ray),
            AlgorithmStats::RaycastGrid(s) => Some(&s.ray),
            _ => None,
        }
    }
}

impl Serialize for AlgorithmStats {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        serialize_entries(&self.entries(), s)
    }
}

/// Declares `Stats::NAME(&self) -> Option<&Type>` for each variant.
macro_rules! stats_accessors {
    ($($fn_name:ident: $variant:ident($ty:ident),)*) => {
        impl Stats {
            $(
                #[doc = concat!("The [`", stringify!($ty), "`] if these are its algorithm's stats.")]
                #[must_use]
                pub fn $fn_name(&self) -> Option<&$ty> {
                    match &self.algorithm {
                        AlgorithmStats::$variant(s) => Some(s),
                        _ => None,
                    }
                }
            )*
        }
    };
}

/// What [`crate::surface::render`] returns: the algorithm's own stats and the
/// milliseconds it took in all. Listed (and serialized) as the algorithm's entries
/// followed by `time_ms`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Stats {
    /// The algorithm's figures.
    pub algorithm: AlgorithmStats,
    /// Milliseconds of the whole render call (budget check and algorithm).
    pub time_ms: f64,
}

impl Stats {
    /// Stats of an algorithm with its time.
    #[must_use]
    pub fn new(algorithm: AlgorithmStats, time_ms: f64) -> Self {
        Stats { algorithm, time_ms }
    }

    /// The figures as `(key, value)` pairs, `time_ms` last.
    #[must_use]
    pub fn entries(&self) -> Vec<(&'static str, f64)> {
        let mut e = self.algorithm.entries();
        e.push(("time_ms", self.time_ms));
        e
    }
}

stats_accessors! {
    zbuffer: ZBuffer(ZBufferStats),
    scanline: Scanline(ScanlineStats),
    depth_sort: DepthSort(DepthSortStats),
    depth_sort_matrix: DepthSortMatrix(DepthSortMatrixStats),
    bsp: Bsp(BspStats),
    warnock: Warnock(WarnockStats),
    raycast: Raycast(RaycastStats),
    raycast_bounds: RaycastBounds(RaycastBoundsStats),
    raycast_bvh: RaycastBvh(RaycastBvhStats),
    raycast_grid: RaycastGrid(RaycastGridStats),
    octree: Octree(OctreeStats),
}

impl Serialize for Stats {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        serialize_entries(&self.entries(), s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_follow_the_fields_and_skip_absent_groups() {
        let mut z = ZBufferStats {
            polygons: 3,
            pixels_tested: 7,
            ..ZBufferStats::default()
        };
        let keys = |s: &ZBufferStats| s.entries().iter().map(|e| e.0).collect::<Vec<_>>();
        assert_eq!(
            keys(&z),
            [
                "polygons",
                "polygons_drawn",
                "pixels_tested",
                "pixels_written"
            ]
        );
        z.fast = Some(ZBufferFastStats {
            big_polygons: 2,
            tiles_ms: 0.5,
            ..ZBufferFastStats::default()
        });
        let s = Stats::new(AlgorithmStats::ZBuffer(z), 1.25);
        let e = s.entries();
        let keys: Vec<_> = e.iter().map(|e| e.0).collect();
        assert_eq!(
            keys,
            [
                "polygons",
                "polygons_drawn",
                "pixels_tested",
                "pixels_written",
                "big_polygons",
                "setup_and_small_ms",
                "binning_ms",
                "tiles_ms",
                "time_ms"
            ]
        );
        assert_eq!((e[2].1, e[4].1, e[7].1, e[8].1), (7.0, 2.0, 0.5, 1.25));
        assert_eq!(s.zbuffer().unwrap().pixels_tested, 7);
        assert!(s.bsp().is_none());
        assert_eq!(s.algorithm.algorithm(), Algorithm::ZBuffer);
    }

    #[test]
    fn flags_list_as_one_or_zero() {
        let b = BspStats {
            front_to_back: true,
            ..BspStats::default()
        };
        let e = b.entries();
        assert_eq!(e[5], ("front_to_back", 1.0));
        assert_eq!(e[14], ("early_exit", 0.0));
    }
}
