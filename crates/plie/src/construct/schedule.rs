//! Runs numbered tasks in parallel and commits their results strictly in order (SPEC §4.7's
//! propagation needs an order; rayon's work-stealing gives none).
//!
//! Workers take tasks `0, 1, 2, ...` from a shared counter and compute them in parallel; whichever
//! worker finds the next result to commit ready commits it, and every ready one after it, one at a
//! time. A commit may change what later tasks will compute (propagation deletes faces of tasks not yet
//! committed), but a task's *outcome* is decided at its commit, in order, so the result is the one a
//! single thread running the tasks in order would get, whatever the thread count or timing. Only the
//! amount of wasted work depends on timing: a task computed before an earlier commit deleted its faces
//! has its result for those faces discarded. There is no barrier: a slow task delays commits, never
//! the other workers.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Computes `compute(k)` for `k` in `0..n` on rayon's threads and calls `commit(k, result)` for every
/// `k` in increasing order (from one thread at a time).
pub fn run_ordered<T, C, M>(n: usize, compute: C, commit: M)
where
    T: Send,
    C: Fn(usize) -> T + Sync,
    M: FnMut(usize, T) + Send,
{
    run_ordered_init(n, || (), |_, k| compute(k), commit);
}

/// [`run_ordered`] with per-worker state, as rayon's `map_init`: each worker makes its own state
/// with `init` once and passes it to `compute` for every task it takes (no lock, no sharing).
pub fn run_ordered_init<S, T, I, C, M>(n: usize, init: I, compute: C, commit: M)
where
    T: Send,
    I: Fn() -> S + Sync,
    C: Fn(&mut S, usize) -> T + Sync,
    M: FnMut(usize, T) + Send,
{
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<T>>> = (0..n).map(|_| Mutex::new(None)).collect();
    let committer = Mutex::new((0usize, commit));
    let committed = AtomicUsize::new(0);
    let take = |k: usize| slots[k].lock().unwrap_or_else(|e| e.into_inner()).take();
    let ready = |k: usize| k < n && slots[k].lock().unwrap_or_else(|e| e.into_inner()).is_some();
    let drain = || loop {
        let Ok(mut guard) = committer.try_lock() else { return };
        let (k, commit) = &mut *guard;
        while *k < n {
            let Some(v) = take(*k) else { break };
            commit(*k, v);
            *k += 1;
        }
        committed.store(*k, Ordering::Release);
        drop(guard);
        // A result may have landed after the loop looked and before the unlock, while its worker's
        // try_lock failed: look again rather than leave it to the end.
        if !ready(committed.load(Ordering::Acquire)) {
            return;
        }
    };
    rayon::scope(|s| {
        for _ in 0..rayon::current_num_threads().max(1) {
            s.spawn(|_| {
                let mut state = init();
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    if k >= n {
                        break;
                    }
                    let v = compute(&mut state, k);
                    *slots[k].lock().unwrap_or_else(|e| e.into_inner()) = Some(v);
                    drain();
                }
            });
        }
    });
    // Every result is in: commit what is left.
    let (k, commit) = &mut *committer.lock().unwrap_or_else(|e| e.into_inner());
    while *k < n {
        let v = take(*k).expect("every task computed");
        commit(*k, v);
        *k += 1;
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::AtomicBool;

    use super::*;

    #[test]
    fn commits_in_order_and_sees_what_earlier_commits_decided() {
        for threads in [1, 2, 4] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let n = 2000;
            // Task k "deletes" task 2k at its commit; a deleted task's result is discarded.
            let deleted: Vec<AtomicBool> = (0..n).map(|_| AtomicBool::new(false)).collect();
            let mut order = Vec::new();
            let mut kept = Vec::new();
            pool.install(|| {
                run_ordered(
                    n,
                    |k| {
                        std::hint::black_box((0..(k % 7) * 100).sum::<usize>());
                        k * 10
                    },
                    |k, v| {
                        order.push(k);
                        assert_eq!(v, k * 10);
                        if !deleted[k].load(Ordering::Relaxed) {
                            kept.push(k);
                            if 2 * k < n && k > 0 {
                                deleted[2 * k].store(true, Ordering::Relaxed);
                            }
                        }
                    },
                )
            });
            assert_eq!(order, (0..n).collect::<Vec<_>>());
            let mut want = Vec::new();
            let mut del = vec![false; n];
            for k in 0..n {
                if !del[k] {
                    want.push(k);
                    if 2 * k < n && k > 0 {
                        del[2 * k] = true;
                    }
                }
            }
            assert_eq!(kept, want, "{threads} threads");
        }
    }
}
