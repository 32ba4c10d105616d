//! A self-contained HTML report: headings, paragraphs, tables, lists and figures, in one file
//! with its style sheet inline and every figure's SVG embedded, so it opens anywhere (mail,
//! an archive, a browser without network). Each figure also links to its SVG and PNG files
//! (`figures/NAME.svg`, `figures/NAME.png`, written by the caller beside the report), for
//! slides and papers.

use std::fmt::Write as _;

/// One block of the report, in order.
#[derive(Debug, Clone, PartialEq)]
enum Block {
    Heading(String),
    Answer(String),
    Paragraph(String),
    Warnings(Vec<String>),
    Table {
        caption: String,
        header: Vec<String>,
        rows: Vec<Vec<String>>,
    },
    Figure {
        name: String,
        caption: String,
        svg: String,
    },
}

/// The report being built.
#[derive(Debug, Clone, PartialEq)]
pub struct HtmlReport {
    title: String,
    blocks: Vec<Block>,
}

/// `s` with the five XML special characters escaped.
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

const STYLE: &str = "body{font-family:sans-serif;max-width:1180px;margin:2em auto;padding:0 1em;color:#222}\
h1{font-size:1.6em}h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc}\
.table{overflow-x:auto;max-width:100%}\
table{border-collapse:collapse;margin:1em 0;font-size:0.85em}\
caption{caption-side:top;max-width:1100px}\
th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}th{background:#f0f0f0}\
caption{text-align:left;font-weight:bold;padding:4px 0}\
figure{margin:1.5em 0}figure svg{max-width:100%;height:auto}\
figcaption{font-size:0.9em;color:#444}.warn{color:#a33}\
.answer{font-size:1.1em;line-height:1.45;border-left:4px solid #943cbd;padding:0.2em 0 0.2em 0.8em}\
@media (max-width:700px){body{margin:1em auto}\
table,tbody,tr,td,caption{display:block;width:100%;box-sizing:border-box}thead{display:none}\
tr{border:1px solid #ccc;margin:0 0 0.6em 0}td{border:0;border-bottom:1px solid #eee;\
position:relative;padding:3px 6px 3px 55%;min-height:1.2em;overflow-wrap:anywhere}\
td::before{content:attr(data-label);position:absolute;left:6px;width:50%;text-align:left;\
font-weight:bold;overflow-wrap:anywhere}}";

impl HtmlReport {
    /// An empty report with a title.
    pub fn new(title: &str) -> Self {
        Self {
            title: title.into(),
            blocks: vec![],
        }
    }

    /// A section heading.
    pub fn heading(&mut self, text: &str) {
        self.blocks.push(Block::Heading(text.into()));
    }

    /// The report's answer: a paragraph set apart at the top of the page.
    pub fn answer(&mut self, text: &str) {
        self.blocks.push(Block::Answer(text.into()));
    }

    /// A paragraph of plain text.
    pub fn paragraph(&mut self, text: &str) {
        self.blocks.push(Block::Paragraph(text.into()));
    }

    /// A list of warnings (nothing when empty).
    pub fn warnings(&mut self, items: &[String]) {
        if !items.is_empty() {
            self.blocks.push(Block::Warnings(items.to_vec()));
        }
    }

    /// A table with a caption, a header and rows of already formatted cells.
    pub fn table(&mut self, caption: &str, header: &[&str], rows: Vec<Vec<String>>) {
        self.blocks.push(Block::Table {
            caption: caption.into(),
            header: header.iter().map(|h| h.to_string()).collect(),
            rows,
        });
    }

    /// A figure: its SVG inline, links to `figures/NAME.svg` and `figures/NAME.png`.
    pub fn figure(&mut self, name: &str, caption: &str, svg: String) {
        self.blocks.push(Block::Figure {
            name: name.into(),
            caption: caption.into(),
            svg,
        });
    }

    /// The figure files the report links to, relative to its folder.
    pub fn figure_files(&self) -> Vec<String> {
        self.blocks
            .iter()
            .filter_map(|b| match b {
                Block::Figure { name, .. } => Some(name),
                _ => None,
            })
            .flat_map(|n| [format!("figures/{n}.svg"), format!("figures/{n}.png")])
            .collect()
    }

    /// The whole document.
    pub fn render(&self) -> String {
        let mut h = String::new();
        let _ = write!(
            h,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<meta \
             name=\"viewport\" content=\"width=device-width, \
             initial-scale=1\">\n<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{}</h1>\n",
            escape(&self.title),
            escape(&self.title)
        );
        let mut figure_no = 0;
        for b in &self.blocks {
            match b {
                Block::Heading(t) => {
                    let _ = writeln!(h, "<h2>{}</h2>", escape(t));
                }
                Block::Paragraph(t) => {
                    let _ = writeln!(h, "<p>{}</p>", escape(t));
                }
                Block::Answer(t) => {
                    let _ = writeln!(h, "<p class=\"answer\">{}</p>", escape(t));
                }
                Block::Warnings(items) => {
                    h.push_str("<ul class=\"warn\">\n");
                    for i in items {
                        let _ = writeln!(h, "<li>{}</li>", escape(i));
                    }
                    h.push_str("</ul>\n");
                }
                Block::Table {
                    caption,
                    header,
                    rows,
                } => {
                    let _ = write!(
                        h,
                        "<div class=\"table\"><table>\n<caption>{}</caption>\n<thead><tr>",
                        escape(caption)
                    );
                    for c in header {
                        let _ = write!(h, "<th>{}</th>", escape(c));
                    }
                    h.push_str("</tr></thead>\n<tbody>\n");
                    for r in rows {
                        h.push_str("<tr>");
                        // Each cell carries its column's name: on a narrow screen a row is
                        // shown as a card of name and value lines (the style sheet).
                        for (k, c) in r.iter().enumerate() {
                            let label = header.get(k).map_or(String::new(), |l| escape(l));
                            let _ = write!(h, "<td data-label=\"{label}\">{}</td>", escape(c));
                        }
                        h.push_str("</tr>\n");
                    }
                    h.push_str("</tbody></table></div>\n");
                }
                Block::Figure { name, caption, svg } => {
                    figure_no += 1;
                    let n = escape(name);
                    let _ = write!(
                        h,
                        "<figure id=\"fig-{n}\">\n{svg}\n<figcaption>Figure {figure_no}: {} (<a \
                         href=\"figures/{n}.svg\">SVG</a>, <a \
                         href=\"figures/{n}.png\">PNG</a>)</figcaption>\n</figure>\n",
                        escape(caption)
                    );
                }
            }
        }
        h.push_str("</body>\n</html>\n");
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_figures_are_linked_and_inline() {
        let mut r = HtmlReport::new("G* <core> & \"more\"");
        r.heading("Results");
        r.answer("G' > 0");
        r.paragraph("a < b");
        r.warnings(&["phi > 0.1".into()]);
        r.table("T", &["f [Hz]"], vec![vec!["1.0".into()]]);
        r.figure("core", "G'(f)", "<svg id=\"x\"></svg>".into());
        let h = r.render();
        assert!(h.contains("G* &lt;core&gt; &amp; &quot;more&quot;"));
        assert!(h.contains("<p>a &lt; b</p>") && h.contains("phi &gt; 0.1"));
        assert!(h.contains("<p class=\"answer\">G&#39; &gt; 0</p>"));
        assert!(h.contains("<td data-label=\"f [Hz]\">1.0</td>"));
        assert!(h.contains("<svg id=\"x\"></svg>"));
        assert!(h.contains("href=\"figures/core.svg\"") && h.contains("href=\"figures/core.png\""));
        assert_eq!(
            r.figure_files(),
            vec![
                "figures/core.svg".to_string(),
                "figures/core.png".to_string()
            ]
        );
        assert!(h.contains("Figure 1: G&#39;(f)"));
    }
}
