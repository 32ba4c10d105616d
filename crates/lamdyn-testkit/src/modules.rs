//! Module cycles of a crate's source tree: which sibling modules use each other in a circle.
//!
//! A module's dependencies are the paths its code names through `crate::`, `super::` and
//! `self::` (use declarations, groups `{a, b::c}` included, and paths in expressions), with
//! comments, string literals and `#[cfg(test)]` modules left out. A path is resolved to the
//! deepest module of the tree that it names, and through a `pub use` re-export to the module
//! the item comes from (`crate::CorePoint` re-exported from `stages` counts as `stages`).
//!
//! A dependency of module `a::b::x` on `a::c::y` is an edge between the siblings `a::b` and
//! `a::c` below their common ancestor; a module's use of its own ancestors or descendants is
//! not an edge. A cycle is a strongly connected set of more than one sibling: the one-way flow
//! that `docs/architecture.md` asks for has none.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module's path below its crate root (empty for the root).
pub type ModulePath = Vec<String>;

/// One use of another module, where it is written.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct Use {
    /// The file and 1-based line of the path.
    pub at: String,
    /// The module using.
    pub from: ModulePath,
    /// The module used.
    pub to: ModulePath,
}

/// A cycle of sibling modules and the uses that close it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cycle {
    /// The siblings in the cycle (full paths, sorted).
    pub modules: Vec<ModulePath>,
    /// The uses between them, one per ordered pair of siblings.
    pub uses: Vec<Use>,
}

impl std::fmt::Display for Cycle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<String> = self.modules.iter().map(|m| join(m)).collect();
        write!(f, "{}:", names.join(" <-> "))?;
        for u in &self.uses {
            write!(f, "\n    {} uses {} ({})", join(&u.from), join(&u.to), u.at)?;
        }
        Ok(())
    }
}

fn join(m: &[String]) -> String {
    if m.is_empty() {
        "crate".into()
    } else {
        m.join("::")
    }
}

/// One source file of a crate: its module path and text.
#[derive(Debug, Clone)]
pub struct SourceFile {
    /// Where it was read from (for messages).
    pub label: String,
    /// Its module path.
    pub module: ModulePath,
    /// Its text.
    pub text: String,
}

/// The source files of the crate whose `src` folder is `src` (a `main.rs` beside a `lib.rs`
/// is a crate of its own and left out).
///
/// # Errors
/// A folder or file that cannot be read.
pub fn read_crate(src: &Path) -> std::io::Result<Vec<SourceFile>> {
    let mut files = Vec::new();
    let mut stack: Vec<PathBuf> = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir)? {
            let path = entry?.path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel = path.strip_prefix(src).unwrap_or(&path);
            let Some(module) = module_of(rel, src.join("lib.rs").exists()) else {
                continue;
            };
            files.push(SourceFile {
                label: path.display().to_string(),
                module,
                text: std::fs::read_to_string(&path)?,
            });
        }
    }
    files.sort_by(|a, b| a.label.cmp(&b.label));
    Ok(files)
}

/// The module path of the file at `rel` (relative to `src`); `None` for a binary root beside a
/// library, and for `src/bin/`.
fn module_of(rel: &Path, has_lib: bool) -> Option<ModulePath> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if parts.first().is_some_and(|p| p == "bin") {
        return None;
    }
    let last = parts.pop()?;
    let stem = last.strip_suffix(".rs")?;
    match (parts.is_empty(), stem) {
        (true, "lib") => {}
        (true, "main") if has_lib => return None,
        (true, "main") => {}
        (_, "mod") => {}
        _ => parts.push(stem.to_string()),
    }
    Some(parts)
}

/// The cycles among sibling modules of the crate made of `files` (module docs).
pub fn cycles(files: &[SourceFile]) -> Vec<Cycle> {
    let modules: BTreeSet<ModulePath> = files.iter().map(|f| f.module.clone()).collect();
    let code: Vec<String> = files.iter().map(|f| code_of(&f.text)).collect();
    let reexports = reexports(files, &code, &modules);
    let mut edges: BTreeMap<(ModulePath, ModulePath), Use> = BTreeMap::new();
    for (f, code) in files.iter().zip(&code) {
        for (line, path) in paths(code) {
            let Some(to) = resolve(&f.module, &path, &modules, &reexports) else {
                continue;
            };
            let Some((a, b)) = siblings(&f.module, &to) else {
                continue;
            };
            edges.entry((a, b)).or_insert_with(|| Use {
                at: format!("{}:{line}", f.label),
                from: f.module.clone(),
                to: to.clone(),
            });
        }
    }
    strongly_connected(&edges)
}

/// Per (module, name) re-exported there by a `pub use` of another module's item: that module.
/// `code` is each file's [`code_of`].
fn reexports(
    files: &[SourceFile],
    code: &[String],
    modules: &BTreeSet<ModulePath>,
) -> BTreeMap<(ModulePath, String), ModulePath> {
    let mut map = BTreeMap::new();
    for (f, code) in files.iter().zip(code) {
        for stmt in code.split(';') {
            let s = stmt.trim_start();
            let Some(rest) = s
                .strip_prefix("pub use ")
                .or_else(|| s.strip_prefix("pub(crate) use "))
            else {
                continue;
            };
            for mut path in use_tree(rest.trim()) {
                // `pub use child::Item` names a child module relative to this one.
                let mut child = f.module.clone();
                child.extend(path.first().cloned());
                if modules.contains(&child) {
                    path.insert(0, "self".into());
                }
                let full = absolute(&f.module, &path);
                let Some((name, from)) = full.split_last() else {
                    continue;
                };
                let name = name.split(" as ").last().unwrap_or(name).trim().to_string();
                if let Some(m) = deepest(from, modules)
                    && m != f.module
                {
                    map.insert((f.module.clone(), name), m);
                }
            }
        }
    }
    map
}

/// The deepest module of `modules` that `path` starts with (the root at least).
fn deepest(path: &[String], modules: &BTreeSet<ModulePath>) -> Option<ModulePath> {
    (0..=path.len())
        .rev()
        .map(|n| path[..n].to_vec())
        .find(|p| modules.contains(p))
}

/// `path` as written in `module` (`crate::`, `super::`, `self::` first) made absolute; a path
/// that starts otherwise (another crate, a local name) is empty.
fn absolute(module: &[String], path: &[String]) -> Vec<String> {
    let mut base: Vec<String> = match path.first().map(String::as_str) {
        Some("crate") => Vec::new(),
        Some("super") | Some("self") => module.to_vec(),
        _ => return Vec::new(),
    };
    let mut rest = path;
    if rest.first().is_some_and(|p| p == "crate") {
        rest = &rest[1..];
    }
    while let Some(first) = rest.first() {
        match first.as_str() {
            "super" => {
                base.pop();
            }
            "self" => {}
            _ => break,
        }
        rest = &rest[1..];
    }
    base.extend(rest.iter().cloned());
    base
}

/// The module a path written in `module` uses, through re-exports; `None` when it names no
/// module of the crate.
fn resolve(
    module: &[String],
    path: &[String],
    modules: &BTreeSet<ModulePath>,
    reexports: &BTreeMap<(ModulePath, String), ModulePath>,
) -> Option<ModulePath> {
    if !matches!(
        path.first().map(String::as_str),
        Some("crate" | "super" | "self")
    ) {
        return None;
    }
    let full = absolute(module, path);
    let m = deepest(&full, modules)?;
    match full.get(m.len()) {
        Some(item) => Some(
            reexports
                .get(&(m.clone(), item.clone()))
                .cloned()
                .unwrap_or(m),
        ),
        None => Some(m),
    }
}

/// The children of the common ancestor of `a` and `b` that hold them; `None` when one holds
/// the other.
fn siblings(a: &[String], b: &[String]) -> Option<(ModulePath, ModulePath)> {
    let common = a.iter().zip(b).take_while(|(x, y)| x == y).count();
    if common == a.len() || common == b.len() {
        return None;
    }
    Some((a[..=common].to_vec(), b[..=common].to_vec()))
}

/// `text` with comments, string and character literals blanked (line breaks kept) and each
/// `#[cfg(test)]` module dropped.
pub fn code_of(text: &str) -> String {
    without_test_modules(&blanked(text))
}

/// `code` (comments and literals blanked) without the modules under a `#[cfg(test)]` that
/// starts a line: from the attribute to the module's closing brace.
fn without_test_modules(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(k) = rest.find("#[cfg(test)]") {
        let at_line_start = rest[..k]
            .rsplit('\n')
            .next()
            .is_some_and(|l| l.trim().is_empty());
        let after = &rest[k..];
        let open = after.find('{');
        let is_mod = open.is_some_and(|o| after[..o].contains("mod "));
        if !(at_line_start && is_mod) {
            out.push_str(&rest[..k + 1]);
            rest = &rest[k + 1..];
            continue;
        }
        out.push_str(&rest[..k]);
        let o = open.unwrap_or(0);
        let mut depth = 0usize;
        let mut end = after.len();
        for (j, ch) in after[o..].char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = o + j + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        out.extend(after[..end].chars().filter(|&ch| ch == '\n'));
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// `text` with comments, string and character literals blanked (line breaks kept).
fn blanked(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let blank = |out: &mut String, ch: char| out.push(if ch == '\n' { '\n' } else { ' ' });
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
        } else if c[i] == 'r'
            && (next == Some('"') || next == Some('#'))
            && !ident_char_before(&c, i)
        {
            let hashes = c[i + 1..].iter().take_while(|&&h| h == '#').count();
            if c.get(i + 1 + hashes) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            i += 2 + hashes;
            while i < c.len() {
                if c[i] == '"'
                    && c[i + 1..]
                        .iter()
                        .take(hashes)
                        .filter(|&&h| h == '#')
                        .count()
                        == hashes
                {
                    i += 1 + hashes;
                    break;
                }
                blank(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    i += 1;
                }
                if i < c.len() {
                    blank(&mut out, c[i]);
                }
                i += 1;
            }
            i += 1;
        } else if c[i] == '\'' && (next == Some('\\') || c.get(i + 2) == Some(&'\'')) {
            i += 1;
            while i < c.len() && c[i] != '\'' {
                if c[i] == '\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

fn ident_char_before(c: &[char], i: usize) -> bool {
    i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_')
}

/// Every path of `code` that starts with `crate`, `super` or `self` followed by `::`, with its
/// 1-based line; a group `{..}` gives one path per leaf.
fn paths(code: &str) -> Vec<(usize, Vec<String>)> {
    let mut found = Vec::new();
    for (n, _) in code.match_indices("::") {
        let before = &code[..n];
        let start = before
            .rfind(|ch: char| !(ch.is_alphanumeric() || ch == '_' || ch == ':'))
            .map_or(0, |k| k + 1);
        // Only the first `::` of a path starts it.
        if code[..start].ends_with("::") || before[start..].contains("::") {
            continue;
        }
        let head = &before[start..];
        if !matches!(head, "crate" | "super" | "self") {
            continue;
        }
        let line = code[..n].matches('\n').count() + 1;
        let tail = tree_text(&code[start..]);
        for p in use_tree(tail) {
            found.push((line, p));
        }
    }
    found
}

/// The text of the path or use tree at the start of `s` (up to its end: balanced braces,
/// then the first character that cannot continue a path).
fn tree_text(s: &str) -> &str {
    let mut depth = 0usize;
    for (k, ch) in s.char_indices() {
        match ch {
            '{' => depth += 1,
            '}' if depth == 0 => return &s[..k],
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return &s[..=k];
                }
            }
            c if depth == 0 && !(c.is_alphanumeric() || c == '_' || c == ':' || c == '*') => {
                return &s[..k];
            }
            _ => {}
        }
    }
    s
}

/// The leaf paths of a use tree `a::b::{c, d::{e, f}}` (whitespace and `as` renames allowed).
fn use_tree(s: &str) -> Vec<Vec<String>> {
    let s = s.trim();
    let Some(open) = s.find('{') else {
        let s = s.split(" as ").next().unwrap_or(s);
        let path: Vec<String> = s
            .split("::")
            .map(|p| p.trim().to_string())
            .filter(|p| !p.is_empty())
            .collect();
        return if path.is_empty() { vec![] } else { vec![path] };
    };
    let prefix: Vec<String> = s[..open]
        .split("::")
        .map(|p| p.trim().to_string())
        .filter(|p| !p.is_empty())
        .collect();
    let close = s.rfind('}').unwrap_or(s.len());
    let inner = &s[open + 1..close.max(open + 1)];
    let mut out = Vec::new();
    let (mut depth, mut from) = (0usize, 0usize);
    let mut items = Vec::new();
    for (k, ch) in inner.char_indices() {
        match ch {
            '{' => depth += 1,
            '}' => depth = depth.saturating_sub(1),
            ',' if depth == 0 => {
                items.push(&inner[from..k]);
                from = k + 1;
            }
            _ => {}
        }
    }
    items.push(&inner[from..]);
    for item in items {
        let item = item.trim();
        if item.is_empty() {
            continue;
        }
        for tail in use_tree(item) {
            if tail.len() == 1 && tail[0] == "self" {
                out.push(prefix.clone());
            } else {
                out.push(prefix.iter().cloned().chain(tail).collect());
            }
        }
    }
    out
}

/// The strongly connected sets of more than one module in the graph of `edges` (Tarjan).
fn strongly_connected(edges: &BTreeMap<(ModulePath, ModulePath), Use>) -> Vec<Cycle> {
    let nodes: Vec<ModulePath> = edges
        .keys()
        .flat_map(|(a, b)| [a.clone(), b.clone()])
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    let index_of = |m: &ModulePath| nodes.iter().position(|n| n == m).unwrap_or(0);
    let mut next: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
    for (a, b) in edges.keys() {
        next[index_of(a)].push(index_of(b));
    }
    let mut state = Tarjan {
        next: &next,
        index: vec![None; nodes.len()],
        low: vec![0; nodes.len()],
        on_stack: vec![false; nodes.len()],
        stack: Vec::new(),
        counter: 0,
        sets: Vec::new(),
    };
    for v in 0..nodes.len() {
        if state.index[v].is_none() {
            state.visit(v);
        }
    }
    state
        .sets
        .into_iter()
        .filter(|s| s.len() > 1)
        .map(|mut s| {
            s.sort_unstable();
            let modules: Vec<ModulePath> = s.iter().map(|&k| nodes[k].clone()).collect();
            let uses = edges
                .iter()
                .filter(|((a, b), _)| modules.contains(a) && modules.contains(b))
                .map(|(_, u)| u.clone())
                .collect();
            Cycle { modules, uses }
        })
        .collect()
}

/// Tarjan's strongly connected components, recursive (module graphs are small).
struct Tarjan<'a> {
    next: &'a [Vec<usize>],
    index: Vec<Option<usize>>,
    low: Vec<usize>,
    on_stack: Vec<bool>,
    stack: Vec<usize>,
    counter: usize,
    sets: Vec<Vec<usize>>,
}

impl Tarjan<'_> {
    fn visit(&mut self, v: usize) {
        self.index[v] = Some(self.counter);
        self.low[v] = self.counter;
        self.counter += 1;
        self.stack.push(v);
        self.on_stack[v] = true;
        for &w in &self.next[v] {
            match self.index[w] {
                None => {
                    self.visit(w);
                    self.low[v] = self.low[v].min(self.low[w]);
                }
                Some(iw) if self.on_stack[w] => self.low[v] = self.low[v].min(iw),
                Some(_) => {}
            }
        }
        if Some(self.low[v]) == self.index[v] {
            let mut set = Vec::new();
            while let Some(w) = self.stack.pop() {
                self.on_stack[w] = false;
                set.push(w);
                if w == v {
                    break;
                }
            }
            self.sets.push(set);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(module: &str, text: &str) -> SourceFile {
        SourceFile {
            label: format!("{module}.rs"),
            module: module
                .split("::")
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect(),
            text: text.into(),
        }
    }

    /// Two siblings that use each other through a group, a re-export and `super::` are one
    /// cycle; comments, strings and the tests module do not count.
    #[test]
    fn a_cycle_through_groups_reexports_and_super_is_found() {
        let files = [
            file(
                "",
                "pub mod a;\npub mod b;\npub mod c;\npub use a::Thing;\n",
            ),
            file("a", "use crate::{x, b::{Other, more}};\npub struct Thing;"),
            file("b", "fn f() -> crate::Thing { crate::Thing }\n"),
            file(
                "c",
                "// crate::a::Thing\nconst S: &str = \"crate::a\";\n#[cfg(test)]\nmod tests \
                 { use crate::a; }\n",
            ),
        ];
        let found = cycles(&files);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(
            found[0].modules,
            [vec!["a".to_string()], vec!["b".to_string()]]
        );
        assert_eq!(found[0].uses.len(), 2);
        let text = found[0].to_string();
        assert!(text.starts_with("a <-> b:"), "{text}");
    }

    /// A child using its parent, a parent its child, and a one-way chain of siblings are no
    /// cycle; nested siblings are compared below their common ancestor.
    #[test]
    fn ancestors_and_one_way_chains_are_no_cycle() {
        let files = [
            file("", "mod a; mod b;\n"),
            file("a", "mod x; mod y; use super::b::B; use crate::a::x::X;"),
            file("a::x", "use super::super::a::y::Y; pub struct X;"),
            file(
                "a::y",
                "use super::*; pub struct Y; fn f() { let _ = self::Y; }",
            ),
            file("b", "pub struct B;"),
        ];
        assert!(cycles(&files).is_empty());
        let looped = [
            file("", "mod a;"),
            file("a", "mod x; mod y;"),
            file("a::x", "use super::y::Y; pub struct X;"),
            file("a::y", "pub struct Y; fn f() { let _ = crate::a::x::X; }"),
        ];
        let found = cycles(&looped);
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].modules[0], ["a", "x"]);
    }

    #[test]
    fn file_paths_map_to_modules() {
        assert_eq!(module_of(Path::new("lib.rs"), true), Some(vec![]));
        assert_eq!(module_of(Path::new("main.rs"), true), None);
        assert_eq!(
            module_of(Path::new("a/mod.rs"), true),
            Some(vec!["a".into()])
        );
        assert_eq!(
            module_of(Path::new("a/b.rs"), true),
            Some(vec!["a".into(), "b".into()])
        );
    }
}
