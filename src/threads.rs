//! How many threads a parallel section of the native code may start.
//!
//! A reconstruction's thread count (`system.threads`) has to reach every parallel section it
//! runs: the rows of the system, the normal equations, the QADP passes, the maps and the image
//! search. Rather than pass it through every map and profile function, the run sets a limit on
//! its own thread with [`with_limit`], and each section asks [`available`]. The limit belongs to
//! the thread that set it (a thread-local), so two runs in one process (tests, the paper's
//! cases side by side) each keep their own. Sections start their helpers from the limited
//! thread; the helpers themselves start none. On wasm32 there is always one thread.

use std::cell::Cell;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Mutex};

thread_local! {
    /// 0 = no limit.
    static LIMIT: Cell<usize> = const { Cell::new(0) };
}

/// Threads a parallel section started on this thread may use: the limit of the innermost
/// [`with_limit`] around it, else every available core (always 1 on wasm32).
pub fn available() -> usize {
    if cfg!(target_arch = "wasm32") {
        return 1;
    }
    match LIMIT.with(Cell::get) {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    }
}

/// Runs `f` with the parallel sections it starts on this thread limited to `threads` threads,
/// within any limit already set around it (0 = no limit of its own: the enclosing one, or
/// every available core). So a run that asks for "all cores" inside a side-by-side section
/// that gave each of its runs one thread keeps to one. The previous limit is restored
/// afterwards, also when `f` panics.
pub fn with_limit<R>(threads: usize, f: impl FnOnce() -> R) -> R {
    struct Restore(usize);
    impl Drop for Restore {
        fn drop(&mut self) {
            LIMIT.with(|l| l.set(self.0));
        }
    }
    let limit = match (LIMIT.with(Cell::get), threads) {
        (outer, 0) => outer,
        (0, inner) => inner,
        (outer, inner) => outer.min(inner),
    };
    let _restore = Restore(LIMIT.with(|l| l.replace(limit)));
    f()
}

/// Threads for a parallel section over `items` items with at least `min_per_thread` items each:
/// `requested` (within a [`with_limit`] around it, if any), or [`available`] when 0; always 1
/// on wasm32.
pub fn count(requested: usize, items: usize, min_per_thread: usize) -> usize {
    if cfg!(target_arch = "wasm32") {
        return 1;
    }
    let wanted = match (requested, LIMIT.with(Cell::get)) {
        (0, _) => available(),
        (n, 0) => n,
        (n, limit) => n.min(limit),
    };
    wanted.min(items / min_per_thread.max(1)).max(1)
}

/// Runs `f` on every job, the jobs dealt in turn to at most `threads` scoped threads (job `k`
/// to thread `k % threads`, so that a few jobs per thread balance uneven ones); on this thread
/// when `threads <= 1` or there is one job, and always on wasm32. The only way the native code
/// splits work over threads, apart from the QADP sweep, whose bands are long-lived threads that
/// meet at barriers every iteration (`solver/sweep.rs`).
pub fn for_each<T: Send>(jobs: Vec<T>, threads: usize, f: impl Fn(T) + Sync) {
    let threads = if cfg!(target_arch = "wasm32") {
        1
    } else {
        threads.min(jobs.len())
    };
    if threads <= 1 {
        jobs.into_iter().for_each(f);
        return;
    }
    let mut per_thread: Vec<Vec<T>> = (0..threads).map(|_| Vec::new()).collect();
    for (k, job) in jobs.into_iter().enumerate() {
        per_thread[k % threads].push(job);
    }
    let f = &f;
    std::thread::scope(|scope| {
        for mine in per_thread {
            scope.spawn(move || mine.into_iter().for_each(f));
        }
    });
}

/// `f` of every item, the items shared between the threads of [`available`], each thread
/// running `f` with a limit of one thread (so that the whole stays within the caller's
/// limit); in order. On one thread (and on wasm32) the items run here, one after another.
pub fn map_items<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    // Nothing reported, nothing to stop: every item runs.
    map_reporting(items, available(), |item, _| f(item), &mut |_, ()| {
        ControlFlow::Continue(())
    })
    .into_iter()
    .map(|r| r.expect("every item was run"))
    .collect()
}

/// `run` of every item, side by side as in [`map_items`] on at most `threads` threads, each
/// run given a `report` that hands what it reports to `progress`, which is called on this
/// thread (so it need not be `Send`) with the item's index, in the order the reports come.
/// Once `progress` breaks, every later `report` breaks (runs that heed it stop early) and no
/// item not yet started is started: its result is `None`. On one thread (and on wasm32) the
/// items run here, one after another, `progress` called directly.
pub fn map_reporting<T: Sync, M: Send, R: Send>(
    items: &[T],
    threads: usize,
    run: impl Fn(&T, &mut dyn FnMut(M) -> ControlFlow<()>) -> R + Sync,
    progress: &mut dyn FnMut(usize, M) -> ControlFlow<()>,
) -> Vec<Option<R>> {
    let threads = if cfg!(target_arch = "wasm32") {
        1
    } else {
        threads.min(items.len())
    };
    let mut out: Vec<Option<R>> = (0..items.len()).map(|_| None).collect();
    if threads <= 1 {
        let mut stopped = false;
        for (i, item) in items.iter().enumerate() {
            if stopped {
                break;
            }
            let mut report = |m: M| {
                if stopped {
                    return ControlFlow::Break(());
                }
                let flow = progress(i, m);
                stopped = flow.is_break();
                flow
            };
            out[i] = Some(run(item, &mut report));
        }
        return out;
    }
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let done = Mutex::new(&mut out);
    let (tx, rx) = mpsc::channel::<(usize, M)>();
    let (next, stop, done, run) = (&next, &stop, &done, &run);
    std::thread::scope(|scope| {
        for _ in 0..threads {
            let tx = tx.clone();
            scope.spawn(move || loop {
                if stop.load(Ordering::Relaxed) {
                    break;
                }
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(item) = items.get(i) else { break };
                let mut report = |m: M| {
                    if stop.load(Ordering::Relaxed) {
                        return ControlFlow::Break(());
                    }
                    // The receiver lives until every sender is gone.
                    let _ = tx.send((i, m));
                    ControlFlow::Continue(())
                };
                let r = with_limit(1, || run(item, &mut report));
                done.lock().unwrap_or_else(|e| e.into_inner())[i] = Some(r);
            });
        }
        // The loop below ends when the last worker's sender is dropped.
        drop(tx);
        for (i, m) in rx {
            if progress(i, m).is_break() {
                stop.store(true, Ordering::Relaxed);
            }
        }
    });
    out
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    #[test]
    fn the_limit_holds_inside_and_is_restored_after() {
        let all = available();
        assert!(all >= 1);
        with_limit(3, || assert_eq!(available(), 3));
        with_limit(1, || {
            assert_eq!(available(), 1);
            // An inner limit keeps within the outer one; 0 asks for no limit of its own.
            with_limit(3, || assert_eq!(available(), 1));
            with_limit(0, || assert_eq!(available(), 1));
            assert_eq!(available(), 1);
            // Another thread does not see this thread's limit.
            let other = std::thread::spawn(available).join().unwrap();
            assert_eq!(other, all);
        });
        assert_eq!(available(), all);
        let _ = std::panic::catch_unwind(|| with_limit(1, || panic!("inside")));
        assert_eq!(available(), all);
    }

    #[test]
    fn map_items_keeps_the_order_and_the_limit() {
        let items: Vec<usize> = (0..9).collect();
        let out = with_limit(2, || map_items(&items, |&i| (i * i, available())));
        assert_eq!(
            out.iter().map(|r| r.0).collect::<Vec<_>>(),
            (0..9).map(|i| i * i).collect::<Vec<_>>()
        );
        assert!(out.iter().all(|r| r.1 == 1));
        let one = with_limit(1, || map_items(&items, |_| available()));
        assert!(one.iter().all(|&n| n == 1));
    }

    #[test]
    fn map_reporting_hands_every_report_to_the_caller_and_stops_on_a_break() {
        let items: Vec<usize> = (0..6).collect();
        for threads in [1, 2, 3] {
            let mut seen = vec![0usize; items.len()];
            let out = map_reporting(
                &items,
                threads,
                |&i, report| {
                    for _ in 0..3 {
                        let _ = report(i * 10);
                    }
                    (i, available())
                },
                &mut |i, m| {
                    assert_eq!(m, i * 10);
                    seen[i] += 1;
                    ControlFlow::Continue(())
                },
            );
            assert_eq!(seen, vec![3; 6], "{threads} threads");
            let got: Vec<usize> = out.iter().map(|r| r.unwrap().0).collect();
            assert_eq!(got, items);
            if threads > 1 {
                assert!(out.iter().all(|r| r.unwrap().1 == 1));
            }
            // A break stops the run that reports after it and starts no new item.
            let out = map_reporting(
                &items,
                threads,
                |_, report| while report(()).is_continue() {},
                &mut |_, ()| ControlFlow::Break(()),
            );
            // (Without the break's reaching the runs, the test would not end.)
            let started = out.iter().flatten().count();
            assert!(
                (1..=threads).contains(&started),
                "{threads} threads: {started}"
            );
        }
    }
}
