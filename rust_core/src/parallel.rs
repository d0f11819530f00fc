//! Many independent computations in parallel: deterministic, panic-safe.
//!
//! Every point is computed by the same pure function of its own inputs, so the results do not
//! depend on the thread count or on how rayon splits the work: bit-identical for 1 and N threads
//! (tested). A panic inside one point is caught and becomes that point's `Status::Panic`, so one
//! bad point cannot take a sweep down. Thread pools are cached per thread count.

use rayon::prelude::*;
use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, Mutex, OnceLock};

/// Environment variable that sets the default thread count (else: all logical cores).
pub const THREADS_ENV: &str = "TRIBOSWEEP_THREADS";

/// The thread count used when none is given: `TRIBOSWEEP_THREADS`, else rayon's default.
pub fn default_threads() -> usize {
    std::env::var(THREADS_ENV)
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1))
}

fn pool(threads: usize) -> Arc<rayon::ThreadPool> {
    static POOLS: OnceLock<Mutex<HashMap<usize, Arc<rayon::ThreadPool>>>> = OnceLock::new();
    let pools = POOLS.get_or_init(|| Mutex::new(HashMap::new()));
    let mut guard = pools.lock().unwrap_or_else(|e| e.into_inner());
    guard
        .entry(threads)
        .or_insert_with(|| {
            Arc::new(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .thread_name(|i| format!("tribosweep-{i}"))
                    .build()
                    .expect("building a rayon thread pool"),
            )
        })
        .clone()
}

/// Message of a caught panic payload.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic with a non-string payload".to_string()
    }
}

/// Apply `f` to every item in parallel on `threads` threads (`None`: [`default_threads`]),
/// in input order. A panic in `f` for an item becomes `on_panic(message)` for that item.
pub fn par_map<T, R, F, P>(items: &[T], threads: Option<usize>, f: F, on_panic: P) -> Vec<R>
where
    T: Sync,
    R: Send,
    F: Fn(&T) -> R + Sync,
    P: Fn(String) -> R + Sync,
{
    let threads = threads.unwrap_or_else(default_threads).max(1);
    let run_one = |item: &T| match catch_unwind(AssertUnwindSafe(|| f(item))) {
        Ok(r) => r,
        Err(payload) => on_panic(panic_message(payload.as_ref())),
    };
    if threads == 1 || items.len() <= 1 {
        return items.iter().map(run_one).collect();
    }
    pool(threads).install(|| items.par_iter().with_min_len(1).map(run_one).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panics_become_data_and_order_is_kept() {
        let items: Vec<u32> = (0..100).collect();
        let prev = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
        let out = par_map(
            &items,
            Some(2),
            |&i| {
                if i == 37 {
                    panic!("boom at {i}");
                }
                Ok(i * 2)
            },
            Err,
        );
        std::panic::set_hook(prev);
        for (i, r) in out.iter().enumerate() {
            if i == 37 {
                assert_eq!(r.as_ref().unwrap_err(), "boom at 37");
            } else {
                assert_eq!(*r.as_ref().unwrap(), 2 * i as u32);
            }
        }
    }

    #[test]
    fn thread_count_does_not_change_results() {
        let items: Vec<f64> = (0..1000).map(|i| i as f64 * 0.37).collect();
        let f = |x: &f64| (0..200).fold(*x, |a, k| (a * 1.0001 + k as f64).sin());
        let a = par_map(&items, Some(1), f, |_| f64::NAN);
        let b = par_map(&items, Some(2), f, |_| f64::NAN);
        let c = par_map(&items, Some(7), f, |_| f64::NAN);
        assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
        assert!(a.iter().zip(&c).all(|(x, y)| x.to_bits() == y.to_bits()));
    }
}
