//! The process's peak memory, as the benches report it.

/// The process's peak resident set size: `VmHWM` of `/proc/self/status` on Linux, else
/// `getrusage` (`ru_maxrss`: kilobytes on the BSDs, bytes on macOS); `None` where the system
/// reports neither.
///
/// Linux's `ru_maxrss` is not used there because it survives `execve`: a child forked from a
/// large parent reports the parent's size at the fork, so a fresh process measuring one run
/// would report whatever the bench had built before it. `VmHWM` belongs to the address space,
/// which `execve` replaces.
pub fn peak_resident_bytes() -> Option<u64> {
    if let Some(bytes) = high_water_mark() {
        return Some(bytes);
    }
    #[cfg(unix)]
    {
        use nix::sys::resource::{getrusage, UsageWho};
        let peak = u64::try_from(getrusage(UsageWho::RUSAGE_SELF).ok()?.max_rss()).ok()?;
        let bytes = if cfg!(target_os = "macos") {
            peak
        } else {
            peak * 1024
        };
        (bytes > 0).then_some(bytes)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// `VmHWM` (kilobytes) from `/proc/self/status`, in bytes; `None` off Linux.
fn high_water_mark() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|line| line.starts_with("VmHWM:"))?;
    let kilobytes: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kilobytes * 1024)
}

#[cfg(test)]
mod tests {
    #[test]
    fn peak_memory_covers_what_this_process_touched() {
        let block = vec![1u8; 64 << 20];
        std::hint::black_box(&block);
        let peak = super::peak_resident_bytes().expect("reported on this system");
        assert!(peak >= 64 << 20, "peak {peak} bytes after touching 64 MiB");
        drop(block);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn linux_reads_the_high_water_mark_of_this_address_space() {
        // The one figure that a process started by a large parent does not inherit.
        let bytes = super::high_water_mark().expect("VmHWM in /proc/self/status");
        assert!(bytes > 0);
    }
}
