//! One memory budget for a run: every structure whose size depends on the input is
//! held to it.
//!
//! A scene file of a few kilobytes can describe billions of faces (one mesh placed
//! ten thousand times), and a few thousand polygons can make a structure grow without
//! end (random large triangles cut a BSP tree's polygons into millions of fragments).
//! Without a bound such a run grows until the allocator fails and the process aborts,
//! naming nothing. With a budget, each such structure is either
//! - **estimated and refused before it is allocated** (frame buffers, the z-buffer's
//!   big-polygon bins, octree nodes from the depth and the scene, the prepared view,
//!   a scene file's instancing totals, acceleration grids), or
//! - **counted while it grows and stopped at the budget** (BSP fragments, depth-sort
//!   splits),
//!
//! with an [`Error::Budget`] that names the structure, the count reached, the bytes
//! and the option that raises the limit (`memory_limit` of
//! [`crate::surface::RenderOptions`] and [`crate::scene::load::LoadOptions`]; the CLI's
//! `--memory-limit`). `Vec::try_reserve` backs the estimates up where a count is only
//! known at run time ([`try_vec`]).
//!
//! # The default
//! [`MemoryBudget::default_limit`]: half of the memory available to the process, the
//! least of
//! - `MemAvailable` of `/proc/meminfo` (Linux),
//! - the cgroup's limit less its usage (`/sys/fs/cgroup/memory.max` and
//!   `memory.current` for cgroup v2, `memory/memory.limit_in_bytes` and
//!   `memory.usage_in_bytes` for v1),
//! - the address-space and data-segment limits of the process (`ulimit -v`, `-d`),
//!
//! and [`FALLBACK_LIMIT`] (4 GiB) where none of them is known (other systems). Half,
//! because the budget bounds each structure's estimate, not the process: the scene,
//! the prepared view and the frame live beside the structure being checked. The
//! default is read once per process.
//!
//! Estimates are upper bounds of the bytes a structure takes (element sizes from
//! `size_of`, growth from the input's counts); counted structures sum their vectors'
//! capacities as they grow. Neither counts the allocator's own overhead.

use std::sync::OnceLock;

use crate::{Error, Result};

/// The default limit where the memory available is unknown: 4 GiB.
pub const FALLBACK_LIMIT: u64 = 4 << 30;

/// The fraction of the memory available that the default budget takes: one half.
pub(crate) const DEFAULT_FRACTION_DIVISOR: u64 = 2;

/// A memory limit in bytes, checked by the structures of a run.
///
/// # Example
/// ```
/// use obscura::budget::MemoryBudget;
/// let budget = MemoryBudget::new(1 << 20); // 1 MiB
/// assert!(budget.check_items("BSP fragments", 1000, 100).is_ok());
/// let e = budget.check_items("BSP fragments", 100_000, 100).unwrap_err();
/// assert!(e.to_string().contains("BSP fragments") && e.to_string().contains("memory_limit"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    limit: u64,
}

impl Default for MemoryBudget {
    fn default() -> Self {
        MemoryBudget::new(MemoryBudget::default_limit())
    }
}

impl MemoryBudget {
    /// A budget of `limit` bytes.
    #[must_use]
    pub fn new(limit: u64) -> Self {
        MemoryBudget { limit }
    }

    /// The budget an option asks for: `Some(bytes)`, or the default when `None`.
    #[must_use]
    pub(crate) fn from_option(limit: Option<u64>) -> Self {
        limit.map_or_else(MemoryBudget::default, MemoryBudget::new)
    }

    /// The limit in bytes.
    #[must_use]
    pub fn limit(&self) -> u64 {
        self.limit
    }

    /// The default limit: half of the memory available (see the module doc), read once
    /// per process.
    #[must_use]
    pub fn default_limit() -> u64 {
        static DEFAULT: OnceLock<u64> = OnceLock::new();
        *DEFAULT.get_or_init(|| default_for(available_to_process()))
    }

    /// An [`Error::Budget`] unless `bytes` fit in the budget; `count` is what the
    /// structure counts (fragments, nodes, faces), for the message.
    pub fn check(&self, structure: &str, count: u64, bytes: u64) -> Result<()> {
        if bytes > self.limit {
            Err(self.exceeded(structure, count, bytes))
        } else {
            Ok(())
        }
    }

    /// [`MemoryBudget::check`] for `count` items of `bytes_each` (the product
    /// saturates).
    pub fn check_items(&self, structure: &str, count: u64, bytes_each: u64) -> Result<()> {
        self.check(structure, count, count.saturating_mul(bytes_each))
    }

    /// The error of a structure that needs `bytes`, over this budget.
    #[must_use]
    pub(crate) fn exceeded(&self, structure: &str, count: u64, bytes: u64) -> Error {
        Error::Budget {
            structure: structure.to_string(),
            count,
            bytes,
            limit: self.limit,
            option: "memory_limit".to_string(),
            at: None,
        }
    }
}

/// The default limit for this much memory available (`None`: unknown).
fn default_for(available: Option<u64>) -> u64 {
    available.map_or(FALLBACK_LIMIT, |a| a / DEFAULT_FRACTION_DIVISOR)
}

/// An empty vector with room for `n` elements, or an [`Error::Budget`] naming
/// `structure` when they exceed the budget or the allocator refuses them (the backstop
/// of an estimate: never an allocator abort).
pub fn try_vec<T>(budget: &MemoryBudget, structure: &str, n: usize) -> Result<Vec<T>> {
    let bytes = (n as u64).saturating_mul(size_of::<T>() as u64);
    budget.check(structure, n as u64, bytes)?;
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| budget.exceeded(structure, n as u64, bytes))?;
    Ok(v)
}

/// Reserves room for `more` elements in `v`, or an [`Error::Budget`] naming `structure`
/// when the allocator refuses (the count reached is `v.len() + more`).
pub(crate) fn try_grow<T>(
    budget: &MemoryBudget,
    structure: &str,
    v: &mut Vec<T>,
    more: usize,
) -> Result<()> {
    v.try_reserve(more).map_err(|_| {
        let n = v.len().saturating_add(more) as u64;
        budget.exceeded(structure, n, n.saturating_mul(size_of::<T>() as u64))
    })
}

/// The memory available to this process, in bytes: the least of the system's
/// available memory, the cgroup's room and the process's limits; `None` when none is
/// known.
#[must_use]
pub(crate) fn available_to_process() -> Option<u64> {
    [meminfo_available(), cgroup_room(), rlimit()]
        .into_iter()
        .flatten()
        .min()
}

/// `MemAvailable` of `/proc/meminfo`.
fn meminfo_available() -> Option<u64> {
    crate::frame::available_memory()
}

/// Reads a number of bytes from a file (`max` and absurd values give `None`).
fn read_bytes(path: &str) -> Option<u64> {
    let text = std::fs::read_to_string(path).ok()?;
    let v: u64 = text.trim().parse().ok()?;
    // cgroup v1 writes "no limit" as a huge page-rounded number.
    (v < 1 << 60).then_some(v)
}

/// The room left under the cgroup's memory limit (v2, else v1).
fn cgroup_room() -> Option<u64> {
    let room = |limit: &str, usage: &str| {
        let l = read_bytes(limit)?;
        Some(l.saturating_sub(read_bytes(usage).unwrap_or(0)))
    };
    room("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current").or_else(|| {
        room(
            "/sys/fs/cgroup/memory/memory.limit_in_bytes",
            "/sys/fs/cgroup/memory/memory.usage_in_bytes",
        )
    })
}

/// The least of the address-space and data-segment limits (`ulimit -v`, `-d`).
#[cfg(unix)]
// `rlim_t` is `u64` on Linux but not on every Unix.
#[allow(clippy::unnecessary_cast)]
fn rlimit() -> Option<u64> {
    let get = |resource| {
        let mut r = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: `getrlimit` writes the limit into the struct it is given.
        let ok = unsafe { libc::getrlimit(resource, &mut r) } == 0;
        (ok && r.rlim_cur != libc::RLIM_INFINITY).then_some(r.rlim_cur as u64)
    };
    [get(libc::RLIMIT_AS), get(libc::RLIMIT_DATA)]
        .into_iter()
        .flatten()
        .min()
}

#[cfg(not(unix))]
fn rlimit() -> Option<u64> {
    None
}

/// Parses a size as the CLI writes it: bytes (`1048576`), or a number with a unit,
/// `K`, `M`, `G`, `T` (powers of 1024, also written `KiB`, `MiB`...; `KB`, `MB`... are
/// powers of 1000), case-insensitive, a fraction allowed (`1.5GiB`).
///
/// ```
/// use obscura::budget::parse_size;
/// assert_eq!(parse_size("512M").unwrap(), 512 << 20);
/// assert_eq!(parse_size("1.5GiB").unwrap(), 3 << 29);
/// assert_eq!(parse_size("2GB").unwrap(), 2_000_000_000);
/// assert_eq!(parse_size("4096").unwrap(), 4096);
/// assert!(parse_size("-1G").is_err() && parse_size("12 apples").is_err());
/// ```
pub fn parse_size(s: &str) -> std::result::Result<u64, String> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let unit = unit.trim().to_ascii_lowercase();
    let scale: f64 = match unit.as_str() {
        "" | "b" => 1.0,
        "k" | "kib" => 1024.0,
        "m" | "mib" => 1024.0 * 1024.0,
        "g" | "gib" => 1024.0 * 1024.0 * 1024.0,
        "t" | "tib" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        "kb" => 1e3,
        "mb" => 1e6,
        "gb" => 1e9,
        "tb" => 1e12,
        _ => {
            return Err(format!(
                "\"{s}\": give bytes or a number with a unit K, M, G or T (e.g. 512M, 1.5GiB)"
            ));
        }
    };
    let value: f64 = number
        .parse()
        .map_err(|_| format!("\"{s}\": not a size (e.g. 512M, 4G, 1.5GiB or bytes)"))?;
    let bytes = (value * scale).round();
    if !(bytes >= 1.0) || bytes > u64::MAX as f64 / 2.0 {
        return Err(format!(
            "\"{s}\": give a size of at least one byte and below 8 EiB"
        ));
    }
    Ok(bytes as u64)
}

/// A size in bytes for messages: MiB with one decimal from 1 MiB up, else bytes.
#[must_use]
pub(crate) fn readable_bytes(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.1} GiB", bytes as f64 / f64::from(1u32 << 30))
    } else if bytes >= 1 << 20 {
        format!("{:.1} MiB", bytes as f64 / f64::from(1u32 << 20))
    } else {
        format!("{bytes} bytes")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks_compare_bytes_with_the_limit() {
        let b = MemoryBudget::new(1000);
        assert!(b.check("x", 10, 1000).is_ok());
        let e = b.check_items("octree nodes", 11, 100).unwrap_err();
        match &e {
            Error::Budget {
                structure,
                count,
                bytes,
                limit,
                ..
            } => {
                assert_eq!(
                    (structure.as_str(), *count, *bytes, *limit),
                    ("octree nodes", 11, 1100, 1000)
                );
            }
            other => panic!("{other:?}"),
        }
        let text = e.to_string();
        assert!(
            text.contains("octree nodes") && text.contains("11") && text.contains("memory_limit"),
            "{text}"
        );
        // Saturation instead of overflow.
        assert!(b.check_items("x", u64::MAX, u64::MAX).is_err());
    }

    #[test]
    fn try_vec_refuses_over_the_budget_and_the_allocator() {
        let b = MemoryBudget::new(1 << 20);
        assert_eq!(try_vec::<u64>(&b, "v", 1000).unwrap().capacity(), 1000);
        assert!(try_vec::<u64>(&b, "v", 1 << 20).is_err());
        let huge = MemoryBudget::new(u64::MAX);
        let e = try_vec::<u64>(&huge, "v", usize::MAX / 4).unwrap_err();
        assert!(matches!(e, Error::Budget { .. }), "{e}");
    }

    #[test]
    fn the_default_is_half_of_what_is_available() {
        assert_eq!(default_for(Some(8 << 30)), 4 << 30);
        assert_eq!(default_for(None), FALLBACK_LIMIT);
        // The memory available moves between two readings: within a quarter.
        let d = MemoryBudget::default_limit();
        if let Some(a) = available_to_process() {
            let (lo, hi) = (a / 2 - a / 8, a / 2 + a / 8);
            assert!((lo..=hi).contains(&d), "{d} not near half of {a}");
        }
        assert_eq!(MemoryBudget::from_option(Some(7)).limit(), 7);
        assert_eq!(MemoryBudget::from_option(None).limit(), d);
    }

    #[test]
    fn sizes_parse_with_units() {
        assert_eq!(parse_size("1").unwrap(), 1);
        assert_eq!(parse_size("10k").unwrap(), 10 * 1024);
        assert_eq!(parse_size("4G").unwrap(), 4 << 30);
        assert_eq!(parse_size("4g").unwrap(), 4 << 30);
        assert_eq!(parse_size("0.5MiB").unwrap(), 1 << 19);
        assert_eq!(parse_size("3MB").unwrap(), 3_000_000);
        for bad in [
            "",
            "G",
            "0",
            "0.1",
            "1.2.3M",
            "5X",
            "-3",
            "nan",
            "1e3",
            "99999999999T",
        ] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }
}
