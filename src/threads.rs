//! The thread pool every parallel kernel runs in: one per process, rebuilt after a `fork`.
//!
//! rayon's global pool is made once per address space. A child made by `fork()` inherits its
//! bookkeeping but not its threads (only the forking thread goes on in the child), so the
//! child's first parallel loop would wait forever for workers that do not exist (issue #26).
//! [`install`] runs a call in this process's own pool instead: the pool remembers the process
//! it was built in (its pid, and a count of forks kept by a `pthread_atfork` child handler, so
//! a reused pid is not mistaken for the builder), and a caller in another process gets a fresh
//! pool. The stale pool is leaked, never dropped: dropping it would wake threads that are gone
//! through locks one of them may have held at the fork.
//!
//! The thread count is, in order: [`set_num_threads`]; else the environment variable
//! [`NUM_THREADS_ENV`] (`MOTIONBLUR_NUM_THREADS`), read once at first use; else
//! `RAYON_NUM_THREADS` (as rayon reads it: a positive count, anything else ignored); else the
//! cores this process may use. A forked child keeps its parent's count. The kernels' results
//! do not depend on it.
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use rayon::{ThreadPool, ThreadPoolBuilder};

use crate::error::{Error, Result};

/// The most threads [`set_num_threads`] and [`NUM_THREADS_ENV`] accept.
pub const MAX_THREADS: usize = 1024;

/// The environment variable read for the thread count at first use, unless
/// [`set_num_threads`] was called before.
pub const NUM_THREADS_ENV: &str = "MOTIONBLUR_NUM_THREADS";

/// A pool and the process it was built for.
struct Built {
    pid: u32,
    forks: u64,
    threads: usize,
    pool: Arc<ThreadPool>,
}

struct State {
    /// The thread count, once set or read from the environment.
    threads: Option<usize>,
    pool: Option<Built>,
}

/// Held only to read or swap these few fields, never while a pool is built or runs.
static STATE: Mutex<State> = Mutex::new(State {
    threads: None,
    pool: None,
});

/// Forks of this process's ancestors and of itself that went through `fork()` (counted in the
/// child by the handler [`watch_forks`] registers).
static FORKS: AtomicU64 = AtomicU64::new(0);

fn state() -> MutexGuard<'static, State> {
    STATE.lock().unwrap_or_else(PoisonError::into_inner)
}

/// `n` if it is a thread count [`set_num_threads`] accepts, else an error naming `name`.
fn check_count(name: &'static str, n: usize) -> Result<usize> {
    if (1..=MAX_THREADS).contains(&n) {
        Ok(n)
    } else {
        Err(Error::value(
            name,
            format!("the number of threads must be from 1 to {MAX_THREADS}, got {n}"),
        ))
    }
}

/// The count [`NUM_THREADS_ENV`] gives, if it is set and not blank; an error naming it when
/// it is not a whole number in `1..=MAX_THREADS`.
fn from_env() -> Result<Option<usize>> {
    match std::env::var(NUM_THREADS_ENV) {
        Ok(text) => parse_env(&text),
        Err(_) => Ok(None),
    }
}

/// [`from_env`] of the variable's text `text`.
fn parse_env(text: &str) -> Result<Option<usize>> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(None);
    }
    let bad = || {
        Error::value(
            NUM_THREADS_ENV,
            format!("expected a whole number of threads from 1 to {MAX_THREADS}, got {text:?}"),
        )
    };
    let n: usize = text.parse().map_err(|_| bad())?;
    check_count(NUM_THREADS_ENV, n).map_err(|_| bad())?;
    Ok(Some(n))
}

/// The count without [`set_num_threads`] or [`NUM_THREADS_ENV`]: rayon's own default.
fn default_threads() -> usize {
    let rayon = std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|s| s.trim().parse::<usize>().ok())
        .filter(|&n| n > 0);
    let n = rayon.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    n.min(MAX_THREADS)
}

impl State {
    /// The thread count; reads the environment the first time. An invalid
    /// [`NUM_THREADS_ENV`] is an error here (and is read again next time).
    fn threads(&mut self) -> Result<usize> {
        if let Some(n) = self.threads {
            return Ok(n);
        }
        let n = from_env()?.unwrap_or_else(default_threads);
        self.threads = Some(n);
        Ok(n)
    }
}

/// The number of threads the parallel kernels of this process run on; the first call reads
/// [`NUM_THREADS_ENV`] unless [`set_num_threads`] was called. Fails naming the variable when
/// its value is not a whole number in `1..=MAX_THREADS`.
pub fn num_threads() -> Result<usize> {
    state().threads()
}

/// Sets the number of threads the parallel kernels run on (`1..=MAX_THREADS`, else an error
/// naming `n`) and returns the previous count. The next parallel call builds a pool of that
/// size; calls already running finish on the pool they started on.
pub fn set_num_threads(n: usize) -> Result<usize> {
    let n = check_count("n", n)?;
    let mut s = state();
    let previous = s.threads().unwrap_or_else(|_| default_threads());
    s.threads = Some(n);
    Ok(previous)
}

/// Runs `f` in this process's thread pool, so the parallel loops inside it (rayon's
/// `par_iter`, `join`, `scope`) run there, never in rayon's global pool, and returns its
/// result. Called on a worker thread of any rayon pool (a kernel calling another, or a Rust
/// caller's own pool), `f` runs right there, in that pool: nesting never waits on itself.
///
/// The pool is built at the first call of each process (again after a `fork`, and after
/// [`set_num_threads`] changed the count) with [`num_threads`] threads, or rayon's default
/// count when [`NUM_THREADS_ENV`] is invalid (the binding layer refuses to call then).
///
/// # Panics
///
/// When the system refuses to start the pool's threads, as rayon's global pool does.
pub fn install<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() {
        return f();
    }
    current_pool().install(f)
}

/// This process's pool at the current thread count, built if needed.
fn current_pool() -> Arc<ThreadPool> {
    let pid = std::process::id();
    let threads = {
        let mut s = state();
        let forks = FORKS.load(Ordering::Acquire);
        let threads = s.threads().unwrap_or_else(|_| default_threads());
        if let Some(b) = &s.pool {
            if (b.pid, b.forks, b.threads) == (pid, forks, threads) {
                return b.pool.clone();
            }
        }
        threads
    };
    // Built without the lock: another thread may build one meanwhile; the first one stored wins.
    watch_forks();
    let fresh = Arc::new(
        ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("motionblur-{i}"))
            .build()
            .unwrap_or_else(|e| panic!("motionblur: cannot start {threads} threads: {e}")),
    );
    let forks = FORKS.load(Ordering::Acquire);
    let (pool, old) = {
        let mut s = state();
        match &s.pool {
            Some(b) if (b.pid, b.forks, b.threads) == (pid, forks, threads) => {
                (b.pool.clone(), None)
            }
            _ => {
                let built = Built {
                    pid,
                    forks,
                    threads,
                    pool: fresh.clone(),
                };
                (fresh, s.pool.replace(built))
            }
        }
    };
    if let Some(old) = old {
        if (old.pid, old.forks) != (pid, forks) {
            // Built in another process: its threads are not here (see the module's docs).
            std::mem::forget(old);
        }
        // Else a pool of another size in this process: dropped here, it ends its threads once
        // the calls running on it return.
    }
    pool
}

/// Registers (once) a `pthread_atfork` child handler that counts forks, so a child whose pid
/// happens to be the pool builder's (a reused pid) still builds its own pool.
#[cfg(unix)]
fn watch_forks() {
    use std::sync::Once;
    extern "C" fn forked() {
        // Async-signal-safe: one atomic add, in the child, right after the fork.
        FORKS.fetch_add(1, Ordering::AcqRel);
    }
    extern "C" {
        fn pthread_atfork(
            prepare: Option<extern "C" fn()>,
            parent: Option<extern "C" fn()>,
            child: Option<extern "C" fn()>,
        ) -> std::ffi::c_int;
    }
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // SAFETY: registers a handler that stays valid for the life of the process (a plain
        // function); it only adds to an atomic. A failed registration (ENOMEM) leaves the pid
        // check alone in force.
        unsafe {
            pthread_atfork(None, None, Some(forked));
        }
    });
}

#[cfg(not(unix))]
fn watch_forks() {}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    /// The tests change the process's count: one at a time.
    static SERIAL: Mutex<()> = Mutex::new(());

    #[test]
    fn runs_on_the_count_set() {
        let _g = SERIAL.lock().unwrap_or_else(PoisonError::into_inner);
        let old = set_num_threads(3).unwrap();
        assert_eq!(num_threads().unwrap(), 3);
        assert_eq!(install(rayon::current_num_threads), 3);
        assert!(install(|| rayon::current_thread_index().is_some()));
        set_num_threads(1).unwrap();
        assert_eq!(install(rayon::current_num_threads), 1);
        assert_eq!(set_num_threads(old).unwrap(), 1);
    }

    #[test]
    fn refuses_bad_counts_naming_n() {
        for n in [0, MAX_THREADS + 1, usize::MAX] {
            let e = set_num_threads(n).unwrap_err().to_string();
            assert!(
                e.starts_with("n: the number of threads must be from 1 to 1024"),
                "{e}"
            );
        }
    }

    #[test]
    fn nested_calls_run_in_place() {
        let _g = SERIAL.lock().unwrap_or_else(PoisonError::into_inner);
        let old = set_num_threads(2).unwrap();
        let sum: u64 = install(|| {
            (0..64u64)
                .into_par_iter()
                .map(|i| install(|| (0..i).into_par_iter().sum::<u64>()))
                .sum()
        });
        assert_eq!(
            sum,
            (0..64u64).map(|i| i * i.saturating_sub(1) / 2).sum::<u64>()
        );
        // From a worker of a foreign pool: runs there.
        let foreign = crate::on_threads(3, || install(rayon::current_num_threads));
        assert_eq!(foreign, 3);
        set_num_threads(old).unwrap();
    }

    #[test]
    fn many_threads_share_one_pool() {
        let _g = SERIAL.lock().unwrap_or_else(PoisonError::into_inner);
        let old = set_num_threads(2).unwrap();
        let sums: Vec<u64> = std::thread::scope(|s| {
            let hs: Vec<_> = (0..8)
                .map(|_| s.spawn(|| install(|| (0..10_000u64).into_par_iter().sum::<u64>())))
                .collect();
            hs.into_iter().map(|h| h.join().unwrap()).collect()
        });
        assert!(sums.iter().all(|&s| s == 49_995_000));
        set_num_threads(old).unwrap();
    }

    #[test]
    fn parses_the_environment_value() {
        // Only the parser: the process's environment is left alone.
        assert_eq!(parse_env(" 4 ").unwrap(), Some(4));
        assert_eq!(parse_env("").unwrap(), None);
        for bad in ["0", "-1", "2.5", "four", "1025", "99999999999999999999999"] {
            let e = parse_env(bad).unwrap_err().to_string();
            assert!(
                e.starts_with("MOTIONBLUR_NUM_THREADS: expected a whole number"),
                "{e}"
            );
        }
        assert!((1..=MAX_THREADS).contains(&default_threads()));
    }
}
