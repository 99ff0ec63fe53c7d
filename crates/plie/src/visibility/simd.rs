//! Proof that the CPU has the vector instructions of the fans' lane kernels (issue 21). The walks
//! and lists compiled for AVX2 hand it down, so that the kernels under them are chosen once per
//! query, not by a run-time check at every node and triangle (which also kept the compiler from
//! treating the walk as AVX2 code throughout).

use std::sync::atomic::{AtomicU8, Ordering};

/// Held only where the CPU has AVX2, POPCNT and BMI1 ([`Avx2::detect`]).
#[derive(Clone, Copy, Debug)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub struct Avx2(());

impl Avx2 {
    /// The proof, if this CPU has AVX2, POPCNT and BMI1. (Asked a few times per query: the three
    /// features' answer is kept as one, so that asking costs one load.)
    #[inline]
    pub(crate) fn detect() -> Option<Avx2> {
        match KNOWN.load(Ordering::Relaxed) {
            YES => Some(Avx2(())),
            NO => None,
            _ => Avx2::find(),
        }
    }

    /// [`Avx2::detect`]'s first answer, kept in [`KNOWN`].
    #[cold]
    fn find() -> Option<Avx2> {
        #[cfg(target_arch = "x86_64")]
        let has = std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("popcnt")
            && std::arch::is_x86_feature_detected!("bmi1");
        #[cfg(not(target_arch = "x86_64"))]
        let has = false;
        KNOWN.store(if has { YES } else { NO }, Ordering::Relaxed);
        has.then_some(Avx2(()))
    }
}

/// Whether the CPU has the features: not yet asked (0), [`NO`] or [`YES`].
static KNOWN: AtomicU8 = AtomicU8::new(0);
const NO: u8 = 1;
const YES: u8 = 2;
