//! A progress bar on stderr (indicatif) behind the library's `Progress` trait.

use indicatif::{ProgressBar, ProgressStyle};
use plie::render::Progress;
use std::sync::Mutex;

/// Shows one bar per stage on stderr, or nothing when quiet.
pub struct Bar {
    quiet: bool,
    bar: Mutex<Option<ProgressBar>>,
}

impl Bar {
    pub fn new(quiet: bool) -> Bar {
        Bar { quiet, bar: Mutex::new(None) }
    }
}

impl Progress for Bar {
    fn start(&self, stage: &str, total: u64) {
        if self.quiet {
            return;
        }
        let b = ProgressBar::new(total);
        b.set_style(
            ProgressStyle::with_template("{prefix:>10} [{elapsed_precise}] {wide_bar} {pos}/{len} {eta}")
                .expect("valid template"),
        );
        b.set_prefix(stage.to_string());
        *self.bar.lock().expect("bar lock") = Some(b);
    }

    fn advance(&self, n: u64) {
        if let Some(b) = self.bar.lock().expect("bar lock").as_ref() {
            b.inc(n);
        }
    }

    fn finish(&self) {
        if let Some(b) = self.bar.lock().expect("bar lock").take() {
            b.finish_and_clear();
        }
    }
}
