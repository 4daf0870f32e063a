//! A small pool of large scratch buffers, reused between calls so that the intermediate images
//! of the oblique filters do not pay the operating system's page faults and zeroing every call.
//! Buffers come back with stale contents: users write every element before reading it.
use std::sync::Mutex;

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
        advise_huge(&v);
        v.resize(n, 0.0);
    }
    Some(v)
}

/// Asks Linux to back the allocation of `v` (its whole capacity) with transparent huge pages,
/// as numpy does for its arrays, when it holds at least 4 MiB: a fresh image the size of a 4K
/// frame (133 MB) then takes about 60 page faults of 2 MiB instead of 32,000 of 4 KiB, which
/// cost more than the kernel that fills it. Call it before the first write. Only advice: a
/// kernel that declines it (huge pages off, or the range too small) changes nothing, and the
/// contents are never touched. Elsewhere than on Linux it does nothing.
pub(crate) fn advise_huge<T>(v: &Vec<T>) {
    #[cfg(target_os = "linux")]
    {
        const MIN: usize = 4 << 20;
        const PAGE: usize = 4096;
        const MADV_HUGEPAGE: i32 = 14;
        extern "C" {
            fn madvise(addr: *mut std::ffi::c_void, len: usize, advice: i32) -> i32;
        }
        let bytes = v.capacity() * std::mem::size_of::<T>();
        if bytes < MIN {
            return;
        }
        let start = (v.as_ptr() as usize).next_multiple_of(PAGE);
        let end = (v.as_ptr() as usize + bytes) / PAGE * PAGE;
        if end > start {
            // SAFETY: [start, end) lies within the allocation of `v` (whole pages of it);
            // MADV_HUGEPAGE is advice about how to back it and never changes its contents.
            unsafe { madvise(start as *mut std::ffi::c_void, end - start, MADV_HUGEPAGE) };
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v;
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
