//! The crates' layers, read from their source: no module imports a module above it in its
//! crate's list of ARCHITECTURE.md's "Layers", and no file of `engine/src/` or `harness/src/` depends on
//! itself through other files of its crate (no circle at file level, inside a module either).
//!
//! Every file under `engine/src/` and `harness/src/` (the binary, `src/main.rs`, sees the library
//! only as `grainchain::`) is read with its comments, doc comments and string literals blanked out. Its
//! dependencies on other files of the crate are its paths that start with `crate::`, `super::`,
//! `self::` or the name of a module the file declares (`mod x;`), in `use` declarations (grouped
//! `use a::{b, c::d}` expanded) and in code alike. A path names the file of the deepest module
//! it reaches (`src/a/b.rs`, `src/a/b/mod.rs` or `src/a.rs` for `crate::a::b`); the item after it
//! is looked up in that file's own `use` declarations and, if it was imported there, followed to
//! the file that defines it (so `super::Item` that a parent only imports or re-exports depends on
//! the file that defines `Item`, not on the parent). A `super::` inside an inline `mod tests {}`
//! names the file itself.
//!
//! Façades. A `pub use` (any `pub(..)`) of a `mod.rs` or any file is a re-export: it is not, by
//! itself, a dependency of the file at file level; the re-exporting file depends on the
//! re-exported file only when its code uses the name too. So a child is never made to depend on
//! its parent by the parent re-exporting it, while a child importing `super::Item` where `Item`
//! is defined in the parent's `mod.rs` does depend on the `mod.rs`. Between modules every path
//! counts, re-exports too (a module re-exporting a module above it still reaches above itself).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// ARCHITECTURE.md's "Layers" lists, one per crate, in their order: a module imports only
/// modules before it in its crate's list. The engine (`engine/src`) comes first; the harness
/// (`src`) sees it only through its public API (`grainchain_engine::`, the compiler's check, not
/// this file's). In the engine, `number` imports nothing and anything may use it (checked apart:
/// [`Layers::bottom`]).
struct Layers {
    /// The crate's source folder, from the repository root.
    src: &'static str,
    /// Its modules, lowest first.
    order: &'static [&'static str],
    /// A module that imports nothing from the crate and that anything may import.
    bottom: Option<&'static str>,
}

const CRATES: &[Layers] = &[
    Layers {
        src: "engine/src",
        order: &[
            "state",
            "chain",
            "integrators",
            "observables",
            "run",
            "error",
            "scene",
            "recorder",
            "analysis",
            "paper",
            "problems",
            "units",
            "protector",
        ],
        bottom: Some("number"),
    },
    Layers {
        src: "harness/src",
        order: &[
            "error",
            "report",
            "export",
            "batch",
            "study",
            "reproduce",
            "work_precision",
            "design",
            "commands",
        ],
        bottom: None,
    },
];

/// Pairs that never import each other either way, though one comes before the other in the list:
/// what both need is below them (ARCHITECTURE.md: `reproduce` and `study` never import each
/// other).
const APART: &[(&str, &str)] = &[("study", "reproduce")];

/// The file-level circles left today, each by its files (the whole strongly connected set). The
/// test fails on a circle not listed here, and on a listed one that is gone or changed, so the
/// list only shrinks; it is empty.
/// (Issue 25 item 3 broke `scene/check.rs` <-> `scene/mod.rs` (the parts of a checked scene
/// moved to `scene/parts.rs`, below both), `integrators/mod.rs` <-> the method files (what
/// every step shares moved to `integrators/step.rs`, below the methods and the registry),
/// `chain/mod.rs` <-> its builder, window and damping (`ChainError` in `chain/error.rs`, the
/// damped runs' data in `law.rs`, the chain's work over the window in `chain/active.rs`),
/// `scene/file.rs` <-> `scene/outer.rs`, `study`'s sweep file -> outputs -> random containers
/// -> sweep file, `work_precision/mod.rs` <-> `statistics.rs`, `report/atomic.rs` <->
/// `outdir.rs`, which issue 24's journal had made, and `reproduce`'s stages and units: each
/// unit keeps its own numbers, the registry `figures/mod.rs` drives the units through the
/// stages and puts their numbers into `Results`, and what the units use (`options.rs`,
/// `plan.rs`, `jobs.rs`, `unit.rs`, `render/`'s pieces) is below them.)
const LEFT: &[&[&str]] = &[];

/// One token of Rust source, comments and literals gone.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    /// `::`
    Sep,
    Punct(char),
}

/// Tokens with their line numbers. Comments (nested block comments too), strings (raw, byte),
/// and char literals are dropped; lifetimes become identifiers, which no path starts with.
fn tokens(src: &str) -> Vec<(Tok, usize)> {
    let c: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    let n = c.len();
    // Skips a string body from just after the opening quote; `hashes` for raw strings.
    let skip_str = |mut i: usize, raw: bool, hashes: usize, line: &mut usize| -> usize {
        while i < n {
            match c[i] {
                '\n' => *line += 1,
                '\\' if !raw => {
                    if i + 1 < n && c[i + 1] == '\n' {
                        *line += 1;
                    }
                    i += 1;
                }
                '"' if (0..hashes).all(|k| i + 1 + k < n && c[i + 1 + k] == '#') => {
                    return i + 1 + hashes;
                }
                _ => {}
            }
            i += 1;
        }
        i
    };
    while i < n {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && i + 1 < n && c[i + 1] == '/' {
            while i < n && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && i + 1 < n && c[i + 1] == '*' {
            let mut depth = 0;
            while i < n {
                if c[i] == '/' && i + 1 < n && c[i + 1] == '*' {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && i + 1 < n && c[i + 1] == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    if c[i] == '\n' {
                        line += 1;
                    }
                    i += 1;
                }
            }
        } else if ch == '"' {
            i = skip_str(i + 1, false, 0, &mut line);
        } else if ch == '\'' {
            // A char literal ('x', '\n', '\u{..}', '\'') or a lifetime ('a).
            if i + 2 < n && c[i + 1] == '\\' {
                i += 2;
                while i < n && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if i + 2 < n && c[i + 2] == '\'' {
                i += 3;
            } else {
                i += 1;
            }
        } else if ch.is_alphanumeric() || ch == '_' {
            let s = i;
            while i < n && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            let word: String = c[s..i].iter().collect();
            let raw = word == "r" || word == "br";
            if (raw || word == "b") && i < n && (c[i] == '"' || (raw && c[i] == '#')) {
                let mut hashes = 0;
                while i < n && c[i] == '#' {
                    hashes += 1;
                    i += 1;
                }
                if i < n && c[i] == '"' {
                    i = skip_str(i + 1, raw, hashes, &mut line);
                    continue;
                }
            }
            if word == "b" && i < n && c[i] == '\'' {
                continue; // b'x': the char literal follows
            }
            if word.chars().next().is_some_and(|f| f.is_ascii_digit()) {
                continue; // a number
            }
            out.push((Tok::Ident(word), line));
        } else if ch == ':' && i + 1 < n && c[i + 1] == ':' {
            out.push((Tok::Sep, line));
            i += 2;
        } else {
            out.push((Tok::Punct(ch), line));
            i += 1;
        }
    }
    out
}

/// One name a `use` declaration binds: the path it names (as written), the name it binds
/// (`None` for a glob), whether it is a re-export (`pub use`), and its line.
#[derive(Clone, Debug)]
struct Binding {
    path: Vec<String>,
    name: Option<String>,
    public: bool,
    line: usize,
    /// The inline module (`mod tests { .. }`) the declaration is in, as names below the file.
    scope: Vec<String>,
}

/// A path in code (not in a `use`) that starts at `crate`, `super`, `self` or a declared module.
#[derive(Clone, Debug)]
struct CodePath {
    path: Vec<String>,
    line: usize,
    scope: Vec<String>,
}

/// What one file says about the rest of the crate.
#[derive(Clone, Debug, Default)]
struct FileInfo {
    /// The module path of the file (`["reproduce", "figures"]` for `src/reproduce/figures/mod.rs`).
    module: Vec<String>,
    /// Modules it declares with `mod x;` (its child files).
    mods: BTreeSet<String>,
    /// Modules it declares under `#[cfg(test)]` (their files are test code).
    test_mods: BTreeSet<String>,
    /// The top-level modules its inline test code names with `crate::` (and the line).
    test_refs: Vec<(String, usize)>,
    uses: Vec<Binding>,
    paths: Vec<CodePath>,
    /// Names the file defines (`struct X`, `fn x`, `enum`, `trait`, `type`, `const`, `static`,
    /// `union`, `macro_rules! x`).
    defines: BTreeSet<String>,
    /// Identifiers in its code outside `use` declarations.
    idents: BTreeSet<String>,
}

/// Parses a use tree from `toks[*i]` on, appending the bindings (prefix + path).
fn use_tree(
    toks: &[(Tok, usize)],
    i: &mut usize,
    prefix: Vec<String>,
    out: &mut Vec<(Vec<String>, Option<String>)>,
) {
    let mut path = prefix;
    if toks.get(*i).map(|t| &t.0) == Some(&Tok::Sep) {
        *i += 1; // a leading `::` (an extern crate)
    }
    loop {
        match toks.get(*i).map(|t| &t.0) {
            Some(Tok::Punct('{')) => {
                *i += 1;
                loop {
                    match toks.get(*i).map(|t| &t.0) {
                        Some(Tok::Punct('}')) => {
                            *i += 1;
                            return;
                        }
                        Some(Tok::Punct(',')) => *i += 1,
                        None => return,
                        _ => use_tree(toks, i, path.clone(), out),
                    }
                }
            }
            Some(Tok::Punct('*')) => {
                *i += 1;
                out.push((path, None));
                return;
            }
            Some(Tok::Ident(s)) => {
                let s = s.clone();
                *i += 1;
                if toks.get(*i).map(|t| &t.0) == Some(&Tok::Sep) {
                    path.push(s);
                    *i += 1;
                    continue;
                }
                // The last segment: `self` binds the module itself.
                let name = if s == "self" {
                    path.last().cloned()
                } else {
                    path.push(s.clone());
                    Some(s)
                };
                let name = if toks.get(*i).map(|t| &t.0) == Some(&Tok::Ident("as".into())) {
                    *i += 1;
                    let alias = match toks.get(*i).map(|t| &t.0) {
                        Some(Tok::Ident(a)) => Some(a.clone()),
                        _ => name,
                    };
                    *i += 1;
                    alias
                } else {
                    name
                };
                out.push((path, name));
                return;
            }
            _ => return,
        }
    }
}

const DEFINERS: &[&str] = &[
    "struct",
    "enum",
    "fn",
    "trait",
    "type",
    "const",
    "static",
    "union",
    "macro_rules",
];

fn read_file(module: Vec<String>, src: &str) -> FileInfo {
    let toks = tokens(src);
    let mut f = FileInfo {
        module,
        ..Default::default()
    };
    let mut depth = 0usize;
    // Inline modules open: (name, brace depth inside it, under `#[cfg(test)]`).
    let mut inline: Vec<(String, usize, bool)> = Vec::new();
    let ident = |k: usize| match toks.get(k).map(|t| &t.0) {
        Some(Tok::Ident(s)) => Some(s.as_str()),
        _ => None,
    };
    let mut i = 0;
    while i < toks.len() {
        let line = toks[i].1;
        let scope: Vec<String> = inline.iter().map(|m| m.0.clone()).collect();
        let in_test = inline.iter().any(|m| m.2);
        match &toks[i].0 {
            Tok::Punct('{') => {
                depth += 1;
                i += 1;
            }
            Tok::Punct('}') => {
                if inline.last().is_some_and(|m| m.1 == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
                i += 1;
            }
            Tok::Ident(w) if w == "mod" && ident(i + 1).is_some() => {
                let name = ident(i + 1).unwrap().to_string();
                // `#[cfg(test)]` right before it (maybe after `pub`): test code.
                let attr = |k: usize| {
                    k >= 7 && {
                        let w: Vec<String> = toks[k - 7..k]
                            .iter()
                            .map(|t| match &t.0 {
                                Tok::Ident(s) => s.clone(),
                                Tok::Sep => "::".into(),
                                Tok::Punct(c) => c.to_string(),
                            })
                            .collect();
                        w.concat() == "#[cfg(test)]"
                    }
                };
                let test = attr(i) || (ident(i.wrapping_sub(1)) == Some("pub") && attr(i - 1));
                match toks.get(i + 2).map(|t| &t.0) {
                    Some(Tok::Punct(';')) if inline.is_empty() => {
                        if test {
                            f.test_mods.insert(name.clone());
                        }
                        f.mods.insert(name);
                    }
                    Some(Tok::Punct('{')) => {
                        inline.push((name, depth + 1, test));
                    }
                    _ => {}
                }
                i += 2;
            }
            Tok::Ident(w) if w == "use" => {
                // `pub use`, `pub(crate) use`, `pub(in path) use`: a re-export.
                let public = i >= 1
                    && (ident(i - 1) == Some("pub")
                        || (toks[i - 1].0 == Tok::Punct(')')
                            && (1..i)
                                .rev()
                                .find(|&k| toks[k].0 == Tok::Punct('('))
                                .is_some_and(|k| ident(k - 1) == Some("pub"))));
                i += 1;
                let mut got = Vec::new();
                use_tree(&toks, &mut i, Vec::new(), &mut got);
                if in_test {
                    for (path, _) in &got {
                        if path.first().is_some_and(|p| p == "crate") && path.len() > 1 {
                            f.test_refs.push((path[1].clone(), line));
                        }
                    }
                }
                for (path, name) in got.into_iter().filter(|_| !in_test) {
                    f.uses.push(Binding {
                        path,
                        name,
                        public,
                        line,
                        scope: scope.clone(),
                    });
                }
            }
            Tok::Ident(w) if DEFINERS.contains(&w.as_str()) => {
                // `macro_rules! name`
                let k = if w == "macro_rules" { i + 2 } else { i + 1 };
                if let Some(name) = ident(k) {
                    f.defines.insert(name.to_string());
                }
                i += 1;
            }
            Tok::Ident(w) => {
                // Every path's start is kept: `edges` follows those that start at `crate`,
                // `super`, `self`, a declared module or a name the file imported.
                let mid_path = i >= 1 && toks[i - 1].0 == Tok::Sep;
                if !mid_path && toks.get(i + 1).map(|t| &t.0) == Some(&Tok::Sep) {
                    let mut path = vec![w.clone()];
                    let mut k = i + 1;
                    while toks.get(k).map(|t| &t.0) == Some(&Tok::Sep) {
                        match ident(k + 1) {
                            Some(s) => path.push(s.to_string()),
                            None => break,
                        }
                        k += 2;
                    }
                    for s in &path {
                        f.idents.insert(s.clone());
                    }
                    if !in_test {
                        f.paths.push(CodePath { path, line, scope });
                    } else if path[0] == "crate" && path.len() > 1 {
                        f.test_refs.push((path[1].clone(), line));
                    }
                    i = k;
                } else {
                    if !in_test {
                        f.idents.insert(w.clone());
                    }
                    i += 1;
                }
            }
            _ => i += 1,
        }
    }
    f
}

/// The crate's files by path relative to `src/`.
struct Crate {
    files: BTreeMap<String, FileInfo>,
    /// Files declared under `#[cfg(test)]` (`integrators/tests.rs`): test code, which is no part
    /// of the library's layers (a test may drive its module with anything).
    tests: BTreeSet<String>,
}

/// An edge's evidence: the line and the path as written.
#[derive(Clone, Debug)]
struct Why {
    line: usize,
    path: String,
}

impl Crate {
    fn load(src: &Path) -> Crate {
        let mut files = BTreeMap::new();
        let mut stack = vec![src.to_path_buf()];
        while let Some(dir) = stack.pop() {
            for e in std::fs::read_dir(&dir).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.extension().is_some_and(|x| x == "rs") {
                    let rel = p
                        .strip_prefix(src)
                        .unwrap()
                        .to_string_lossy()
                        .replace('\\', "/");
                    let mut module: Vec<String> = rel
                        .trim_end_matches(".rs")
                        .split('/')
                        .map(String::from)
                        .collect();
                    if module.last().is_some_and(|m| m == "mod" || m == "lib") {
                        module.pop();
                    }
                    let text = std::fs::read_to_string(&p).unwrap();
                    files.insert(rel, read_file(module, &text));
                }
            }
        }
        let mut krate = Crate {
            files,
            tests: BTreeSet::new(),
        };
        let tests: BTreeSet<String> = krate
            .files
            .values()
            .flat_map(|f| {
                f.test_mods
                    .iter()
                    .filter_map(|m| krate.file_of(&[f.module.clone(), vec![m.clone()]].concat()))
            })
            .collect();
        krate.tests = tests;
        krate
    }

    /// The file of module `m`, if it has one of its own.
    fn file_of(&self, m: &[String]) -> Option<String> {
        if m.is_empty() {
            return Some("lib.rs".into());
        }
        let j = m.join("/");
        [format!("{j}.rs"), format!("{j}/mod.rs")]
            .into_iter()
            .find(|f| self.files.contains_key(f))
    }

    /// The module path a path written in `file` (inside its inline modules `scope`) names, from
    /// the crate's root, with the length of its own start (`None`: it leaves the crate).
    fn absolute(
        &self,
        file: &str,
        scope: &[String],
        path: &[String],
    ) -> Option<(Vec<String>, usize)> {
        let info = &self.files[file];
        let mut base: Vec<String> = info.module.iter().chain(scope).cloned().collect();
        let mut rest = path;
        match rest.first().map(String::as_str) {
            Some("crate") => {
                base.clear();
                rest = &rest[1..];
            }
            Some("self") => rest = &rest[1..],
            Some("super") => {
                while rest.first().is_some_and(|s| s == "super") {
                    base.pop();
                    rest = &rest[1..];
                }
            }
            Some(m) if scope.is_empty() && info.mods.contains(m) => {}
            _ => return None,
        }
        Some((base.iter().chain(rest).cloned().collect(), base.len()))
    }

    /// Whether a path names a module that has a file (`use crate::report::plot;`).
    fn names_module(&self, file: &str, scope: &[String], path: &[String]) -> bool {
        self.absolute(file, scope, path)
            .is_some_and(|(full, _)| self.file_of(&full).is_some())
    }

    /// The file a path written in `file` (inside its inline modules `scope`) depends on, or
    /// `None` when it leaves the crate. `hops` bounds following imports.
    fn resolve(
        &self,
        file: &str,
        scope: &[String],
        path: &[String],
        hops: usize,
    ) -> Option<String> {
        let (full, base_len) = self.absolute(file, scope, path)?;
        // The deepest module on the path that has a file of its own; an inline module
        // (`mod tests {}`) lives in the file above it.
        let j = (0..=full.len())
            .rev()
            .find(|&j| self.file_of(&full[..j]).is_some())?;
        let target = self.file_of(&full[..j])?;
        if j < base_len || j == full.len() {
            return Some(target);
        }
        // The item: followed through the target file's own imports to where it is defined.
        let item = &full[j];
        let t = &self.files[&target];
        if hops == 0 || t.defines.contains(item) {
            return Some(target);
        }
        let top_level = t.uses.iter().filter(|b| b.scope.is_empty());
        if let Some(b) = top_level.clone().find(|b| b.name.as_ref() == Some(item)) {
            return self
                .resolve(&target, &[], &b.path, hops - 1)
                .or(Some(target));
        }
        for b in top_level.filter(|b| b.name.is_none()) {
            let p: Vec<String> = b.path.iter().chain([item]).cloned().collect();
            if let Some(found) = self.resolve(&target, &[], &p, hops - 1) {
                if self.files[&found].defines.contains(item) {
                    return Some(found);
                }
            }
        }
        Some(target)
    }

    /// Every dependency between files: (from, to) → the first place that makes it, and whether
    /// it is only a re-export.
    fn edges(&self) -> BTreeMap<(String, String), (Why, bool)> {
        let mut out: BTreeMap<(String, String), (Why, bool)> = BTreeMap::new();
        let mut add = |from: &str, to: Option<String>, why: Why, reexport: bool| {
            let Some(to) = to else { return };
            if to == from {
                return;
            }
            let e = out.entry((from.to_string(), to)).or_insert((why, reexport));
            e.1 &= reexport;
        };
        for (name, f) in self.files.iter().filter(|(n, _)| !self.tests.contains(*n)) {
            for b in &f.uses {
                let why = Why {
                    line: b.line,
                    path: b.path.join("::"),
                };
                // A re-export is a façade unless the file's code uses the name as well.
                let used = match &b.name {
                    Some(n) => f.idents.contains(n),
                    None => false,
                };
                if b.name.is_none() && b.public {
                    // A glob re-export: each name of the file's code that resolves through it.
                    for id in &f.idents {
                        if f.defines.contains(id)
                            || f.uses.iter().any(|u| u.name.as_ref() == Some(id))
                        {
                            continue;
                        }
                        let mut p = b.path.clone();
                        p.push(id.clone());
                        let to = self.resolve(name, &b.scope, &p, 8);
                        if to
                            .as_ref()
                            .is_some_and(|t| self.files[t].defines.contains(id))
                        {
                            add(
                                name,
                                to,
                                Why {
                                    line: b.line,
                                    path: p.join("::"),
                                },
                                false,
                            );
                        }
                    }
                }
                // Importing a module (`use super::step_check;`) is no dependency on its file by
                // itself: the paths through it (`step_check::rows`) are, each to the file that
                // defines what it names. Between modules it counts.
                let module = b.name.is_some() && self.names_module(name, &b.scope, &b.path);
                add(
                    name,
                    self.resolve(name, &b.scope, &b.path, 8),
                    why,
                    module || (b.public && !used),
                );
            }
            for p in &f.paths {
                let why = Why {
                    line: p.line,
                    path: p.path.join("::"),
                };
                let first = &p.path[0];
                let direct = matches!(first.as_str(), "crate" | "super" | "self")
                    || (p.scope.is_empty() && f.mods.contains(first));
                if direct {
                    add(name, self.resolve(name, &p.scope, &p.path, 8), why, false);
                    continue;
                }
                // A path through an imported name (`figures::ENERGY_FLOOR` after
                // `use crate::reproduce::figures;`), the nearest enclosing import first.
                let via = f
                    .uses
                    .iter()
                    .filter(|b| b.name.as_ref() == Some(first) && p.scope.starts_with(&b.scope))
                    .max_by_key(|b| b.scope.len());
                if let Some(b) = via {
                    let full: Vec<String> = b.path.iter().chain(&p.path[1..]).cloned().collect();
                    add(name, self.resolve(name, &b.scope, &full, 8), why, false);
                }
            }
        }
        out
    }
}

/// The top-level module a file belongs to (`None` for `lib.rs`).
fn top(file: &str) -> Option<String> {
    if file == "lib.rs" {
        return None;
    }
    Some(
        file.split('/')
            .next()
            .unwrap()
            .trim_end_matches(".rs")
            .to_string(),
    )
}

/// Strongly connected components with more than one file (Tarjan), each sorted.
fn circles(nodes: &BTreeSet<String>, adj: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct T<'a> {
        adj: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<String, usize>,
        low: BTreeMap<String, usize>,
        stack: Vec<String>,
        on: BTreeSet<String>,
        out: Vec<Vec<String>>,
    }
    fn visit(t: &mut T, v: &str) {
        let i = t.index.len();
        t.index.insert(v.into(), i);
        t.low.insert(v.into(), i);
        t.stack.push(v.into());
        t.on.insert(v.into());
        for w in t.adj.get(v).cloned().unwrap_or_default() {
            if !t.index.contains_key(&w) {
                visit(t, &w);
                let l = t.low[&w].min(t.low[v]);
                t.low.insert(v.into(), l);
            } else if t.on.contains(&w) {
                let l = t.index[&w].min(t.low[v]);
                t.low.insert(v.into(), l);
            }
        }
        if t.low[v] == t.index[v] {
            let mut scc = Vec::new();
            loop {
                let w = t.stack.pop().unwrap();
                t.on.remove(&w);
                let done = w == v;
                scc.push(w);
                if done {
                    break;
                }
            }
            if scc.len() > 1 {
                scc.sort();
                t.out.push(scc);
            }
        }
    }
    let mut t = T {
        adj,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in nodes {
        if !t.index.contains_key(v) {
            visit(&mut t, v);
        }
    }
    t.out.sort();
    t.out
}

fn crate_src(layers: &Layers) -> Crate {
    Crate::load(&Path::new(ROOT).join(layers.src))
}

/// The file-level graph's circles, each listed with the dependencies inside it.
fn file_circles(krate: &Crate, src: &str) -> Vec<(Vec<String>, String)> {
    let edges = krate.edges();
    let mut adj: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for ((a, b), (_, reexport)) in &edges {
        if !reexport {
            adj.entry(a.clone()).or_default().insert(b.clone());
        }
    }
    let nodes: BTreeSet<String> = krate.files.keys().cloned().collect();
    circles(&nodes, &adj)
        .into_iter()
        .map(|scc| {
            let mut s = format!(
                "circle of {} files in {src}: {}\n",
                scc.len(),
                scc.join(", ")
            );
            for ((a, b), (why, reexport)) in &edges {
                if !reexport && scc.contains(a) && scc.contains(b) {
                    s += &format!("    {src}/{a}:{} -> {src}/{b}   ({})\n", why.line, why.path);
                }
            }
            (scc.iter().map(|f| format!("{src}/{f}")).collect(), s)
        })
        .collect()
}

/// Dependencies between top-level modules against a crate's [`Layers`] and [`APART`].
fn layer_violations(krate: &Crate, layers: &Layers) -> Vec<String> {
    let rank = |m: &str| layers.order.iter().position(|l| *l == m);
    let src = layers.src;
    let bottom = |m: &str| layers.bottom == Some(m);
    let mut bad = Vec::new();
    for ((a, b), (why, _)) in krate.edges() {
        let (Some(ma), Some(mb)) = (top(&a), top(&b)) else {
            continue;
        };
        if ma == mb || bottom(&mb) {
            continue;
        }
        let ok = match (rank(&ma), rank(&mb)) {
            _ if bottom(&ma) => false,
            (Some(ra), Some(rb)) => {
                rb < ra
                    && !APART
                        .iter()
                        .any(|&(x, y)| (x == ma && y == mb) || (x == mb && y == ma))
            }
            _ => false, // a module the list does not name: the list must be updated
        };
        if !ok {
            bad.push(format!(
                "{src}/{a}:{} -> {src}/{b}   ({}): `{ma}` may not import `{mb}`",
                why.line, why.path
            ));
        }
    }
    bad
}

#[test]
fn every_module_imports_only_modules_below_it() {
    let mut bad = Vec::new();
    for layers in CRATES {
        let krate = crate_src(layers);
        // Every top-level module of lib.rs is in the list, so none escapes the check.
        for f in krate.files.keys() {
            if let Some(m) = top(f) {
                assert!(
                    layers.bottom == Some(m.as_str()) || layers.order.contains(&m.as_str()),
                    "module `{m}` ({}/{f}) is not in its crate's Layers: add it where \
                     ARCHITECTURE.md's \"Layers\" puts it",
                    layers.src
                );
            }
        }
        bad.extend(layer_violations(&krate, layers));
    }
    assert!(
        bad.is_empty(),
        "imports against ARCHITECTURE.md's layers:\n{}",
        bad.join("\n")
    );
}

/// Test code stays in its layer too: a module's tests (an inline `mod tests {}` or a test file
/// it declares) name no module above it with `crate::` (a test that drives whole runs belongs
/// to a layer that has them, or to `validation/`).
#[test]
fn no_test_module_reaches_above_its_layer() {
    let mut bad = Vec::new();
    for layers in CRATES {
        let krate = crate_src(layers);
        let rank = |m: &str| layers.order.iter().position(|l| *l == m);
        for (name, f) in &krate.files {
            let Some(own) = top(name) else { continue };
            let mut refs = f.test_refs.clone();
            if krate.tests.contains(name) {
                refs.extend(
                    f.uses
                        .iter()
                        .filter(|b| b.path[0] == "crate" && b.path.len() > 1)
                        .map(|b| (b.path[1].clone(), b.line)),
                );
                refs.extend(
                    f.paths
                        .iter()
                        .filter(|p| p.path[0] == "crate" && p.path.len() > 1)
                        .map(|p| (p.path[1].clone(), p.line)),
                );
            }
            for (m, line) in refs {
                let above = match (rank(&own), rank(&m)) {
                    (Some(a), Some(b)) => b > a,
                    _ => false,
                };
                if above {
                    bad.push(format!(
                        "{}/{name}:{line}: a test of `{own}` names `crate::{m}`, above it",
                        layers.src
                    ));
                }
            }
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn no_file_depends_on_itself_through_others() {
    let found: Vec<(Vec<String>, String)> = CRATES
        .iter()
        .flat_map(|layers| file_circles(&crate_src(layers), layers.src))
        .collect();
    let left: Vec<Vec<String>> = LEFT
        .iter()
        .map(|c| c.iter().map(|f| f.to_string()).collect())
        .collect();
    let mut problems = Vec::new();
    for (files, listing) in &found {
        if !left.contains(files) {
            problems.push(format!("a circle between files of one crate (each file must depend only on files it does not reach back from):\n{listing}"));
        }
    }
    for files in &left {
        if !found.iter().any(|(f, _)| f == files) {
            problems.push(format!(
                "a circle of LEFT is gone or changed (it was {}): take it off the list",
                files.join(", ")
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The checker sees what it is meant to see: an upward import, a file-level circle through a
/// parent's `mod.rs`, a grouped import, and that a parent re-exporting its children (a façade)
/// or a `mod tests {}` using `super::*` makes no circle.
#[test]
fn the_checker_finds_what_it_should() {
    let file = |m: &[&str], src: &str| read_file(m.iter().map(|s| s.to_string()).collect(), src);
    let mut files = BTreeMap::new();
    // A façade that re-exports `b::B` and defines `Top`, which `b.rs` uses: a real dependency
    // of `b.rs` on `mod.rs`, while the re-export is none of `mod.rs` on `b.rs`.
    files.insert("m/mod.rs".to_string(), file(&["m"], "mod a; mod b; mod c; pub use b::B; pub struct Top; // use crate::x::y;\n#[cfg(test)] mod tests { use super::*; }"));
    files.insert(
        "m/a.rs".to_string(),
        file(
            &["m", "a"],
            "use super::{b::{B, C}, Top as T}; /* crate::m::b */ fn f() { let s = \"super::b\"; }",
        ),
    );
    files.insert(
        "m/b.rs".to_string(),
        file(
            &["m", "b"],
            "pub struct B; pub struct C; fn g() -> crate::m::Top { crate::m::Top }",
        ),
    );
    // Importing a module is no dependency on its `mod.rs`; a path through it is, to the file
    // that defines what it names (`B`, re-exported by `mod.rs`, is `b.rs`'s).
    files.insert(
        "m/c.rs".to_string(),
        file(&["m", "c"], "use crate::m; fn k(_: m::B) {}"),
    );
    files.insert("lib.rs".to_string(), file(&[], "pub mod m;"));
    let krate = Crate {
        files,
        tests: BTreeSet::new(),
    };
    let edges: Vec<(String, String, bool)> = krate
        .edges()
        .into_iter()
        .map(|((a, b), (_, r))| (a, b, r))
        .collect();
    let has = |a: &str, b: &str, r: bool| edges.contains(&(a.to_string(), b.to_string(), r));
    assert!(has("m/a.rs", "m/b.rs", false), "{edges:?}");
    assert!(has("m/a.rs", "m/mod.rs", false), "{edges:?}");
    assert!(has("m/b.rs", "m/mod.rs", false), "{edges:?}");
    assert!(
        has("m/mod.rs", "m/b.rs", true),
        "the façade's re-export: {edges:?}"
    );
    assert!(has("m/c.rs", "m/b.rs", false), "{edges:?}");
    assert!(
        has("m/c.rs", "m/mod.rs", true),
        "the module's import alone: {edges:?}"
    );
    assert_eq!(
        edges.len(),
        6,
        "nothing from comments, strings or the test module: {edges:?}"
    );
    assert!(file_circles(&krate, "src").is_empty());
    // `mod.rs` using its child's item in code as well: now a circle.
    krate_with(
        &krate,
        "m/mod.rs",
        file(
            &["m"],
            "mod a; mod b; mod c; pub use b::B; pub struct Top; fn h(_: B) {}",
        ),
        |k| {
            let found = file_circles(k, "src");
            assert_eq!(found.len(), 1);
            assert_eq!(found[0].0, ["src/m/b.rs", "src/m/mod.rs"]);
        },
    );
}

/// `krate` with one file replaced, handed to `check`.
fn krate_with(krate: &Crate, name: &str, info: FileInfo, check: impl Fn(&Crate)) {
    let mut files = krate.files.clone();
    files.insert(name.to_string(), info);
    check(&Crate {
        files,
        tests: krate.tests.clone(),
    });
}

/// The modules of a crate reachable from outside (`lib.rs`'s `pub mod`s and theirs), by path.
fn public_modules(src: &Path) -> BTreeSet<Vec<String>> {
    let file_of = |m: &[String]| {
        let base = src.join(m.join("/"));
        if m.is_empty() {
            Some(src.join("lib.rs"))
        } else {
            [base.with_extension("rs"), base.join("mod.rs")]
                .into_iter()
                .find(|p| p.exists())
        }
    };
    let mut out = BTreeSet::new();
    let mut stack = vec![Vec::new()];
    while let Some(m) = stack.pop() {
        let Some(file) = file_of(&m) else { continue };
        let text = std::fs::read_to_string(file).unwrap();
        for line in text.lines() {
            if let Some(name) = line
                .strip_prefix("pub mod ")
                .and_then(|l| l.strip_suffix(';'))
            {
                let mut child = m.clone();
                child.push(name.to_string());
                stack.push(child);
            }
        }
        out.insert(m);
    }
    out
}

/// Every `pub use` (plain `pub`, at the top of a file) of a reachable module whose source is a
/// reachable module of the same crate: the item would be reachable at two paths.
fn second_paths(src: &Path) -> Vec<String> {
    let public = public_modules(src);
    let mut bad = Vec::new();
    for m in &public {
        let rel = if m.is_empty() {
            "lib.rs".to_string()
        } else {
            let j = m.join("/");
            if src.join(format!("{j}.rs")).exists() {
                format!("{j}.rs")
            } else {
                format!("{j}/mod.rs")
            }
        };
        let text = std::fs::read_to_string(src.join(&rel)).unwrap();
        let mut rest = text.as_str();
        while let Some(i) = rest.find("\npub use ") {
            let stmt = &rest[i + "\npub use ".len()..];
            let end = stmt.find(';').unwrap_or(stmt.len());
            let path = stmt[..end].split("::{").next().unwrap();
            let mut parts: Vec<&str> = path.split("::").map(str::trim).collect();
            if !stmt[..end].contains("::{") {
                parts.pop(); // the item itself
            }
            let target: Option<Vec<String>> = match parts.first() {
                Some(&"crate") => Some(parts[1..].iter().map(|s| s.to_string()).collect()),
                Some(&"super") => Some(
                    m[..m.len().saturating_sub(1)]
                        .iter()
                        .cloned()
                        .chain(parts[1..].iter().map(|s| s.to_string()))
                        .collect(),
                ),
                // A child module of this one: relative; anything else is another crate.
                Some(first) => {
                    let dir = src.join(m.join("/"));
                    let child = dir.join(format!("{first}.rs")).exists()
                        || dir.join(first).join("mod.rs").exists();
                    child.then(|| {
                        m.iter()
                            .cloned()
                            .chain(parts.iter().map(|s| s.to_string()))
                            .collect()
                    })
                }
                None => None,
            };
            if let Some(t) = target {
                if public.contains(&t) {
                    bad.push(format!("{}/{rel}: pub use {}", src.display(), &stmt[..end]));
                }
            }
            rest = &stmt[end..];
        }
    }
    bad
}

/// Each public item of the engine and of the harness library is reachable at one path: no
/// reachable module re-exports (plain `pub use`) what another reachable module already shows.
#[test]
fn every_public_item_has_one_path() {
    let mut bad = Vec::new();
    for layers in CRATES {
        bad.extend(second_paths(&Path::new(ROOT).join(layers.src)));
    }
    assert!(
        bad.is_empty(),
        "items reachable at two paths:\n{}",
        bad.join("\n")
    );
}
