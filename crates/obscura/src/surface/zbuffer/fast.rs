//! The fast z-buffer's drawing loop: the polygons of a view drawn into a band of rows
//! of the frame, with the block rasterizer ([`crate::raster::block`]) compiled for the
//! processor's vector extensions.
//!
//! Per band, one pass over its polygons: each is set up once (consecutive triangles
//! eight at a time, [`block::triangles8`]); a small one is drawn at once, a big one
//! (wider or taller than [`BIG`] pixels) is kept. The big ones are sorted once,
//! nearest first, and put in that order in the bins of the 64x64 tiles they overlap.
//! Then each tile draws its big polygons while its keys and ids
//! (32 KiB) stay in the first-level cache, nearest first, skipping the blocks that hide
//! them (see [`crate::raster::block::BlockTarget::with_farthest`]), and turns its keys
//! and encoded ids into depths and face ids. The depth test takes the nearer key and, on a tie, the lower
//! face id, so drawing small polygons before big ones gives the frame that drawing
//! all in order would.
//!
//! Why the small polygons are drawn before the big ones and never culled: they are the
//! big ones' best occluders, and culling them does not pay for its second pass. Measured
//! on the Sponza atrium (1920x1080, one thread, 169k small triangles of which the final
//! frame's 16x8-block grid would hide 65k): drawing the big polygons first and skipping
//! the small ones whose [`block::nearest_key`] is below every farthest key of their
//! blocks culled 32.5k, 51k when the grid was refreshed as small ones were drawn, but the
//! big ones, no longer hidden by the small ones, tested 6.3M pixels instead of 5.5M:
//! 5 % more instructions, 12 % more time (39 % with the refresh). Keeping this order
//! and culling the small ones against the blocks that some big polygon covers whole (a
//! bound valid in any order) culled only 13.4k: 0.5 % fewer instructions but 13 % more
//! time (the second pass reads the small triangles' vertices again).

use crate::Frame;
#[cfg(target_arch = "x86_64")]
use crate::cpu::Avx512;
use crate::cpu::Kernel;
use crate::raster::block::{self, Align, BlockSetup, BlockTarget, Counts};
use crate::raster::lanes::{Lanes, Portable, lanes_below};
use crate::raster::{FillRule, PixelRect, PolygonCoverage, PolygonSetup};
use crate::view::PreparedView;

/// Side of a tile, in pixels: a tile's keys and ids take 32 KiB.
pub(super) const TILE: u32 = 64;

/// Bytes a big polygon holds while its band is drawn: its setup, face and nearest key,
/// and its entry in the sorted order (for the memory budget, see `super::check_budget`).
pub(super) const BIG_ENTRY_BYTES: u64 = {
    let t = size_of::<(BlockSetup<3>, u32, f32)>();
    let o = size_of::<(Setup, u32, f32)>();
    (if t > o { t } else { o }) as u64 + size_of::<(f32, u32)>() as u64
};

/// Polygons wider or taller than this many pixels are drawn tile by tile (the
/// `big_polygons` of the stats); the others are drawn at once.
pub const BIG: u32 = 64;

/// Marks a bin entry that indexes the big polygons other than triangles.
const OTHER: u32 = 1 << 31;

/// Rows `y0..y1` of a frame being drawn: keys and encoded ids (see
/// [`crate::raster::lanes`]), `width` pixels per row.
pub(super) struct Band<'a> {
    pub keys: &'a mut [f32],
    pub ids: &'a mut [u32],
    pub width: u32,
    pub height: u32,
    pub y0: u32,
}

/// The keys and encoded ids of one tile, aligned so that a row of a 16-pixel block is
/// one cache line.
#[repr(C, align(64))]
struct TileBuffer {
    keys: [f32; (TILE * TILE) as usize],
    ids: [u32; (TILE * TILE) as usize],
    /// Per block of 16 x 8 pixels, the smallest (farthest) key it holds.
    farthest: [f32; FAR_BLOCKS],
}

/// Columns of a block of the grid (`2 BLOCK`).
const FAR_W: usize = 2 * block::BLOCK as usize;

/// Blocks of the grid per tile.
const FAR_BLOCKS: usize = (TILE * TILE) as usize / (FAR_W * block::BLOCK as usize);

/// The smallest key of each `FAR_W x BLOCK` block of a tile's keys (row after row of
/// `TILE` keys), into `farthest`. Rows past `rows` count as empty (key 0).
#[inline(always)]
fn farthest_keys(keys: &[f32], rows: usize, farthest: &mut [f32; FAR_BLOCKS]) {
    const T: usize = TILE as usize;
    const B: usize = block::BLOCK as usize;
    for (k, far) in farthest.iter_mut().enumerate() {
        let (by, bx) = ((k / (T / FAR_W)) * B, (k % (T / FAR_W)) * FAR_W);
        if by + B > rows {
            *far = 0.0;
            continue;
        }
        // Lane-wise minima (vector instructions), reduced at the end.
        let mut m = [f32::INFINITY; FAR_W];
        for y in by..by + B {
            let row = &keys[y * T + bx..y * T + bx + FAR_W];
            for (m, &v) in m.iter_mut().zip(row) {
                *m = if v < *m { v } else { *m };
            }
        }
        *far = block::min16(m);
    }
}

/// A polygon other than a triangle ready to draw (triangles are set up in batches,
/// [`block::triangles8`]).
#[derive(Clone)]
enum Setup {
    Quad(BlockSetup<4>),
    /// Five to [`block::MAX_EDGES`] edges.
    Polygon(BlockSetup<8>),
    /// More edges: drawn row span by row span (the setup has no edges; it carries the
    /// rectangle and the plane).
    Spans(PolygonCoverage, BlockSetup<0>),
}

impl Setup {
    /// [`block::nearest_key`] over its rectangle (NaN sorts it anywhere).
    fn nearest_key(&self) -> f32 {
        let r = self.rect();
        match self {
            Setup::Quad(s) => block::nearest_key(s, r),
            Setup::Polygon(s) => block::nearest_key(s, r),
            Setup::Spans(_, s) => block::nearest_key(s, r),
        }
    }

    fn rect(&self) -> PixelRect {
        match self {
            Setup::Quad(s) => s.rect,
            Setup::Polygon(s) => s.rect,
            Setup::Spans(_, s) => s.rect,
        }
    }
}

/// The setup of polygon `p` of the view (not a triangle), `None` when it covers no
/// sample (as the reference decides).
#[inline(always)]
fn setup(
    view: &PreparedView<'_>,
    p: usize,
    fill: FillRule,
    width: u32,
    height: u32,
    scratch: &mut PolygonSetup<16>,
) -> Option<Setup> {
    let (starts, indices, _) = view.polygon_arrays();
    let vertices = view.vertices();
    let (s, e) = (starts[p] as usize, starts[p + 1] as usize);
    let point = |i: u32| {
        let v = &vertices[i as usize];
        (v.x, v.y, v.zq)
    };
    if PolygonSetup::<16>::fits(e - s) {
        let mut points = [(0.0, 0.0, 0.0); 16];
        for (q, &i) in points.iter_mut().zip(&indices[s..e]) {
            *q = point(i);
        }
        if !scratch.set(&points[..e - s], fill, width, height) {
            return None;
        }
        let plane = scratch.depth_plane()?;
        let (edges, rect) = (scratch.edges(), scratch.rect());
        if edges.len() <= 4 {
            return BlockSetup::new(edges, rect, &plane).map(Setup::Quad);
        }
        if let Some(b) = BlockSetup::new(edges, rect, &plane) {
            return Some(Setup::Polygon(b));
        }
    }
    // Rare: more edges than a block setup holds. The shared coverage, with its
    // allocations.
    let poly = view.polygon(p);
    let cov = poly.coverage(fill, width, height)?;
    let plane = poly.depth_plane()?;
    let carrier = BlockSetup::new(&[], cov.rect(), &plane)?;
    Some(Setup::Spans(cov, carrier))
}

/// Draws a polygon of [`Setup::Spans`] in `region`: row spans of the shared coverage,
/// each pixel depth-tested with the key and test of the block rasterizer.
#[inline(always)]
fn draw_spans<L: Lanes>(
    l: L,
    cov: &PolygonCoverage,
    s: &BlockSetup<0>,
    region: PixelRect,
    target: &mut BlockTarget<'_>,
    face: u32,
    counts: &mut Counts,
) {
    let t = target.rect();
    for y in region.y0.max(s.rect.y0).max(t.y0)..region.y1.min(s.rect.y1).min(t.y1) {
        let Some((a, b)) = cov.row_span(y) else {
            continue;
        };
        let (a, b) = (a.max(region.x0).max(t.x0), b.min(region.x1).min(t.x1));
        let mut x = a;
        while x < b {
            let n = (b - x).min(8);
            let mut z = [0.0; 8];
            for (k, zk) in z.iter_mut().enumerate() {
                *zk = s.key(x + k as u32, y);
            }
            let (keys, ids) = target.row_mut(x, y, n as usize);
            // SAFETY: the slices hold the `n` pixels of the mask.
            let taken =
                unsafe { l.depth_test8(keys, ids, 0, lanes_below(n as usize), l.load(&z), face) };
            counts.tested += u64::from(n);
            counts.written += u64::from(taken.count_ones());
            x += n;
        }
    }
}

/// Draws a set-up polygon in `region`.
#[inline(always)]
fn draw_setup<L: Lanes>(
    l: L,
    setup: &Setup,
    region: PixelRect,
    align: Align,
    target: &mut BlockTarget<'_>,
    face: u32,
    counts: &mut Counts,
) {
    match setup {
        Setup::Quad(s) => block::draw(l, s, region, align, target, face, counts),
        Setup::Polygon(s) => block::draw(l, s, region, align, target, face, counts),
        Setup::Spans(cov, s) => draw_spans(l, cov, s, region, target, face, counts),
    }
}

/// The buffers of the drawing loop, kept from one frame to the next so that a renderer
/// drawing many frames allocates (and faults in) nothing after the first: the bins of
/// the tiles, the big polygons and their order, the tiles' cleared flags and the
/// aligned tile buffer. Their contents never carry over: each band starts them empty.
#[derive(Default)]
pub(super) struct Scratch {
    bins: Vec<Vec<u32>>,
    big_triangles: Vec<(BlockSetup<3>, u32, f32)>,
    big: Vec<(Setup, u32, f32)>,
    order: Vec<(f32, u32)>,
    /// Per tile of the band, whether its pixels in the band hold the empty buffer
    /// (zero bits): set when the first small polygon reaching it clears it.
    cleared: Vec<bool>,
    tile: Option<Box<TileBuffer>>,
}

impl std::fmt::Debug for Scratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scratch")
            .field("tiles", &self.bins.len())
            .field(
                "big_capacity",
                &(self.big_triangles.capacity() + self.big.capacity()),
            )
            .finish_non_exhaustive()
    }
}

impl Scratch {
    /// Empties every buffer for a band of `tiles` tiles (keeping their memory).
    fn start(&mut self, tiles: usize) {
        self.bins.truncate(tiles);
        for bin in &mut self.bins {
            bin.clear();
        }
        self.bins.resize_with(tiles, Vec::new);
        self.big_triangles.clear();
        self.big.clear();
        self.order.clear();
        self.cleared.clear();
        self.cleared.resize(tiles, false);
    }
}

/// Draws polygons `polygons` (indices into the view) into the band, then resolves the
/// band's keys and ids into depths and face ids.
///
/// The band's pixels may hold anything on entry (a fresh frame's zero bits, or the
/// previous frame of a reused one): nothing is read before it is written. A tile is
/// cleared to the empty buffer (zero bits) in the band only when the first small
/// polygon reaching it is drawn; a tile no small polygon reached is never read: its big
/// polygons start from an empty tile buffer (in cache), and a tile with no polygon at
/// all is written as background once. So the frame is written about once, and read
/// only where small polygons drew.
#[inline(always)]
fn draw_band_impl<L: Lanes>(
    l: L,
    view: &PreparedView<'_>,
    polygons: impl Iterator<Item = usize>,
    fill: FillRule,
    band: &mut Band<'_>,
    scratch: &mut Scratch,
) -> super::Counts {
    let start = std::time::Instant::now();
    let (_, _, faces) = view.polygon_arrays();
    let (width, height, y0) = (band.width, band.height, band.y0);
    let w = width as usize;
    let Some(mut target) = BlockTarget::new(&mut *band.keys, &mut *band.ids, w, 0, y0) else {
        return super::Counts::default();
    };
    let whole = target.rect();
    let y1 = whole.y1;
    let tiles_x = width.div_ceil(TILE) as usize;
    let tiles_y = (y1 - y0).div_ceil(TILE) as usize;
    scratch.start(tiles_x * tiles_y);
    let Scratch {
        bins,
        big_triangles,
        big,
        order,
        cleared,
        tile: tile_buffer,
    } = scratch;
    // Big polygons: triangles (bin entries below OTHER), and the others.
    // Each with its face and its nearest key.
    let (starts, indices, _) = view.polygon_arrays();
    let vertices = view.vertices();
    let is_big = |r: PixelRect| r.x1 - r.x0 > BIG || r.y1 - r.y0 > BIG;
    let tiles_of = |r: PixelRect| {
        let (tx0, tx1) = (r.x0 / TILE, (r.x1 - 1) / TILE + 1);
        let (ty0, ty1) = (
            (r.y0.max(y0) - y0) / TILE,
            (r.y1.min(y1) - 1 - y0) / TILE + 1,
        );
        (tx0 as usize..tx1 as usize, ty0 as usize..ty1 as usize)
    };
    // Bin entry `n` (a big polygon) into the bins of the tiles `r` overlaps.
    let put_in_bins = |bins: &mut [Vec<u32>], r: PixelRect, n: u32| {
        let (xs, ys) = tiles_of(r);
        for ty in ys {
            for bin in &mut bins[ty * tiles_x..][xs.clone()] {
                bin.push(n);
            }
        }
    };
    // The pixels of tile `(tx, ty)` of the band.
    let tile_rect = |tx: usize, ty: usize| PixelRect {
        x0: tx as u32 * TILE,
        y0: y0 + ty as u32 * TILE,
        x1: ((tx as u32 + 1) * TILE).min(width),
        y1: (y0 + (ty as u32 + 1) * TILE).min(y1),
    };
    // Before a small polygon (rectangle `r`, inside the band's rows) is drawn: the
    // tiles it reaches that are not cleared yet, cleared.
    let clear_tiles = |target: &mut BlockTarget<'_>, cleared: &mut [bool], r: PixelRect| {
        let (xs, ys) = tiles_of(r);
        for ty in ys {
            for tx in xs.clone() {
                let done = &mut cleared[ty * tiles_x + tx];
                if *done {
                    continue;
                }
                *done = true;
                let t = tile_rect(tx, ty);
                let n = (t.x1 - t.x0) as usize;
                for y in t.y0..t.y1 {
                    let (k, i) = target.row_mut(t.x0, y, n);
                    k.fill(0.0);
                    i.fill(0);
                }
            }
        }
    };
    let mut setup_scratch = PolygonSetup::<16>::new();
    let mut counts = Counts::default();
    let mut drawn = 0u64;
    // Triangles, most polygons of most scenes, are set up eight at a time (the other
    // polygons one by one as they come: the order-free depth test makes the order of
    // drawing irrelevant).
    let mut points = block::TrianglePoints::default();
    let mut batch_polygons = [0usize; 8];
    let mut batched = 0;
    let mut polygons = polygons.into_iter();
    loop {
        let next = polygons.next();
        let mut other = None;
        if let Some(p) = next {
            let (a, b) = (starts[p] as usize, starts[p + 1] as usize);
            if let &[i, j, k] = &indices[a..b] {
                for (v, q) in [i, j, k].into_iter().enumerate() {
                    let q = &vertices[q as usize];
                    (
                        points.x[v][batched],
                        points.y[v][batched],
                        points.zq[v][batched],
                    ) = (q.x, q.y, q.zq);
                }
                batch_polygons[batched] = p;
                batched += 1;
                if batched < 8 {
                    continue;
                }
            } else {
                other = Some(p);
            }
        }
        // A full batch, the last one, or the triangles before another polygon (so
        // that polygons are drawn in their order: the counts of pixels written
        // depend on it).
        if batched > 0 {
            // Lanes past `batched` hold earlier triangles again: they are not drawn.
            let batch = block::triangles8(&points, fill, width, height);
            for (lane, &p) in batch_polygons[..batched].iter().enumerate() {
                if batch.valid >> lane & 1 == 0 {
                    continue;
                }
                let t = batch.get(lane);
                let rect = t.rect;
                if rect.y0 >= y0 && rect.y0 < y1 {
                    drawn += 1;
                }
                if rect.y1 <= y0 || rect.y0 >= y1 {
                    continue;
                }
                let face = !faces[p];
                if is_big(rect) {
                    big_triangles.push((t, face, block::nearest_key(&t, rect)));
                } else {
                    clear_tiles(&mut target, cleared, rect);
                    block::draw(l, &t, whole, Align::Polygon, &mut target, face, &mut counts);
                }
            }
            batched = 0;
        }
        // Other polygons, one by one.
        if let Some(p) = other
            && let Some(s) = setup(view, p, fill, width, height, &mut setup_scratch)
        {
            let rect = s.rect();
            // A polygon reaching several bands is counted by the band of its first row.
            if rect.y0 >= y0 && rect.y0 < y1 {
                drawn += 1;
            }
            if rect.y1 > y0 && rect.y0 < y1 {
                let face = !faces[p];
                if is_big(rect) {
                    let near = s.nearest_key();
                    big.push((s, face, near));
                } else {
                    clear_tiles(&mut target, cleared, rect);
                    draw_setup(l, &s, whole, Align::Polygon, &mut target, face, &mut counts);
                }
            }
        }
        if next.is_none() {
            break;
        }
    }
    let small_done = std::time::Instant::now();
    // The big polygons into the bins of their tiles nearest first (one sort for all
    // bins), so that each tile draws them nearest first: the blocks they fill hide
    // the polygons behind them.
    order.extend(
        big_triangles
            .iter()
            .enumerate()
            .map(|(k, b)| (b.2, k as u32))
            .chain(big.iter().enumerate().map(|(k, b)| (b.2, OTHER | k as u32))),
    );
    order.sort_by(|a, b| b.0.total_cmp(&a.0));
    for &(_, k) in order.iter() {
        let rect = if k & OTHER == 0 {
            big_triangles[k as usize].0.rect
        } else {
            big[(k & !OTHER) as usize].0.rect()
        };
        put_in_bins(bins, rect, k);
    }
    let binned = std::time::Instant::now();
    let depth = view.transform().key_depths();
    let tb = &mut **tile_buffer.get_or_insert_with(|| {
        Box::new(TileBuffer {
            keys: [0.0; (TILE * TILE) as usize],
            ids: [0; (TILE * TILE) as usize],
            farthest: [0.0; FAR_BLOCKS],
        })
    });
    let (keys, ids) = (&mut *band.keys, &mut *band.ids);
    for ty in 0..tiles_y {
        for tx in 0..tiles_x {
            let tile = tile_rect(tx, ty);
            let n = (tile.x1 - tile.x0) as usize;
            let (bin, was_cleared) = (&bins[ty * tiles_x + tx], cleared[ty * tiles_x + tx]);
            if bin.is_empty() {
                for y in tile.y0..tile.y1 {
                    let at = (y - y0) as usize * w + tile.x0 as usize;
                    let (k, i) = (&mut keys[at..at + n], &mut ids[at..at + n]);
                    if was_cleared {
                        l.resolve_in_place(k, i, depth);
                    } else {
                        // What resolving the empty buffer gives.
                        k.fill(f32::INFINITY);
                        i.fill(crate::frame::BACKGROUND);
                    }
                }
                continue;
            }
            let rows = (tile.y1 - tile.y0) as usize * TILE as usize;
            if was_cleared {
                // The tile's pixels into the aligned buffer, its big polygons drawn
                // there (in cache), then resolved back into the frame.
                for y in tile.y0..tile.y1 {
                    let at = (y - y0) as usize * w + tile.x0 as usize;
                    let t = (y - tile.y0) as usize * TILE as usize;
                    tb.keys[t..t + n].copy_from_slice(&keys[at..at + n]);
                    tb.ids[t..t + n].copy_from_slice(&ids[at..at + n]);
                }
                // Columns past the image's edge hold stale keys: no block there is
                // culled.
                if n == TILE as usize {
                    farthest_keys(&tb.keys, (tile.y1 - tile.y0) as usize, &mut tb.farthest);
                } else {
                    tb.farthest = [0.0; FAR_BLOCKS];
                }
            } else {
                // No small polygon drew here: the empty buffer, made in cache (what
                // copying the cleared pixels in would give, and its farthest keys).
                tb.keys[..rows].fill(0.0);
                tb.ids[..rows].fill(0);
                tb.farthest = [0.0; FAR_BLOCKS];
            }
            let Some(t) = BlockTarget::new(
                &mut tb.keys[..rows],
                &mut tb.ids[..rows],
                TILE as usize,
                tile.x0,
                tile.y0,
            ) else {
                continue;
            };
            let mut t = t.with_farthest(&mut tb.farthest);
            // Nearest first (the bins' order).
            for &k in bin {
                if k & OTHER == 0 {
                    let (s, face, _) = &big_triangles[k as usize];
                    block::draw(l, s, tile, Align::Grid, &mut t, *face, &mut counts);
                } else {
                    let (s, face, _) = &big[(k & !OTHER) as usize];
                    draw_setup(l, s, tile, Align::Grid, &mut t, *face, &mut counts);
                }
            }
            block::resolve(l, &t, tile, keys, ids, w, y0, depth);
        }
    }
    let end = std::time::Instant::now();
    super::Counts {
        drawn,
        tested: counts.tested,
        written: counts.written,
        // A big polygon reaching several bands counts in the band of its first row.
        big: big_triangles
            .iter()
            .map(|b| b.0.rect)
            .chain(big.iter().map(|b| b.0.rect()))
            .filter(|r| r.y0 >= y0)
            .count() as u64,
        seconds: [
            (small_done - start).as_secs_f64(),
            (binned - small_done).as_secs_f64(),
            (end - binned).as_secs_f64(),
        ],
    }
}

fn draw_band_portable(
    view: &PreparedView<'_>,
    polygons: impl Iterator<Item = usize>,
    fill: FillRule,
    band: &mut Band<'_>,
    scratch: &mut Scratch,
) -> super::Counts {
    draw_band_impl(Portable, view, polygons, fill, band, scratch)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn draw_band_avx2(
    _: crate::cpu::Avx2,
    view: &PreparedView<'_>,
    polygons: impl Iterator<Item = usize>,
    fill: FillRule,
    band: &mut Band<'_>,
    scratch: &mut Scratch,
) -> super::Counts {
    draw_band_impl(Portable, view, polygons, fill, band, scratch)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
fn draw_band_avx512(
    l: Avx512,
    view: &PreparedView<'_>,
    polygons: impl Iterator<Item = usize>,
    fill: FillRule,
    band: &mut Band<'_>,
    scratch: &mut Scratch,
) -> super::Counts {
    draw_band_impl(l, view, polygons, fill, band, scratch)
}

/// Draws `polygons` into the band with the kernel (the best one below it if the
/// processor lacks the kernel's instructions: [`Kernel::resolve`]), and resolves the
/// band.
pub(super) fn draw_band(
    view: &PreparedView<'_>,
    polygons: impl Iterator<Item = usize>,
    fill: FillRule,
    kernel: Kernel,
    band: &mut Band<'_>,
    scratch: &mut Scratch,
) -> super::Counts {
    #[cfg(target_arch = "x86_64")]
    {
        if let Some(l) = kernel.avx512() {
            // SAFETY: `Avx512::new` checked every feature `draw_band_avx512` enables.
            return unsafe { draw_band_avx512(l, view, polygons, fill, band, scratch) };
        }
        if let Some(cpu) = kernel.avx2() {
            // SAFETY: `Avx2::new` checked every feature `draw_band_avx2` enables.
            return unsafe { draw_band_avx2(cpu, view, polygons, fill, band, scratch) };
        }
    }
    draw_band_portable(view, polygons, fill, band, scratch)
}

/// Draws every polygon of the view into the whole frame on this thread (whatever the
/// frame held before), with the buffers of `scratch`.
pub(super) fn draw_all(
    view: &PreparedView<'_>,
    fill: FillRule,
    kernel: Kernel,
    frame: &mut Frame,
    scratch: &mut Scratch,
) -> super::Counts {
    let mut band = Band {
        keys: &mut frame.depth,
        ids: &mut frame.ids,
        width: frame.width,
        height: frame.height,
        y0: 0,
    };
    draw_band(
        view,
        0..view.polygon_count(),
        fill,
        kernel,
        &mut band,
        scratch,
    )
}
