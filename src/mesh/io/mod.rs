//! Mesh readers and writers.
//!
//! | format | read | write | notes |
//! |---|---|---|---|
//! | gmsh `.msh` (ASCII 4.1 and 2.2) | [`msh::read_msh`] | – | triangles and quadrangles; physical line tags become boundary tags |
//! | FVCA5 `.typ1` | [`typ1::read_typ1`] | – | triangles and quadrangles; hanging nodes are inserted into the cells |
//! | FVCA5 / HArDCore `.typ2` | [`typ2::read_typ2`] | [`typ2::write_typ2`] | polygons |
//! | VTK `.vtu` (ASCII XML) | – | [`vtu::write_vtu`] | polygons with any number of point and cell data arrays |
//!
//! [`read_mesh`] picks the reader from the file extension. Every reader returns
//! [`Error::MeshIo`] (with the file and the 1-based line) when the text
//! cannot be parsed, and [`Error::InvalidMesh`] when it parses but
//! the mesh is geometrically or topologically invalid (the checks of
//! [`PolyMesh::from_cells`]). Readers never panic on bad input.
//!
//! **Bounded reading.** A mesh file is text, so the readers stop reading at the first line that
//! is not: a byte that is neither printable nor a blank (`\t`, `\n`, `\r`, form feed) such as
//! the zeros of `/dev/zero`, invalid UTF-8, or a line longer than [`MAX_LINE_BYTES`]. The text
//! before that line is parsed as usual, and its parse error, if any, is reported (a binary
//! gmsh file is still reported as such); otherwise the non-text line is. No file larger than
//! [`MemoryBudget::max_file_bytes`] (a quarter of the memory budget the caller passes) is read:
//! an endless stream of text is refused once that much has been read. Counts announced by
//! headers never reserve more memory than the rest of the file could fill.

pub mod msh;
pub mod typ1;
pub mod typ2;
pub mod vtu;

pub use msh::{MshMesh, read_msh};
pub use typ1::read_typ1;
pub use typ2::{read_typ2, write_typ2};
pub use vtu::write_vtu;

use crate::budget::MemoryBudget;
use crate::budget::{AllocFailure, try_vec};
use crate::error::{Error, Result};
use crate::mesh::PolyMesh;
use std::fmt::Display;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// Reads a mesh, choosing the reader from the extension of `path` (case-insensitive):
/// `.msh` (gmsh ASCII 4.1 or 2.2, see [`read_msh`]), `.typ1` ([`read_typ1`]) or `.typ2`
/// ([`read_typ2`]). For gmsh files the physical-group names are dropped; call [`read_msh`] to
/// keep them. No file larger than [`MemoryBudget::max_file_bytes`] of `budget` is read.
pub fn read_mesh(path: impl AsRef<Path>, budget: MemoryBudget) -> Result<PolyMesh> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("msh") => read_msh(path, budget).map(|m| m.mesh),
        Some("typ1") => read_typ1(path, budget),
        Some("typ2") => read_typ2(path, budget),
        _ => Err(Error::MeshIo {
            path: path.to_path_buf(),
            line: 0,
            msg: "unknown mesh format: expected the extension .msh, .typ1 or .typ2".into(),
        }),
    }
}

/// The longest line a mesh file may have (1 MiB; the longest line of a valid file is a cell of
/// [`MAX_CELL_VERTICES`](crate::mesh::MAX_CELL_VERTICES) vertices, about 10 KB).
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// The first line of a file that is not text: its 1-based number and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct NotText {
    line: usize,
    msg: String,
}

/// The text of a mesh file: its bytes up to the first line that is not text (if any).
pub(crate) struct Text {
    pub(crate) bytes: Vec<u8>,
    pub(crate) stop: Option<NotText>,
}

/// Whether `b` may appear in a text line: printable ASCII, a blank other than the newline, or a
/// byte of a multi-byte UTF-8 character (checked per line).
fn is_text_byte(b: u8) -> bool {
    matches!(b, b' '..=b'~' | b'\t' | b'\r' | 0x0c | 0x80..=0xff)
}

/// Incremental check that a growing buffer is text, line by line.
#[derive(Default)]
struct TextScan {
    /// Start of the current (unfinished) line.
    line_start: usize,
    /// Its 1-based number, minus one.
    line: usize,
    /// Bytes of the current line already checked.
    pos: usize,
    /// Whether the current line has non-ASCII bytes (checked as UTF-8 when it ends).
    non_ascii: bool,
}

impl TextScan {
    /// Checks `bytes[self.pos..]`, `end` telling whether the file ends there. At the first line
    /// that is not text, returns the offset where that line starts and what is wrong.
    fn scan(&mut self, bytes: &[u8], end: bool) -> Option<(usize, NotText)> {
        let stop = |s: &Self, msg: String| {
            Some((
                s.line_start,
                NotText {
                    line: s.line + 1,
                    msg,
                },
            ))
        };
        while self.pos < bytes.len() {
            let rest = &bytes[self.pos..];
            let run = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
            let chunk = &rest[..run];
            if let Some(i) = chunk.iter().position(|&b| !is_text_byte(b)) {
                let msg = format!(
                    "byte 0x{:02x} is not text (byte offset {}): is this a binary file?",
                    chunk[i],
                    self.pos + i
                );
                return stop(self, msg);
            }
            self.non_ascii |= !chunk.is_ascii();
            self.pos += run;
            if self.pos - self.line_start > MAX_LINE_BYTES {
                return stop(
                    self,
                    format!(
                        "a line longer than {MAX_LINE_BYTES} bytes (from byte offset {}): not \
                         a mesh file",
                        self.line_start
                    ),
                );
            }
            if run == rest.len() {
                break;
            }
            if let Some(err) = self.end_line(bytes) {
                return Some(err);
            }
            self.pos += 1;
            self.line += 1;
            self.line_start = self.pos;
        }
        if end && self.line_start < bytes.len() {
            return self.end_line(bytes);
        }
        None
    }

    /// The UTF-8 check of the line that ends at `self.pos`.
    fn end_line(&mut self, bytes: &[u8]) -> Option<(usize, NotText)> {
        let bad = match self.non_ascii {
            true => std::str::from_utf8(&bytes[self.line_start..self.pos]).err(),
            false => None,
        };
        self.non_ascii = false;
        bad.map(|e| {
            let msg = format!(
                "invalid text (not UTF-8) at byte offset {}: is this a binary file?",
                self.line_start + e.valid_up_to()
            );
            (
                self.line_start,
                NotText {
                    line: self.line + 1,
                    msg,
                },
            )
        })
    }
}

/// The text part of `bytes` (the whole file): its prefix before the first line that is not text.
pub(crate) fn text_prefix(bytes: &[u8]) -> (&[u8], Option<NotText>) {
    match TextScan::default().scan(bytes, true) {
        Some((cut, stop)) => (&bytes[..cut], Some(stop)),
        None => (bytes, None),
    }
}

/// Reads a mesh file up to its first line that is not text (see the module docs), at most
/// [`MemoryBudget::max_file_bytes`] bytes of `budget`; I/O failures are [`Error::Io`], a file
/// too large [`Error::MeshIo`].
pub(crate) fn read_text(path: &Path, budget: MemoryBudget) -> Result<Text> {
    use std::io::Read;
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let limit = usize::try_from(budget.max_file_bytes()).unwrap_or(usize::MAX);
    let too_large = |what: String| Error::MeshIo {
        path: path.to_path_buf(),
        line: 0,
        msg: format!(
            "{what}, more than the limit of {limit} bytes (a quarter of the memory budget)"
        ),
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let known = file
        .metadata()
        .ok()
        .filter(|m| m.is_file())
        .map(|m| m.len());
    if let Some(len) = known.filter(|&len| len > limit as u64) {
        return Err(too_large(format!("the file has {len} bytes")));
    }
    const CHUNK: usize = 1 << 20;
    let what = || format!("reading {}", path.display());
    let first = known.map_or(0, |l| l as usize).saturating_add(1);
    let mut bytes: Vec<u8> = try_vec(first, &what())?;
    let mut scan = TextScan::default();
    loop {
        let len = bytes.len();
        bytes.try_reserve(CHUNK).map_err(|_| AllocFailure {
            what: what(),
            bytes: (len + CHUNK) as u64,
        })?;
        bytes.resize(len + CHUNK, 0);
        let n = match file.read(&mut bytes[len..]) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => 0,
            Err(e) => return Err(io(e)),
        };
        bytes.truncate(len + n);
        if bytes.len() > limit {
            return Err(too_large(format!("more than {limit} bytes read")));
        }
        if let Some((cut, stop)) = scan.scan(&bytes, n == 0) {
            bytes.truncate(cut);
            return Ok(Text {
                bytes,
                stop: Some(stop),
            });
        }
        if n == 0 {
            return Ok(Text { bytes, stop: None });
        }
    }
}

/// Capacity to reserve for `count` records announced by a file of which `len` bytes remain:
/// never more than those bytes could hold (a record takes at least 4 bytes, such as `"0 0\n"`),
/// so that an absurd count cannot exhaust memory before it is checked.
pub(crate) fn capacity(count: usize, len: usize) -> usize {
    count.min(len / 4 + 1)
}

/// A whitespace tokenizer over the bytes of a text file that tracks 1-based line numbers.
///
/// Tokens are maximal runs of non-whitespace bytes; they are converted to `&str` on demand, so
/// binary content that is never reached is never examined.
pub(crate) struct Tokens<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    /// Byte offset of the next unread byte.
    pos: usize,
    /// Line number at `pos`.
    line: usize,
    /// Line of the last token returned (or of `pos` before any token).
    tok_line: usize,
    /// Why the text ends early: reported when the parser reaches the end of `bytes`.
    stop: Option<NotText>,
}

impl<'a> Tokens<'a> {
    /// A tokenizer over the text part of `bytes` (see [`text_prefix`]), reporting errors
    /// against `path`.
    pub(crate) fn new(path: &'a Path, bytes: &'a [u8]) -> Self {
        let (bytes, stop) = text_prefix(bytes);
        Tokens {
            path,
            bytes,
            pos: 0,
            line: 1,
            tok_line: 1,
            stop,
        }
    }

    /// A tokenizer over a file read by [`read_text`].
    pub(crate) fn from_text(path: &'a Path, text: &'a Text) -> Self {
        Tokens {
            path,
            bytes: &text.bytes,
            pos: 0,
            line: 1,
            tok_line: 1,
            stop: text.stop.clone(),
        }
    }

    /// The end of the text: `Ok(None)` at the end of the file, the reason why the text stops
    /// early otherwise.
    fn end(&self) -> Result<Option<&'a str>> {
        match &self.stop {
            None => Ok(None),
            Some(s) => Err(self.err_at(s.line, s.msg.clone())),
        }
    }

    /// `Err` if the file stops being text somewhere after the part read so far (for readers
    /// that skip the end of a file).
    pub(crate) fn check_text(&self) -> Result<()> {
        self.end().map(|_| ())
    }

    /// Number of bytes not yet read.
    pub(crate) fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// Line of the last token returned.
    pub(crate) fn token_line(&self) -> usize {
        self.tok_line
    }

    /// A parse error at `line`.
    pub(crate) fn err_at(&self, line: usize, msg: impl Into<String>) -> Error {
        Error::MeshIo {
            path: PathBuf::from(self.path),
            line,
            msg: msg.into(),
        }
    }

    /// A parse error at the line of the last token.
    pub(crate) fn err(&self, msg: impl Into<String>) -> Error {
        self.err_at(self.tok_line, msg)
    }

    /// The number of the last line of the file (a final newline does not start a new line).
    fn last_line(&self) -> usize {
        if self.line > 1 && self.bytes.last() == Some(&b'\n') {
            self.line - 1
        } else {
            self.line
        }
    }

    fn skip_whitespace(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    /// The next token as raw bytes, or `None` at the end of the file.
    fn next_raw(&mut self) -> Option<&'a [u8]> {
        self.skip_whitespace();
        if self.pos >= self.bytes.len() {
            self.tok_line = self.last_line();
            return None;
        }
        let start = self.pos;
        while let Some(&b) = self.bytes.get(self.pos) {
            if b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        self.tok_line = self.line;
        self.bytes.get(start..self.pos)
    }

    /// The next token, or `None` at the end of the file.
    pub(crate) fn next_opt(&mut self) -> Result<Option<&'a str>> {
        match self.next_raw() {
            None => self.end(),
            Some(raw) => std::str::from_utf8(raw)
                .map(Some)
                .map_err(|_| self.err("invalid text (not ASCII/UTF-8): is this a binary file?")),
        }
    }

    /// The next token; the end of the file is an error mentioning `what` was expected.
    pub(crate) fn next(&mut self, what: &str) -> Result<&'a str> {
        self.next_with(what)
    }

    /// As [`Tokens::next`], with `what` formatted only if there is an error: readers pass
    /// `format_args!("x of node {tag}")`, which costs nothing when the value reads fine (the
    /// `…_with` methods exist so that a million-node file does not format a million messages).
    pub(crate) fn next_with(&mut self, what: impl Display) -> Result<&'a str> {
        match self.next_opt()? {
            Some(t) => Ok(t),
            None => Err(self.err(format!("unexpected end of file while reading {what}"))),
        }
    }

    /// The rest of the line of the last token (trimmed); consumes the end of line.
    pub(crate) fn rest_of_line(&mut self) -> Result<&'a str> {
        let start = self.pos;
        while let Some(&b) = self.bytes.get(self.pos) {
            if b == b'\n' {
                break;
            }
            self.pos += 1;
        }
        let raw = self.bytes.get(start..self.pos).unwrap_or_default();
        std::str::from_utf8(raw)
            .map(str::trim)
            .map_err(|_| self.err("invalid text (not ASCII/UTF-8): is this a binary file?"))
    }

    /// The next non-blank line (trimmed), with its line number; `None` at the end of the file.
    pub(crate) fn next_line(&mut self) -> Result<Option<(usize, &'a str)>> {
        self.skip_whitespace();
        if self.pos >= self.bytes.len() {
            self.tok_line = self.last_line();
            return self.end().map(|_| None);
        }
        self.tok_line = self.line;
        let line = self.line;
        self.rest_of_line().map(|s| Some((line, s)))
    }

    /// Reads a header line and checks it against `accepted` (case-insensitive, runs of blanks
    /// treated as one space). Returns the line number.
    pub(crate) fn expect_header(&mut self, accepted: &[&str]) -> Result<usize> {
        let list = accepted
            .iter()
            .map(|a| format!("\"{a}\""))
            .collect::<Vec<_>>()
            .join(" or ");
        let Some((line, text)) = self.next_line()? else {
            return Err(self.err(format!(
                "unexpected end of file: expected the header {list}"
            )));
        };
        let norm = normalize_header(text);
        if accepted.iter().any(|a| norm == *a) {
            Ok(line)
        } else {
            Err(self.err_at(
                line,
                format!("expected the header {list}, found \"{text}\""),
            ))
        }
    }

    /// The next token parsed as `T`; `what` names the value in error messages.
    pub(crate) fn parse<T: FromStr>(&mut self, what: &str) -> Result<T> {
        self.parse_with(what)
    }

    /// As [`Tokens::parse`], with `what` formatted only on error (see [`Tokens::next_with`]).
    pub(crate) fn parse_with<T: FromStr>(&mut self, what: impl Display) -> Result<T> {
        let tok = self.next_with(&what)?;
        tok.parse::<T>()
            .map_err(|_| self.err(format!("cannot read {what} from \"{tok}\"")))
    }

    /// As [`Tokens::parse_with`]`::<u64>` (gmsh node and element tags), with a fast path for the
    /// usual token of 1 to 19 ASCII digits, which cannot overflow and is converted while it is
    /// scanned; any other token is read again by [`Tokens::parse_with`], so values and errors are
    /// exactly those of `str::parse`.
    pub(crate) fn parse_u64_with(&mut self, what: impl Display) -> Result<u64> {
        let saved = (self.pos, self.line, self.tok_line);
        self.skip_whitespace();
        let start = self.pos;
        let mut end = start;
        let mut value: u64 = 0;
        while let Some(&b) = self.bytes.get(end) {
            if !b.is_ascii_digit() {
                break;
            }
            value = value.wrapping_mul(10).wrapping_add(u64::from(b - b'0'));
            end += 1;
        }
        let token_ends = self.bytes.get(end).is_none_or(|b| b.is_ascii_whitespace());
        if (1..=19).contains(&(end - start)) && token_ends {
            self.pos = end;
            self.tok_line = self.line;
            Ok(value)
        } else {
            (self.pos, self.line, self.tok_line) = saved;
            self.parse_with(what)
        }
    }

    /// A record count: a non-negative integer (a negative one gets a specific message).
    pub(crate) fn count(&mut self, what: &str) -> Result<usize> {
        self.count_with(what)
    }

    /// As [`Tokens::count`], with `what` formatted only on error (see [`Tokens::next_with`]).
    pub(crate) fn count_with(&mut self, what: impl Display) -> Result<usize> {
        let tok = self.next_with(&what)?;
        match tok.parse::<i64>() {
            Ok(n) if n < 0 => Err(self.err(format!("negative {what}: {n}"))),
            Ok(n) => usize::try_from(n).map_err(|_| self.err(format!("{what} {n} is too large"))),
            Err(_) => Err(self.err(format!(
                "cannot read {what} from \"{tok}\" (expected a non-negative integer)"
            ))),
        }
    }

    /// A finite floating-point number.
    pub(crate) fn coord(&mut self, what: &str) -> Result<f64> {
        self.coord_with(what)
    }

    /// As [`Tokens::coord`], with `what` formatted only on error (see [`Tokens::next_with`]).
    pub(crate) fn coord_with(&mut self, what: impl Display) -> Result<f64> {
        let tok = self.next_with(&what)?;
        match tok.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            Ok(_) => Err(self.err(format!("{what} is not finite: \"{tok}\""))),
            Err(_) => Err(self.err(format!("cannot read {what} from \"{tok}\""))),
        }
    }

    /// A 1-based index in `1..=n`, returned 0-based.
    pub(crate) fn index1(&mut self, what: &str, n: usize) -> Result<usize> {
        let tok = self.next(what)?;
        match tok.parse::<u64>() {
            Ok(i) if i >= 1 && i <= n as u64 => Ok(i as usize - 1),
            Ok(i) => Err(self.err(format!("{what} {i} is out of range 1..={n}"))),
            Err(_) => Err(self.err(format!(
                "cannot read {what} from \"{tok}\" (expected a positive integer)"
            ))),
        }
    }
}

/// Lower-cases a header and collapses runs of blanks into single spaces.
pub(crate) fn normalize_header(text: &str) -> String {
    text.split_ascii_whitespace()
        .map(str::to_ascii_lowercase)
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokenizer_tracks_lines() {
        let p = Path::new("t.txt");
        let mut t = Tokens::new(p, b"  a b\r\n\n c\n d e f \n");
        assert_eq!(t.next("x").unwrap(), "a");
        assert_eq!(t.token_line(), 1);
        assert_eq!(t.rest_of_line().unwrap(), "b");
        assert_eq!(t.next("x").unwrap(), "c");
        assert_eq!(t.token_line(), 3);
        assert_eq!(t.next_line().unwrap(), Some((4, "d e f")));
        assert_eq!(t.next_opt().unwrap(), None);
        let e = t.next("the answer").unwrap_err().to_string();
        assert!(e.contains("t.txt:4:") && e.contains("end of file"), "{e}");
    }

    #[test]
    fn u64_fast_path_matches_str_parse() {
        let p = Path::new("t.txt");
        let text = "7 0012 +5 18446744073709551615 18446744073709551616 \
                    1234567890123456789 12345678901234567890 -1 3x 4.0 \u{e9}9";
        let mut fast = Tokens::new(p, text.as_bytes());
        let mut slow = Tokens::new(p, text.as_bytes());
        // 11 tokens, then the end of the file
        for _ in 0..12 {
            let a = fast.parse_u64_with("n").map_err(|e| e.to_string());
            let b = slow.parse::<u64>("n").map_err(|e| e.to_string());
            assert_eq!(a, b);
            assert_eq!(
                (fast.pos, fast.line, fast.tok_line),
                (slow.pos, slow.line, slow.tok_line)
            );
        }
        assert_eq!(fast.pos, text.len());
        let mut t = Tokens::new(p, b"\n\n 42\n");
        assert_eq!(t.parse_u64_with("n").unwrap(), 42);
        assert_eq!(t.token_line(), 3);
        let e = t.parse_u64_with("the tag").unwrap_err().to_string();
        assert!(
            e.contains("t.txt:3:") && e.contains("end of file while reading the tag"),
            "{e}"
        );
    }

    #[test]
    fn numbers() {
        let p = Path::new("t.txt");
        let mut t = Tokens::new(p, b"-3 0. 7.8E-002 nan 0 5 x");
        assert!(t.count("n").unwrap_err().to_string().contains("negative"));
        assert_eq!(t.coord("x").unwrap(), 0.0);
        assert_eq!(t.coord("x").unwrap(), 7.8e-2);
        assert!(t.coord("x").is_err());
        assert!(t.index1("id", 5).is_err());
        assert_eq!(t.index1("id", 5).unwrap(), 4);
        assert!(t.parse::<i32>("tag").is_err());
    }

    /// Small edits of valid typ1 and typ2 files are rejected with messages that start with
    /// `prefix` (the file and line) and contain `needle`.
    #[test]
    fn edited_files_are_rejected() {
        type Parser = fn(&Path, &[u8]) -> Result<crate::mesh::PolyMesh>;
        let (t1, t2): (Parser, Parser) = (typ1::parse_typ1, typ2::parse_typ2);
        let (hanging, square) = (typ1::tests::HANGING, typ2::tests::SQUARE);
        let cases = [
            // typ1: wrong cells for an edge
            (
                t1,
                "h.typ1",
                hanging,
                "7 8 2 3\n",
                "7 8 2 1\n",
                "h.typ1:38:",
                "",
            ),
            // typ1: a missing boundary edge
            (
                t1,
                "h.typ1",
                hanging,
                " 7\n1 2\n2 3\n",
                " 6\n1 2\n",
                "",
                "boundary edges",
            ),
            // typ1: L out of range
            (
                t1,
                "h.typ1",
                hanging,
                "7 8 2 3\n",
                "7 8 2 4\n",
                "h.typ1:38:",
                "",
            ),
            // typ2: a bad number, a vertex out of range, a bad block name
            (
                t2,
                "sq.typ2",
                square,
                "1 1.0E+000",
                "1 1.0E+0x0",
                "sq.typ2:5:",
                "",
            ),
            (
                t2,
                "sq.typ2",
                square,
                "4 1 2 3 4",
                "4 1 2 3 5",
                "sq.typ2:9:",
                "",
            ),
            (t2, "sq.typ2", square, "centers", "more", "sq.typ2:10:", ""),
        ];
        for (parse, name, text, from, to, prefix, needle) in cases {
            assert!(text.contains(from), "{name}: no {from:?} to edit");
            let bad = text.replace(from, to);
            let e = parse(Path::new(name), bad.as_bytes())
                .unwrap_err()
                .to_string();
            assert!(e.starts_with(prefix) && e.contains(needle), "{e}");
        }
    }

    /// Every prefix and many random byte corruptions of the valid test files: errors, never
    /// panics (in memory, so that it is fast; tests/unit/mesh_io.rs does a sample via files).
    #[test]
    fn fuzz_truncations_and_corruptions() {
        let cases: [(&str, &[u8]); 5] = [
            (
                "a.msh",
                include_bytes!("../../../tests/data/good/square_41.msh"),
            ),
            (
                "b.msh",
                include_bytes!("../../../tests/data/good/square_22.msh"),
            ),
            (
                "c.msh",
                include_bytes!("../../../tests/data/good/square_41_gmsh22.msh"),
            ),
            (
                "d.typ1",
                include_bytes!("../../../tests/data/good/hanging.typ1"),
            ),
            (
                "e.typ2",
                include_bytes!("../../../tests/data/good/hanging.typ2"),
            ),
        ];
        let parse = |p: &Path, b: &[u8]| match p.extension().and_then(|e| e.to_str()) {
            Some("msh") => msh::parse_msh(p, b).map(|_| ()),
            Some("typ1") => typ1::parse_typ1(p, b).map(|_| ()),
            _ => typ2::parse_typ2(p, b).map(|_| ()),
        };
        let mut rand = crate::mesh::xorshift(0x2545_f491_4f6c_dd1d);
        const NOISE: &[u8] = b"0123456789-.eE+ \n$\"x\xff";
        for (name, bytes) in cases {
            let path = Path::new(name);
            assert!(parse(path, bytes).is_ok(), "{name}");
            let run = |b: &[u8]| {
                let r = std::panic::catch_unwind(|| parse(path, b));
                assert!(
                    r.is_ok(),
                    "{name}: panic on {:?}",
                    String::from_utf8_lossy(b)
                );
            };
            for len in 0..bytes.len() {
                run(&bytes[..len]);
            }
            for _ in 0..3000 {
                let mut b = bytes.to_vec();
                for _ in 0..1 + rand() % 3 {
                    let i = (rand() % b.len() as u64) as usize;
                    b[i] = NOISE[(rand() % NOISE.len() as u64) as usize];
                }
                run(&b);
            }
        }
    }

    /// The text ends at the first line with a byte that is not text, invalid UTF-8 or more
    /// than [`MAX_LINE_BYTES`] bytes; the parser sees the lines before and then that error.
    #[test]
    fn text_stops_at_the_first_line_that_is_not_text() {
        let p = Path::new("t.msh");
        let mut long = b"a b\n".to_vec();
        long.extend(std::iter::repeat_n(b'7', MAX_LINE_BYTES + 1));
        let cases: [(&[u8], usize, &str); 6] = [
            (
                b"a b\nc \x00 d\ne\n",
                2,
                "byte 0x00 is not text (byte offset 6)",
            ),
            (
                b"a b\n\xc3\xa9\n\xff\xfe\n",
                3,
                "not UTF-8) at byte offset 7",
            ),
            (
                b"a b\n\x1b[0m\n",
                2,
                "byte 0x1b is not text (byte offset 4)",
            ),
            (b"a b\nc\n\xe9", 3, "not UTF-8) at byte offset 6"),
            (b"a b\nc\nd \xc3\xa9\xe9", 3, "not UTF-8) at byte offset 10"),
            (&long, 2, "longer than 1048576 bytes (from byte offset 4)"),
        ];
        for (bytes, line, what) in cases {
            let mut t = Tokens::new(p, bytes);
            assert_eq!(t.next("x").unwrap(), "a");
            let e = loop {
                match t.next_opt() {
                    Ok(Some(_)) => {}
                    Ok(None) => panic!("no error for {what}"),
                    Err(e) => break e.to_string(),
                }
            };
            assert!(
                e.starts_with(&format!("t.msh:{line}: ")) && e.contains(what),
                "{e}"
            );
            let mut t = Tokens::new(p, bytes);
            t.next_line().unwrap();
            if line > 2 {
                t.next_line().unwrap();
            }
            assert!(t.next_line().is_err() && t.check_text().is_err());
        }
        assert!(Tokens::new(p, "x \u{e9}\n".as_bytes()).check_text().is_ok());
        // a parse error before the non-text line wins
        let e = msh::parse_msh(p, b"$MeshFormat\n4.1 1 8\n\x01\x00\x00\x00\n").unwrap_err();
        assert!(e.to_string().starts_with("t.msh:2: binary .msh"), "{e}");
    }

    /// An endless file of zeros is refused at once, without reading it to the end.
    #[test]
    fn endless_files_are_not_read_to_the_end() {
        let zero = Path::new("/dev/zero");
        if !zero.exists() {
            return;
        }
        let t0 = std::time::Instant::now();
        let text = read_text(zero, MemoryBudget::DEFAULT).unwrap();
        assert!(text.bytes.is_empty());
        assert_eq!(text.stop.unwrap().line, 1);
        let e = msh::parse_msh(zero, &[0; 4096]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "/dev/zero:1: byte 0x00 is not text (byte offset 0): is this a binary file?"
        );
        assert!(t0.elapsed().as_secs_f64() < 5.0);
    }

    #[test]
    fn unknown_extension() {
        let e = read_mesh("foo.obj", MemoryBudget::DEFAULT).unwrap_err();
        assert!(matches!(e, Error::MeshIo { .. }), "{e}");
    }
}
