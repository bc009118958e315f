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
}
