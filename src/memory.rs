//! What this process can still allocate, and what happens when an allocation
//! fails anyway. The estimates of a run's needs, checked against
//! [`available_bytes`] before it starts, are in `pipeline::memory`; this module
//! is below every stage, so that the scene loader can check an OBJ before
//! reading it.
//!
//! Why both: an estimate refuses up front what cannot fit, with the file or
//! option to change; but estimates are not exact and other processes take
//! memory too, and Rust's default answer to a failed allocation is
//! `abort()` (status 134, a core, and a "memory allocation of N bytes failed"
//! line that names nothing). [`OneLineOom`] turns that into the project's one
//! `error:` line, naming what the process was doing ([`doing`]), and status 1.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// Memory this process can still get: the least of the system's
/// `MemAvailable`, what its memory cgroup allows beyond what the cgroup already
/// uses (a container's limit, which `MemAvailable` does not show), and what its
/// address-space limit (`ulimit -v`) leaves above its present size; `None` when
/// none of them is known.
pub fn available_bytes() -> Option<u64> {
    [
        meminfo_available(),
        cgroup_headroom(),
        address_space_headroom(),
    ]
    .into_iter()
    .flatten()
    .min()
}

/// What a run may plan on: `limit` when one is given (`--max-memory`), else
/// 90 % of [`available_bytes`]; `None` when neither is known.
pub fn cap(limit: Option<u64>) -> Option<u64> {
    limit.or_else(|| available_bytes().map(|a| a / 10 * 9))
}

thread_local! {
    /// The limit [`limited`] sets for this thread's checks.
    static LIMIT: std::cell::Cell<Option<u64>> = const { std::cell::Cell::new(None) };
}

/// Runs `f` with `limit` (`--max-memory`) as what this thread's checks below
/// the pipeline may plan on: the scene loader's, which the option does not
/// reach through its arguments. The previous limit is back when `f` returns.
pub fn limited<R>(limit: Option<u64>, f: impl FnOnce() -> R) -> R {
    let before = LIMIT.replace(limit);
    let result = f();
    LIMIT.set(before);
    result
}

/// The limit [`limited`] set on this thread, if any.
pub fn limit() -> Option<u64> {
    LIMIT.get()
}

/// What exceeds the cap, in words ("`what` needs about 1.2 GiB of memory,
/// more than the 0.9 GiB available", or "allowed by --max-memory" with a
/// `limit`), or `None` when `bytes` fit or nothing is known to compare with.
pub fn exceeds(bytes: u64, limit: Option<u64>, what: &str) -> Option<String> {
    let cap = cap(limit)?;
    (bytes > cap).then(|| {
        format!(
            "{what} needs about {} of memory, more than the {} {}",
            size(bytes),
            size(cap),
            if limit.is_some() {
                "allowed by --max-memory"
            } else {
                "available"
            }
        )
    })
}

/// `bytes` in GiB, for messages.
fn gib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 30) as f64
}

/// `bytes` for a message: "1.3 GiB", or "120 MiB" below a GiB (where one
/// decimal of GiB would read 0.1 for both of two different figures).
pub fn size(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.1} GiB", gib(bytes))
    } else {
        format!("{:.0} MiB", bytes as f64 / (1u64 << 20) as f64)
    }
}

/// `MemAvailable` of `/proc/meminfo`.
fn meminfo_available() -> Option<u64> {
    proc_kib("/proc/meminfo", "MemAvailable:")
}

/// The value, in bytes, of the `key` line of a `/proc` file that counts in kB.
fn proc_kib(file: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(file).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The limit of this process's memory cgroup less its usage (page cache not
/// counted): cgroup v2
/// (`memory.max`, `memory.current`) or v1 (`memory.limit_in_bytes`,
/// `memory.usage_in_bytes`), in the group `/proc/self/cgroup` names, or at the
/// mount's root where a container shows only its own group there.
fn cgroup_headroom() -> Option<u64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    headroom_of_groups(&groups, |path| std::fs::read_to_string(path).ok())
}

/// [`cgroup_headroom`] from the text of `/proc/self/cgroup` and a file reader.
fn headroom_of_groups(groups: &str, read: impl Fn(&str) -> Option<String>) -> Option<u64> {
    let number = |path: String| -> Option<u64> { read(&path)?.trim().parse().ok() };
    let mut best = None::<u64>;
    for line in groups.lines() {
        // "0::/path" (v2) or "4:memory:/path" (v1).
        let mut parts = line.splitn(3, ':');
        let (_, Some(controllers), Some(group)) = (parts.next(), parts.next(), parts.next()) else {
            continue;
        };
        // The files, and memory.stat's key for the page cache the usage counts.
        let (base, limit, usage, cache) = match controllers {
            "" => ("/sys/fs/cgroup", "memory.max", "memory.current", "file"),
            c if c.split(',').any(|c| c == "memory") => (
                "/sys/fs/cgroup/memory",
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
                "total_cache",
            ),
            _ => continue,
        };
        let group = group.trim_end_matches('/');
        for dir in [format!("{base}{group}"), base.to_string()] {
            // v2's "max" does not parse: no limit there.
            let (l, u) = (
                number(format!("{dir}/{limit}")),
                number(format!("{dir}/{usage}")),
            );
            if let (Some(l), Some(u)) = (l, u) {
                // The usage counts the page cache (a build's files, say), which
                // the kernel reclaims before it fails an allocation.
                let cached = read(&format!("{dir}/memory.stat"))
                    .and_then(|stat| {
                        stat.lines().find_map(|l| {
                            l.strip_prefix(cache)?
                                .strip_prefix(' ')?
                                .trim()
                                .parse()
                                .ok()
                        })
                    })
                    .unwrap_or(0);
                let headroom = l.saturating_sub(u.saturating_sub(cached));
                best = Some(best.map_or(headroom, |b| b.min(headroom)));
                break;
            }
        }
    }
    best
}

/// `RLIMIT_AS` (`ulimit -v`) less this process's address space (`VmSize`), when
/// the limit is set: past it every allocation fails, whatever memory is free.
#[cfg(target_os = "linux")]
fn address_space_headroom() -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the struct it is given.
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } != 0
        || limit.rlim_cur == libc::RLIM_INFINITY
    {
        return None;
    }
    let size = proc_kib("/proc/self/status", "VmSize:")?;
    #[allow(clippy::unnecessary_cast)] // rlim_t is 32-bit on some targets
    Some((limit.rlim_cur as u64).saturating_sub(size))
}

#[cfg(not(target_os = "linux"))]
fn address_space_headroom() -> Option<u64> {
    None
}

/// What the process is doing, as the start of the out-of-memory line: e.g.
/// "scene.toml: out of memory while rendering". Empty: "out of memory".
static DOING: Mutex<String> = Mutex::new(String::new());

/// Restores the previous [`doing`] text when dropped.
#[must_use = "the text holds only while the guard lives"]
pub struct Doing(String);

/// Names what the process does until the guard drops, for [`OneLineOom`]'s
/// line: `path` and the activity ("rendering", "loading the OBJ").
pub fn doing(path: &std::path::Path, activity: &str) -> Doing {
    // Formatted before the lock: the allocator's handler only ever try-locks.
    let mut text = format!("{}: out of memory while {activity}", path.display());
    if let Ok(mut d) = DOING.lock() {
        std::mem::swap(&mut *d, &mut text);
    }
    Doing(text)
}

impl Drop for Doing {
    fn drop(&mut self) {
        if let Ok(mut d) = DOING.lock() {
            std::mem::swap(&mut *d, &mut self.0);
        }
    }
}

/// The system allocator, except that a failed allocation ends the process
/// with one line, `error: <doing> (an allocation of N MiB failed); …`, and
/// status 1, instead of `abort()`. The binary installs it
/// (`#[global_allocator]` in `main.rs`). Nothing here allocates: the line is
/// written from a stack buffer, and the exit skips destructors (an output
/// being written is an anonymous file the kernel drops, `output::atomic`).
pub struct OneLineOom;

// SAFETY: every call is System's own; only a null result is handled here.
unsafe impl GlobalAlloc for OneLineOom {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc(layout);
        if p.is_null() {
            out_of_memory(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc_zeroed(layout);
        if p.is_null() {
            out_of_memory(layout.size());
        }
        p
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = System.realloc(ptr, layout, new_size);
        if p.is_null() {
            out_of_memory(new_size);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

/// Prints the line once and exits with status 1; a second thread that runs out
/// meanwhile waits for the exit.
#[cold]
fn out_of_memory(size: usize) -> ! {
    static FAILED: AtomicBool = AtomicBool::new(false);
    if FAILED.swap(true, Ordering::SeqCst) {
        loop {
            std::thread::sleep(std::time::Duration::from_secs(1));
        }
    }
    let mut buf = [0u8; 1024];
    let len = {
        let mut w = &mut buf[..];
        let doing = DOING.try_lock();
        let doing = match &doing {
            Ok(d) if !d.is_empty() => d.as_str(),
            _ => "out of memory",
        };
        let _ = write!(w, "error: {doing} (an allocation of ");
        let _ = match size {
            0..=0xFFFFF => write!(w, "{size} bytes"),
            _ => write!(w, "{:.1} MiB", size as f64 / (1u64 << 20) as f64),
        };
        let _ = writeln!(
            w,
            " failed); free memory or raise the process's limit (ulimit -v, the \
             container's memory limit)"
        );
        1024 - w.len()
    };
    let _ = std::io::stderr().write_all(&buf[..len]);
    exit_now(1)
}

/// Ends the process at once: no destructors, no atexit handlers (which might
/// allocate).
fn exit_now(code: i32) -> ! {
    #[cfg(target_os = "linux")]
    // SAFETY: _exit never returns and touches no Rust state.
    unsafe {
        libc::_exit(code)
    }
    #[cfg(not(target_os = "linux"))]
    std::process::exit(code)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_limit_holds_inside_limited_only_and_refusals_name_it() {
        assert_eq!(limit(), None);
        let inner = limited(Some(5 << 20), || {
            // Nested: the inner limit, then the outer one back.
            let nested = limited(Some(1), limit);
            (nested, limit(), cap(limit()))
        });
        assert_eq!(inner, (Some(1), Some(5 << 20), Some(5 << 20)));
        assert_eq!(limit(), None);
        assert_eq!(
            exceeds(3 << 20, Some(2 << 20), "this").as_deref(),
            Some("this needs about 3 MiB of memory, more than the 2 MiB allowed by --max-memory")
        );
        assert_eq!(exceeds(2 << 20, Some(2 << 20), "this"), None);
    }

    #[test]
    fn sizes_read_in_mib_below_a_gib() {
        assert_eq!(size(120 << 20), "120 MiB");
        assert_eq!(size((1 << 30) - 1), "1024 MiB");
        assert_eq!(size(1 << 30), "1.0 GiB");
        assert_eq!(size(3 << 29), "1.5 GiB");
    }

    /// A fake `/sys/fs/cgroup`: each path's contents.
    fn files<'a>(entries: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |path| {
            entries
                .iter()
                .find(|(p, _)| *p == path)
                .map(|(_, t)| t.to_string())
        }
    }

    #[test]
    fn cgroup_v2_limit_less_usage_in_the_process_group() {
        let fs = files(&[
            ("/sys/fs/cgroup/job/memory.max", "1000\n"),
            ("/sys/fs/cgroup/job/memory.current", "300\n"),
            ("/sys/fs/cgroup/memory.max", "max\n"),
        ]);
        assert_eq!(headroom_of_groups("0::/job\n", &fs), Some(700));
        // The page cache within the usage is reclaimable: not counted.
        let fs = files(&[
            ("/sys/fs/cgroup/job/memory.max", "1000\n"),
            ("/sys/fs/cgroup/job/memory.current", "900\n"),
            (
                "/sys/fs/cgroup/job/memory.stat",
                "anon 300\nfile 600\nfile_mapped 7\n",
            ),
        ]);
        assert_eq!(headroom_of_groups("0::/job\n", &fs), Some(700));
        // No limit ("max") anywhere: unknown, not zero.
        let fs = files(&[
            ("/sys/fs/cgroup/memory.max", "max\n"),
            ("/sys/fs/cgroup/memory.current", "5\n"),
        ]);
        assert_eq!(headroom_of_groups("0::/\n", &fs), None);
    }

    #[test]
    fn cgroup_v1_memory_controller_and_the_container_root() {
        // The group's directory is not mounted (a container sees its own group
        // at the root): the root's files count.
        let fs = files(&[
            ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "2048\n"),
            ("/sys/fs/cgroup/memory/memory.usage_in_bytes", "4096\n"),
        ]);
        let groups = "5:cpu,cpuacct:/x\n4:memory:/docker/abc\n0::/\n";
        // Usage above the limit: nothing left, not an underflow.
        assert_eq!(headroom_of_groups(groups, &fs), Some(0));
        let fs = files(&[
            (
                "/sys/fs/cgroup/memory/docker/abc/memory.limit_in_bytes",
                "9000",
            ),
            (
                "/sys/fs/cgroup/memory/docker/abc/memory.usage_in_bytes",
                "3000",
            ),
            (
                "/sys/fs/cgroup/memory/docker/abc/memory.stat",
                "cache 5\ntotal_cache 2000\n",
            ),
        ]);
        assert_eq!(headroom_of_groups(groups, &fs), Some(8000));
        assert_eq!(headroom_of_groups("4:cpu:/a\n", &fs), None);
    }

    #[test]
    fn available_is_at_most_meminfo() {
        if let (Some(a), Some(m)) = (available_bytes(), meminfo_available()) {
            assert!(a <= m);
        }
    }
}
