//! Quantitative invisibility along one edge: the covers of its occluders swept in
//! parameter order, the edge cut at every cover's end, each piece given the number of
//! faces in front of it (Appel's quantitative invisibility), neighbours of equal
//! invisibility merged.

use super::cut::Cover;

/// Pieces shorter than this in the edge's parameter (relative to the whole edge) are
/// rounding, not geometry (e.g. a shared vertex whose eye-space position misses an
/// occluder's plane by an ulp): they are given to the piece before them (or after, for
/// the first).
pub(super) const MIN_PIECE: f64 = 1e-12;

/// A piece of an edge before it is projected: parameter interval and invisibility.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct RawPiece {
    pub t: [f64; 2],
    pub invisibility: u32,
}

/// Work space reused from edge to edge.
#[derive(Default)]
pub(super) struct Sweep {
    cuts: Vec<f64>,
    order: Vec<u32>,
    active: Vec<u32>,
    faces: Vec<u32>,
}

impl Sweep {
    /// Cuts the interval `range` at every end of `covers` and appends the pieces to
    /// `out`. A piece's invisibility is the number of distinct faces that cover it
    /// through their interior, plus one when boundaries of other faces cover it too (an
    /// edge lying exactly behind a drawn edge is hidden once, however many faces meet
    /// along that edge).
    pub fn pieces(&mut self, range: [f64; 2], covers: &[Cover], out: &mut Vec<RawPiece>) {
        let start = out.len();
        self.cuts.clear();
        self.cuts.push(range[0]);
        self.cuts.push(range[1]);
        for c in covers {
            self.cuts.push(c.t[0]);
            self.cuts.push(c.t[1]);
        }
        self.cuts.sort_unstable_by(f64::total_cmp);
        self.cuts.dedup();
        self.order.clear();
        self.order.extend(0..covers.len() as u32);
        self.order
            .sort_unstable_by(|&a, &b| covers[a as usize].t[0].total_cmp(&covers[b as usize].t[0]));
        self.active.clear();
        let mut next = 0;
        for k in 1..self.cuts.len() {
            let (a, b) = (self.cuts[k - 1], self.cuts[k]);
            if a < range[0] || b > range[1] {
                continue;
            }
            while next < self.order.len() && covers[self.order[next] as usize].t[0] <= a {
                self.active.push(self.order[next]);
                next += 1;
            }
            self.active.retain(|&k| covers[k as usize].t[1] >= b);
            let invisibility = self.count(covers);
            push_piece(out, start, [a, b], invisibility);
        }
        if out.len() > start
            && out[start].t[1] - out[start].t[0] < MIN_PIECE
            && out.len() > start + 1
        {
            // A first piece too short for any other: given to the next.
            let t0 = out[start].t[0];
            out.remove(start);
            out[start].t[0] = t0;
        }
    }

    fn count(&mut self, covers: &[Cover]) -> u32 {
        let faces = &mut self.faces;
        faces.clear();
        let mut boundary_only = false;
        for &k in &self.active {
            let c = &covers[k as usize];
            if !c.boundary && !faces.contains(&c.face) {
                faces.push(c.face);
            }
        }
        for &k in &self.active {
            let c = &covers[k as usize];
            if c.boundary && !faces.contains(&c.face) {
                boundary_only = true;
            }
        }
        faces.len() as u32 + u32::from(boundary_only)
    }
}

/// Appends a piece, merging it with the last one (from `start`) of equal invisibility,
/// and giving a piece too short to matter to the one before. (Only the first piece can
/// be too short and stand; [`Sweep::pieces`] gives it to the second.)
fn push_piece(out: &mut Vec<RawPiece>, start: usize, t: [f64; 2], invisibility: u32) {
    if let Some(last) = out[start..].last_mut()
        && (last.invisibility == invisibility || t[1] - t[0] < MIN_PIECE)
    {
        last.t[1] = t[1];
        return;
    }
    out.push(RawPiece { t, invisibility });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cover(t0: f64, t1: f64, face: u32, boundary: bool) -> Cover {
        Cover {
            t: [t0, t1],
            face,
            boundary,
        }
    }

    fn run(covers: &[Cover]) -> Vec<(f64, f64, u32)> {
        let mut out = Vec::new();
        Sweep::default().pieces([0.0, 1.0], covers, &mut out);
        out.iter()
            .map(|p| (p.t[0], p.t[1], p.invisibility))
            .collect()
    }

    #[test]
    fn no_cover_is_one_visible_piece() {
        assert_eq!(run(&[]), vec![(0.0, 1.0, 0)]);
    }

    #[test]
    fn overlapping_covers_count_and_abutting_ones_merge() {
        let got = run(&[
            cover(0.2, 0.5, 1, false),
            cover(0.4, 0.8, 2, false),
            // Two polygons of face 3 meeting at 0.65 (a shared diagonal): one face.
            cover(0.6, 0.65, 3, false),
            cover(0.65, 0.7, 3, false),
        ]);
        assert_eq!(
            got,
            vec![
                (0.0, 0.2, 0),
                (0.2, 0.4, 1),
                (0.4, 0.5, 2),
                (0.5, 0.6, 1),
                (0.6, 0.7, 2),
                (0.7, 0.8, 1),
                (0.8, 1.0, 0)
            ]
        );
    }

    #[test]
    fn boundaries_hide_once() {
        // Two faces meeting along the edge's image, both in front: hidden once.
        let got = run(&[cover(0.0, 1.0, 1, true), cover(0.0, 1.0, 2, true)]);
        assert_eq!(got, vec![(0.0, 1.0, 1)]);
        // Boundaries of other faces add one to the faces covering through their
        // interior; a face's own boundary adds nothing.
        let got = run(&[cover(0.0, 1.0, 1, false), cover(0.5, 1.0, 2, true)]);
        assert_eq!(got, vec![(0.0, 0.5, 1), (0.5, 1.0, 2)]);
        let got = run(&[cover(0.0, 1.0, 1, false), cover(0.5, 1.0, 1, true)]);
        assert_eq!(got, vec![(0.0, 1.0, 1)]);
    }

    #[test]
    fn rounding_slivers_are_absorbed() {
        let got = run(&[cover(0.0, 1e-15, 1, false), cover(0.3, 0.7, 2, false)]);
        assert_eq!(got, vec![(0.0, 0.3, 0), (0.3, 0.7, 1), (0.7, 1.0, 0)]);
        let got = run(&[cover(0.5, 0.5 + 1e-14, 1, false)]);
        assert_eq!(got, vec![(0.0, 1.0, 0)]);
    }
}
