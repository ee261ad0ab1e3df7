//! Running time: a time limit and a stop flag for a run, and estimates of the work an
//! algorithm will do before it starts.
//!
//! The memory budget ([`crate::budget`]) bounds what a run allocates; this bounds how
//! long it runs. A few megabytes of input can ask for hours of work: 400,000 copies
//! of one large triangle make every ray of a ray caster test every copy and every
//! painter's algorithm paint every pixel 400,000 times; a brute-force ray caster on a
//! 262k-triangle scene tests 34 billion ray-triangle pairs. Each long run is bounded
//! two ways:
//! - **estimated and refused before it starts**, where the work is a product of
//!   counts known up front ([`Estimate`]): the ray-triangle pairs of brute-force and
//!   bounding-volume ray casting, the pixels the painter's algorithms paint (the sum
//!   of the polygons' areas on screen), the pixels of the image. The estimate is
//!   turned into seconds with the cost per item measured on the reference machine (a
//!   2-core x86-64 of 2026, see the constants), and refused when it passes the limit;
//! - **checked while it runs** ([`Deadline::check`]) in every loop whose length the
//!   input decides (BSP construction and traversal, depth-sort comparisons, Warnock's
//!   windows, rays, octree and grid construction), so that no estimate, however
//!   wrong, lets a run go on past its limit.
//!
//! Either way the run ends with an [`Error::TimeLimit`] that names the work, the
//! estimate when there is one, the limit and the option that raises it
//! ([`crate::surface::RenderOptions::time_limit`]; the CLI's `--time-limit`), or an
//! [`Error::Stopped`] when another thread raised the run's stop flag
//! ([`crate::surface::RenderOptions::stop`]). The library has no time limit unless one
//! is given; the CLI's default is [`CLI_DEFAULT_SECONDS`].

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::{Error, Result};

/// The time limit the command line gives a run unless told otherwise, in seconds.
pub const CLI_DEFAULT_SECONDS: f64 = 8.0;

/// Measured cost of one ray-triangle test of the brute-force and bounding-volume ray
/// casters on the reference machine, both cores (Sponza at 480x270: 34.0 billion tests
/// in 60.2 s), in nanoseconds. Estimates use a little less, so that they refuse only
/// what would certainly pass the limit.
pub const NS_PER_RAY_TRIANGLE: f64 = 1.5;

/// Measured cost of one pixel painted by a painter's algorithm (depth sort, its matrix
/// variant, a back-to-front BSP) on the reference machine, in nanoseconds, rounded
/// down.
pub const NS_PER_PAINTED_PIXEL: f64 = 1.0;

/// Cost of one pixel the z-buffer tests on the reference machine, in nanoseconds,
/// rounded down (its tiles reject most pixels of hidden polygons whole, so this is
/// far below a painter's cost).
pub const NS_PER_ZBUFFER_PIXEL: f64 = 0.1;

/// Cost of one (triangle, voxel) pair of the octree's estimate (an upper bound of
/// the pairs its build meets) on the reference machine, in nanoseconds, rounded down
/// from the least measured: Sponza at depth 7, 2.07e7 pairs built in 136 ms (6.6 ns);
/// 20,000 random large triangles, 1.47e8 pairs in 5.1 s (35 ns).
pub const NS_PER_OCTREE_PAIR: f64 = 5.0;

/// Cost of one piece of a drawing in plotting (joining, removing duplicates, ordering for
/// pen travel: `lines::plot`) on the reference machine, in nanoseconds. Measured on
/// floating horizons: 805,454 pieces in 345 ms (0.43 us each), 7.2 million in 9.5 s
/// (1.3 us each, the memory of the larger drawing costing more per piece); between
/// the two, so a drawing of a few million pieces near the limit may be refused that
/// would have finished, while none runs for many times the limit.
pub const NS_PER_PLOT_PIECE: f64 = 1000.0;

/// A stop flag another thread can raise to stop a run (see [`Deadline`]).
pub type StopFlag = Arc<AtomicBool>;

/// When a run must end: an instant (from a time limit) and a stop flag, each optional.
/// Cheap to clone and to check; checked in the loops whose length the input decides.
///
/// # Example
/// ```
/// use std::time::Duration;
/// use obscura::work::Deadline;
/// let none = Deadline::default();
/// assert!(none.check("BSP construction").is_ok());
/// let spent = Deadline::new(Some(Duration::ZERO), None);
/// let e = spent.check("BSP construction").unwrap_err();
/// assert!(e.to_string().contains("BSP construction") && e.to_string().contains("time_limit"));
/// ```
#[derive(Clone, Debug, Default)]
pub struct Deadline {
    at: Option<Instant>,
    limit: Option<Duration>,
    stop: Option<StopFlag>,
}

impl Deadline {
    /// No limit and no stop flag.
    pub const NONE: Deadline = Deadline {
        at: None,
        limit: None,
        stop: None,
    };

    /// A deadline `limit` from now (`None`: no limit), with an optional stop flag.
    #[must_use]
    pub fn new(limit: Option<Duration>, stop: Option<StopFlag>) -> Self {
        let now = Instant::now();
        Deadline {
            at: limit.map(|l| {
                now.checked_add(l)
                    .unwrap_or(now + Duration::from_secs(1 << 40))
            }),
            limit,
            stop,
        }
    }

    /// The time limit this deadline was made from.
    #[must_use]
    pub fn limit(&self) -> Option<Duration> {
        self.limit
    }

    /// The time left before the deadline (`None`: no limit).
    #[must_use]
    pub fn remaining(&self) -> Option<Duration> {
        self.at
            .map(|at| at.saturating_duration_since(Instant::now()))
    }

    /// Whether the run must end now: the limit passed or the stop flag raised.
    #[must_use]
    pub fn is_over(&self) -> bool {
        self.stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Relaxed))
            || self.at.is_some_and(|at| Instant::now() >= at)
    }

    /// `Ok` while the run may go on; else the error that ends it, naming `work` (what
    /// was being done, e.g. `"BSP construction"`).
    pub fn check(&self, work: &str) -> Result<()> {
        if self.is_over() {
            Err(self.error(work))
        } else {
            Ok(())
        }
    }

    /// The error that ends `work` once [`Deadline::is_over`] said so: stopped when the
    /// flag is raised, else over the time limit.
    #[must_use]
    pub fn error(&self, work: &str) -> Error {
        if self
            .stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Relaxed))
        {
            Error::Stopped {
                work: work.to_string(),
            }
        } else {
            self.exceeded(work, None)
        }
    }

    /// The [`Error::TimeLimit`] of `work` over this deadline's limit, with an estimate
    /// in seconds when the work was refused before it started.
    #[must_use]
    pub fn exceeded(&self, work: &str, estimate_s: Option<f64>) -> Error {
        Error::TimeLimit {
            work: work.to_string(),
            estimate_s,
            limit_s: self.limit.map_or(0.0, |l| l.as_secs_f64()),
            option: "time_limit".to_string(),
            at: None,
        }
    }

    /// Refuses `work` before it starts when its estimate passes the time left.
    pub fn admit(&self, estimate: &Estimate) -> Result<()> {
        match self.remaining() {
            Some(left) if estimate.seconds > left.as_secs_f64() => {
                Err(self.exceeded(&estimate.describe(), Some(estimate.seconds)))
            }
            _ => Ok(()),
        }
    }
}

/// An estimate of the work an algorithm will do: a count of items of one kind and
/// what they take on the reference machine.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// What is counted, e.g. `"ray-triangle tests"`.
    pub items: &'static str,
    /// How many.
    pub count: f64,
    /// The seconds they take on the reference machine.
    pub seconds: f64,
    /// What is doing the work, e.g. `"raycast"`.
    pub by: String,
}

impl Estimate {
    /// `count` items of `ns_each` nanoseconds each, done by `by`.
    #[must_use]
    pub fn new(by: &str, items: &'static str, count: f64, ns_each: f64) -> Self {
        Estimate {
            items,
            count,
            seconds: count * ns_each * 1e-9,
            by: by.to_string(),
        }
    }

    /// `by: about N items` for messages.
    #[must_use]
    pub fn describe(&self) -> String {
        format!(
            "{}: about {} {}",
            self.by,
            readable_count(self.count),
            self.items
        )
    }
}

/// A large count in three significant digits (`3.4e10`), small ones as integers.
#[must_use]
pub fn readable_count(n: f64) -> String {
    if n < 1e6 {
        format!("{}", n.round() as u64)
    } else {
        let s = format!("{n:.2e}");
        // 3.40e10 -> 3.4e10
        match s.split_once('e') {
            Some((m, e)) => {
                let m = m.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{e}")
            }
            None => s,
        }
    }
}

/// The message of an [`Error::TimeLimit`].
pub(crate) fn time_limit_message(
    work: &str,
    estimate_s: Option<f64>,
    limit_s: f64,
    option: &str,
) -> String {
    let limit = readable_seconds(limit_s);
    match estimate_s {
        Some(e) => format!(
            "{work} would take about {} on the reference machine, over the time limit \
             ({limit} left); raise the limit with {option}, or reduce the input or the \
             image size",
            readable_seconds(e)
        ),
        // A run's limit already spent when this work was to start (a `compare` whose
        // earlier algorithms took the time).
        None if limit_s < 1e-3 => format!(
            "{work}: not started, no time left under the time limit; raise the limit with \
             {option}, or reduce the input or the image size"
        ),
        None => format!(
            "{work}: stopped at the time limit of {limit}; raise the limit with {option}, \
             or reduce the input or the image size"
        ),
    }
}

/// Seconds in a message: `8 s`, `0.25 s`, `1.2e3 s`.
fn readable_seconds(s: f64) -> String {
    if s >= 1e4 {
        format!("{s:.1e} s")
    } else if s >= 10.0 {
        format!("{s:.0} s")
    } else {
        format!("{} s", (s * 100.0).round() / 100.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_limit_never_ends() {
        let d = Deadline::default();
        assert!(!d.is_over());
        assert!(d.remaining().is_none());
        assert!(
            d.admit(&Estimate::new("raycast", "ray-triangle tests", 1e30, 1.0))
                .is_ok()
        );
    }

    #[test]
    fn a_spent_limit_ends_with_the_work_named() {
        let d = Deadline::new(Some(Duration::ZERO), None);
        let e = d.check("Warnock windows").unwrap_err();
        assert!(
            matches!(
                e,
                Error::TimeLimit {
                    estimate_s: None,
                    ..
                }
            ),
            "{e}"
        );
        let m = e.to_string();
        assert!(
            m.contains("Warnock windows") && m.contains("time_limit"),
            "{m}"
        );
    }

    #[test]
    fn a_raised_stop_flag_ends_with_stopped() {
        let flag: StopFlag = Arc::new(AtomicBool::new(false));
        let d = Deadline::new(None, Some(flag.clone()));
        assert!(d.check("rays").is_ok());
        flag.store(true, Ordering::Relaxed);
        let e = d.check("rays").unwrap_err();
        assert!(matches!(e, Error::Stopped { .. }), "{e}");
        assert!(e.to_string().contains("rays"));
    }

    #[test]
    fn estimates_over_the_time_left_are_refused() {
        let d = Deadline::new(Some(Duration::from_secs(8)), None);
        // 1e10 tests at 1.5 ns: 15 s.
        let big = Estimate::new("raycast", "ray-triangle tests", 1e10, 1.5);
        assert!((big.seconds - 15.0).abs() < 1e-9);
        let e = d.admit(&big).unwrap_err();
        let m = e.to_string();
        assert!(m.contains("raycast: about 1e10 ray-triangle tests"), "{m}");
        assert!(m.contains("15 s"), "{m}");
        // 1e9 tests: 1.5 s, admitted.
        let small = Estimate::new("raycast", "ray-triangle tests", 1e9, 1.5);
        assert!(d.admit(&small).is_ok());
    }

    #[test]
    fn counts_read_well() {
        assert_eq!(readable_count(123.4), "123");
        assert_eq!(readable_count(3.4e10), "3.4e10");
        assert_eq!(readable_count(1.0e7), "1e7");
        assert_eq!(readable_count(1.23456e12), "1.23e12");
    }
}
