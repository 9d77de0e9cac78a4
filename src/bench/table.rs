//! One report table, written as CSV (for scripts) and as Markdown (for BENCHMARKS.md).

use anyhow::{Context, Result};
use std::path::Path;

/// Rows of already formatted cells under one header.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    pub fn new<S: Into<String>>(header: impl IntoIterator<Item = S>) -> Table {
        Table {
            header: header.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }

    pub fn push(&mut self, row: Vec<String>) {
        debug_assert_eq!(row.len(), self.header.len(), "cells per row");
        self.rows.push(row);
    }

    /// Comma-separated; a cell holding a comma, quote or newline is quoted.
    pub fn to_csv(&self) -> String {
        let line = |cells: &[String]| {
            let quoted: Vec<String> = cells.iter().map(|c| csv_cell(c)).collect();
            quoted.join(",") + "\n"
        };
        let mut s = line(&self.header);
        for r in &self.rows {
            s += &line(r);
        }
        s
    }

    /// Reads what [`Table::to_csv`] wrote: the first line is the header, every row
    /// must have as many cells. Quoted cells may hold commas, quotes and newlines.
    pub fn from_csv(text: &str) -> Result<Table, String> {
        let mut lines = parse_csv(text)?.into_iter();
        let header = lines.next().ok_or("empty CSV: no header")?;
        let mut t = Table {
            header,
            rows: Vec::new(),
        };
        for (i, row) in lines.enumerate() {
            if row.len() != t.header.len() {
                return Err(format!(
                    "CSV line {}: {} cells, the header has {}",
                    i + 2,
                    row.len(),
                    t.header.len()
                ));
            }
            t.rows.push(row);
        }
        Ok(t)
    }

    /// A GitHub-flavoured Markdown table: a `|` inside a cell is escaped, so every row
    /// has as many cells as the header.
    pub fn to_markdown(&self) -> String {
        let line = |cells: &[String]| {
            let cells: Vec<String> = cells.iter().map(|c| markdown_cell(c)).collect();
            format!("| {} |\n", cells.join(" | "))
        };
        let mut s = line(&self.header);
        s += &format!("|{}\n", "---|".repeat(self.header.len()));
        for r in &self.rows {
            s += &line(r);
        }
        s
    }

    /// Writes `<stem>.csv` and `<stem>.md`.
    pub fn write(&self, stem: &Path) -> Result<()> {
        for (ext, text) in [("csv", self.to_csv()), ("md", self.to_markdown())] {
            let p = stem.with_extension(ext);
            std::fs::write(&p, text).with_context(|| format!("{}: cannot write", p.display()))?;
        }
        Ok(())
    }
}

/// A cell's text for a Markdown table: `|` would end the cell, a newline the row.
fn markdown_cell(c: &str) -> String {
    c.replace('|', "\\|").replace('\n', " ")
}

/// The cells of each row of a Markdown table (header and rule included), counting
/// `\|` as text: what a reader of the table sees.
pub fn markdown_cell_counts(md: &str) -> Vec<usize> {
    md.lines()
        .filter(|l| l.starts_with('|'))
        .map(|l| l.replace("\\|", "").matches('|').count() - 1)
        .collect()
}

fn csv_cell(c: &str) -> String {
    if c.contains([',', '"', '\n']) {
        format!("\"{}\"", c.replace('"', "\"\""))
    } else {
        c.to_string()
    }
}

/// Records of RFC 4180 CSV (a final newline optional).
fn parse_csv(text: &str) -> Result<Vec<Vec<String>>, String> {
    let (mut records, mut record, mut cell) = (Vec::new(), Vec::new(), String::new());
    let mut chars = text.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                cell.push('"');
            }
            (true, '"') => quoted = false,
            (true, c) => cell.push(c),
            (false, '"') if cell.is_empty() => quoted = true,
            (false, ',') => record.push(std::mem::take(&mut cell)),
            (false, '\n') => {
                record.push(std::mem::take(&mut cell));
                records.push(std::mem::take(&mut record));
            }
            (false, '\r') => {}
            (false, c) => cell.push(c),
        }
    }
    if quoted {
        return Err("CSV ends inside a quoted cell".into());
    }
    if !cell.is_empty() || !record.is_empty() {
        record.push(cell);
        records.push(record);
    }
    Ok(records)
}

#[cfg(test)]
mod tests {
    use super::Table;

    #[test]
    fn csv_quotes_what_needs_it_and_markdown_has_a_rule() {
        let mut t = Table::new(["a", "b"]);
        t.push(vec!["1".into(), "x, \"y\"".into()]);
        assert_eq!(t.to_csv(), "a,b\n1,\"x, \"\"y\"\"\"\n");
        assert_eq!(t.to_markdown(), "| a | b |\n|---|---|\n| 1 | x, \"y\" |\n");
    }

    #[test]
    fn markdown_escapes_pipes_so_rows_keep_their_cell_count() {
        let mut t = Table::new(["case", "note"]);
        t.push(vec!["6".into(), "max |y| 2.4e-7".into()]);
        let md = t.to_markdown();
        assert!(md.contains("max \\|y\\| 2.4e-7"), "{md}");
        assert_eq!(super::markdown_cell_counts(&md), [2, 2, 2]);
    }

    #[test]
    fn csv_reads_back_what_it_wrote() {
        let mut t = Table::new(["a", "b", "c"]);
        t.push(vec!["1".into(), "x, \"y\"".into(), "two\nlines".into()]);
        t.push(vec!["".into(), "".into(), "z".into()]);
        assert_eq!(Table::from_csv(&t.to_csv()), Ok(t));
        assert!(Table::from_csv("a,b\n1\n").unwrap_err().contains("line 2"));
        assert!(Table::from_csv("a\n\"open\n").is_err());
    }
}
