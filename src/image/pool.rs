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
    reuse(n).or_else(|| zeroed(n))
}

/// A new buffer of `n` zeros, or `None` when it cannot be allocated. Asked of the allocator
/// zeroed: a large one comes as fresh pages that are zero already, not written over once more
/// before its user writes it.
fn zeroed(n: usize) -> Option<Vec<f32>> {
    if n == 0 {
        return Some(Vec::new());
    }
    let layout = std::alloc::Layout::array::<f32>(n).ok()?;
    // SAFETY: the layout's size is not zero (n > 0).
    let p = unsafe { std::alloc::alloc_zeroed(layout) } as *mut f32;
    if p.is_null() {
        return None;
    }
    // SAFETY: `p` was allocated by the global allocator with the layout of `n` f32, all of
    // them initialised (zero bits are 0.0).
    let v = unsafe { Vec::from_raw_parts(p, n, n) };
    advise_huge_pages(&v);
    Some(v)
}

/// A buffer of exactly `n` floats from the pool (unspecified but initialised contents), or
/// `None` when none is large enough (a new one is then the caller's: written once, it need not
/// be cleared first).
pub(crate) fn reuse(n: usize) -> Option<Vec<f32>> {
    let mut pool = POOL.lock().unwrap_or_else(|e| e.into_inner());
    let i = (0..pool.len())
        .filter(|&i| pool[i].capacity() >= n)
        .min_by_key(|&i| pool[i].capacity())?;
    let mut v = pool.swap_remove(i);
    drop(pool);
    // (within the capacity: no allocation)
    v.resize(n, 0.0);
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
