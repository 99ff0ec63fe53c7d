//! A line filter between an OBJ/MTL file and `tobj` (SPEC §1 scene input): it counts lines, so every
//! error names one, and passes on only the lines plie uses, each checked and normalised first.
//!
//! `tobj` reports errors without line numbers, finds out-of-range indices only at the end of a group,
//! accepts `nan` as a coordinate, and panics on some malformed lines (`Ka 0.5`). The filter checks each
//! line with [`LineRules`] before `tobj` sees it; a line it rejects stops the read with an I/O error, and
//! the loader reports the filter's message and line instead of `tobj`'s. Lines plie does not need
//! (normals, texture coordinates, other material parameters) become blank lines, so `tobj` never
//! parses them and line numbers stay the same.
//!
//! Lines end in `\n`, `\r\n` or a lone `\r` (old Mac files), and a UTF-8 byte-order mark before the first
//! line is skipped, so such files read like any other; `tobj` always gets `\n` line endings.

use std::io::{self, BufRead, Read};

/// The longest line read (16 MiB): a longer one is an error, so a file without line breaks cannot
/// make the reader allocate without bound.
pub(super) const MAX_LINE_BYTES: u64 = 16 << 20;

/// Checks and rewrites one line of a file for `tobj`.
pub(super) trait LineRules {
    /// Writes the line (1-based number `line`, no line ending) as `tobj` should see it into `out` (empty
    /// to drop it), or returns what is wrong with it.
    fn rewrite(&mut self, line: usize, text: &str, out: &mut String) -> Result<(), String>;
}

/// A [`BufRead`] that reads `inner` line by line through [`LineRules`].
pub(super) struct LineFilter<R, L> {
    inner: R,
    /// The rules (public to the loader after reading).
    pub rules: L,
    raw: Vec<u8>,
    out: String,
    pos: usize,
    line: usize,
    error: Option<(usize, String)>,
}

impl<R: BufRead, L: LineRules> LineFilter<R, L> {
    /// A filter over `inner`.
    pub fn new(inner: R, rules: L) -> Self {
        LineFilter { inner, rules, raw: Vec::new(), out: String::new(), pos: 0, line: 0, error: None }
    }

    /// Number of lines read so far (the line being parsed, while `tobj` works on it).
    pub fn line(&self) -> usize {
        self.line
    }

    /// The first line the filter rejected and why.
    pub fn error(&self) -> Option<&(usize, String)> {
        self.error.as_ref()
    }

    fn fail(&mut self, message: String) -> io::Error {
        let e = io::Error::new(io::ErrorKind::InvalidData, message.clone());
        self.error.get_or_insert((self.line, message));
        e
    }

    /// Reads, checks and rewrites the next line into `out`; at the end of the file `out` stays empty.
    fn next_line(&mut self) -> io::Result<()> {
        self.out.clear();
        self.pos = 0;
        if self.error.is_some() {
            // The error was reported once; after it the file ends, so no reader can loop on errors.
            return Ok(());
        }
        self.raw.clear();
        let complete = match read_line(&mut self.inner, &mut self.raw) {
            Ok(Some(complete)) => complete,
            Ok(None) => return Ok(()),
            Err(e) => {
                self.line += 1;
                return Err(self.fail(format!("read error: {e}")));
            }
        };
        self.line += 1;
        if self.raw.len() as u64 > MAX_LINE_BYTES {
            return Err(self.fail(format!("the line is longer than the limit of {MAX_LINE_BYTES} bytes")));
        }
        // A byte-order mark (written by some Windows editors) is not part of the first line's text.
        let start = if self.line == 1 && self.raw.starts_with(BOM) { BOM.len() } else { 0 };
        let raw = std::mem::take(&mut self.raw);
        let result = match std::str::from_utf8(&raw[start..]) {
            Ok(text) => self.rules.rewrite(self.line, text, &mut self.out),
            Err(_) => Err("the line is not valid UTF-8 text".to_string()),
        };
        self.raw = raw;
        if let Err(mut message) = result {
            if !complete {
                message.push_str(" (the file ends in the middle of this line: is it truncated?)");
            }
            return Err(self.fail(message));
        }
        self.out.push('\n');
        Ok(())
    }
}

/// The UTF-8 byte-order mark.
const BOM: &[u8] = b"\xEF\xBB\xBF";

/// Reads one line of `inner` into `raw`, without its line ending: `\n`, `\r\n` or a lone `\r` (old Mac
/// files). `Some(true)` if a line ending was read, `Some(false)` if the file ends in the line or the line
/// is longer than [`MAX_LINE_BYTES`] (reading stops there), `None` at the end of the file.
fn read_line(inner: &mut impl BufRead, raw: &mut Vec<u8>) -> io::Result<Option<bool>> {
    let mut any = false;
    loop {
        let buf = match inner.fill_buf() {
            Ok(buf) => buf,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if buf.is_empty() {
            return Ok(any.then_some(false));
        }
        any = true;
        let Some(i) = buf.iter().position(|&b| b == b'\n' || b == b'\r') else {
            let n = buf.len();
            raw.extend_from_slice(buf);
            inner.consume(n);
            if raw.len() as u64 > MAX_LINE_BYTES {
                return Ok(Some(false));
            }
            continue;
        };
        let cr = buf[i] == b'\r';
        raw.extend_from_slice(&buf[..i]);
        inner.consume(i + 1);
        if cr {
            // `\r\n` is one line ending.
            loop {
                match inner.fill_buf() {
                    Ok(next) => {
                        if next.first() == Some(&b'\n') {
                            inner.consume(1);
                        }
                        break;
                    }
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                    Err(e) => return Err(e),
                }
            }
        }
        return Ok(Some(true));
    }
}

impl<R: BufRead, L: LineRules> Read for LineFilter<R, L> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let avail = self.fill_buf()?;
        let n = avail.len().min(buf.len());
        buf[..n].copy_from_slice(&avail[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl<R: BufRead, L: LineRules> BufRead for LineFilter<R, L> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        if self.pos >= self.out.len() {
            self.next_line()?;
        }
        Ok(&self.out.as_bytes()[self.pos..])
    }

    fn consume(&mut self, amt: usize) {
        self.pos = (self.pos + amt).min(self.out.len());
    }
}

/// The line without its comment: everything from a `#` that starts a word.
pub(super) fn strip_comment(line: &str) -> &str {
    if !line.as_bytes().contains(&b'#') {
        return line;
    }
    let mut prev_space = true;
    for (i, ch) in line.char_indices() {
        if ch == '#' && prev_space {
            return &line[..i];
        }
        prev_space = ch.is_whitespace();
    }
    line
}

/// The text after the first word (`usemtl`, `mtllib`, `newmtl`, `g`), trimmed.
pub(super) fn rest_after_keyword<'a>(line: &'a str, keyword: &str) -> &'a str {
    line.trim_start().get(keyword.len()..).unwrap_or("").trim()
}

/// Parses a finite `f32`; `what` names the value's owner in the error (a closure, so the name is only
/// formatted on error).
pub(super) fn parse_finite<S: std::fmt::Display>(token: &str, what: impl Fn() -> S) -> Result<f32, String> {
    match token.parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(format!("{} has a non-finite value '{}'", what(), super::input::short(token))),
        Err(_) => Err(format!("malformed number '{}' in {}", super::input::short(token), what())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Upper;
    impl LineRules for Upper {
        fn rewrite(&mut self, _: usize, text: &str, out: &mut String) -> Result<(), String> {
            if text == "bad" {
                return Err("bad line".into());
            }
            out.push_str(&text.to_uppercase());
            Ok(())
        }
    }

    #[test]
    fn rewrites_lines_and_counts_them() {
        let mut f = LineFilter::new(&b"a\r\nb\n\nc"[..], Upper);
        let lines: Vec<String> = (&mut f).lines().map(|l| l.unwrap()).collect();
        assert_eq!(lines, ["A", "B", "", "C"]);
        assert_eq!(f.line(), 4);
    }

    #[test]
    fn lone_carriage_returns_end_lines() {
        // Old Mac files end lines with `\r` alone; `\r\n` stays one line ending, also when the reader's
        // buffer ends between the two bytes.
        let text = b"a\rb\r\n\rc\r\nd\r";
        let expected = ["A", "B", "", "C", "D"];
        for capacity in [1, 2, 3, 64] {
            let mut f = LineFilter::new(io::BufReader::with_capacity(capacity, &text[..]), Upper);
            let lines: Vec<String> = (&mut f).lines().map(|l| l.unwrap()).collect();
            assert_eq!(lines, expected, "buffer of {capacity} bytes");
            assert_eq!(f.line(), 5);
        }
    }

    #[test]
    fn a_byte_order_mark_is_skipped() {
        let mut f = LineFilter::new(&b"\xEF\xBB\xBFa\nb\n"[..], Upper);
        let lines: Vec<String> = (&mut f).lines().map(|l| l.unwrap()).collect();
        assert_eq!(lines, ["A", "B"]);
        // Only at the start of the file.
        let mut f = LineFilter::new(&b"a\n\xEF\xBB\xBFb\n"[..], Upper);
        let lines: Vec<String> = (&mut f).lines().map(|l| l.unwrap()).collect();
        assert_eq!(lines, ["A", "\u{FEFF}B"]);
    }

    #[test]
    fn stops_at_a_bad_line_and_notes_truncation() {
        let mut f = LineFilter::new(&b"a\nbad"[..], Upper);
        let lines: Vec<_> = (&mut f).lines().collect();
        assert_eq!(lines.len(), 2, "the file ends after the error");
        assert!(lines[1].is_err());
        let (line, msg) = f.error().unwrap();
        assert_eq!(*line, 2);
        assert!(msg.contains("truncated"), "{msg}");
    }

    #[test]
    fn lines_are_bounded() {
        let long = vec![b'x'; MAX_LINE_BYTES as usize + 10];
        let mut f = LineFilter::new(&long[..], Upper);
        assert!((&mut f).lines().next().unwrap().is_err());
        let (line, msg) = f.error().unwrap();
        assert_eq!(*line, 1);
        assert!(msg.contains("longer than the limit"), "{msg}");
    }

    #[test]
    fn comments() {
        assert_eq!(strip_comment("Ka 1 2 3 # red"), "Ka 1 2 3 ");
        assert_eq!(strip_comment("newmtl a#b"), "newmtl a#b");
        assert_eq!(strip_comment("# all"), "");
    }
}
