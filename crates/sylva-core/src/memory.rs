//! What the machine has free, for the memory estimates every allocation a user's numbers
//! size is checked against before it happens (wind fields, forests, trees).

/// Memory the kernel reports as available (`MemAvailable` of `/proc/meminfo`), bytes;
/// `None` where unknown (not Linux, or the file unreadable).
pub fn available_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

/// The share of [`available_memory`] one piece of work may plan to use: a quarter stays
/// free for the rest of the process and the machine.
pub const USABLE_SHARE: f64 = 0.75;
