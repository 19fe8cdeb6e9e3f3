//! This process's CPU time (user + system, every thread): the cost measure of
//! `compare --equal cpu`, which other jobs on a shared machine inflate far less
//! than the wall time.

/// Process CPU seconds since it started, where the OS reports them (Linux:
/// `CLOCK_PROCESS_CPUTIME_ID`, the kernel's user + system time of every thread).
pub fn process_s() -> Option<f64> {
    #[cfg(target_os = "linux")]
    {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: clock_gettime writes one timespec through a valid pointer.
        let ok = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) } == 0;
        ok.then_some(t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9)
    }
    #[cfg(not(target_os = "linux"))]
    None
}

#[cfg(test)]
mod tests {
    #[cfg(target_os = "linux")]
    #[test]
    fn a_busy_loop_costs_cpu_time() {
        let t0 = super::process_s().unwrap();
        let start = std::time::Instant::now();
        let mut x = 0u64;
        while start.elapsed().as_secs_f64() < 0.05 {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        let spent = super::process_s().unwrap() - t0;
        // One thread spinning 50 ms: some CPU time, and no more than the wall
        // time it ran plus the test harness's other threads' slack.
        assert!(spent > 0.005, "{spent}");
        assert!(spent < 1.0, "{spent}");
    }
}
