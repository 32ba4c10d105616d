//! Functions longer than a screen: the code of a crate's source files (comments, literals and
//! `#[cfg(test)]` modules left out, [`crate::modules::code_of`]) scanned for `fn NAME` with a
//! body, each body's length counted in lines from its `fn` to its closing brace.

use crate::modules::{SourceFile, code_of};

/// A function and its length.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FunctionLength {
    /// The file it is in (as [`SourceFile::label`]).
    pub file: String,
    /// Its name.
    pub name: String,
    /// Its 1-based line.
    pub line: usize,
    /// Lines from its `fn` to its closing brace, both included.
    pub lines: usize,
}

/// Every function with a body in `files` longer than `max_lines`, test modules and files of
/// a module named `tests` left out.
pub fn longer_than(files: &[SourceFile], max_lines: usize) -> Vec<FunctionLength> {
    files
        .iter()
        .filter(|f| f.module.last().is_none_or(|m| m != "tests"))
        .flat_map(|f| functions(&f.label, &code_of(&f.text)))
        .filter(|f| f.lines > max_lines)
        .collect()
}

/// The functions with a body in `code` (comments and literals blanked).
fn functions(label: &str, code: &str) -> Vec<FunctionLength> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(at) = next_fn(&c, i) {
        i = at + 2;
        let name: String = c[at + 2..]
            .iter()
            .skip_while(|ch| ch.is_whitespace())
            .take_while(|ch| ch.is_alphanumeric() || **ch == '_')
            .collect();
        let Some(end) = body_end(&c, at) else {
            continue;
        };
        let line = 1 + c[..at].iter().filter(|&&ch| ch == '\n').count();
        let lines = 1 + c[at..end].iter().filter(|&&ch| ch == '\n').count();
        out.push(FunctionLength {
            file: label.to_string(),
            name,
            line,
            lines,
        });
    }
    out
}

/// The index of the next keyword `fn` at or after `from` (a whole word followed by white
/// space).
fn next_fn(c: &[char], from: usize) -> Option<usize> {
    let word = |k: usize| k < c.len() && (c[k].is_alphanumeric() || c[k] == '_');
    (from..c.len().saturating_sub(2)).find(|&k| {
        c[k] == 'f' && c[k + 1] == 'n' && c[k + 2].is_whitespace() && (k == 0 || !word(k - 1))
    })
}

/// The index of the closing brace of the body of the function whose `fn` is at `at`; `None`
/// for a declaration without a body (a `;` before any `{`).
fn body_end(c: &[char], at: usize) -> Option<usize> {
    let open = at + c[at..].iter().position(|&ch| ch == '{' || ch == ';')?;
    if c[open] == ';' {
        return None;
    }
    let mut depth = 0usize;
    for (k, &ch) in c.iter().enumerate().skip(open) {
        match ch {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return Some(k);
                }
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body's lines run from its `fn` to its closing brace; a trait's declaration has none;
    /// braces in strings and comments do not count (they are blanked first).
    #[test]
    fn lengths_count_from_fn_to_the_closing_brace() {
        let text = "trait T {\n    fn declared(&self);\n}\n\
                    /// a { in a comment\n\
                    pub fn three(x: u8) -> u8 {\n    let s = \"}\";\n    x\n}\n\
                    fn one() {}\n";
        let found = functions("f.rs", &code_of(text));
        let of = |n: &str| {
            found
                .iter()
                .find(|f| f.name == n)
                .map(|f| (f.line, f.lines))
        };
        assert_eq!(of("three"), Some((5, 4)));
        assert_eq!(of("one"), Some((9, 1)));
        assert_eq!(of("declared"), None);
    }
}
