//! Progress on stderr behind the library's `Progress` trait: a bar with an ETA (indicatif) when stderr
//! is a terminal, one line every [`LINE_EVERY`] otherwise (logs, CI), nothing when quiet. Also the
//! Ctrl-C flag ([`install_interrupt`]) that long work polls through [`Progress::cancelled`].

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use plie::Progress;

/// Interval of the one-line progress when stderr is not a terminal.
const LINE_EVERY: Duration = Duration::from_secs(10);

/// Set by the Ctrl-C handler.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Makes Ctrl-C (SIGINT, SIGTERM) set a flag that [`Bar::cancelled`] reports instead of killing the
/// process, so a build returns an "interrupted" error and writes nothing.
pub fn install_interrupt() -> anyhow::Result<()> {
    ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst))
        .map_err(|e| anyhow::anyhow!("cannot install the Ctrl-C handler: {e}"))
}

/// Whether Ctrl-C was pressed.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// One-line progress of a stage (stderr not a terminal).
struct Lines {
    stage: String,
    total: u64,
    done: u64,
    start: Instant,
    last: Instant,
}

/// Shows one bar per stage on stderr, or periodic lines, or nothing when quiet.
pub struct Bar {
    quiet: bool,
    terminal: bool,
    bar: Mutex<Option<ProgressBar>>,
    lines: Mutex<Option<Lines>>,
}

impl Bar {
    pub fn new(quiet: bool) -> Bar {
        Bar { quiet, terminal: std::io::stderr().is_terminal(), bar: Mutex::new(None), lines: Mutex::new(None) }
    }

    /// A warning on stderr, unless quiet.
    pub fn warn(&self, msg: &str) {
        if !self.quiet {
            match self.bar.lock().expect("bar lock").as_ref() {
                Some(b) => b.suspend(|| eprintln!("warning: {msg}")),
                None => eprintln!("warning: {msg}"),
            }
        }
    }
}

/// `12 s`, `3 min 4 s`, `1 h 2 min`.
fn duration(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {} s", s / 60, s % 60),
        _ => format!("{} h {} min", s / 3600, s % 3600 / 60),
    }
}

impl Progress for Bar {
    fn start(&self, stage: &str, total: u64) {
        if self.quiet {
            return;
        }
        if !self.terminal {
            let now = Instant::now();
            *self.lines.lock().expect("lines lock") =
                Some(Lines { stage: stage.to_string(), total, done: 0, start: now, last: now });
            return;
        }
        let b = ProgressBar::new(total);
        b.set_style(
            ProgressStyle::with_template("{prefix:>10} [{elapsed_precise}] {wide_bar} {pos}/{len} ETA {eta}")
                .expect("valid template"),
        );
        b.set_prefix(stage.to_string());
        *self.bar.lock().expect("bar lock") = Some(b);
    }

    fn advance(&self, n: u64) {
        if let Some(b) = self.bar.lock().expect("bar lock").as_ref() {
            b.inc(n);
        }
        if let Some(l) = self.lines.lock().expect("lines lock").as_mut() {
            l.done += n;
            if l.last.elapsed() >= LINE_EVERY {
                l.last = Instant::now();
                let elapsed = l.start.elapsed().as_secs_f64();
                let eta =
                    if l.done > 0 { elapsed * (l.total - l.done.min(l.total)) as f64 / l.done as f64 } else { 0.0 };
                eprintln!(
                    "{}: {}/{} ({:.0}%), {} elapsed, ETA {}",
                    l.stage,
                    l.done,
                    l.total,
                    100.0 * l.done as f64 / l.total.max(1) as f64,
                    duration(elapsed),
                    duration(eta)
                );
            }
        }
    }

    fn finish(&self) {
        if let Some(b) = self.bar.lock().expect("bar lock").take() {
            b.finish_and_clear();
        }
        self.lines.lock().expect("lines lock").take();
    }

    fn cancelled(&self) -> bool {
        interrupted()
    }
}
