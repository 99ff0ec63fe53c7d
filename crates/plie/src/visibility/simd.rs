//! Proof that the CPU has the vector instructions of the fans' lane kernels (issue 21). The walks
//! and lists compiled for AVX2 hand it down, so that the kernels under them are chosen once per
//! query, not by a run-time check at every node and triangle (which also kept the compiler from
//! treating the walk as AVX2 code throughout).

use std::sync::OnceLock;

/// Held only where the CPU has AVX2, POPCNT and BMI1 ([`Avx2::detect`]).
#[derive(Clone, Copy, Debug)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub struct Avx2(());

impl Avx2 {
    /// The proof, if this CPU has AVX2, POPCNT and BMI1. (Asked a few times per query: the three
    /// features' answer is kept as one, so that asking costs one load.)
    #[inline]
    pub(crate) fn detect() -> Option<Avx2> {
        static HAS: OnceLock<bool> = OnceLock::new();
        HAS.get_or_init(Avx2::find).then_some(Avx2(()))
    }

    /// Whether the CPU has the three features ([`Avx2::detect`]'s first answer).
    #[cold]
    fn find() -> bool {
        #[cfg(target_arch = "x86_64")]
        return std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("popcnt")
            && std::arch::is_x86_feature_detected!("bmi1");
        #[cfg(not(target_arch = "x86_64"))]
        false
    }
}
