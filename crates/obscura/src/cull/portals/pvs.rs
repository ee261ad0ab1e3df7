//! The PVS table: per cell, the cells potentially visible from anywhere inside it
//! (seed 000 "από-Περιοχή (1)-(3)"; `ALGORITHMS.md`, worked example 4).
//!
//! Row `c` is read off the stab tree of `c` ([`super::stab`]); the table is then made
//! symmetric (each row united with its column), which is sound because visibility
//! between two regions is symmetric: a line of sight from `a` to `b` is one from `b`
//! to `a`. Computed once per scene ([`crate::SceneIndex::pvs`]), in parallel over the
//! cells with the `parallel` feature, with a progress callback, a deadline and a
//! budget of portal sequences per cell.

use std::sync::atomic::{AtomicUsize, Ordering};

use super::model::CellGraph;
use super::stab::{Adjacency, stab_tree};
use crate::Result;
use crate::work::Deadline;

/// Options of [`compute`].
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct PvsOptions {
    /// Portal sequences tested per source cell before its row falls back to every
    /// cell the graph reaches (conservative).
    pub max_sequences: u64,
    /// When the computation must end.
    pub deadline: Deadline,
}

impl Default for PvsOptions {
    fn default() -> Self {
        PvsOptions {
            max_sequences: 200_000,
            deadline: Deadline::NONE,
        }
    }
}

/// The PVS table, one bit per (from, to) cell pair.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pvs {
    cells: usize,
    words: usize,
    bits: Vec<u64>,
    /// The cells whose stab tree passed the budget (their rows hold every reachable
    /// cell).
    pub incomplete: Vec<u32>,
    /// Portal sequences tested, all cells together.
    pub sequences: u64,
}

impl Pvs {
    /// A table of `cells` cells with nothing visible.
    #[must_use]
    pub fn empty(cells: usize) -> Pvs {
        let words = cells.div_ceil(64);
        Pvs {
            cells,
            words,
            bits: vec![0; cells * words],
            incomplete: Vec::new(),
            sequences: 0,
        }
    }

    /// The number of cells.
    #[must_use]
    pub fn len(&self) -> usize {
        self.cells
    }

    /// Whether the table has no cells.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.cells == 0
    }

    /// Whether cell `to` is potentially visible from cell `from` (`false` for cells
    /// out of range).
    #[must_use]
    pub fn contains(&self, from: u32, to: u32) -> bool {
        let (f, t) = (from as usize, to as usize);
        f < self.cells && t < self.cells && self.bits[f * self.words + t / 64] >> (t % 64) & 1 == 1
    }

    /// Marks `to` visible from `from`.
    pub fn insert(&mut self, from: u32, to: u32) {
        let (f, t) = (from as usize, to as usize);
        self.bits[f * self.words + t / 64] |= 1 << (t % 64);
    }

    /// The cells visible from `from`, in order.
    pub fn row(&self, from: u32) -> impl Iterator<Item = u32> + '_ {
        (0..self.cells as u32).filter(move |&t| self.contains(from, t))
    }

    /// How many cells are visible from `from`.
    #[must_use]
    pub fn count(&self, from: u32) -> usize {
        let f = from as usize;
        self.bits[f * self.words..(f + 1) * self.words]
            .iter()
            .map(|w| w.count_ones() as usize)
            .sum()
    }

    /// Whether the table is symmetric.
    #[must_use]
    pub fn is_symmetric(&self) -> bool {
        (0..self.cells as u32)
            .all(|a| (0..self.cells as u32).all(|b| self.contains(a, b) == self.contains(b, a)))
    }

    /// Unites each row with its column.
    fn symmetrize(&mut self) {
        for a in 0..self.cells as u32 {
            for b in 0..a {
                if self.contains(a, b) || self.contains(b, a) {
                    self.insert(a, b);
                    self.insert(b, a);
                }
            }
        }
    }
}

/// The PVS table of a cell graph: each cell's stab tree, then the union with the
/// transpose. `progress(done, total)` is called as cells finish (from any thread).
///
/// # Errors
/// [`crate::Error::TimeLimit`] or [`crate::Error::Stopped`] from the options'
/// deadline.
///
/// # Example
/// ```
/// use obscura::cull::portals::{Cell, CellGraph, Portal, pvs};
/// let g = CellGraph::new(vec![], vec![]);
/// let t = pvs::compute(&g, &pvs::PvsOptions::default(), &|_, _| {}).unwrap();
/// assert!(t.is_empty());
/// ```
pub fn compute(
    graph: &CellGraph,
    options: &PvsOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Pvs> {
    let n = graph.cells.len();
    let adjacency = Adjacency::new(graph);
    let done = AtomicUsize::new(0);
    let row = |c: usize| -> Result<(Vec<bool>, bool, u64)> {
        let tree = stab_tree(
            graph,
            &adjacency,
            c as u32,
            options.max_sequences,
            &options.deadline,
        )?;
        let v = tree.visible(&adjacency);
        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
        progress(d, n);
        Ok((v, tree.complete, tree.sequences))
    };
    #[cfg(feature = "parallel")]
    let rows: Vec<Result<(Vec<bool>, bool, u64)>> = {
        use rayon::prelude::*;
        (0..n).into_par_iter().map(row).collect()
    };
    #[cfg(not(feature = "parallel"))]
    let rows: Vec<Result<(Vec<bool>, bool, u64)>> = (0..n).map(row).collect();
    let mut pvs = Pvs::empty(n);
    for (a, r) in rows.into_iter().enumerate() {
        let (visible, complete, sequences) = r?;
        pvs.sequences += sequences;
        if !complete {
            pvs.incomplete.push(a as u32);
        }
        for (b, &v) in visible.iter().enumerate() {
            if v {
                pvs.insert(a as u32, b as u32);
            }
        }
    }
    pvs.symmetrize();
    Ok(pvs)
}
