//! Many independent computations in parallel: deterministic, panic-safe.
//!
//! Every point is computed by the same pure function of its own inputs, so the results do not
//! depend on the thread count or on how rayon splits the work: bit-identical for 1 and N threads
//! (tested). A panic inside one point is caught and becomes that point's `Status::Panic`, so one
//! bad point cannot take a sweep down. Thread pools are cached per thread count (and per process:
//! a forked child makes its own, [`PerProcess`]).

use crate::cancel;
use rayon::prelude::*;
use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, Mutex};

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

/// A value made once per process: in a child made by `fork` (Python's `multiprocessing` on Linux
/// by default), made again. A child inherits its parent's thread pools without their threads:
/// work handed to one of them waited forever (a forked child's first parallel call hung). The
/// parent's value is leaked in the child, not dropped (dropping a pool signals threads that do
/// not exist there).
pub struct PerProcess<T> {
    slot: Mutex<Option<(u32, T)>>,
}

impl<T> PerProcess<T> {
    /// Empty; the first [`PerProcess::with`] makes the value.
    pub const fn new() -> Self {
        PerProcess { slot: Mutex::new(None) }
    }

    /// `f` of this process's value (under its lock), made by `make` if there is none yet (or only
    /// the parent's).
    pub fn with<R>(&self, make: impl FnOnce() -> T, f: impl FnOnce(&mut T) -> R) -> R {
        let pid = std::process::id();
        let mut guard = self.slot.lock().unwrap_or_else(|e| e.into_inner());
        if guard.as_ref().is_none_or(|(owner, _)| *owner != pid) {
            if let Some(parents) = guard.replace((pid, make())) {
                std::mem::forget(parents);
            }
        }
        f(&mut guard.as_mut().expect("made above").1)
    }
}

impl<T> Default for PerProcess<T> {
    fn default() -> Self {
        Self::new()
    }
}

fn pool(threads: usize) -> Arc<rayon::ThreadPool> {
    static POOLS: PerProcess<HashMap<usize, Arc<rayon::ThreadPool>>> = PerProcess::new();
    POOLS.with(HashMap::new, |pools| {
        pools
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
    })
}

/// `f(i)` for every `i` in `0..n`, in blocks of `block` indices on `threads` threads (`None`:
/// [`default_threads`]), each value written in place into the result: no serial gather, and the
/// pages of the new vector are first touched by the threads that fill them. On many cores a serial
/// copy of per-trajectory data caps the speed-up of short runs (Amdahl). The error is that of the
/// lowest failing index, as a serial loop would return. A panic in `f` propagates. On an error
/// the values already written are leaked, not dropped (meant for plain data).
pub fn par_fill<T, E, F>(n: usize, threads: Option<usize>, block: usize, f: F) -> Result<Vec<T>, E>
where
    T: Send,
    E: Send,
    F: Fn(usize) -> Result<T, E> + Sync,
{
    let block = block.max(1);
    let threads = threads.unwrap_or_else(default_threads).max(1);
    let mut out: Vec<T> = Vec::with_capacity(n);
    let slots = &mut out.spare_capacity_mut()[..n];
    let fill = |(b, chunk): (usize, &mut [std::mem::MaybeUninit<T>])| -> Result<(), E> {
        for (k, slot) in chunk.iter_mut().enumerate() {
            slot.write(f(b * block + k)?);
        }
        Ok(())
    };
    let done: Vec<Result<(), E>> = if threads == 1 || n <= block {
        slots.chunks_mut(block).enumerate().map(fill).collect()
    } else {
        pool(threads).install(|| slots.par_chunks_mut(block).enumerate().map(fill).collect())
    };
    // Blocks are in index order and each stops at its first error: the first `Err` is the lowest.
    done.into_iter().collect::<Result<(), E>>()?;
    // SAFETY: every block returned `Ok`, so each of the first `n` slots was written once.
    unsafe { out.set_len(n) };
    Ok(out)
}

/// Results by index from `(index, result)` pairs, moved once into place: `missing(i)` for every
/// index in `0..n` that no pair holds. Panics on an index twice or out of range (the values
/// already placed are then leaked, not dropped).
pub fn scatter<R>(n: usize, pairs: impl IntoIterator<Item = (usize, R)>, missing: impl Fn(usize) -> R) -> Vec<R> {
    let mut out: Vec<R> = Vec::with_capacity(n);
    let mut filled = vec![false; n];
    let slots = &mut out.spare_capacity_mut()[..n];
    for (i, r) in pairs {
        assert!(!filled[i], "scatter: index {i} given twice");
        slots[i].write(r);
        filled[i] = true;
    }
    for (i, _) in filled.iter().enumerate().filter(|(_, f)| !**f) {
        slots[i].write(missing(i));
    }
    // SAFETY: each of the first `n` slots was written exactly once, by a pair or by `missing`.
    unsafe { out.set_len(n) };
    out
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
/// in input order. A panic in `f` for an item becomes `on_panic(message)` for that item; an item
/// not started because the caller cancelled ([`crate::cancel`]) becomes
/// `on_panic(cancel::CANCELLED)` (see [`par_map_or`] to tell the two apart).
pub fn par_map<T, R, F, P>(items: &[T], threads: Option<usize>, f: F, on_panic: P) -> Vec<R>
where
    T: Sync,
    R: Send,
    F: Fn(&T) -> R + Sync,
    P: Fn(String) -> R + Sync,
{
    par_map_or(items, threads, f, &on_panic, || on_panic(cancel::CANCELLED.to_string()))
}

/// [`par_map`] with its own result for the items not started because the caller cancelled:
/// `on_cancel()`. The caller's stop request ([`cancel::current`]) is handed to the worker threads,
/// so that `f` sees it there too; it is looked at before each item.
pub fn par_map_or<T, R, F, P, C>(items: &[T], threads: Option<usize>, f: F, on_panic: P, on_cancel: C) -> Vec<R>
where
    T: Sync,
    R: Send,
    F: Fn(&T) -> R + Sync,
    P: Fn(String) -> R + Sync,
    C: Fn() -> R + Sync,
{
    let threads = threads.unwrap_or_else(default_threads).max(1);
    let token = cancel::current();
    let run_one = |item: &T| {
        cancel::scope_opt(token.as_ref(), || {
            if cancel::requested() {
                return on_cancel();
            }
            match catch_unwind(AssertUnwindSafe(|| f(item))) {
                Ok(r) => r,
                Err(payload) => on_panic(panic_message(payload.as_ref())),
            }
        })
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
    fn a_per_process_value_is_made_once_in_a_process() {
        let made = std::sync::atomic::AtomicUsize::new(0);
        let cell: PerProcess<Arc<u32>> = PerProcess::new();
        let make = || {
            made.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            Arc::new(7)
        };
        let get = |make: &dyn Fn() -> Arc<u32>| cell.with(make, |v| v.clone());
        let a = get(&make);
        let b = get(&make);
        assert!(Arc::ptr_eq(&a, &b) && *a == 7);
        assert_eq!(made.load(std::sync::atomic::Ordering::Relaxed), 1);
        // As in a forked child: the value is another process's, so it is made again.
        cell.slot.lock().unwrap().as_mut().unwrap().0 ^= 1;
        let c = get(&make);
        assert!(!Arc::ptr_eq(&a, &c));
        assert_eq!(made.load(std::sync::atomic::Ordering::Relaxed), 2);
        assert!(Arc::ptr_eq(&c, &get(&make)));
    }

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
    fn a_cancelled_caller_stops_the_workers() {
        // Items after the cancel are not started, on every thread; the token reaches the workers.
        // Item 0 cancels; every other item waits for the cancel (at most 10 s), so that no thread
        // runs more than one item before it: rayon runs the leftmost item on the calling worker.
        let items: Vec<u32> = (0..64).collect();
        for threads in [1, 3] {
            let token = cancel::Token::new();
            let out = token.scope(|| {
                par_map_or(
                    &items,
                    Some(threads),
                    |&i| {
                        if i == 0 {
                            cancel::current().expect("the token reaches the worker").cancel();
                        }
                        let start = std::time::Instant::now();
                        while !cancel::requested() && start.elapsed().as_secs() < 10 {
                            std::thread::yield_now();
                        }
                        Some(cancel::requested())
                    },
                    |_| None,
                    || None,
                )
            });
            assert_eq!(out[0], Some(true));
            // With one thread every later item is skipped; with several, only those already
            // running when the cancel came may still run (and they see it).
            let ran = out.iter().filter(|o| o.is_some()).count();
            assert!(ran <= threads, "{threads} threads: {ran} items ran");
            assert!(out.iter().flatten().all(|&seen| seen));
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

    #[test]
    fn par_fill_is_in_order_and_reports_the_lowest_failing_index() {
        let f = |i: usize| if i % 1000 == 777 { Err(i) } else { Ok((i as f64 * 0.37).sin()) };
        for (threads, block) in [(1, 64), (2, 64), (7, 5), (3, 10_000)] {
            // Every failing index is reported as the lowest would be by a serial loop.
            assert_eq!(par_fill(5000, Some(threads), block, f), Err(777), "{threads} threads, block {block}");
            let ok = par_fill(700, Some(threads), block, |i| Ok::<_, ()>((i as f64 * 0.37).sin())).unwrap();
            assert_eq!(ok.len(), 700);
            assert!(ok.iter().enumerate().all(|(i, v)| v.to_bits() == (i as f64 * 0.37).sin().to_bits()));
        }
        assert_eq!(par_fill(0, Some(2), 8, |_| Ok::<u8, ()>(1)), Ok(vec![]));
    }

    #[test]
    fn scatter_places_every_pair_and_fills_the_rest() {
        let pairs = vec![(3, "c".to_string()), (0, "a".to_string()), (4, "d".to_string())];
        let out = scatter(6, pairs, |i| format!("missing {i}"));
        assert_eq!(out, ["a", "missing 1", "missing 2", "c", "d", "missing 5"]);
        let twice = std::panic::catch_unwind(|| scatter(3, [(1, 1u8), (1, 2u8)], |_| 0));
        assert!(twice.is_err(), "an index given twice is a bug, not data");
        let outside = std::panic::catch_unwind(|| scatter(3, [(3, 1u8)], |_| 0));
        assert!(outside.is_err());
    }
}
