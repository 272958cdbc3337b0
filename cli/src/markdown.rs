//! Markdown for the three reports (`REPORT.md`, `CROSSCHECK.md`, `BENCHMARKS.md`): a document
//! of headings, paragraphs and tables ([`Doc`], [`Table`]), number formats and verdicts. Every
//! report writer is a sequence of short section functions over these.

use std::fmt::{self, Display};
use std::path::Path;

/// The text of a missing value.
pub const NONE: &str = "–";

/// A markdown document being written; blocks are separated by blank lines.
#[derive(Debug, Default)]
pub struct Doc(String);

impl Doc {
    /// A heading of `level` (1: `#`, 2: `##`, …).
    pub fn heading(&mut self, level: usize, text: impl Display) {
        self.0 += &format!("{} {text}\n\n", "#".repeat(level));
    }
    /// A heading of `level` followed by the paragraph `intro`.
    pub fn section(&mut self, level: usize, title: impl Display, intro: impl Display) {
        self.heading(level, title);
        self.para(intro);
    }
    /// A paragraph (or any block: a list, an image).
    pub fn para(&mut self, text: impl Display) {
        self.0 += &format!("{text}\n\n");
    }
    /// A table.
    pub fn table(&mut self, table: &Table) {
        self.0 += &format!("{table}\n");
    }
    /// Inserts `text` at byte `at` of the document (e.g. a summary known only at the end).
    pub fn insert(&mut self, at: usize, text: &str) {
        self.0.insert_str(at, text);
    }
    /// The byte offset of the end of the document so far (a place for [`Doc::insert`]).
    pub fn end(&self) -> usize {
        self.0.len()
    }
    /// Writes the document to `path` (ending in a single newline).
    pub fn write(&self, path: &Path) -> gradvi::Result<()> {
        std::fs::write(path, format!("{}\n", self.0.trim_end())).map_err(|source| {
            gradvi::Error::Io {
                path: path.to_path_buf(),
                source,
            }
        })
    }
}

impl Display for Doc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// A markdown table: a header row, an alignment per column, rows of cells.
#[derive(Debug, Clone)]
pub struct Table {
    header: Vec<String>,
    right: Vec<bool>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with the column headers `header`, separated by `|` (e.g. `"mesh | h"`); `align`
    /// has one letter per column, `l` (left) or `r` (right, for numbers).
    pub fn new(header: &str, align: &str) -> Self {
        let header: Vec<String> = header.split('|').map(|h| h.trim().to_string()).collect();
        assert_eq!(header.len(), align.len(), "one alignment letter per column");
        Self {
            header,
            right: align.chars().map(|c| c == 'r').collect(),
            rows: Vec::new(),
        }
    }
    /// Appends a row (see [`cells!`]).
    pub fn row(&mut self, cells: Vec<String>) {
        assert_eq!(cells.len(), self.header.len(), "one cell per column");
        self.rows.push(cells);
    }
}

impl Display for Table {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let line = |cells: &[String]| {
            let padded: Vec<String> = (cells.iter())
                .map(|c| {
                    if c.is_empty() {
                        " ".into()
                    } else {
                        format!(" {c} ")
                    }
                })
                .collect();
            format!("|{}|", padded.join("|"))
        };
        writeln!(f, "{}", line(&self.header))?;
        let rule: Vec<&str> = (self.right.iter())
            .map(|&r| if r { "---:" } else { "---" })
            .collect();
        writeln!(f, "|{}|", rule.join("|"))?;
        for r in &self.rows {
            writeln!(f, "{}", line(r))?;
        }
        Ok(())
    }
}

/// The cells of a table row from values that implement `Display`: `cells![a, b, c]`.
#[macro_export]
macro_rules! cells {
    ($($x:expr),* $(,)?) => { vec![$($x.to_string()),*] };
}
pub use cells;

/// `x` with `d` decimals; [`NONE`] when not finite.
pub fn fixed(x: f64, d: usize) -> String {
    if x.is_finite() {
        format!("{x:.d$}")
    } else {
        NONE.into()
    }
}

/// [`fixed`] of an optional value.
pub fn opt(x: Option<f64>, d: usize) -> String {
    fixed(x.unwrap_or(f64::NAN), d)
}

/// An optional value in scientific notation with two decimals (`1.23e-4`).
pub fn sci(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:.2e}"),
        _ => NONE.into(),
    }
}

/// A duration in seconds with three significant digits or so (`0.012`, `1.23`, `12.3`, `123`).
pub fn seconds(x: f64) -> String {
    let d = match x {
        x if x >= 100.0 => 0,
        x if x >= 10.0 => 1,
        x if x >= 0.1 => 2,
        _ => 3,
    };
    fixed(x, d)
}

/// Items joined by ", ".
pub fn list<T: Display>(items: impl IntoIterator<Item = T>) -> String {
    let v: Vec<String> = items.into_iter().map(|x| x.to_string()).collect();
    v.join(", ")
}

/// The verdict of a comparison with a tolerance: **PASS** or **FAIL**.
pub fn pass(ok: bool) -> &'static str {
    if ok { "**PASS**" } else { "**FAIL**" }
}

/// The verdict on a target: **met** or **not met**.
pub fn met(ok: bool) -> &'static str {
    if ok { "**met**" } else { "**not met**" }
}

/// "yes" or "no".
pub fn yes_no(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}

/// Convergence orders ln(e₁/e₂)/ln(h₁/h₂) between successive rows of `(h, e)` with two
/// decimals; [`NONE`] for the first row and where an error is missing.
pub fn orders(he: &[(f64, Option<f64>)]) -> Vec<String> {
    let pair = |w: &[(f64, Option<f64>)]| match (w[0], w[1]) {
        ((h1, Some(e1)), (h2, Some(e2))) => fixed(gradvi::post::order(e1, e2, h1, h2), 2),
        _ => NONE.into(),
    };
    let first = (!he.is_empty()).then(|| NONE.to_string());
    first.into_iter().chain(he.windows(2).map(pair)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_renders_header_rule_and_rows() {
        let mut t = Table::new("case | h |", "lrl");
        t.row(cells!["a", fixed(0.25, 3), "ok"]);
        t.row(cells!["b", fixed(f64::NAN, 3), ""]);
        let text = t.to_string();
        let expected = "| case | h | |\n|---|---:|---|\n| a | 0.250 | ok |\n| b | – | |\n";
        assert_eq!(text, expected);
        let mut doc = Doc::default();
        doc.heading(2, "Meshes");
        doc.table(&t);
        doc.para("end");
        assert!(doc.to_string().starts_with("## Meshes\n\n| case |"));
        assert!(doc.to_string().ends_with("| |\n\nend\n\n"));
    }

    #[test]
    fn number_formats_and_verdicts() {
        assert_eq!(seconds(123.4), "123");
        assert_eq!(seconds(12.34), "12.3");
        assert_eq!(seconds(0.1234), "0.12");
        assert_eq!(seconds(0.01234), "0.012");
        assert_eq!(seconds(f64::NAN), NONE);
        assert_eq!(sci(Some(0.000123)), "1.23e-4");
        assert_eq!(sci(None), NONE);
        assert_eq!(opt(Some(1.0), 1), "1.0");
        assert_eq!(list([1, 2, 3]), "1, 2, 3");
        assert_eq!((pass(true), pass(false)), ("**PASS**", "**FAIL**"));
        assert_eq!((met(true), met(false)), ("**met**", "**not met**"));
        let o = orders(&[(0.2, Some(0.04)), (0.1, Some(0.01)), (0.05, None)]);
        assert_eq!(o, ["–", "2.00", "–"]);
    }
}
