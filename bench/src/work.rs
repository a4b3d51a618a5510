//! The benchmarks' work queue: jobs 0..n on scoped threads, each thread taking
//! the next index, the results kept in index order.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Runs `job(i)` for every i in 0..`n` on `threads` threads (at least one);
/// calls `progress(done, n)` after each job. Once a job fails no further
/// job starts. Returns every result in index order, or the first error in
/// index order.
pub fn try_map<T: Send>(
    n: usize,
    threads: usize,
    job: impl Fn(usize) -> Result<T, String> + Sync,
    progress: impl Fn(usize, usize) + Sync,
) -> Result<Vec<T>, String> {
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<T, String>>>> = Mutex::new((0..n).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= n {
                    break;
                }
                let r = job(i);
                if r.is_err() {
                    // no further job starts
                    next.store(n, Ordering::Relaxed);
                }
                if let Ok(mut all) = results.lock() {
                    all[i] = Some(r);
                }
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, n);
            });
        }
    });
    let all = results
        .into_inner()
        .map_err(|_| "a worker panicked".to_string())?;
    let mut out = Vec::with_capacity(n);
    let mut skipped = false;
    for r in all {
        match r {
            Some(Ok(v)) => out.push(v),
            Some(Err(e)) => return Err(e),
            None => skipped = true,
        }
    }
    if skipped {
        return Err("a job did not run".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_job_runs_once_and_the_results_keep_their_order() {
        let calls = AtomicUsize::new(0);
        let last = AtomicUsize::new(0);
        let out = try_map(
            50,
            3,
            |i| {
                calls.fetch_add(1, Ordering::Relaxed);
                Ok(i * i)
            },
            |done, n| {
                assert_eq!(n, 50);
                last.fetch_max(done, Ordering::Relaxed);
            },
        )
        .expect("no job fails");
        assert_eq!(out, (0..50).map(|i| i * i).collect::<Vec<_>>());
        assert_eq!(calls.load(Ordering::Relaxed), 50);
        assert_eq!(last.load(Ordering::Relaxed), 50);
    }

    #[test]
    fn a_failed_job_stops_the_queue_and_its_error_is_returned() {
        let calls = AtomicUsize::new(0);
        let r: Result<Vec<usize>, String> = try_map(
            1000,
            1,
            |i| {
                calls.fetch_add(1, Ordering::Relaxed);
                if i == 3 {
                    Err(format!("job {i} failed"))
                } else {
                    Ok(i)
                }
            },
            |_, _| {},
        );
        assert_eq!(r, Err("job 3 failed".into()));
        // one thread: jobs 0-3 ran, none after
        assert_eq!(calls.load(Ordering::Relaxed), 4);
    }
}
