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

pub mod msh;
pub mod typ1;
pub mod typ2;
pub mod vtu;

pub use msh::{MshMesh, read_msh};
pub use typ1::read_typ1;
pub use typ2::{read_typ2, write_typ2};
pub use vtu::write_vtu;

use crate::error::{Error, Result};
use crate::mesh::PolyMesh;
use std::fmt::Display;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// Reads a mesh, choosing the reader from the extension of `path` (case-insensitive):
/// `.msh` (gmsh ASCII 4.1 or 2.2, see [`read_msh`]), `.typ1` ([`read_typ1`]) or `.typ2`
/// ([`read_typ2`]). For gmsh files the physical-group names are dropped; call [`read_msh`] to
/// keep them.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<PolyMesh> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("msh") => read_msh(path).map(|m| m.mesh),
        Some("typ1") => read_typ1(path),
        Some("typ2") => read_typ2(path),
        _ => Err(Error::MeshIo {
            path: path.to_path_buf(),
            line: 0,
            msg: "unknown mesh format: expected the extension .msh, .typ1 or .typ2".into(),
        }),
    }
}

/// Reads a whole file, mapping failures to [`Error::Io`].
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Capacity to reserve for `count` records announced by a file of `len` bytes: never more than
/// the file could hold, so that an absurd count cannot exhaust memory before it is checked.
pub(crate) fn capacity(count: usize, len: usize) -> usize {
    count.min(len / 2 + 1)
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
}

impl<'a> Tokens<'a> {
    /// A tokenizer over `bytes`, reporting errors against `path`.
    pub(crate) fn new(path: &'a Path, bytes: &'a [u8]) -> Self {
        Tokens {
            path,
            bytes,
            pos: 0,
            line: 1,
            tok_line: 1,
        }
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
            None => Ok(None),
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
            return Ok(None);
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

    /// Every prefix and many random byte corruptions of the valid test files: errors, never
    /// panics (in memory, so that it is fast; tests/unit/mesh_io.rs does a sample via files).
    #[test]
    fn fuzz_truncations_and_corruptions() {
        type Parser = fn(&Path, &[u8]) -> Result<()>;
        let cases: [(&str, &[u8], Parser); 5] = [
            (
                "a.msh",
                include_bytes!("../../../tests/data/good/square_41.msh"),
                |p, b| msh::parse_msh(p, b).map(|_| ()),
            ),
            (
                "b.msh",
                include_bytes!("../../../tests/data/good/square_22.msh"),
                |p, b| msh::parse_msh(p, b).map(|_| ()),
            ),
            (
                "c.msh",
                include_bytes!("../../../tests/data/good/square_41_gmsh22.msh"),
                |p, b| msh::parse_msh(p, b).map(|_| ()),
            ),
            (
                "d.typ1",
                include_bytes!("../../../tests/data/good/hanging.typ1"),
                |p, b| typ1::parse_typ1(p, b).map(|_| ()),
            ),
            (
                "e.typ2",
                include_bytes!("../../../tests/data/good/hanging.typ2"),
                |p, b| typ2::parse_typ2(p, b).map(|_| ()),
            ),
        ];
        let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
        let mut rand = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        const NOISE: &[u8] = b"0123456789-.eE+ \n$\"x\xff";
        for (name, bytes, parse) in cases {
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

    #[test]
    fn unknown_extension() {
        let e = read_mesh("foo.obj").unwrap_err();
        assert!(matches!(e, Error::MeshIo { .. }), "{e}");
    }
}
