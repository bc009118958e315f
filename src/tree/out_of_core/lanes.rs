//! Jobs run [`LANES`] at a time, each lane a thread that takes the next job not yet
//! taken, and the work a lane leaves running behind it ([`Behind`]): a built part's
//! write, so that the lane's next job starts while the device takes the bytes.
//!
//! Why behind: the jobs of an evenly sampled tile are alike, so the lanes run in step
//! and reach their part writes together, both cores then waiting on the device. On the
//! 200 M-point tile's first 8 jobs (`spt jobs build`, 2 AMD EPYC cores, 2026-12-03),
//! writing no part at all took 36.1 and 35.6 s against 38.0 and 36.4 s; with the
//! writes behind the lanes, the share of the cores' time left idle, 1 − CPU time /
//! (2 × wall), went from 6.0–9.8 % (mean 7.3 %, five runs) to 5.7–6.6 % (mean
//! 6.1 %, six runs; alternated, the plan's files in the page cache), with the same
//! parts and the same peak memory. The machine's own speed drifted more than that
//! between runs (35.7–44.6 s for the same 8 jobs).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::thread::JoinHandle;

use super::LANES;

/// The work a lane left running: at most one piece, finished (and its error taken)
/// before the lane starts another and before the lane ends. Dropped unfinished (the
/// lane failed), it is still waited for, so that no write outlives its build.
#[derive(Default)]
pub struct Behind(Option<JoinHandle<anyhow::Result<()>>>);

impl Behind {
    /// Runs `work` on a thread of its own, once the piece before it has finished;
    /// returns that piece's error, if any (then `work` is not started).
    pub fn start(
        &mut self,
        work: impl FnOnce() -> anyhow::Result<()> + Send + 'static,
    ) -> anyhow::Result<()> {
        self.finish()?;
        self.0 = Some(std::thread::spawn(work));
        Ok(())
    }

    /// Waits for the piece running, if any; returns its error.
    pub fn finish(&mut self) -> anyhow::Result<()> {
        match self.0.take() {
            Some(running) => running
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p)),
            None => Ok(()),
        }
    }
}

impl Drop for Behind {
    fn drop(&mut self) {
        if let Some(running) = self.0.take() {
            let _ = running.join();
        }
    }
}

/// Runs `work` on each of `jobs`, [`LANES`] at a time: each lane takes the next job
/// not yet taken, with its own [`Behind`], finished when the lane has no job left. The
/// jobs' parallel work shares the one thread pool; a lane's serial work runs on its
/// own thread. The first error stops the lanes from taking more jobs and is returned.
pub fn in_lanes(
    jobs: &[usize],
    work: &(dyn Fn(usize, &mut Behind) -> anyhow::Result<()> + Sync),
) -> anyhow::Result<()> {
    let (next, failed) = (AtomicUsize::new(0), AtomicBool::new(false));
    let lane = || -> anyhow::Result<()> {
        let mut behind = Behind::default();
        let result = (|| {
            while !failed.load(Ordering::Relaxed) {
                let Some(&j) = jobs.get(next.fetch_add(1, Ordering::Relaxed)) else {
                    break;
                };
                work(j, &mut behind)?;
            }
            behind.finish()
        })();
        if result.is_err() {
            failed.store(true, Ordering::Relaxed);
        }
        result
    };
    let results: Vec<anyhow::Result<()>> = std::thread::scope(|scope| {
        let lanes: Vec<_> = (0..LANES).map(|_| scope.spawn(lane)).collect();
        lanes
            .into_iter()
            .map(|l| l.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    results.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn every_job_runs_once_and_its_work_behind_finishes_before_in_lanes_returns() {
        let done = Mutex::new(Vec::new());
        let behind_done = std::sync::Arc::new(Mutex::new(Vec::new()));
        let jobs: Vec<usize> = (0..9).collect();
        in_lanes(&jobs, &|j, behind| {
            done.lock().unwrap().push(j);
            let record = behind_done.clone();
            behind.start(move || {
                std::thread::sleep(std::time::Duration::from_millis(5));
                record.lock().unwrap().push(j);
                Ok(())
            })
        })
        .unwrap();
        let (mut ran, mut behind) = (
            done.into_inner().unwrap(),
            behind_done.lock().unwrap().clone(),
        );
        ran.sort_unstable();
        behind.sort_unstable();
        assert_eq!(ran, jobs);
        assert_eq!(behind, jobs);
    }

    #[test]
    fn an_error_behind_a_lane_is_returned_and_stops_it() {
        let started = AtomicUsize::new(0);
        let jobs: Vec<usize> = (0..50).collect();
        let error = in_lanes(&jobs, &|j, behind| {
            started.fetch_add(1, Ordering::Relaxed);
            std::thread::sleep(std::time::Duration::from_millis(2));
            behind.start(move || match j {
                3 => anyhow::bail!("part 3 not written"),
                _ => Ok(()),
            })
        })
        .unwrap_err();
        assert_eq!(error.to_string(), "part 3 not written");
        assert!(started.load(Ordering::Relaxed) < jobs.len());
    }
}
