//! Coherence between rows (seed 003: "if no new segments appear in the list, the
//! order stays the same and the nearest face is not sought again"): the previous
//! row's spans with several faces, each with its set of faces, its nearest face and
//! whether that face is known to stay the nearest.
//!
//! Spans are asked for left to right, so a cursor finds the previous row's span at the
//! same place in amortised O(1). A set of faces is recognised by an order-independent
//! hash kept up to date as flags flip, then confirmed member by member (the members
//! are slots; `faces` guarantees a slot named by the previous row still holds the same
//! face, or none). Memory: one `u32` per face per remembered span, reused row to row.

/// Whether the nearest face of a set of faces is known to stay the nearest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Order {
    /// Not checked yet (the set was seen on one row only).
    Unknown,
    /// The winner hides every other face of the set wherever they overlap.
    Fixed,
    /// The check failed: faces of the set may swap, so it is not tried again.
    MayChange,
}

/// A span with several faces remembered for the next row.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RememberedSpan {
    x0: u32,
    x1: u32,
    hash: u64,
    count: u32,
    /// The slot of the nearest face.
    pub winner: u32,
    /// What is known of the order.
    pub order: Order,
    /// Its faces' slots in the members array.
    members: (u32, u32),
}

/// The previous row's multi-face spans, and the current row's being recorded.
#[derive(Debug, Default)]
pub(crate) struct Coherence {
    previous: Vec<RememberedSpan>,
    previous_members: Vec<u32>,
    current: Vec<RememberedSpan>,
    current_members: Vec<u32>,
    cursor: usize,
}

impl Coherence {
    /// The current row becomes the previous one.
    pub fn next_row(&mut self) {
        std::mem::swap(&mut self.previous, &mut self.current);
        std::mem::swap(&mut self.previous_members, &mut self.current_members);
        self.current.clear();
        self.current_members.clear();
        self.cursor = 0;
    }

    /// The previous row's span overlapping `x0..x1` with exactly the set of faces in
    /// now (`count` faces with this hash; `position[s] != NONE` for the slots in it).
    #[inline]
    pub fn find(
        &mut self,
        x0: u32,
        x1: u32,
        hash: u64,
        count: usize,
        position: &[u32],
    ) -> Option<RememberedSpan> {
        while self.cursor < self.previous.len() && self.previous[self.cursor].x1 <= x0 {
            self.cursor += 1;
        }
        self.previous[self.cursor..]
            .iter()
            .take_while(|s| s.x0 < x1)
            .find(|s| {
                s.hash == hash
                    && s.count as usize == count
                    && self.previous_members[s.members.0 as usize..s.members.1 as usize]
                        .iter()
                        .all(|&m| position[m as usize] != super::faces::NONE)
            })
            .copied()
    }

    /// Records a span of this row with its faces' slots.
    #[inline]
    pub fn remember(
        &mut self,
        span: (u32, u32),
        hash: u64,
        members: &[u32],
        winner: u32,
        order: Order,
    ) {
        let a = self.current_members.len() as u32;
        self.current_members.extend_from_slice(members);
        let b = self.current_members.len() as u32;
        self.current.push(RememberedSpan {
            x0: span.0,
            x1: span.1,
            hash,
            count: b - a,
            winner,
            order,
            members: (a, b),
        });
    }
}
