//! Placeholder: being implemented.

/// How a BSP tree chooses its splitting planes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct BspOptions {
    /// Candidate planes sampled per node.
    pub candidates: usize,
    /// Cost weight of a polygon split by the plane.
    pub split_weight: f64,
    /// Cost weight of the imbalance between the two sides.
    pub balance_weight: f64,
}

impl Default for BspOptions {
    fn default() -> Self {
        BspOptions {
            candidates: 8,
            split_weight: 8.0,
            balance_weight: 1.0,
        }
    }
}
