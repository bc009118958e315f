//! Statistics every command reports the same way: quantiles by nearest rank (the value
//! at rank ⌈q·n⌉ of the n sorted samples, so the median of an even count is the lower
//! middle value), and the process's peak memory.

/// The value at quantile `q` (0–1) of `values` (sorted here), nearest rank; `None` when
/// there is none.
pub fn quantile(values: &mut [f64], q: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let rank = ((values.len() as f64 * q).ceil() as usize).clamp(1, values.len());
    Some(values[rank - 1])
}

/// Median and 95th percentile of a set of timings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    pub count: usize,
    pub median: f64,
    pub p95: f64,
}

impl Summary {
    /// The summary of `values` (sorted here); `None` when empty.
    pub fn of(values: &mut [f64]) -> Option<Summary> {
        Some(Summary {
            count: values.len(),
            median: quantile(values, 0.5)?,
            p95: quantile(values, 0.95)?,
        })
    }
}

/// Peak resident set size of this process, from /proc (Linux only).
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// CPU time this process has used so far, user and system, in seconds, all threads
/// together (`getrusage`; Linux only, like [`peak_memory_bytes`]).
pub fn process_cpu_seconds() -> Option<f64> {
    #[cfg(target_os = "linux")]
    {
        let mut usage = std::mem::MaybeUninit::<libc::rusage>::uninit();
        // SAFETY: getrusage writes the whole struct it is given, and reads nothing of ours.
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr()) } != 0 {
            return None;
        }
        // SAFETY: a call that returned 0 filled it.
        let usage = unsafe { usage.assume_init() };
        let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        Some(seconds(usage.ru_utime) + seconds(usage.ru_stime))
    }
    #[cfg(not(target_os = "linux"))]
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_quantiles() {
        let mut v = vec![4.0, 1.0, 3.0, 2.0];
        assert_eq!(quantile(&mut v, 0.5), Some(2.0));
        assert_eq!(quantile(&mut v, 0.95), Some(4.0));
        assert_eq!(quantile(&mut v, 0.0), Some(1.0));
        assert_eq!(quantile(&mut [], 0.5), None);
        let s = Summary::of(&mut [5.0, 1.0, 3.0]).unwrap();
        assert_eq!((s.count, s.median, s.p95), (3, 3.0, 5.0));
    }

    #[test]
    fn cpu_time_grows_with_work() {
        let Some(before) = process_cpu_seconds() else {
            return;
        };
        // About 50 ms of one core's work, kept from being optimised away.
        let start = std::time::Instant::now();
        let mut x = 1u64;
        while start.elapsed().as_millis() < 50 {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        let after = process_cpu_seconds().unwrap();
        assert!(after - before >= 0.02, "{before} -> {after}");
    }
}
