//! A small pool of large scratch buffers, reused between calls so that the intermediate images
//! of the oblique filters do not pay the operating system's page faults and zeroing every call.
//! Buffers come back with stale contents: users write every element before reading it.
use std::sync::Mutex;

use crate::budget::advise_huge_pages;

static POOL: Mutex<Vec<Vec<f32>>> = Mutex::new(Vec::new());

/// Keeps at most this many buffers, holding at most `MAX_FLOATS` floats in all (64 MB).
const KEEP: usize = 4;
const MAX_FLOATS: usize = 16 << 20;

/// A buffer of exactly `n` floats with unspecified (but initialised) contents, or `None` when
/// the memory cannot be allocated (instead of aborting the process).
pub(crate) fn try_take(n: usize) -> Option<Vec<f32>> {
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
        v.try_reserve_exact(n - v.len()).ok()?;
        advise_huge_pages(&v);
        v.resize(n, 0.0);
    }
    Some(v)
}

/// Returns a buffer to the pool.
pub(crate) fn give(v: Vec<f32>) {
    let mut pool = POOL.lock().unwrap_or_else(|e| e.into_inner());
    if v.capacity() > MAX_FLOATS {
        return;
    }
    pool.push(v);
    // Keep the smallest buffers within the budget (they serve the common sizes).
    pool.sort_by_key(|b| b.capacity());
    let mut total = 0;
    let keep = pool
        .iter()
        .take(KEEP)
        .take_while(|b| {
            total += b.capacity();
            total <= MAX_FLOATS
        })
        .count();
    pool.truncate(keep);
}

/// `try_take`, failing with a `ValueError` naming `name` (the image the buffer is for).
pub(crate) fn take_for(name: &'static str, n: usize) -> crate::error::Result<Vec<f32>> {
    try_take(n).ok_or_else(|| {
        crate::error::Error::value(name, format!("is too large: cannot allocate {n} floats"))
    })
}
