//! Whether kernels run their vector forms: one process-wide switch over run-time detection.
//!
//! Every kernel with a vector form (AVX2 on x86-64: the opaque blur's rows and shears, the
//! rasterizer's resolve, the analytic method's tiles) also has a plain form, and both perform
//! the same IEEE operations in the same order, so they give the same bits. The vector form runs
//! where [`simd_enabled`] says so: the CPU has AVX2 (detected at run time, the build targets
//! plain x86-64) and the forms are not switched off, by [`set_simd`] or by the environment
//! variable `MOTIONBLUR_SIMD=0` read on the first call. Switching them off exists so that tests
//! can compare the two forms and so that a user can rule them out; it never changes a result.
use std::sync::atomic::{AtomicU8, Ordering};

const UNSET: u8 = 0;
const OFF: u8 = 1;
const ON: u8 = 2;

static STATE: AtomicU8 = AtomicU8::new(UNSET);

/// Whether the CPU has AVX2 (the standard library caches the answer).
#[inline]
fn detected() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The switch: `set_simd`'s last value, or the environment's on the first call.
#[inline]
fn allowed() -> bool {
    match STATE.load(Ordering::Relaxed) {
        ON => true,
        OFF => false,
        _ => {
            let off = std::env::var("MOTIONBLUR_SIMD").is_ok_and(|v| v.trim() == "0");
            let state = if off { OFF } else { ON };
            // A concurrent `set_simd` wins over the environment.
            let _ = STATE.compare_exchange(UNSET, state, Ordering::Relaxed, Ordering::Relaxed);
            STATE.load(Ordering::Relaxed) == ON
        }
    }
}

/// Whether kernels run their vector forms: AVX2 detected and the forms not switched off.
#[inline]
pub fn simd_enabled() -> bool {
    allowed() && detected()
}

/// Allows (`true`) or forbids (`false`) the vector forms and returns whether they were allowed
/// before. Allowing them on a CPU without AVX2 still runs the plain forms. Results are the same
/// bits either way; kernels already running finish with the forms they chose.
pub fn set_simd(enabled: bool) -> bool {
    let before = allowed();
    STATE.store(if enabled { ON } else { OFF }, Ordering::Relaxed);
    before
}

/// Held by tests that flip the switch, so that no other test flips it under them.
#[cfg(test)]
pub(crate) static SWITCH: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_switch_rules_over_detection() {
        let _guard = SWITCH.lock().unwrap_or_else(|e| e.into_inner());
        let before = set_simd(false);
        assert!(!simd_enabled());
        assert!(!set_simd(true));
        assert_eq!(simd_enabled(), detected());
        set_simd(before);
    }
}
