//! `plie`: the command-line tool. Parses arguments, calls the library, prints results and errors.
//! One file per subcommand; errors get context here and end the process with a one-line message and
//! exit code 1 (clap's usage errors exit with 2).

mod bench;
mod bench_chart;
mod bench_data;
mod bench_path;
mod bench_report;
mod bench_soft;
mod budget;
mod build;
mod checks;
mod image_args;
mod inspect;
mod out_dir;
mod path_args;
mod plie_args;
mod progress;
mod render;
mod render_path;
mod scene_arg;
mod scenes;
mod threads_arg;
mod verify;
mod walkthrough;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// Exact soft shadows from area lights with Preprocessed Local Illumination Environments.
#[derive(Parser)]
#[command(name = "plie", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in scenes: name, triangles, lights, and what each one is.
    Scenes(scenes::Args),
    /// Render a scene: direct lighting from its area lights, or global illumination (--integrator path).
    Render(Box<render::Args>),
    /// Build a scene's P-LIE and save it (.plie) for `plie render --plie`: per octree cell face and
    /// light, the triangles that can block the light and where the face is fully or partly shadowed.
    Build(Box<build::Args>),
    /// Show what the P-LIE stores for a cell: a picture, a glTF scene, or a per-leaf summary.
    Inspect(Box<inspect::Args>),
    /// Check a P-LIE file against a rebuild: a sample of records by shadow rays, or all (--full).
    Verify(Box<verify::Args>),
    /// Measure P-LIE build, shading and shadow-ray throughput per scene and mode, and write a report.
    Bench(Box<bench::Args>),
}

fn main() {
    // Output piped into a reader that stops early (`plie scenes --json | head -1`) ends the process
    // quietly, as for other command-line tools, instead of a panic in `println!`.
    #[cfg(unix)]
    // SAFETY: called first in `main`, before any other thread exists; SIG_DFL is a valid handler.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let parsed = Cli::command().try_get_matches().and_then(|m| Cli::from_arg_matches(&m).map(|cli| (cli, m)));
    let (cli, matches) = match parsed {
        Ok(parsed) => parsed,
        Err(e) if e.use_stderr() => {
            // One line: clap's first paragraph (the problem), without the usage and tips that follow.
            let text = e.render().to_string();
            let first: Vec<&str> = text.lines().map(str::trim).take_while(|l| !l.is_empty()).collect();
            eprintln!("{}", checks::shorten_long_words(&first.join(" ")));
            std::process::exit(e.exit_code());
        }
        Err(e) => e.exit(),
    };
    // The subcommand's matches: which options were given explicitly (`plie render --plie`).
    let sub = matches.subcommand().map(|(_, m)| m.clone()).unwrap_or_default();
    let result = match cli.command {
        Command::Scenes(a) => scenes::run(&a),
        Command::Render(a) => render::run(&a, &sub),
        Command::Build(a) => build::run(&a),
        Command::Inspect(a) => inspect::run(&a, &sub),
        Command::Bench(a) => bench::run(&a),
        Command::Verify(a) => verify::run(&a),
    };
    if let Err(e) = result {
        eprintln!("error: {}", checks::shorten_long_words(&one_line(&e)));
        std::process::exit(1);
    }
}

/// The error and its causes on one line.
fn one_line(e: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in e.chain() {
        let s = cause.to_string().replace('\n', " ");
        if !parts.iter().any(|p| p.contains(&s)) {
            parts.push(s);
        }
    }
    parts.join(": ")
}
