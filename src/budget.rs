//! The memory budget: the most bytes one call may allocate, and the checks every kernel makes
//! against it before allocating.
//!
//! A kernel whose memory is a product of sizes (faces x directions, pixels x layers, faces x
//! segments, ...) adds up what it will allocate in a [`Need`] (checked arithmetic: a product
//! that overflows 64 bits is an absurd count, a `ValueError`) and checks it against
//! [`memory_budget`] first: past the budget it fails with [`Error::Memory`] (a `MemoryError`
//! in Python) naming the arguments of the largest term and the bytes, before anything is
//! allocated. Growth that cannot be known up front goes through [`try_vec`] and
//! [`try_reserve`], which turn an allocation the system refuses into the same error instead of
//! aborting the process.
//!
//! The budget is one process-wide number (default [`DEFAULT_MEMORY_BUDGET`]), set from Python
//! with `motionblur.set_memory_budget`.
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

/// The default memory budget: 4 GiB, whatever the machine (a call accepted on one machine is
/// accepted on every other).
pub const DEFAULT_MEMORY_BUDGET: u64 = 4 << 30;

/// The smallest budget [`set_memory_budget`] accepts (1 MiB): below it no frame fits.
pub const MIN_MEMORY_BUDGET: u64 = 1 << 20;

static BUDGET: AtomicU64 = AtomicU64::new(DEFAULT_MEMORY_BUDGET);

/// The most bytes one call may allocate.
pub fn memory_budget() -> u64 {
    BUDGET.load(Ordering::Relaxed)
}

/// Sets the budget (bytes, at least [`MIN_MEMORY_BUDGET`]) and returns the previous one.
pub fn set_memory_budget(bytes: u64) -> Result<u64> {
    if bytes < MIN_MEMORY_BUDGET {
        return Err(Error::value(
            "bytes",
            format!("the memory budget must be >= {MIN_MEMORY_BUDGET} bytes, got {bytes}"),
        ));
    }
    Ok(BUDGET.swap(bytes, Ordering::Relaxed))
}

/// `bytes` for people: "5.37 GB (5368709120 bytes)".
pub fn human(bytes: u64) -> String {
    format!("{} ({bytes} bytes)", short(bytes))
}

/// `bytes` in GB, MB or kB: "5.37 GB".
fn short(bytes: u64) -> String {
    let (v, unit) = match bytes {
        b if b >= 1_000_000_000 => (b as f64 / 1e9, "GB"),
        b if b >= 1_000_000 => (b as f64 / 1e6, "MB"),
        b => (b as f64 / 1e3, "kB"),
    };
    format!("{v:.2} {unit}")
}

/// The product of the named `sizes` times `each` bytes, or a `ValueError` naming them when it
/// does not fit in 64 bits (an absurd count).
pub fn product(sizes: &[(&'static str, u64)], each: u64) -> Result<u64> {
    sizes
        .iter()
        .try_fold(each, |acc, &(_, n)| acc.checked_mul(n))
        .ok_or_else(|| Error::Value {
            name: sizes.first().map_or("size", |s| s.0),
            reason: format!(
                "{} = {} is absurd: its memory overflows 64 bits",
                names(sizes),
                values(sizes)
            ),
        })
}

fn names(sizes: &[(&'static str, u64)]) -> String {
    sizes.iter().map(|s| s.0).collect::<Vec<_>>().join(" x ")
}

fn values(sizes: &[(&'static str, u64)]) -> String {
    sizes
        .iter()
        .map(|s| s.1.to_string())
        .collect::<Vec<_>>()
        .join(" x ")
}

/// What one call will allocate: named terms, each a product of sizes times bytes each.
#[derive(Debug, Clone)]
pub struct Need {
    call: &'static str,
    terms: Vec<(String, String, u64)>,
    total: u64,
}

impl Need {
    /// An empty need of the call named `call` (as the Python API spells it).
    pub fn new(call: &'static str) -> Self {
        Need {
            call,
            terms: Vec::new(),
            total: 0,
        }
    }

    /// Adds the product of `sizes` times `each` bytes; fails at once when it or the total
    /// overflows 64 bits.
    pub fn add(mut self, sizes: &[(&'static str, u64)], each: u64) -> Result<Self> {
        let bytes = product(sizes, each)?;
        self.total = self.total.checked_add(bytes).ok_or_else(|| {
            Error::value(
                sizes.first().map_or("size", |s| s.0),
                "the call's memory overflows 64 bits",
            )
        })?;
        self.terms.push((names(sizes), values(sizes), bytes));
        Ok(self)
    }

    /// The bytes added so far.
    pub fn bytes(&self) -> u64 {
        self.total
    }

    /// Fails with [`Error::Memory`] when the total is over the budget: the error names the
    /// arguments of the largest term and lists every term.
    pub fn check(&self) -> Result<()> {
        self.check_within(memory_budget())
    }

    /// [`Need::check`] against `budget` bytes.
    pub fn check_within(&self, budget: u64) -> Result<()> {
        if self.total <= budget {
            return Ok(());
        }
        let largest = self
            .terms
            .iter()
            .max_by_key(|t| t.2)
            .map_or(String::from("size"), |t| t.0.clone());
        let parts = self
            .terms
            .iter()
            .map(|(n, v, b)| format!("{n} = {v} ({})", short(*b)))
            .collect::<Vec<_>>()
            .join(" + ");
        Err(Error::Memory {
            name: largest,
            reason: format!(
                "{} needs {}: {parts}; over the memory budget of {} \
                 (motionblur.set_memory_budget raises it)",
                self.call,
                human(self.total),
                human(budget)
            ),
        })
    }
}

/// The error of an allocation of `bytes` the system refused.
pub fn refused(name: &str, bytes: u64) -> Error {
    Error::Memory {
        name: name.to_string(),
        reason: format!(
            "the system refused to allocate {} (within the memory budget of {}: \
             the process's address space or the machine's memory is smaller)",
            human(bytes),
            human(memory_budget())
        ),
    }
}

/// Room for `additional` more elements in `v`, or [`Error::Memory`] naming `name` when the
/// system refuses the allocation (instead of aborting the process).
pub fn try_reserve<T>(v: &mut Vec<T>, additional: usize, name: &str) -> Result<()> {
    v.try_reserve(additional).map_err(|_| {
        let bytes = (v.len() as u64).saturating_add(additional as u64);
        refused(name, bytes.saturating_mul(std::mem::size_of::<T>() as u64))
    })
}

/// Asks Linux to back the allocation of `v` (its whole capacity) with transparent huge pages
/// when it holds at least 4 MiB, as numpy does for its arrays: glibc serves a block above its
/// largest mmap threshold (32 MiB: a 4K frame's colour is 127 MiB, a 1080p one's 31.6) with
/// fresh pages at every allocation, and 4 KiB pages cost one fault each (32,400 for that
/// colour buffer, more than the rasterizer that fills it); 2 MiB pages take 64. Call it before
/// the first write. Only advice: a kernel that declines it (huge pages off) changes nothing,
/// and the contents are never touched. Elsewhere than on Linux it does nothing.
pub fn advise_huge_pages<T>(v: &Vec<T>) {
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

/// `vec![value; n]`, or [`Error::Memory`] naming `name` when the system refuses it.
#[cfg_attr(not(feature = "python"), allow(dead_code))]
pub fn try_vec<T: Clone>(n: usize, value: T, name: &str) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        refused(
            name,
            (n as u64).saturating_mul(std::mem::size_of::<T>() as u64),
        )
    })?;
    v.resize(n, value);
    Ok(v)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::sync::Mutex;

    /// Tests that change the process-wide budget hold this lock.
    pub(crate) static BUDGET_LOCK: Mutex<()> = Mutex::new(());

    #[test]
    fn products_overflow_into_a_value_error_naming_the_sizes() {
        let e = product(&[("faces", u64::MAX / 2), ("directions", 3)], 1).unwrap_err();
        assert!(matches!(e, Error::Value { name: "faces", .. }));
        assert!(e.to_string().contains("faces x directions"), "{e}");
        assert_eq!(product(&[("a", 3), ("b", 5)], 8).unwrap(), 120);
        let e = Need::new("f")
            .add(&[("a", u64::MAX / 2)], 1)
            .unwrap()
            .add(&[("b", u64::MAX / 2 + 2)], 1)
            .unwrap_err();
        assert!(e.to_string().contains("overflows"), "{e}");
    }

    #[test]
    fn a_need_over_the_budget_names_its_largest_term_and_raising_the_budget_lets_it_through() {
        let need = Need::new("ContourTable")
            .add(&[("faces", 1 << 20), ("directions", 1 << 12)], 1)
            .unwrap()
            .add(&[("faces", 1 << 20)], 16)
            .unwrap();
        assert_eq!(need.bytes(), (1 << 32) + (1 << 24));
        let e = need.check_within(1 << 30).unwrap_err();
        let Error::Memory { name, reason } = &e else {
            panic!("{e:?}")
        };
        assert_eq!(name, "faces x directions");
        assert!(reason.starts_with("ContourTable needs 4.31 GB"), "{reason}");
        assert!(reason.contains("1048576 x 4096"), "{reason}");
        need.check_within(1 << 33).unwrap();
        // the process-wide budget (the default 4 GiB) refuses it, a raised one lets it through
        let _lock = BUDGET_LOCK.lock().unwrap();
        assert!(need.check().is_err());
        let old = set_memory_budget(1 << 40).unwrap();
        need.check().unwrap();
        assert!(set_memory_budget(10).is_err());
        assert_eq!(set_memory_budget(old).unwrap(), 1 << 40);
    }

    #[test]
    fn refused_allocations_are_errors() {
        let e = try_vec(usize::MAX / 4, 0u64, "draws").unwrap_err();
        assert!(matches!(e, Error::Memory { .. }), "{e:?}");
        assert!(
            e.to_string().starts_with("draws: the system refused"),
            "{e}"
        );
        let mut v: Vec<u32> = Vec::new();
        assert!(try_reserve(&mut v, usize::MAX / 2, "x").is_err());
        assert_eq!(try_vec(3, 7u8, "x").unwrap(), vec![7, 7, 7]);
    }
}
