//! Progress of long work (the P-LIE construction, shading): the library never prints; the caller
//! shows a bar and can ask long work to stop.

/// Reports progress of long work; the library never prints, the CLI shows a bar.
pub trait Progress: Sync {
    /// A stage of `total` steps begins.
    fn start(&self, _stage: &str, _total: u64) {}
    /// `n` more steps are done.
    fn advance(&self, _n: u64) {}
    /// The stage is done.
    fn finish(&self) {}
    /// The user asked to stop (Ctrl-C): long work that can be interrupted returns early with
    /// an error (the P-LIE construction: [`crate::Error::Interrupted`]).
    fn cancelled(&self) -> bool {
        false
    }
}

/// Progress that goes nowhere.
pub struct NoProgress;
impl Progress for NoProgress {}
