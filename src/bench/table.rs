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

    /// A GitHub-flavoured Markdown table.
    pub fn to_markdown(&self) -> String {
        let line = |cells: &[String]| format!("| {} |\n", cells.join(" | "));
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

fn csv_cell(c: &str) -> String {
    if c.contains([',', '"', '\n']) {
        format!("\"{}\"", c.replace('"', "\"\""))
    } else {
        c.to_string()
    }
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
}
