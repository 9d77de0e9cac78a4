//! The write-up as a page: sections of figure rows, tables and text, written once as
//! `index.html` (static: no script, one inline style sheet, images by relative link)
//! and once as `README.md` (GitHub Markdown) with the same content.
//!
//! Text is plain with `backquoted` code, which both writers turn into code spans.

use std::fmt::Write as _;

/// The whole write-up.
#[derive(Clone, Debug, Default)]
pub struct Page {
    pub title: String,
    pub intro: Vec<String>,
    pub sections: Vec<Section>,
}

#[derive(Clone, Debug, Default)]
pub struct Section {
    /// Anchor of the section (`part1`), for the contents list.
    pub id: String,
    pub title: String,
    pub blocks: Vec<Block>,
}

#[derive(Clone, Debug)]
pub enum Block {
    Text(String),
    Figures(FigureRow),
    Table(TableBlock),
}

/// Images shown side by side, each with its label and the commands that made it.
#[derive(Clone, Debug, Default)]
pub struct FigureRow {
    pub caption: String,
    pub figures: Vec<Figure>,
}

#[derive(Clone, Debug, Default)]
pub struct Figure {
    /// Path relative to the page, with `/` separators.
    pub image: String,
    pub label: String,
    /// Pixel size, so the page lays out before the images arrive.
    pub width: u32,
    pub height: u32,
    /// The `ember` command lines that reproduce the image (one, or the inputs of a
    /// computed image, whose `note` says how it is computed).
    pub commands: Vec<String>,
    pub note: String,
}

#[derive(Clone, Debug, Default)]
pub struct TableBlock {
    pub caption: String,
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

/// Narrower figures are given this width (in CSS pixels) for their caption's sake.
const MIN_FIGURE_WIDTH: u32 = 240;
/// The width four figures share (CSS pixels: a little under the style sheet's
/// `max-width`, for a scroll bar), and `.row`'s gap between figures.
const PAGE_WIDTH: u32 = 1200;
const ROW_GAP: u32 = 14;

/// Figures per row in the Markdown (GitHub scrolls wider tables sideways).
const MARKDOWN_COLUMNS: usize = 4;

const STYLE: &str = "\
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:1280px;margin:2em auto;padding:0 1em;color:#1b1b1b;background:#fff;line-height:1.45}
h1{font-size:1.9em}h2{margin-top:2em;border-bottom:1px solid #ddd;padding-bottom:.2em}
.row{display:flex;flex-wrap:wrap;gap:14px;align-items:flex-start;margin:.6em 0 1.4em}
figure{margin:0;max-width:100%}figure img{display:block;max-width:100%;height:auto;border:1px solid #ccc}
figcaption{font-size:.82em;margin-top:.3em;overflow-wrap:anywhere}figcaption b{display:block}
code{font-family:ui-monospace,Menlo,Consolas,monospace;font-size:.92em;background:#f3f3f3;padding:0 .2em;overflow-wrap:anywhere}
table{border-collapse:collapse;margin:.6em 0 1.4em;font-size:.9em}th,td{border:1px solid #ccc;padding:.25em .6em;text-align:left}th{background:#f3f3f3}
.caption{font-weight:600;margin-bottom:.2em}nav ol{columns:2}";

impl Page {
    pub fn to_html(&self) -> String {
        let mut h = String::new();
        h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
        h += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
        // No favicon request: the page loads nothing but its own images.
        h += "<link rel=\"icon\" href=\"data:,\">\n";
        let _ = writeln!(h, "<title>{}</title>", escape(&self.title));
        let _ = writeln!(h, "<style>\n{STYLE}\n</style>\n</head>\n<body>");
        let _ = writeln!(h, "<h1>{}</h1>", inline_html(&self.title));
        for p in &self.intro {
            let _ = writeln!(h, "<p>{}</p>", inline_html(p));
        }
        h += "<nav><ol>\n";
        for s in &self.sections {
            let _ = writeln!(
                h,
                "<li><a href=\"#{}\">{}</a></li>",
                s.id,
                inline_html(&s.title)
            );
        }
        h += "</ol></nav>\n";
        for s in &self.sections {
            let _ = writeln!(
                h,
                "<section id=\"{}\">\n<h2>{}</h2>",
                s.id,
                inline_html(&s.title)
            );
            for b in &s.blocks {
                block_html(&mut h, b);
            }
            h += "</section>\n";
        }
        h += "</body>\n</html>\n";
        h
    }

    pub fn to_markdown(&self) -> String {
        let mut m = format!("# {}\n\n", self.title);
        for p in &self.intro {
            m += &format!("{p}\n\n");
        }
        for (i, s) in self.sections.iter().enumerate() {
            m += &format!("{}. [{}](#{})\n", i + 1, s.title, s.id);
        }
        for s in &self.sections {
            // An explicit anchor: GitHub's own would depend on the title's words.
            m += &format!("\n<a id=\"{}\"></a>\n\n## {}\n\n", s.id, s.title);
            for b in &s.blocks {
                block_markdown(&mut m, b);
            }
        }
        m
    }

    /// Every image the page links to, relative to it.
    pub fn images(&self) -> Vec<&str> {
        let figures = self.sections.iter().flat_map(|s| &s.blocks);
        figures
            .filter_map(|b| match b {
                Block::Figures(row) => Some(row.figures.iter().map(|f| f.image.as_str())),
                _ => None,
            })
            .flatten()
            .collect()
    }
}

fn block_html(h: &mut String, b: &Block) {
    match b {
        Block::Text(t) => {
            let _ = writeln!(h, "<p>{}</p>", inline_html(t));
        }
        Block::Figures(row) => {
            if !row.caption.is_empty() {
                let _ = writeln!(h, "<p class=\"caption\">{}</p>", inline_html(&row.caption));
            }
            h.push_str("<div class=\"row\">\n");
            // Up to four figures side by side in the page's width.
            let k = row.figures.len().clamp(1, 4) as u32;
            let slot = (PAGE_WIDTH - ROW_GAP * (k - 1)) / k;
            for f in &row.figures {
                let _ = write!(
                    h,
                    "<figure style=\"width:{}px\"><img src=\"{}\" alt=\"{}\" width=\"{}\" height=\"{}\">\
                     <figcaption><b>{}</b>",
                    f.width.min(slot).max(MIN_FIGURE_WIDTH),
                    escape(&f.image),
                    escape(&f.label),
                    f.width,
                    f.height,
                    inline_html(&f.label)
                );
                for c in &f.commands {
                    let _ = write!(h, "<code>{}</code><br>", escape(c));
                }
                if !f.note.is_empty() {
                    let _ = write!(h, "{}", inline_html(&f.note));
                }
                h.push_str("</figcaption></figure>\n");
            }
            h.push_str("</div>\n");
        }
        Block::Table(t) => {
            if !t.caption.is_empty() {
                let _ = writeln!(h, "<p class=\"caption\">{}</p>", inline_html(&t.caption));
            }
            h.push_str("<table>\n<tr>");
            for c in &t.header {
                let _ = write!(h, "<th>{}</th>", inline_html(c));
            }
            h.push_str("</tr>\n");
            for r in &t.rows {
                h.push_str("<tr>");
                for c in r {
                    let _ = write!(h, "<td>{}</td>", inline_html(c));
                }
                h.push_str("</tr>\n");
            }
            h.push_str("</table>\n");
        }
    }
}

fn block_markdown(m: &mut String, b: &Block) {
    match b {
        Block::Text(t) => *m += &format!("{t}\n\n"),
        Block::Figures(row) => {
            if !row.caption.is_empty() {
                *m += &format!("**{}**\n\n", row.caption);
            }
            for chunk in row.figures.chunks(MARKDOWN_COLUMNS) {
                let cells = |f: &dyn Fn(&Figure) -> String| -> String {
                    let cells: Vec<String> = chunk.iter().map(f).collect();
                    format!("| {} |\n", cells.join(" | "))
                };
                *m += &cells(&|f| cell_markdown(&f.label));
                *m += &format!("|{}\n", "---|".repeat(chunk.len()));
                *m += &cells(&|f| format!("![{}]({})", cell_markdown(&f.label), f.image));
                *m += &cells(&|f| {
                    let mut parts: Vec<String> = f.commands.iter().map(|c| code_span(c)).collect();
                    if !f.note.is_empty() {
                        parts.push(cell_markdown(&f.note));
                    }
                    parts.join("<br>")
                });
                *m += "\n";
            }
        }
        Block::Table(t) => {
            if !t.caption.is_empty() {
                *m += &format!("**{}**\n\n", t.caption);
            }
            let line = |cells: &[String]| {
                let cells: Vec<String> = cells.iter().map(|c| cell_markdown(c)).collect();
                format!("| {} |\n", cells.join(" | "))
            };
            *m += &line(&t.header);
            *m += &format!("|{}\n", "---|".repeat(t.header.len()));
            for r in &t.rows {
                *m += &line(r);
            }
            *m += "\n";
        }
    }
}

/// Text for a Markdown table cell: a `|` would end the cell.
fn cell_markdown(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// `s` as an inline code span, with a fence longer than any run of backquotes in it.
fn code_span(s: &str) -> String {
    let longest = s.split(|c| c != '`').map(str::len).max().unwrap_or(0);
    let fence = "`".repeat(longest + 1);
    let pad = if s.starts_with('`') || s.ends_with('`') {
        " "
    } else {
        ""
    };
    cell_markdown(&format!("{fence}{pad}{s}{pad}{fence}"))
}

/// `s` with HTML's special characters escaped.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// Plain text with `backquoted` spans as escaped HTML with `<code>` elements.
fn inline_html(s: &str) -> String {
    let mut out = String::new();
    for (i, part) in s.split('`').enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<code>{}</code>", escape(part));
        } else {
            out.push_str(&escape(part));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn page() -> Page {
        Page {
            title: "Write-up".into(),
            intro: vec!["Made by `ember report`.".into()],
            sections: vec![Section {
                id: "part1".into(),
                title: "Part 1 <one>".into(),
                blocks: vec![
                    Block::Figures(FigureRow {
                        caption: "Normals".into(),
                        figures: vec![Figure {
                            image: "figures/a.png".into(),
                            label: "a | b".into(),
                            width: 80,
                            height: 60,
                            commands: vec!["ember -f 'x y.png' a.dae".into()],
                            note: String::new(),
                        }],
                    }),
                    Block::Table(TableBlock {
                        caption: "t".into(),
                        header: vec!["x".into(), "y".into()],
                        rows: vec![vec!["1".into(), "`2`".into()]],
                    }),
                ],
            }],
        }
    }

    #[test]
    fn html_escapes_text_and_links_every_image() {
        let h = page().to_html();
        assert!(h.contains("<h2>Part 1 &lt;one&gt;</h2>"), "{h}");
        assert!(h.contains("<img src=\"figures/a.png\""), "{h}");
        assert!(
            h.contains("<code>ember -f &#39;x y.png&#39; a.dae</code>"),
            "{h}"
        );
        assert!(h.contains("<td><code>2</code></td>"), "{h}");
        assert!(!h.contains("<script"));
        assert_eq!(page().images(), ["figures/a.png"]);
    }

    #[test]
    fn markdown_tables_keep_one_cell_per_column() {
        let m = page().to_markdown();
        assert!(m.contains("![a \\| b](figures/a.png)"), "{m}");
        for line in m.lines().filter(|l| l.starts_with('|')) {
            let cells = line.replace("\\|", "").matches('|').count() - 1;
            assert!(cells == 1 || cells == 2, "{line}");
        }
        assert!(m.contains("1. [Part 1 <one>](#part1)"), "{m}");
    }

    #[test]
    fn code_spans_survive_backquotes() {
        assert_eq!(code_span("a`b"), "``a`b``");
        assert_eq!(code_span("x"), "`x`");
    }
}
