//! `--threads T`, shared by the subcommands that compute (`build`, `render`, `inspect`, `verify`,
//! `bench`): the size of the worker pool. No result depends on it.

use anyhow::Result;

/// The worker-thread option.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct ThreadsArg {
    /// Worker threads (default: all cores; 1 to 1024). Images, P-LIEs and figures other than times
    /// do not depend on it.
    #[arg(long, value_name = "T")]
    pub threads: Option<usize>,
}

impl ThreadsArg {
    /// Sizes the global worker pool ([`crate::checks::set_threads`]).
    pub fn install(&self) -> Result<()> {
        crate::checks::set_threads(self.threads)
    }
}
