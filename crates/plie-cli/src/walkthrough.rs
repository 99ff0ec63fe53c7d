//! `plie render --camera-path PATH.json --frames A..B -o out/frame_####.png`: a walkthrough, one
//! image per frame of a keyframed camera path ([`plie::io::camera_path::CameraPath`]), all rendered from the
//! scene and the P-LIE loaded once (a P-LIE serves every camera, SPEC §4). Each frame is written
//! atomically; `--resume` skips frames whose file exists. This is what one task of a Slurm job array
//! or another render-farm manager runs.

use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use glam::Vec3;
use plie::io::camera_path::CameraPath;
use plie::Camera;
use serde_json::json;

/// A value of `--frames`: `A..B` (both included) or one frame `N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame.
    pub first: u32,
    /// Last frame (included).
    pub last: u32,
}

impl FromStr for FrameRange {
    type Err = String;

    fn from_str(s: &str) -> Result<FrameRange, String> {
        let num = |p: &str| {
            p.trim().parse::<u32>().map_err(|_| format!("`{s}` is not a frame range A..B (both included) or a frame N"))
        };
        let (first, last) = match s.split_once("..") {
            Some((a, b)) => (num(a)?, num(b.strip_prefix('=').unwrap_or(b))?),
            None => (num(s)?, num(s)?),
        };
        if last < first {
            return Err(format!("`{s}`: the last frame comes before the first"));
        }
        Ok(FrameRange { first, last })
    }
}

/// Most frames one command renders (and checks before it starts): over 11 hours of film at 24
/// frames a second; a longer path is rendered in ranges.
pub const MAX_FRAMES: u64 = 1_000_000;

/// The frames to render and where each goes.
pub struct Plan {
    path: CameraPath,
    frames: FrameRange,
    pattern: Pattern,
    resume: bool,
}

/// An output name with one run of `#` that the frame number, zero-padded to the run's length, replaces.
struct Pattern {
    before: String,
    width: usize,
    after: String,
}

impl Pattern {
    fn new(output: &Path) -> Result<Pattern> {
        let s = output.to_str().with_context(|| format!("{}: the output name is not UTF-8", output.display()))?;
        let runs =
            s.as_bytes().windows(2).filter(|w| w[0] != b'#' && w[1] == b'#').count() + usize::from(s.starts_with('#'));
        if runs != 1 {
            bail!(
                "-o {s}: a walkthrough's output needs one run of # for the frame number (e.g. out/frame_####.png), found {runs}"
            );
        }
        let start = s.find('#').expect("one run");
        let width = s[start..].bytes().take_while(|&b| b == b'#').count();
        Ok(Pattern { before: s[..start].into(), width, after: s[start + width..].into() })
    }

    fn file(&self, frame: u32) -> PathBuf {
        PathBuf::from(format!("{}{frame:0w$}{}", self.before, self.after, w = self.width))
    }
}

impl Plan {
    /// Reads and checks the camera path, the frame range (default: the whole path) and the output
    /// pattern, before any long work.
    pub fn new(camera_path: &Path, frames: Option<FrameRange>, output: &Path, resume: bool) -> Result<Plan> {
        let pattern = Pattern::new(output)?;
        let path = CameraPath::load(camera_path)?;
        let (first, last) = path.frames();
        let frames = frames.unwrap_or(FrameRange { first, last });
        if frames.first < first || frames.last > last {
            bail!(
                "--frames {}..{} is outside the camera path's frames {first}..{last} ({})",
                frames.first,
                frames.last,
                camera_path.display()
            );
        }
        let count = u64::from(frames.last - frames.first) + 1;
        if count > MAX_FRAMES {
            bail!(
                "--frames {}..{} asks for {count} frames of {}; one command renders at most {MAX_FRAMES} \
                 (give a smaller --frames range, e.g. one per render-farm task)",
                frames.first,
                frames.last,
                camera_path.display()
            );
        }
        let plan = Plan { path, frames, pattern, resume };
        for f in frames.first..=frames.last {
            plan.path.camera(f).with_context(|| format!("{}", camera_path.display()))?;
        }
        crate::checks::output_folder_exists(&plan.pattern.file(frames.first))?;
        Ok(plan)
    }

    /// The output file of `frame`.
    pub fn file(&self, frame: u32) -> PathBuf {
        self.pattern.file(frame)
    }

    /// The output files of the frames to render that exist now (the only ones that can be an
    /// input of the command), and the first frame's.
    pub fn existing_files(&self) -> impl Iterator<Item = PathBuf> + '_ {
        let (a, b) = (self.frames.first, self.frames.last);
        (a..=b).map(|f| self.file(f)).enumerate().filter(|(n, p)| *n == 0 || p.exists()).map(|(_, p)| p)
    }

    /// Renders every frame of the plan with `render` (camera to linear radiance) and writes it with
    /// `save`, skipping existing files with `--resume`. Reports each frame on stderr (unless quiet) or
    /// as one JSON line on stdout (with `json`).
    pub fn run(
        &self,
        quiet: bool,
        json: bool,
        mut render: impl FnMut(&Camera) -> Result<Vec<Vec3>>,
        save: impl Fn(&Path, Vec<Vec3>) -> Result<()>,
    ) -> Result<()> {
        let (a, b) = (self.frames.first, self.frames.last);
        let total = b - a + 1;
        for (n, frame) in (a..=b).enumerate() {
            let out = self.file(frame);
            let skipped = self.resume && out.exists();
            let t = Instant::now();
            if !skipped {
                let camera = self.path.camera(frame)?;
                let pixels = render(&camera).with_context(|| format!("frame {frame}"))?;
                save(&out, pixels)?;
            }
            let seconds = t.elapsed().as_secs_f64();
            if json {
                println!(
                    "{}",
                    json!({ "frame": frame, "output": out.display().to_string(), "skipped": skipped, "seconds": seconds })
                );
            } else if !quiet {
                let what = if skipped { "skipped (exists)".to_string() } else { format!("wrote ({seconds:.2} s)") };
                eprintln!("frame {frame} ({} of {total}) {what} {}", n + 1, out.display());
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges() {
        assert_eq!("3..7".parse(), Ok(FrameRange { first: 3, last: 7 }));
        assert_eq!("3..=7".parse(), Ok(FrameRange { first: 3, last: 7 }));
        assert_eq!("5".parse(), Ok(FrameRange { first: 5, last: 5 }));
        assert!("7..3".parse::<FrameRange>().is_err());
        assert!("a..b".parse::<FrameRange>().is_err());
        assert!("-1..3".parse::<FrameRange>().is_err());
    }

    #[test]
    fn patterns() {
        let p = Pattern::new(Path::new("out/frame_####.png")).unwrap();
        assert_eq!(p.file(7), PathBuf::from("out/frame_0007.png"));
        assert_eq!(p.file(123456), PathBuf::from("out/frame_123456.png"));
        assert_eq!(Pattern::new(Path::new("#.pfm")).unwrap().file(3), PathBuf::from("3.pfm"));
        assert!(Pattern::new(Path::new("out/frame.png")).is_err());
        assert!(Pattern::new(Path::new("out/#/frame_##.png")).is_err());
    }
}
