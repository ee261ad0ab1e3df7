//! A lean scanline over triangles, for measuring only. It has the per-row structure
//! of `obscura::surface::scanline`: faces set up on their first row, two edges per face
//! stepped by `1/m`, crossings emitted, counting-sorted and walked with in/out flags,
//! the nearest face of a span decided at its ends and kept along the row, faces hidden
//! on entering left out. Its live faces are one flat array of what the sweep reads
//! (edges, rows, plane); the walk's set holds the keys of its members. It has none of what makes
//! the library's exact: no bound on the stepped crossings (so no edge functions and no
//! fallback to them), no check of span ends against the third edge, fans for polygons
//! of more than three vertices; no stats either. So it does less per face and per row
//! than the library, with one exception: it has no coherence between rows (on Sponza
//! that spares the library about 95,000 of 804,100 span decisions). Its picture
//! differs from the z-buffer's where rounding puts a crossing on the other side of a
//! pixel centre.

use obscura::view::PreparedView;

/// A face entering on this row: its key along the row, `c + dzdx (px - x0)`, the end
/// of its span and its slot.
#[derive(Clone, Copy, Default)]
struct Member {
    c: f64,
    dzdx: f64,
    x0: f64,
    end: u32,
    slot: u32,
}

impl Member {
    #[inline(always)]
    fn key(&self, px: f64) -> f64 {
        self.c + self.dzdx * (px - self.x0)
    }
}

#[inline(always)]
fn surely_nearer(a: f64, b: f64) -> bool {
    a - b > (a.abs() + b.abs()) * (1.0 / (1u64 << 22) as f64) + 1e-15
}

/// `floor(v)` without a library call (the target may lack a rounding instruction),
/// for `|v| < 2^51`.
#[inline(always)]
fn floor(v: f64) -> f64 {
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let r = (v + ROUND) - ROUND;
    r - f64::from(u8::from(r > v))
}

/// `ceil(v)`, see [`floor`].
#[inline(always)]
fn ceil(v: f64) -> f64 {
    -floor(-v)
}

/// `v` clamped to `0..=hi` as an index (0 for NaN).
#[inline(always)]
fn index(v: f64, hi: f64) -> u32 {
    v.clamp(0.0, hi) as u32
}

/// A live face with all the sweep reads and writes, together: its long edge (top to
/// bottom vertex), its short side's edge now and the one below the middle vertex (`x`
/// on the row's sample line, step per row), the row where the short side changes
/// edge, its last row, whether the short side is the left one, its key plane.
#[derive(Clone, Copy, Default)]
struct Live {
    x_long: f64,
    d_long: f64,
    x_short: f64,
    d_short: f64,
    x_lower: f64,
    d_lower: f64,
    switch_row: u32,
    last_row: u32,
    short_left: bool,
    slot: u32,
    /// The key plane: `z0 + dzdx (x - ax) + dzdy (y - ay)`.
    z0: f64,
    dzdx: f64,
    dzdy: f64,
    ax: f64,
    ay: f64,
}

/// The faces' ids and places in the set of faces in, by slot, and the live faces.
#[derive(Default)]
struct Faces {
    face: Vec<u32>,
    /// Per slot: its place in the set of faces in, or `u32::MAX`.
    position: Vec<u32>,
    live: Vec<Live>,
    free: Vec<u32>,
}

impl Faces {
    fn slot(&mut self) -> usize {
        if let Some(s) = self.free.pop() {
            return s as usize;
        }
        let s = self.face.len();
        self.face.push(0);
        self.position.push(u32::MAX);
        s
    }
}

/// Reused buffers of [`render`].
#[derive(Default)]
pub struct Lean {
    /// Per row (and one past the last): where its triangles start in `by_row`.
    row_starts: Vec<u32>,
    first_rows: Vec<u32>,
    by_row: Vec<u32>,
    triangles: Vec<[u32; 4]>,
    /// Seconds in the setup of new faces, the sweep, the sort and the walk, summed
    /// over calls.
    pub seconds: [f64; 4],
    faces: Faces,
    unsorted: Vec<(u32, u32)>,
    crossings: Vec<(u32, u32)>,
    bucket: Vec<u32>,
    entering: Vec<Member>,
    set: Vec<Member>,
}

/// Renders `view` into `ids` and `keys` (`width x height`, row after row; faces' ids
/// and `f32` keys, `u32::MAX` where none); returns the number of spans with faces.
/// The table (triangles bucketed by first row) is built first and is in no stage's
/// time.
pub fn render(lean: &mut Lean, view: &PreparedView<'_>, ids: &mut [u32], keys: &mut [f32]) -> u64 {
    let vp = view.viewport();
    let (width, height) = (vp.width, vp.height);
    let (w, h) = (f64::from(width), f64::from(height));
    ids.fill(u32::MAX);
    let (starts, indices, face_ids) = view.polygon_arrays();
    let vertices = view.vertices();
    let n = face_ids.len();
    // The table: triangles bucketed by the first row whose sample line they reach.
    let first_rows = &mut lean.first_rows;
    first_rows.clear();
    let bucket_starts = &mut lean.row_starts;
    bucket_starts.clear();
    bucket_starts.resize(height as usize + 1, 0);
    // Polygons of more vertices (clipped ones) as fans of triangles.
    let tris = &mut lean.triangles;
    tris.clear();
    for p in 0..n {
        let (a, b) = (starts[p] as usize, starts[p + 1] as usize);
        for k in a + 1..b.saturating_sub(1) {
            tris.push([indices[a], indices[k], indices[k + 1], p as u32]);
        }
    }
    for t in tris.iter() {
        let v = [t[0], t[1], t[2]].map(|i| &vertices[i as usize]);
        let miny = v[0].y.min(v[1].y).min(v[2].y);
        let maxy = v[0].y.max(v[1].y).max(v[2].y);
        let minx = v[0].x.min(v[1].x).min(v[2].x);
        let maxx = v[0].x.max(v[1].x).max(v[2].x);
        // The rows and columns whose sample lines the box reaches.
        let y0 = index(ceil(miny - 0.5), h);
        let y1 = index(floor(maxy - 0.5) + 1.0, h);
        let x0 = index(ceil(minx - 0.5), w);
        let x1 = index(floor(maxx - 0.5) + 1.0, w);
        let mut row = u32::MAX;
        if y0 < y1 && x0 < x1 {
            row = y0;
            bucket_starts[y0 as usize + 1] += 1;
        }
        first_rows.push(row);
    }
    for r in 0..height as usize {
        bucket_starts[r + 1] += bucket_starts[r];
    }
    let by_row = &mut lean.by_row;
    by_row.clear();
    by_row.resize(bucket_starts[height as usize] as usize, 0);
    {
        let mut next = bucket_starts.clone();
        for (t, &row) in first_rows.iter().enumerate() {
            if row != u32::MAX {
                by_row[next[row as usize] as usize] = t as u32;
                next[row as usize] += 1;
            }
        }
    }
    let f = &mut lean.faces;
    f.live.clear();
    f.free.clear();
    f.free.extend((0..f.face.len() as u32).rev());
    lean.bucket.clear();
    lean.bucket.resize(width as usize + 2, 0);
    let mut spans = 0u64;
    for y in 0..height {
        let py = f64::from(y) + 0.5;
        let t0 = std::time::Instant::now();
        // New faces.
        for &t in
            &by_row[bucket_starts[y as usize] as usize..bucket_starts[y as usize + 1] as usize]
        {
            let t = lean.triangles[t as usize];
            let mut v = [t[0], t[1], t[2]].map(|i| &vertices[i as usize]);
            v.sort_by(|p, q| p.y.total_cmp(&q.y));
            let [va, vb, vc] = v;
            let (ax, ay, az) = (vb.x - va.x, vb.y - va.y, vb.zq - va.zq);
            let (bx, by, bz) = (vc.x - va.x, vc.y - va.y, vc.zq - va.zq);
            let area2 = ax * by - ay * bx;
            if area2 == 0.0 || !area2.is_finite() || vc.y == va.y {
                continue;
            }
            let s = f.slot();
            let d_long = (vc.x - va.x) / (vc.y - va.y);
            let d_upper = if vb.y > va.y {
                (vb.x - va.x) / (vb.y - va.y)
            } else {
                0.0
            };
            let d_lower = if vc.y > vb.y {
                (vc.x - vb.x) / (vc.y - vb.y)
            } else {
                0.0
            };
            let switch = index(ceil(vb.y - 0.5), h);
            let (x_short, d_short) = if y >= switch {
                (vb.x + (py - vb.y) * d_lower, d_lower)
            } else {
                (va.x + (py - va.y) * d_upper, d_upper)
            };
            f.live.push(Live {
                x_long: va.x + (py - va.y) * d_long,
                d_long,
                x_short,
                d_short,
                x_lower: vb.x + (f64::from(switch) + 0.5 - vb.y) * d_lower,
                d_lower,
                switch_row: switch,
                last_row: index(floor(vc.y - 0.5), h - 1.0),
                // With the vertices in y order, a negative area puts the middle vertex
                // left of the long edge.
                short_left: area2 < 0.0,
                slot: s as u32,
                z0: va.zq,
                dzdx: (az * by - bz * ay) / area2,
                dzdy: (ax * bz - bx * az) / area2,
                ax: va.x,
                ay: va.y,
            });
            f.face[s] = face_ids[t[3] as usize];
        }
        let t1 = std::time::Instant::now();
        lean.seconds[0] += (t1 - t0).as_secs_f64();
        // The sweep: every live face's span, its crossings, its edges stepped.
        lean.unsorted.clear();
        lean.entering.clear();
        let mut i = 0;
        while i < f.live.len() {
            let l = &mut f.live[i];
            if y == l.switch_row {
                l.x_short = l.x_lower;
                l.d_short = l.d_lower;
            }
            let s = l.slot as usize;
            let (xs, xl) = (l.x_short, l.x_long);
            let (left, right) = if l.short_left { (xs, xl) } else { (xl, xs) };
            // The pixels whose centres lie in `[left, right)`.
            let lo = index(ceil(left - 0.5), w);
            let hi = index(ceil(right - 0.5), w);
            l.x_short = xs + l.d_short;
            l.x_long = xl + l.d_long;
            let done = y >= l.last_row;
            if lo < hi {
                lean.unsorted
                    .push((lo, (lean.entering.len() as u32) << 1 | 1));
                lean.unsorted.push((hi, (s as u32) << 1));
                lean.entering.push(Member {
                    c: l.z0 + l.dzdy * (py - l.ay),
                    dzdx: l.dzdx,
                    x0: l.ax,
                    end: hi,
                    slot: s as u32,
                });
            }
            if done {
                f.free.push(s as u32);
                f.live.swap_remove(i);
            } else {
                i += 1;
            }
        }
        let t2 = std::time::Instant::now();
        lean.seconds[1] += (t2 - t1).as_secs_f64();
        // Counting sort, leaving before entering at a pixel.
        let counts = &mut lean.bucket;
        counts.fill(0);
        for c in &lean.unsorted {
            counts[c.0 as usize + 1] += 1;
        }
        let mut before = 0;
        for c in counts.iter_mut() {
            before += *c;
            *c = before;
        }
        lean.crossings.resize(lean.unsorted.len(), (0, 0));
        for side in [1, 0] {
            for pair in lean.unsorted.chunks_exact(2) {
                let c = pair[side];
                let at = &mut counts[c.0 as usize];
                lean.crossings[*at as usize] = c;
                *at += 1;
            }
        }
        let t3 = std::time::Instant::now();
        lean.seconds[2] += (t3 - t2).as_secs_f64();
        // The walk.
        let row = y as usize * width as usize;
        let set = &mut lean.set;
        let mut kept: Option<Member> = None;
        let mut x = 0;
        let mut span = |x0: u32, x1: u32, set: &mut Vec<Member>, kept: &mut Option<Member>| {
            let winner = match set.len() {
                0 => return,
                1 => {
                    *kept = Some(set[0]);
                    set[0]
                }
                _ => match *kept {
                    Some(k) => k,
                    None => {
                        let (pl, pr) = (f64::from(x0) + 0.5, f64::from(x1) - 0.5);
                        let (mut wi, mut best) = (0, f64::NEG_INFINITY);
                        for (g, m) in set.iter().enumerate() {
                            if m.key(pl) > best {
                                (wi, best) = (g, m.key(pl));
                            }
                        }
                        let mw = set[wi];
                        let (mut proven, mut keep) = (true, true);
                        for (g, m) in set.iter().enumerate() {
                            if g == wi {
                                continue;
                            }
                            if !surely_nearer(best, m.key(pl)) {
                                proven = false;
                                break;
                            }
                            let b = f64::from(mw.end.min(m.end)) - 0.5;
                            if !surely_nearer(mw.key(b), m.key(b)) {
                                keep = false;
                                if !surely_nearer(mw.key(pr), m.key(pr)) {
                                    proven = false;
                                    break;
                                }
                            }
                        }
                        if !proven {
                            // Pixel by pixel.
                            for px in x0..x1 {
                                let c = f64::from(px) + 0.5;
                                let m = set
                                    .iter()
                                    .max_by(|a, b| (a.key(c) as f32).total_cmp(&(b.key(c) as f32)))
                                    .copied()
                                    .unwrap_or_default();
                                ids[row + px as usize] = f.face[m.slot as usize];
                                keys[row + px as usize] = m.key(c) as f32;
                            }
                            return;
                        }
                        if keep {
                            *kept = Some(mw);
                        }
                        mw
                    }
                },
            };
            let id = f.face[winner.slot as usize];
            let mut z = winner.key(f64::from(x0) + 0.5);
            let dz = winner.dzdx;
            let (a, b) = (row + x0 as usize, row + x1 as usize);
            for (i, k) in ids[a..b].iter_mut().zip(&mut keys[a..b]) {
                *i = id;
                *k = z as f32;
                z += dz;
            }
        };
        for &(cx, data) in &lean.crossings {
            if cx > x {
                spans += u64::from(!set.is_empty());
                span(x, cx, set, &mut kept);
                x = cx;
            }
            if data & 1 != 0 {
                let e = lean.entering[(data >> 1) as usize];
                if let Some(k) = kept {
                    let last = k.end.min(e.end);
                    let (pa, pb) = (f64::from(cx) + 0.5, f64::from(last) - 0.5);
                    let hides = last > cx
                        && surely_nearer(k.key(pa), e.key(pa))
                        && surely_nearer(k.key(pb), e.key(pb));
                    if !hides {
                        kept = None;
                    } else if e.end <= k.end {
                        continue;
                    }
                }
                f.position[e.slot as usize] = set.len() as u32;
                set.push(e);
            } else {
                let s = (data >> 1) as usize;
                let p = f.position[s];
                if p == u32::MAX {
                    continue;
                }
                f.position[s] = u32::MAX;
                let p = p as usize;
                set.swap_remove(p);
                if let Some(m) = set.get(p) {
                    f.position[m.slot as usize] = p as u32;
                }
                if kept.is_some_and(|k| k.slot as usize == s) {
                    kept = None;
                }
            }
        }
        if x < width {
            span(x, width, set, &mut kept);
        }
        lean.seconds[3] += t3.elapsed().as_secs_f64();
    }
    spans
}
