//! The per-stage counts and times of the view pipeline (`--stats`).

use std::time::Instant;

use serde::Serialize;

/// Counts and time of one pipeline stage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageStats {
    /// The stage's name.
    pub stage: &'static str,
    /// What is counted: `objects`, `vertices`, `faces` or `polygons`.
    pub unit: &'static str,
    /// How many went in.
    pub input: u64,
    /// How many came out.
    pub output: u64,
    /// Milliseconds spent.
    pub ms: f64,
}

/// The stages of [`prepare`](super::prepare), in order.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PipelineStats {
    /// One entry per stage.
    pub stages: Vec<StageStats>,
}

impl PipelineStats {
    pub(super) fn push(
        &mut self,
        stage: &'static str,
        unit: &'static str,
        input: u64,
        output: u64,
        since: Instant,
    ) {
        self.stages.push(StageStats {
            stage,
            unit,
            input,
            output,
            ms: since.elapsed().as_secs_f64() * 1e3,
        });
    }

    pub(super) fn push_ms(
        &mut self,
        stage: &'static str,
        unit: &'static str,
        input: u64,
        output: u64,
        ms: f64,
    ) {
        self.stages.push(StageStats {
            stage,
            unit,
            input,
            output,
            ms,
        });
    }

    pub(super) fn push_untimed(
        &mut self,
        stage: &'static str,
        unit: &'static str,
        input: u64,
        output: u64,
    ) {
        self.stages.push(StageStats {
            stage,
            unit,
            input,
            output,
            ms: 0.0,
        });
    }

    /// The one stage whose name starts with `name` (a name may carry a note after it,
    /// e.g. "faces: clip (Sutherland-Hodgman) (timed above)" for "faces: clip"):
    /// `None` if no stage or several match. Pick stages by name, not by position.
    #[must_use]
    pub fn stage(&self, name: &str) -> Option<&StageStats> {
        let mut found = self.stages.iter().filter(|s| s.stage.starts_with(name));
        let first = found.next()?;
        found.next().is_none().then_some(first)
    }

    /// Total milliseconds of all stages.
    #[must_use]
    pub fn total_ms(&self) -> f64 {
        self.stages.iter().map(|s| s.ms).sum()
    }
}
