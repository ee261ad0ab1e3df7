//! For tests: what the kernel says about huge pages. One file for the library's
//! `memory` tests and the command line's allocator tests (which compile it by path).

/// Whether this system backs advised ranges with huge pages (transparent huge pages in
/// `madvise` or `always` mode).
pub(crate) fn huge_pages_enabled() -> bool {
    std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled")
        .is_ok_and(|s| s.contains("[madvise]") || s.contains("[always]"))
}

/// `AnonHugePages` of the mapping holding `addr`, in KiB, from `/proc/self/smaps`.
pub(crate) fn anon_huge_kib(addr: usize) -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/smaps").ok()?;
    let mut inside = false;
    for line in text.lines() {
        let first = line.split_whitespace().next().unwrap_or("");
        if let Some((a, b)) = first.split_once('-')
            && let (Ok(a), Ok(b)) = (usize::from_str_radix(a, 16), usize::from_str_radix(b, 16))
        {
            inside = a <= addr && addr < b;
            continue;
        }
        if inside && let Some(rest) = line.strip_prefix("AnonHugePages:") {
            return rest.trim().trim_end_matches("kB").trim().parse().ok();
        }
    }
    None
}
