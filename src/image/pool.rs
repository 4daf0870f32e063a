//! A small pool of large scratch buffers, reused between calls so that the intermediate images
//! of the oblique filters do not pay the operating system's page faults and zeroing every call.
//! Buffers come back with stale contents: users write every element before reading it.
use std::sync::Mutex;

static POOL: Mutex<Vec<Vec<f32>>> = Mutex::new(Vec::new());

/// Keeps at most this many buffers.
const KEEP: usize = 4;

/// A buffer of exactly `n` floats with unspecified (but initialised) contents.
pub(crate) fn take(n: usize) -> Vec<f32> {
    let mut pool = POOL.lock().unwrap_or_else(|e| e.into_inner());
    let best = (0..pool.len())
        .filter(|&i| pool[i].capacity() >= n)
        .min_by_key(|&i| pool[i].capacity());
    let mut v = match best {
        Some(i) => pool.swap_remove(i),
        None => Vec::new(),
    };
    drop(pool);
    if v.len() >= n {
        v.truncate(n);
    } else {
        v.resize(n, 0.0);
    }
    v
}

/// Returns a buffer to the pool.
pub(crate) fn give(v: Vec<f32>) {
    let mut pool = POOL.lock().unwrap_or_else(|e| e.into_inner());
    pool.push(v);
    if pool.len() > KEEP {
        pool.sort_by_key(|b| std::cmp::Reverse(b.capacity()));
        pool.truncate(KEEP);
    }
}
