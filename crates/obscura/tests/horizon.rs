//! The floating horizon (`lines::horizon`): every drawing checked against a brute-force
//! horizon computed here from the grid (every earlier segment evaluated at each sampled
//! column), the seed's crossing formula on worked numbers, tilted planes with known
//! answers, refused views, and the loaders round-tripping small grids.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{DVec2, DVec3, DVec4};
use obscura::lines::Drawing;
use obscura::lines::horizon::{
    Curves, HeightField, HorizonOptions, HorizonStats, crossing, crossing_fraction, draw,
};
use obscura::{Camera, Error, Projection, Viewport};

// ---------------------------------------------------------------------------------
// The brute-force oracle

/// A sample's pixel position (x right, y down), computed here from the camera's
/// matrices.
fn project(camera: &Camera, vp: Viewport, p: DVec3) -> DVec2 {
    let m = camera.projection_matrix(vp.aspect()) * camera.view_matrix();
    let c: DVec4 = m * p.extend(1.0);
    DVec2::new(
        (c.x / c.w + 1.0) * 0.5 * f64::from(vp.width),
        (1.0 - c.y / c.w) * 0.5 * f64::from(vp.height),
    )
}

/// Whether the rows are drawn from the last to the first (the eye on the `+z` side).
fn last_row_first(field: &HeightField, camera: &Camera) -> bool {
    match camera.projection {
        Projection::Perspective { .. } => camera.eye.z > field.z_range[1],
        Projection::Orthographic { .. } => camera.target.z < camera.eye.z,
    }
}

/// The grid's segments in drawing order, as groups: the curve of each row, then the
/// segments of constant x toward the next row (all columns when they are drawn, the
/// two side columns otherwise). Each segment is a pair of `(column, row)`.
fn groups(field: &HeightField, camera: &Camera, curves: Curves) -> Vec<Vec<[(usize, usize); 2]>> {
    let (nx, nz) = (field.nx, field.nz);
    let rows: Vec<usize> = if last_row_first(field, camera) {
        (0..nz).rev().collect()
    } else {
        (0..nz).collect()
    };
    let mut out = Vec::new();
    for (step, &k) in rows.iter().enumerate() {
        out.push((0..nx - 1).map(|i| [(i, k), (i + 1, k)]).collect());
        if let Some(&k2) = rows.get(step + 1) {
            let cols: Vec<usize> = if curves == Curves::ConstantZ {
                vec![0, nx - 1]
            } else {
                (0..nx).collect()
            };
            out.push(cols.into_iter().map(|i| [(i, k), (i, k2)]).collect());
        }
    }
    out
}

/// The highest and lowest image (smallest and largest pixel y) of `segments` at column
/// `x`, or `None` where none of them reaches it.
fn brute_horizon(segments: &[[DVec2; 2]], x: f64) -> Option<(f64, f64)> {
    let mut r: Option<(f64, f64)> = None;
    for [a, b] in segments {
        let (l, h) = if a.x <= b.x { (a, b) } else { (b, a) };
        if !(l.x <= x && x <= h.x) || l.x == h.x {
            continue;
        }
        let y = l.y + (h.y - l.y) * (x - l.x) / (h.x - l.x);
        r = Some(r.map_or((y, y), |(u, w)| (u.min(y), w.max(y))));
    }
    r
}

/// Checks a drawing made with hidden parts against the brute-force horizons: every
/// edge is covered by its pieces from t = 0 to 1; the ends of each piece are the
/// projections of its edge's points at its `t`; along every visible piece the points
/// lie on or above the upper horizon of all earlier groups or on or below the lower
/// one (or where no earlier segment reaches); along every hidden piece they lie between
/// them. Returns (visible, hidden) piece counts.
fn check_against_brute_force(
    field: &HeightField,
    camera: &Camera,
    vp: Viewport,
    options: &HorizonOptions,
    drawing: &Drawing,
) -> (usize, usize) {
    let tol = 1e-6;
    let groups = groups(field, camera, options.curves);
    let proj = |(i, k): (usize, usize)| project(camera, vp, field.point(i, k));
    // The group of each segment, by its sample pair.
    let mut group_of = std::collections::HashMap::new();
    for (g, segs) in groups.iter().enumerate() {
        for s in segs {
            group_of.insert(*s, g);
            group_of.insert([s[1], s[0]], g);
        }
    }
    let earlier: Vec<Vec<[DVec2; 2]>> = (0..groups.len())
        .map(|g| {
            groups[..g]
                .iter()
                .flatten()
                .map(|&[a, b]| [proj(a), proj(b)])
                .collect()
        })
        .collect();
    let index = |p: DVec3| {
        let i = ((p.x - field.x_range[0]) / (field.x_range[1] - field.x_range[0])
            * (field.nx - 1) as f64)
            .round() as usize;
        let k = ((p.z - field.z_range[0]) / (field.z_range[1] - field.z_range[0])
            * (field.nz - 1) as f64)
            .round() as usize;
        (i, k)
    };
    let mut covered = vec![0.0f64; drawing.edges.len()];
    let (mut nv, mut nh) = (0, 0);
    for piece in &drawing.pieces {
        let e = &drawing.edges[piece.edge as usize];
        let key = [index(e.world[0]), index(e.world[1])];
        let g = *group_of.get(&key).expect("an edge of the grid");
        assert!(
            (covered[piece.edge as usize] - piece.t[0]).abs() < 1e-12,
            "pieces of edge {} leave a gap before t = {}",
            piece.edge,
            piece.t[0]
        );
        covered[piece.edge as usize] = piece.t[1];
        for (j, &t) in piece.t.iter().enumerate() {
            let p = project(camera, vp, e.point(t));
            assert!(
                p.distance(piece.points[j]) < 1e-6,
                "piece end {:?} is not the edge's point at t = {t} ({p})",
                piece.points[j]
            );
        }
        for m in 1..10 {
            let s = f64::from(m) / 10.0;
            let pt = piece.points[0] + (piece.points[1] - piece.points[0]) * s;
            let h = brute_horizon(&earlier[g], pt.x);
            if piece.is_visible() {
                nv += 1;
                if let Some((top, bottom)) = h {
                    let above = pt.y <= top + tol;
                    let below = !options.ridgeline && pt.y >= bottom - tol;
                    assert!(
                        above || below,
                        "visible point {pt} of group {g} lies between the horizons {top}..{bottom}"
                    );
                }
            } else {
                nh += 1;
                let (top, bottom) = h.unwrap_or_else(|| {
                    panic!("hidden point {pt} of group {g} where no earlier curve reaches")
                });
                assert!(
                    pt.y >= top - tol && (options.ridgeline || pt.y <= bottom + tol),
                    "hidden point {pt} of group {g} lies outside the horizons {top}..{bottom}"
                );
            }
        }
    }
    for (e, &c) in covered.iter().enumerate() {
        assert_eq!(c, 1.0, "edge {e} covered only up to t = {c}");
    }
    (nv, nh)
}

fn run(
    field: &HeightField,
    camera: &Camera,
    vp: Viewport,
    options: &HorizonOptions,
) -> (Drawing, HorizonStats) {
    draw(field, camera, vp, options).unwrap()
}

fn ortho_front(height_above: f64) -> Camera {
    Camera::orthographic(
        DVec3::new(0.0, height_above, 5.0),
        DVec3::ZERO,
        DVec3::Y,
        3.0,
        0.1,
        20.0,
    )
}

// ---------------------------------------------------------------------------------
// The seed's crossing formula

#[test]
fn crossing_formula_on_worked_numbers() {
    // Current segment A(0,0)-B(4,4), previous C(0,3)-D(4,1): the lines y = x and
    // y = 3 - x/2 cross at (2, 2).
    let (a, b, c, d) = (
        DVec2::new(0., 0.),
        DVec2::new(4., 4.),
        DVec2::new(0., 3.),
        DVec2::new(4., 1.),
    );
    let p = crossing(a, b, c, d).unwrap();
    assert!((p - DVec2::new(2., 2.)).length() < 1e-12, "{p}");
    // The formula as the seed prints it (+ inside the brackets) gives x = -2 here: the
    // sign slip that `crossing` corrects.
    let (dx1, dy1, dx2, dy2) = (4.0, 4.0, 4.0, -2.0);
    let printed =
        (dx2 * (a.y * dx1 + a.x * dy1) - dx1 * (c.y * dx2 + c.x * dy2)) / (dy1 * dx2 - dy2 * dx1);
    assert_eq!(printed, -2.0);
    // Both segments over one interval: the fraction of the interval.
    assert_eq!(crossing_fraction(0.0, 4.0, 3.0, -2.0), Some(0.5));
}

#[test]
fn crossing_formula_agrees_with_cramers_rule() {
    let mut rng = obscura::bench_support::SplitMix64(23);
    let mut checked = 0;
    for _ in 0..1000 {
        let mut r = || DVec2::new(rng.range(-50.0, 50.0), rng.range(-50.0, 50.0));
        let (a, b, c, d) = (r(), r(), r(), r());
        // Cramer's rule on a + s (b - a) = c + u (d - c).
        let (e, f) = (b - a, c - d);
        let det = e.x * f.y - e.y * f.x;
        if det.abs() < 1e-3 || (b.x - a.x).abs() < 1e-3 {
            continue;
        }
        let g = c - a;
        let s = (g.x * f.y - g.y * f.x) / det;
        let expect = a + e * s;
        let p = crossing(a, b, c, d).unwrap();
        assert!(
            p.distance(expect) < 1e-7 * (1.0 + expect.length()),
            "{p} vs {expect}"
        );
        // The common-interval form: both clipped to the same x interval [x0, x1].
        let (x0, x1) = (a.x.min(b.x), a.x.max(b.x));
        let (l, h) = if a.x <= b.x { (a, b) } else { (b, a) };
        let at2 = |x: f64| c.y + (d.y - c.y) * (x - c.x) / (d.x - c.x);
        if (d.x - c.x).abs() < 1e-3 {
            continue;
        }
        if expect.x > x0 + 1e-6 && expect.x < x1 - 1e-6 {
            let lam = crossing_fraction(l.y, h.y - l.y, at2(x0), at2(x1) - at2(x0))
                .expect("lines that cross are not parallel");
            let x = x0 + (x1 - x0) * lam;
            assert!((x - expect.x).abs() < 1e-6 * (1.0 + expect.x.abs()));
            checked += 1;
        }
    }
    assert!(
        checked > 100,
        "only {checked} crossings inside their interval"
    );
}

// ---------------------------------------------------------------------------------
// Drawings checked by brute force

#[test]
fn a_single_bump_hides_what_its_silhouette_covers() {
    let field = HeightField::function("bump", 41, 25).unwrap();
    let vp = Viewport::new(400, 300).unwrap();
    let camera = ortho_front(1.0);
    let options = HorizonOptions::default().with_hidden(true);
    let (d, stats) = run(&field, &camera, vp, &options);
    let (nv, nh) = check_against_brute_force(&field, &camera, vp, &options, &d);
    assert!(nv > 0 && nh > 0, "visible {nv}, hidden {nh}");
    assert_eq!(stats.curves, 25);
    assert_eq!(d.edges.len(), 25 * 40);
    // The row just behind the bump's top (z = 0 is row 12; drawn from row 24 down)
    // is hidden in the middle and visible at both sides.
    let row = 10;
    let z = field.z(row);
    let pieces: Vec<_> = d
        .pieces
        .iter()
        .filter(|p| d.edges[p.edge as usize].world[0].z == z)
        .collect();
    let x_of =
        |p: &obscura::lines::Piece| d.edges[p.edge as usize].point(0.5 * (p.t[0] + p.t[1])).x;
    assert!(
        pieces
            .iter()
            .any(|p| !p.is_visible() && x_of(p).abs() < 0.1)
    );
    assert!(pieces.iter().any(|p| p.is_visible() && x_of(p) < -0.8));
    assert!(pieces.iter().any(|p| p.is_visible() && x_of(p) > 0.8));
}

#[test]
fn every_visible_piece_lies_beyond_the_earlier_horizons() {
    let vp = Viewport::new(320, 240).unwrap();
    let mut rng = obscura::bench_support::SplitMix64(4);
    for (name, curves, ridgeline) in [
        ("ripple", Curves::ConstantZ, false),
        ("peaks", Curves::Both, false),
        ("waves", Curves::ConstantX, false),
        ("bumps", Curves::Both, true),
        ("saddle", Curves::Both, false),
    ] {
        let field = HeightField::function(name, 23, 17).unwrap();
        for _ in 0..3 {
            // A camera in front (either side), above or below the surface, sometimes
            // orthographic.
            let side = if rng.next_f64() < 0.3 { -1.0 } else { 1.0 };
            let eye = DVec3::new(
                rng.range(-2.0, 2.0),
                rng.range(-1.0, 2.5),
                side * rng.range(2.5, 5.0),
            );
            let target = DVec3::new(rng.range(-0.3, 0.3), 0.0, rng.range(-0.3, 0.3));
            let camera = if rng.next_f64() < 0.5 {
                Camera::perspective(eye, target, DVec3::Y, 50.0, 0.1, 20.0)
            } else {
                Camera::orthographic(eye, target, DVec3::Y, 3.5, 0.1, 20.0)
            };
            let mut options = HorizonOptions::default()
                .with_curves(curves)
                .with_ridgeline(ridgeline)
                .with_hidden(true);
            let (d, _) = run(&field, &camera, vp, &options);
            check_against_brute_force(&field, &camera, vp, &options, &d);
            // Without the hidden parts: the same visible pieces.
            options.hidden = false;
            let (v, _) = run(&field, &camera, vp, &options);
            let visible: Vec<_> = d.visible().copied().collect();
            assert_eq!(v.pieces, visible, "{name}");
            assert_eq!(v.edges, d.edges);
        }
    }
}

#[test]
fn a_view_from_behind_draws_the_mirrored_field() {
    // The field seen from -z equals its mirror image (rows reversed, z negated) seen
    // from the mirrored camera.
    let field = HeightField::function("bumps", 21, 15).unwrap();
    let mut mirrored = field.clone();
    for k in 0..field.nz {
        for i in 0..field.nx {
            mirrored.heights[k * field.nx + i] = field.height(i, field.nz - 1 - k);
        }
    }
    let vp = Viewport::new(300, 200).unwrap();
    let front = Camera::perspective(
        DVec3::new(0.0, 1.5, 4.0),
        DVec3::ZERO,
        DVec3::Y,
        45.0,
        0.1,
        20.0,
    );
    // Mirroring z turns a right-handed view into a left-handed one: mirror x as well
    // (a rotation by 180 degrees about y), and mirror the columns to match.
    let back = Camera::perspective(
        DVec3::new(0.0, 1.5, -4.0),
        DVec3::ZERO,
        DVec3::Y,
        45.0,
        0.1,
        20.0,
    );
    let mut rotated = mirrored.clone();
    for k in 0..field.nz {
        for i in 0..field.nx {
            rotated.heights[k * field.nx + i] = mirrored.height(field.nx - 1 - i, k);
        }
    }
    let options = HorizonOptions::default().with_curves(Curves::Both);
    let (a, sa) = run(&rotated, &front, vp, &options);
    let (b, sb) = run(&field, &back, vp, &options);
    assert!(sa.last_row_first && !sb.last_row_first);
    assert_eq!(a.pieces.len(), b.pieces.len());
    let mut pa: Vec<_> = a.visible().map(|p| p.points).collect();
    let mut pb: Vec<_> = b.visible().map(|p| p.points).collect();
    let key = |p: &[DVec2; 2]| {
        let (l, h) = if (p[0].x, p[0].y) <= (p[1].x, p[1].y) {
            (p[0], p[1])
        } else {
            (p[1], p[0])
        };
        [l.x, l.y, h.x, h.y]
    };
    pa.sort_by(|x, y| key(x).partial_cmp(&key(y)).unwrap());
    pb.sort_by(|x, y| key(x).partial_cmp(&key(y)).unwrap());
    for (x, y) in pa.iter().zip(&pb) {
        let (x, y) = (key(x), key(y));
        for j in 0..4 {
            assert!((x[j] - y[j]).abs() < 1e-6, "{x:?} vs {y:?}");
        }
    }
}

// ---------------------------------------------------------------------------------
// Tilted planes

/// The plane `y = slope z` on a 9 x 7 grid.
fn plane(slope: f64) -> HeightField {
    HeightField::from_fn(
        9,
        7,
        &obscura::budget::MemoryBudget::new(1 << 20),
        |_, z| slope * z,
    )
    .unwrap()
}

#[test]
fn a_plane_tilted_toward_the_viewer_is_all_visible() {
    // The viewer looks down at 0.1; the plane rises away from it (y = -0.5 z).
    let vp = Viewport::new(200, 200).unwrap();
    for camera in [
        ortho_front(0.5),
        Camera::perspective(
            DVec3::new(0.3, 0.5, 5.0),
            DVec3::ZERO,
            DVec3::Y,
            40.0,
            0.1,
            20.0,
        ),
    ] {
        for curves in [Curves::ConstantZ, Curves::Both] {
            let options = HorizonOptions::default()
                .with_curves(curves)
                .with_hidden(true);
            let (d, s) = run(&plane(-0.5), &camera, vp, &options);
            assert_eq!(s.hidden_pieces, 0, "{curves:?}");
            assert_eq!(d.pieces.len(), d.edges.len());
            check_against_brute_force(&plane(-0.5), &camera, vp, &options, &d);
        }
    }
}

#[test]
fn a_plane_tilted_away_shows_its_front_edge_only_as_a_ridgeline() {
    // The plane falls away (y = 0.5 z) more steeply than the line of sight: its rows
    // come lower on the picture one after the other.
    let vp = Viewport::new(200, 200).unwrap();
    let camera = ortho_front(0.5);
    let field = plane(0.5);
    let front_z = field.z_range[1];
    // Ridgeline: each row hides what lies below it; only the first (front) row shows.
    let options = HorizonOptions::default()
        .with_curves(Curves::Both)
        .with_ridgeline(true)
        .with_hidden(true);
    let (d, _) = run(&field, &camera, vp, &options);
    check_against_brute_force(&field, &camera, vp, &options, &d);
    for p in &d.pieces {
        let e = &d.edges[p.edge as usize];
        let front_row = e.world[0].z == front_z && e.world[1].z == front_z;
        assert_eq!(p.is_visible(), front_row, "{e:?}");
        assert_eq!((p.t[0], p.t[1]), (0.0, 1.0));
    }
    // With both horizons the plane's underside shows below the lower one: all visible.
    let options = HorizonOptions::default()
        .with_curves(Curves::Both)
        .with_hidden(true);
    let (d, s) = run(&field, &camera, vp, &options);
    assert_eq!(s.hidden_pieces, 0);
    assert_eq!(d.pieces.len(), d.edges.len());
}

#[test]
fn a_plane_seen_edge_on_shows_its_first_curve_only() {
    // The line of sight falls 0.1 per unit of z, as the plane y = 0.1 z: every row
    // projects onto the front row's line.
    let vp = Viewport::new(200, 200).unwrap();
    let camera = ortho_front(0.5);
    let field = plane(0.1);
    let options = HorizonOptions::default()
        .with_curves(Curves::Both)
        .with_hidden(true);
    let (d, s) = run(&field, &camera, vp, &options);
    assert_eq!(s.visible_pieces, 8, "only the 8 segments of the front row");
    for p in d.visible() {
        assert_eq!(d.edges[p.edge as usize].world[0].z, 1.0);
    }
}

// ---------------------------------------------------------------------------------
// Refusals

#[test]
fn views_not_from_the_front_are_refused() {
    let field = HeightField::function("bump", 11, 11).unwrap();
    let vp = Viewport::new(100, 100).unwrap();
    let o = HorizonOptions::default();
    let refused = |camera: Camera, what: &str| {
        let e = draw(&field, &camera, vp, &o).unwrap_err();
        assert!(matches!(e, Error::InvalidOption { .. }), "{e}");
        assert!(e.to_string().contains(what), "{e}");
    };
    // From above: the eye's z within [-1, 1].
    refused(
        Camera::perspective(
            DVec3::new(0.0, 5.0, 0.5),
            DVec3::ZERO,
            DVec3::Z * -1.0,
            40.0,
            0.1,
            20.0,
        ),
        "from the front",
    );
    // Orthographic along x: the rows are seen edge on.
    refused(
        Camera::orthographic(
            DVec3::new(5.0, 0.0, 0.0),
            DVec3::ZERO,
            DVec3::Y,
            3.0,
            0.1,
            20.0,
        ),
        "edge on",
    );
    // Rolled by 90 degrees.
    refused(
        Camera::perspective(
            DVec3::new(0.0, 1.0, 5.0),
            DVec3::ZERO,
            DVec3::X,
            40.0,
            0.1,
            20.0,
        ),
        "rolled",
    );
    // In front in z, but the surface behind the camera.
    refused(
        Camera::perspective(
            DVec3::new(0.0, 0.5, 3.0),
            DVec3::new(0.0, 0.5, 6.0),
            DVec3::Y,
            40.0,
            0.1,
            20.0,
        ),
        "near plane",
    );
}

#[test]
fn nan_heights_and_empty_grids_are_refused() {
    let e = HeightField::new(3, 2, vec![0., 1., 2., 3., f64::NAN, 5.]).unwrap_err();
    assert!(e.to_string().contains("row 1, column 1"), "{e}");
    assert!(
        HeightField::new(0, 0, vec![])
            .unwrap_err()
            .to_string()
            .contains("empty")
    );
    assert!(HeightField::new(1, 3, vec![0.; 3]).is_err());
    assert!(HeightField::new(3, 3, vec![0.; 8]).is_err());
    let budget = obscura::budget::MemoryBudget::new(1 << 20);
    assert!(HeightField::from_fn(4, 4, &budget, |x, _| 1.0 / (x - x)).is_err());
    let e = HeightField::from_fn(10_000, 10_000, &budget, |_, _| 0.0).unwrap_err();
    assert!(matches!(e, Error::Budget { .. }), "{e}");
    assert!(
        HeightField::function("nope", 4, 4)
            .unwrap_err()
            .to_string()
            .contains("ripple")
    );
    // A field made by hand is checked by draw too.
    let bad = HeightField {
        heights: vec![0.0, f64::INFINITY, 0.0, 0.0],
        nx: 2,
        nz: 2,
        ..HeightField::default()
    };
    let vp = Viewport::new(50, 50).unwrap();
    assert!(draw(&bad, &ortho_front(0.5), vp, &HorizonOptions::default()).is_err());
    assert!(
        draw(
            &HeightField::default(),
            &ortho_front(0.5),
            vp,
            &HorizonOptions::default()
        )
        .is_err()
    );
}

// ---------------------------------------------------------------------------------
// Loaders

struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> Self {
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "obscura-horizon-{}-{tag}-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, contents).unwrap();
        p
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// An NPY file (version 1) of `descr`, with `data` already encoded.
fn npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
    let f = if fortran { "True" } else { "False" };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': {f}, 'shape': {shape}, }}");
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat(total.div_ceil(64) * 64 - total));
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

/// The 3 x 4 grid of the loader tests (rows z, columns x).
const GRID: [[f64; 4]; 3] = [
    [0.0, 1.0, 2.0, 3.0],
    [4.0, 5.0, 6.5, -7.0],
    [8.0, 9.0, 10.0, 11.0],
];

fn assert_grid(f: &HeightField, scale: f64) {
    assert_eq!((f.nx, f.nz), (4, 3));
    for (k, row) in GRID.iter().enumerate() {
        for (i, &h) in row.iter().enumerate() {
            assert_eq!(f.height(i, k), h * scale, "row {k}, column {i}");
        }
    }
    assert_eq!((f.x(0), f.x(3), f.z(0), f.z(2)), (-1.0, 1.0, -1.0, 1.0));
}

#[test]
fn npy_grids_round_trip() {
    let dir = TempDir::new("npy");
    let flat: Vec<f64> = GRID.iter().flatten().copied().collect();
    let f8: Vec<u8> = flat.iter().flat_map(|v| v.to_le_bytes()).collect();
    let f4: Vec<u8> = flat
        .iter()
        .flat_map(|&v| (v as f32).to_le_bytes())
        .collect();
    let i2: Vec<u8> = flat
        .iter()
        .flat_map(|&v| (v as i16).to_le_bytes())
        .collect();
    let p = dir.write("f8.npy", npy("<f8", false, "(3, 4)", &f8));
    assert_grid(&HeightField::load(&p).unwrap(), 1.0);
    let p = dir.write("f4.npy", npy("<f4", false, "(3, 4)", &f4));
    assert_grid(&HeightField::load(&p).unwrap(), 1.0);
    let p = dir.write("i2.npy", npy("<i2", false, "(3, 4)", &i2));
    let mut g = HeightField::load(&p).unwrap();
    g.heights[6] = 6.5; // the integer file holds 6
    assert_grid(&g, 1.0);
    // Fortran order: columns first.
    let cols: Vec<u8> = (0..4)
        .flat_map(|i| (0..3).map(move |k| GRID[k][i]))
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let p = dir.write("fortran.npy", npy("<f8", true, "(3, 4)", &cols));
    assert_grid(&HeightField::load(&p).unwrap(), 1.0);
    // Refusals name the file and the element.
    let mut nan = f8.clone();
    nan[5 * 8..6 * 8].copy_from_slice(&f64::NAN.to_le_bytes());
    let p = dir.write("nan.npy", npy("<f8", false, "(3, 4)", &nan));
    let e = HeightField::load(&p).unwrap_err().to_string();
    assert!(e.contains("nan.npy") && e.contains("element (1, 1)"), "{e}");
    let p = dir.write("big.npy", npy(">f8", false, "(3, 4)", &f8));
    assert!(
        HeightField::load(&p)
            .unwrap_err()
            .to_string()
            .contains("'>f8'")
    );
    let p = dir.write("empty.npy", npy("<f8", false, "(0, 4)", &[]));
    assert!(
        HeightField::load(&p)
            .unwrap_err()
            .to_string()
            .contains("empty")
    );
    let p = dir.write("short.npy", npy("<f8", false, "(3, 4)", &f8[..40]));
    assert!(
        HeightField::load(&p)
            .unwrap_err()
            .to_string()
            .contains("bytes of data")
    );
    let p = dir.write("three.npy", npy("<f8", false, "(1, 3, 4)", &f8));
    assert!(
        HeightField::load(&p)
            .unwrap_err()
            .to_string()
            .contains("2D")
    );
}

#[test]
fn csv_grids_round_trip() {
    let dir = TempDir::new("csv");
    let text: String = GRID
        .iter()
        .map(|r| {
            r.iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let p = dir.write("g.csv", format!("# heights\n{text}\n\n"));
    assert_grid(&HeightField::load(&p).unwrap(), 1.0);
    let p = dir.write("nan.csv", "1,2\n3,NaN\n");
    let e = HeightField::load(&p).unwrap_err().to_string();
    assert!(e.contains("nan.csv:2") && e.contains("column 2"), "{e}");
    let p = dir.write("ragged.csv", "1,2,3\n4,5\n");
    assert!(
        HeightField::load(&p)
            .unwrap_err()
            .to_string()
            .contains("ragged.csv:2")
    );
    let p = dir.write("word.csv", "1,2\nx,5\n");
    assert!(
        HeightField::load(&p)
            .unwrap_err()
            .to_string()
            .contains("'x' is not a number")
    );
    let p = dir.write("empty.csv", "# nothing\n\n");
    assert!(
        HeightField::load(&p)
            .unwrap_err()
            .to_string()
            .contains("empty")
    );
    let p = dir.write("g.obj", "1,2\n");
    assert!(HeightField::load(&p).is_err());
}

fn write_png(path: &PathBuf, w: u32, h: u32, depth: png::BitDepth, data: &[u8]) {
    let file = std::fs::File::create(path).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(depth);
    let mut writer = enc.write_header().unwrap();
    writer.write_image_data(data).unwrap();
}

#[test]
fn png_grids_round_trip() {
    let dir = TempDir::new("png");
    // 16 bits: the grid's values times 1000 (plus 7000 to stay positive), big-endian.
    let v16: Vec<u16> = GRID
        .iter()
        .flatten()
        .map(|&v| (v * 1000.0 + 7000.0) as u16)
        .collect();
    let bytes: Vec<u8> = v16.iter().flat_map(|v| v.to_be_bytes()).collect();
    let p = dir.0.join("g16.png");
    write_png(&p, 4, 3, png::BitDepth::Sixteen, &bytes);
    let f = HeightField::load(&p).unwrap();
    assert_eq!((f.nx, f.nz), (4, 3));
    for (k, row) in GRID.iter().enumerate() {
        for (i, &h) in row.iter().enumerate() {
            assert_eq!(f.height(i, k), (h * 1000.0 + 7000.0) / 65535.0);
        }
    }
    let bytes: Vec<u8> = GRID.iter().flatten().map(|&v| (v + 7.0) as u8).collect();
    let p = dir.0.join("g8.png");
    write_png(&p, 4, 3, png::BitDepth::Eight, &bytes);
    let f = HeightField::load(&p).unwrap();
    assert_eq!(f.height(3, 1), 0.0);
    assert_eq!(f.height(3, 2), 18.0 / 255.0);
    // Colour images are refused, naming the file.
    let file = std::fs::File::create(dir.0.join("rgb.png")).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), 1, 1);
    enc.set_color(png::ColorType::Rgb);
    enc.write_header()
        .unwrap()
        .write_image_data(&[1, 2, 3])
        .unwrap();
    let e = HeightField::load(dir.0.join("rgb.png"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("rgb.png") && e.contains("grayscale"), "{e}");
}
