//! Proof that the CPU has the vector instructions of the fans' lane kernels (issue 21). The walks
//! and lists compiled for AVX2 hand it down, so that the kernels under them are chosen once per
//! query, not by a run-time check at every node and triangle (which also kept the compiler from
//! treating the walk as AVX2 code throughout).

/// Held only where the CPU has AVX2, POPCNT and BMI1 ([`Avx2::detect`]).
#[derive(Clone, Copy, Debug)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub struct Avx2(());

impl Avx2 {
    /// The proof, if this CPU has AVX2, POPCNT and BMI1.
    #[inline]
    pub(crate) fn detect() -> Option<Avx2> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("popcnt")
            && std::arch::is_x86_feature_detected!("bmi1")
        {
            return Some(Avx2(()));
        }
        None
    }
}
