//! The block rasterizer against the per-pixel rule, and its kernels against each other.

use super::pairs::PAIR_WIDTH;
use super::setup::whole_to_u32;
use super::*;
use crate::raster::lanes::{Lanes, Portable, key_of};
use crate::raster::{FillRule, PixelRect};
use crate::rng::SplitMix64;

/// The bits of a setup, for comparisons that tell `-0.0` from `0.0` and accept
/// equal NaNs.
fn setup_bits(s: &BlockSetup<3>) -> Vec<u64> {
    let mut v: Vec<u64> = [s.ox, s.oy, s.sdx, s.sdy, s.bound]
        .iter()
        .flatten()
        .map(|x| x.to_bits())
        .collect();
    v.extend([s.z0, s.dzdx, s.dzdy].map(f64::to_bits));
    v.extend([s.rect.x0, s.rect.y0, s.rect.x1, s.rect.y1].map(u64::from));
    v
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
fn triangles8_avx512(
    _: crate::cpu::Avx512,
    p: &TrianglePoints,
    fill: FillRule,
    w: u32,
    h: u32,
) -> TriangleBatch {
    triangles8(p, fill, w, h)
}

/// A random triangle of one of the kinds the setups must agree on.
fn random_triangle(rng: &mut SplitMix64) -> [(f64, f64, f64); 3] {
    let kind = rng.next_u64() % 8;
    let scale = [0.3, 2.0, 9.0, 40.0, 300.0, 1e-6, 5e8, 4.0][kind as usize];
    let (cx, cy) = (rng.range(-20.0, 140.0), rng.range(-20.0, 100.0));
    let mut p = [(0.0, 0.0, 0.0); 3];
    for q in &mut p {
        *q = (
            cx + rng.range(-1.0, 1.0) * scale,
            cy + rng.range(-1.0, 1.0) * scale,
            rng.range(0.001, 1.0),
        );
        if kind == 7 {
            // On the pixel-centre grid and its lines: ties on edges and samples.
            *q = ((q.0 * 2.0).round() / 2.0, (q.1 * 2.0).round() / 2.0, q.2);
        }
    }
    match rng.next_u64() % 16 {
        0 => p[2] = p[0], // two equal points: no area
        1 => p[2] = (2.0 * p[1].0 - p[0].0, 2.0 * p[1].1 - p[0].1, p[2].2), // collinear
        2 => p[1].0 = f64::NAN,
        3 => p[2].1 = f64::INFINITY,
        4 => p[0].2 = f64::NAN, // a non-finite depth
        5 => p[1].1 = p[0].1,   // a horizontal edge
        _ => {}
    }
    p
}

#[test]
fn eight_triangles_at_once_are_set_up_as_one_at_a_time() {
    let mut rng = SplitMix64(41);
    let (w, h) = (120, 80);
    let mut valid = 0;
    #[cfg(target_arch = "x86_64")]
    let fast = crate::cpu::Avx512::new();
    #[cfg(target_arch = "x86_64")]
    if fast.is_none() {
        crate::cpu::simd_test_skipped(
            "AVX-512",
            "eight triangles set up with AVX-512 against one at a time",
        );
    }
    for _ in 0..4000 {
        let tris: Vec<_> = (0..8).map(|_| random_triangle(&mut rng)).collect();
        let mut pts = TrianglePoints::default();
        for (l, t) in tris.iter().enumerate() {
            for (v, q) in t.iter().enumerate() {
                (pts.x[v][l], pts.y[v][l], pts.zq[v][l]) = *q;
            }
        }
        for fill in [FillRule::TopLeft, FillRule::Inclusive] {
            let mut batches = vec![triangles8(&pts, fill, w, h)];
            #[cfg(target_arch = "x86_64")]
            if let Some(cpu) = fast {
                // SAFETY: `Avx512::new` checked every feature `triangles8_avx512` enables.
                batches.push(unsafe { triangles8_avx512(cpu, &pts, fill, w, h) });
            }
            for batch in &batches {
                for (l, t) in tris.iter().enumerate() {
                    let one = triangle(*t, fill, w, h);
                    assert_eq!(batch.valid >> l & 1 == 1, one.is_some(), "{t:?}");
                    if let Some(one) = one {
                        valid += 1;
                        assert_eq!(setup_bits(&batch.get(l)), setup_bits(&one), "{t:?}");
                    }
                }
            }
        }
    }
    // Most random triangles are valid; the special kinds make the rest.
    assert!(valid > 20_000, "{valid}");
}

/// One triangle drawn alone into an empty `w x h` buffer with `align`: its keys,
/// ids and counts.
fn draw_alone<L: Lanes>(
    l: L,
    s: &BlockSetup<3>,
    align: Align,
    w: u32,
    h: u32,
) -> (Vec<f32>, Vec<u32>, Counts) {
    let (mut keys, mut ids) = (vec![0.0; (w * h) as usize], vec![0; (w * h) as usize]);
    let mut counts = Counts::default();
    let mut target = BlockTarget::new(&mut keys, &mut ids, w as usize, 0, 0).unwrap();
    let whole = target.rect();
    // Then twice more over the same keys: exact ties everywhere, which the larger
    // encoded id (9) wins and the smaller (8) loses.
    for face in [7, 9, 8] {
        draw(l, s, whole, align, &mut target, face, &mut counts);
    }
    (keys, ids, counts)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
fn draw_alone_avx512(
    l: crate::cpu::Avx512,
    s: &BlockSetup<3>,
    align: Align,
    w: u32,
    h: u32,
) -> (Vec<f32>, Vec<u32>, Counts) {
    draw_alone(l, s, align, w, h)
}

#[test]
fn narrow_polygons_drawn_row_by_row_cover_the_samples_of_the_rule() {
    // Polygons at most 16 pixels wide drawn with `Align::Polygon` take the
    // row-by-row walk (two rows at a time up to four pixels wide); with
    // `Align::Grid` the block walk, which classifies blocks (and skips the edge
    // tests in covered ones). Both must give exactly the pixels whose sample the
    // per-pixel rule covers, with the same keys, and break ties alike.
    let mut rng = SplitMix64(23);
    let (w, h) = (120, 80);
    let (mut paired, mut narrow, mut wide) = (0, 0, 0);
    #[cfg(target_arch = "x86_64")]
    let fast = crate::cpu::Avx512::new();
    #[cfg(target_arch = "x86_64")]
    if fast.is_none() {
        crate::cpu::simd_test_skipped(
            "AVX-512",
            "polygons drawn with AVX-512 lanes against portable ones",
        );
    }
    for _ in 0..6000 {
        let t = random_triangle(&mut rng);
        for fill in [FillRule::TopLeft, FillRule::Inclusive] {
            let Some(s) = triangle(t, fill, w, h) else {
                continue;
            };
            let width = s.rect.x1 - s.rect.x0;
            // (A non-finite depth wins no pixel: not what this test is about.)
            if width > 2 * BLOCK || !(s.z0 + s.dzdx + s.dzdy).is_finite() {
                continue;
            }
            if width <= PAIR_WIDTH {
                paired += 1;
            } else if width <= BLOCK {
                narrow += 1;
            } else {
                wide += 1;
            }
            let mut runs = vec![
                draw_alone(Portable, &s, Align::Polygon, w, h),
                draw_alone(Portable, &s, Align::Grid, w, h),
            ];
            #[cfg(target_arch = "x86_64")]
            if let Some(l) = fast {
                for align in [Align::Polygon, Align::Grid] {
                    // SAFETY: `Avx512::new` checked every feature `draw_alone_avx512` enables.
                    runs.push(unsafe { draw_alone_avx512(l, &s, align, w, h) });
                }
            }
            let (keys, ids, counts) = &runs[0];
            let mut covered = 0;
            for j in 0..h {
                for i in 0..w {
                    let at = (j * w + i) as usize;
                    let inside = s.covers_sample(f64::from(i) + 0.5, f64::from(j) + 0.5);
                    covered += u64::from(inside);
                    assert_eq!(ids[at] == 9, inside, "{t:?} {fill:?} pixel ({i}, {j})");
                    assert_eq!(keys[at] > 0.0, inside, "{t:?} {fill:?} pixel ({i}, {j})");
                }
            }
            assert_eq!(counts.tested, 3 * covered, "{t:?}");
            assert_eq!(counts.written, 2 * covered, "{t:?}");
            for (k, run) in runs.iter().enumerate().skip(1) {
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&run.0), bits(keys), "run {k}: {t:?} {fill:?}");
                assert_eq!(&run.1, ids, "run {k}: {t:?} {fill:?}");
                assert_eq!(run.2, *counts, "run {k}: {t:?} {fill:?}");
            }
        }
    }
    assert!(
        paired > 300 && narrow > 300 && wide > 300,
        "{paired} paired, {narrow} narrow, {wide} wide"
    );
}

#[test]
fn whole_numbers_convert_as_the_cast_does() {
    let mut rng = SplitMix64(5);
    let specials = [0.0, -0.0, 1.0, 1920.0, 16384.0, 65535.0, 4_294_967_295.0];
    let random = (0..10_000).map(|_| (rng.next_u64() >> 32) as f64);
    for v in specials.into_iter().chain(random) {
        assert_eq!(whole_to_u32(v), v as u32, "{v}");
    }
}

#[test]
fn nearest_key_bounds_every_key_of_the_rectangle() {
    let mut rng = SplitMix64(17);
    let mut tight = 0;
    for round in 0..3000 {
        let x0 = (rng.next_u64() % 200) as u32;
        let y0 = (rng.next_u64() % 200) as u32;
        let rect = PixelRect {
            x0,
            y0,
            x1: x0 + 1 + (rng.next_u64() % 40) as u32,
            y1: y0 + 1 + (rng.next_u64() % 40) as u32,
        };
        let scale = [1.0, 1e-3, 1e3][round % 3];
        let s = BlockSetup::<0> {
            ox: [],
            oy: [],
            sdx: [],
            sdy: [],
            bound: [],
            rect,
            z0: rng.range(-0.1, 1.0),
            dzdx: rng.range(-1e-2, 1e-2) * scale,
            dzdy: rng.range(-1e-2, 1e-2) / scale,
        };
        let near = nearest_key(&s, rect);
        let mut top = 0.0f32;
        for j in rect.y0..rect.y1 {
            for i in rect.x0..rect.x1 {
                // Both orders of the sum: the row part first (as `key`), the column
                // part first.
                let a = key_of(s.key(i, j));
                let b = key_of(
                    s.z0 + (s.dzdx * (f64::from(i) - f64::from(rect.x0))
                        + s.dzdy * (f64::from(j) - f64::from(rect.y0))),
                );
                assert!(a <= near && b <= near, "{s:?}: {a} {b} {near}");
                top = top.max(a);
            }
        }
        tight += usize::from(top == near);
    }
    // The margin is far below an f32 unit: the bound is usually the largest key.
    assert!(tight > 2500, "{tight}");
    let nan = BlockSetup::<0> {
        ox: [],
        oy: [],
        sdx: [],
        sdy: [],
        bound: [],
        rect: PixelRect {
            x0: 0,
            y0: 0,
            x1: 2,
            y1: 2,
        },
        z0: f64::NAN,
        dzdx: 0.0,
        dzdy: 0.0,
    };
    assert!(nearest_key(&nan, nan.rect).is_nan());
}

/// The halving minimum equals the serial `f32::min` fold on keys as the buffers hold
/// them (zero, positive, infinite; any order), the minimum anywhere among the lanes.
#[test]
fn min16_is_the_smallest_lane() {
    let mut rng = crate::rng::SplitMix64(16);
    for k in 0..2000 {
        let mut m = [0.0f32; 16];
        for v in &mut m {
            *v = match rng.range(0.0, 4.0) as u32 {
                0 => 0.0,
                1 => f32::INFINITY,
                _ => rng.range(1e-6, 10.0) as f32,
            };
        }
        // Every position once the smallest, zero or not.
        if k % 2 == 0 {
            m[k / 2 % 16] = 1e-9;
        }
        let fold = m.into_iter().fold(f32::INFINITY, f32::min);
        assert_eq!(super::min16(m).to_bits(), fold.to_bits(), "{m:?}");
    }
}
