//! The circle test: no two files import each other, unless one is a module the other lies inside
//! (a `mod.rs` and its children use each other's items by design). Between top-level modules the
//! layer test already forbids a circle; this finds the two-file circles inside one module, such
//! as a reader's map type imported by the voxels that the reader's map module imports back.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use super::layers::{Source, is_ident, rust_files, test_ranges};

/// The module path of the file at `path` (`tui::app` for `tui/app/mod.rs`; empty for the roots).
fn module_of(path: &str) -> String {
    let p = path.trim_end_matches(".rs");
    let p = p.strip_suffix("/mod").unwrap_or(p);
    match p {
        "lib" | "main" => String::new(),
        _ => p.replace('/', "::"),
    }
}

/// `module::name`, or `name` under the root.
fn join(module: &str, name: &str) -> String {
    if module.is_empty() {
        name.to_string()
    } else {
        format!("{module}::{name}")
    }
}

/// The parent of `module` (the root's is the root).
fn parent(module: &str) -> &str {
    module.rsplit_once("::").map_or("", |(p, _)| p)
}

/// Every path `rest` starts with, as its names, a `{…}` group expanded (`a::{b, c::d}` is
/// `a::b` and `a::c::d`).
fn paths(rest: &str) -> Vec<Vec<&str>> {
    let rest = rest.trim_start();
    if let Some(group) = rest.strip_prefix('{') {
        let (mut depth, mut start, mut out) = (0usize, 0, Vec::new());
        for (k, c) in group.char_indices() {
            match c {
                '{' => depth += 1,
                '}' if depth == 0 => {
                    out.extend(paths(&group[start..k]));
                    break;
                }
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    out.extend(paths(&group[start..k]));
                    start = k + 1;
                }
                _ => {}
            }
        }
        return out;
    }
    let end = rest.find(|c: char| !is_ident(c)).unwrap_or(rest.len());
    let (name, after) = rest.split_at(end);
    if name.is_empty() {
        return vec![];
    }
    match after.strip_prefix("::") {
        Some(more) => {
            let tails = paths(more);
            if tails.is_empty() {
                return vec![vec![name]];
            }
            tails
                .into_iter()
                .map(|t| std::iter::once(name).chain(t).collect())
                .collect()
        }
        None => vec![vec![name]],
    }
}

/// The files each file imports (through `crate::`, `slabscope::`, `super::` or `self::`, outside
/// `#[cfg(test)]` code), by module path: the deepest module of each path that is a file.
fn imports(sources: &[Source]) -> BTreeMap<String, BTreeSet<String>> {
    let modules: BTreeSet<String> = sources.iter().map(|s| module_of(&s.path)).collect();
    let mut edges = BTreeMap::new();
    for s in sources {
        let own = module_of(&s.path);
        let tests = test_ranges(&s.code);
        let mut to = BTreeSet::new();
        for via in ["crate", "slabscope", "super", "self"] {
            for (at, _) in s.code.match_indices(&format!("{via}::")) {
                let before = s.code[..at].chars().next_back();
                if before.is_some_and(|c| is_ident(c) || c == ':' || c == '$')
                    || tests.iter().any(|&(a, e)| a <= at && at < e)
                {
                    continue;
                }
                let base = match via {
                    "super" => parent(&own).to_string(),
                    "self" => own.clone(),
                    _ => String::new(),
                };
                for names in paths(&s.code[at + via.len() + 2..]) {
                    let mut module = base.clone();
                    for name in names {
                        match name {
                            "super" => module = parent(&module).to_string(),
                            _ if modules.contains(&join(&module, name)) => {
                                module = join(&module, name);
                            }
                            _ => break,
                        }
                    }
                    to.insert(module);
                }
            }
        }
        to.remove(&own);
        edges.insert(own, to);
    }
    edges
}

/// Whether one of two modules lies inside the other.
fn nested(a: &str, b: &str) -> bool {
    let inside = |x: &str, y: &str| y.is_empty() || x.starts_with(&format!("{y}::"));
    inside(a, b) || inside(b, a)
}

/// Every two modules (files) that import each other, neither inside the other.
fn circles(sources: &[Source]) -> Vec<String> {
    let edges = imports(sources);
    let mut found = Vec::new();
    for (a, to) in &edges {
        for b in to.iter().filter(|b| a < *b && !nested(a, b)) {
            if edges.get(b).is_some_and(|back| back.contains(a)) {
                found.push(format!("{a} and {b} import each other"));
            }
        }
    }
    found
}

#[test]
fn no_two_files_import_each_other() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut sources = Vec::new();
    rust_files(&src, &src, &mut sources);
    let edges = imports(&sources);
    let reached: usize = edges.values().map(BTreeSet::len).sum();
    assert!(
        reached > 300,
        "only {reached} imports between files were read"
    );
    let found = circles(&sources);
    assert!(
        found.is_empty(),
        "{} two-file import circles (move what both need to where it belongs):\n{}",
        found.len(),
        found.join("\n")
    );
}

#[test]
fn the_checker_finds_a_circle_between_siblings_but_not_with_a_parent() {
    let source = |path: &str, text: &str| Source {
        path: path.into(),
        code: super::layers::code_only(text),
    };
    let sources = [
        source("lib.rs", "pub mod v;"),
        source(
            "v/mod.rs",
            "mod a;\nmod io;\nuse self::a::X;\npub struct V;",
        ),
        source("v/a.rs", "use super::V;\nfn f() { super::io::m::g(); }"),
        source("v/io/mod.rs", "pub mod m;\nuse crate::v::V;"),
        source(
            "v/io/m.rs",
            "use crate::v::{V, a::X}; // crate::v::io in a comment\n\
             #[cfg(test)]\nmod tests { use super::super::super::a::X; }",
        ),
    ];
    assert_eq!(circles(&sources), ["v::a and v::io::m import each other"]);
    let edges = imports(&sources);
    let of = |m: &str| edges[m].iter().cloned().collect::<Vec<_>>();
    assert_eq!(of("v::io::m"), ["v", "v::a"]);
    assert_eq!(of("v"), ["v::a"]);
}
