//! The layer test: every path to one of our modules, in every file under `src/`, checked against
//! the layer order of `docs/design.md` (the fenced `text` block after `## Layers`), so that no
//! module imports one above it or beside it and no two top-level modules import each other.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// A file of the crate: its path under `src/` (with `/` between components) and its code with
/// comments and the contents of string and character literals blanked out, so that only real
/// paths are read.
pub(super) struct Source {
    pub(super) path: String,
    pub(super) code: String,
}

/// One path to one of our modules: the crate it goes through (`crate` or `slabscope`), the first
/// name after it, and whether it lies in `#[cfg(test)]` code.
struct Reach<'a> {
    via: &'a str,
    name: &'a str,
    in_test: bool,
}

/// What a file may reach: the top-level modules of the library and of the binary, each
/// module's line in the layer order, and the files compiled only for tests.
struct Rules {
    library: BTreeSet<String>,
    binary: BTreeSet<String>,
    line: BTreeMap<String, usize>,
    test_files: Vec<String>,
}

/// Each module's line in the fenced `text` block right after the heading `## Layers`, lowest
/// first; `None` when there is no such block.
fn layer_lines(design: &str) -> Option<BTreeMap<String, usize>> {
    let mut lines = design.lines().skip_while(|l| l.trim() != "## Layers");
    lines.next()?;
    lines.find(|l| l.trim() == "```text")?;
    let block = lines.take_while(|l| l.trim() != "```");
    let mut line = BTreeMap::new();
    for (n, text) in block.filter(|l| !l.trim().is_empty()).enumerate() {
        for module in text.split_whitespace() {
            line.insert(module.to_string(), n);
        }
    }
    Some(line)
}

/// `text` with comments removed and string and character literals emptied (`"…"` becomes
/// `""`), so that braces and paths inside them are not read as code.
pub(super) fn code_only(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < c.len() {
        if let Some((end, kept)) = skipped(&c, i) {
            out.push_str(kept);
            i = end;
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// The end of the comment or literal starting at `i`, and what stands for it in the code; `None`
/// when none starts there.
fn skipped(c: &[char], i: usize) -> Option<(usize, &'static str)> {
    let after_ident = i > 0 && is_ident(c[i - 1]);
    match (c[i], c.get(i + 1).copied()) {
        ('/', Some('/')) => {
            let line = c[i..].iter().position(|&x| x == '\n');
            Some((line.map_or(c.len(), |p| i + p), ""))
        }
        ('/', Some('*')) => Some((block_comment_end(c, i), " ")),
        ('"', _) => Some((string_end(c, i + 1, None), "\"\"")),
        ('r', Some('"' | '#')) if !after_ident || is_byte_prefix(c, i) => {
            let (body, hashes) = raw_string_start(c, i)?;
            Some((string_end(c, body, Some(hashes)), "\"\""))
        }
        ('\'', _) => Some((char_literal_end(c, i)?, "' '")),
        _ => None,
    }
}

pub(super) fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// Whether the `r` at `i` follows the `b` of a raw byte string (`br"…"`).
fn is_byte_prefix(c: &[char], i: usize) -> bool {
    i > 0 && c[i - 1] == 'b' && (i < 2 || !is_ident(c[i - 2]))
}

/// The index after the block comment opening at `i` (block comments nest).
fn block_comment_end(c: &[char], mut i: usize) -> usize {
    let mut depth = 0;
    while i < c.len() {
        match (c[i], c.get(i + 1).copied()) {
            ('/', Some('*')) => (depth, i) = (depth + 1, i + 2),
            ('*', Some('/')) => {
                (depth, i) = (depth - 1, i + 2);
                if depth == 0 {
                    return i;
                }
            }
            _ => i += 1,
        }
    }
    i
}

/// The body's start and the number of `#` of the raw string opening at `i` (`r"`, `r#"`, ...).
fn raw_string_start(c: &[char], i: usize) -> Option<(usize, usize)> {
    let hashes = c[i + 1..].iter().take_while(|&&x| x == '#').count();
    (c.get(i + 1 + hashes) == Some(&'"')).then_some((i + 2 + hashes, hashes))
}

/// The index after the string whose body starts at `i`: a plain string (`raw` of `None`) ends
/// at a quote not escaped, a raw string at a quote followed by its `raw` hashes.
fn string_end(c: &[char], mut i: usize, raw: Option<usize>) -> usize {
    while i < c.len() {
        match (c[i], raw) {
            ('\\', None) => i += 2,
            ('"', None) => return i + 1,
            ('"', Some(hashes))
                if c.len() > i + hashes && c[i + 1..=i + hashes].iter().all(|&x| x == '#') =>
            {
                return i + 1 + hashes;
            }
            _ => i += 1,
        }
    }
    i
}

/// The index after the character literal opening at `i`, or `None` for a lifetime (`'a`).
fn char_literal_end(c: &[char], i: usize) -> Option<usize> {
    match c.get(i + 1)? {
        '\\' => Some(i + 2 + c[i + 2..].iter().position(|&x| x == '\'')? + 1),
        _ if c.get(i + 2) == Some(&'\'') => Some(i + 3),
        _ => None,
    }
}

/// The byte ranges of `code` that only tests compile: each item after `#[cfg(test)]`, to its
/// `;` or its closing brace.
pub(super) fn test_ranges(code: &str) -> Vec<(usize, usize)> {
    let bytes = code.as_bytes();
    let mut ranges = Vec::new();
    for (start, _) in code.match_indices("#[cfg(test)]") {
        let mut depth = 0usize;
        let mut end = code.len();
        for (k, &b) in bytes.iter().enumerate().skip(start) {
            match b {
                b'{' => depth += 1,
                b'}' if depth == 1 => {
                    end = k + 1;
                    break;
                }
                b'}' => depth = depth.saturating_sub(1),
                b';' if depth == 0 => {
                    end = k + 1;
                    break;
                }
                _ => {}
            }
        }
        ranges.push((start, end));
    }
    ranges
}

/// The modules declared as `mod NAME;` in `code`, each with whether it is only for tests.
fn declared_modules(code: &str) -> Vec<(String, bool)> {
    let tests = test_ranges(code);
    let mut found = Vec::new();
    for (at, _) in code.match_indices("mod ") {
        if at > 0 && is_ident(char::from(code.as_bytes()[at - 1])) {
            continue;
        }
        let rest = &code[at + 4..];
        let name: String = rest.chars().take_while(|&c| is_ident(c)).collect();
        if !name.is_empty() && rest[name.len()..].trim_start().starts_with(';') {
            let in_test = tests.iter().any(|&(s, e)| s <= at && at < e);
            found.push((name, in_test));
        }
    }
    found
}

/// The folder under `src/` where the modules declared in the file at `path` live.
fn child_folder(path: &str) -> String {
    if path == "lib.rs" || path == "main.rs" {
        return String::new();
    }
    match path.rsplit_once('/') {
        Some((dir, "mod.rs")) => format!("{dir}/"),
        _ => format!("{}/", path.trim_end_matches(".rs")),
    }
}

/// The files (and folders, ending in `/`) that only tests compile: those declared under
/// `#[cfg(test)]`, with everything below them.
fn test_only(sources: &[Source]) -> Vec<String> {
    let mut paths = Vec::new();
    for s in sources {
        for (name, in_test) in declared_modules(&s.code) {
            if in_test {
                let dir = child_folder(&s.path);
                paths.push(format!("{dir}{name}.rs"));
                paths.push(format!("{dir}{name}/"));
            }
        }
    }
    paths
}

/// The file's top-level module: `view` for `view/rate/lanes.rs`; `None` for the two roots.
fn top_module(path: &str) -> Option<&str> {
    if path == "lib.rs" || path == "main.rs" {
        return None;
    }
    let first = path.split('/').next().unwrap_or(path);
    Some(first.trim_end_matches(".rs"))
}

/// Every path in `code` through `crate::` or `slabscope::`, with the first name after it (each
/// name of a `{…}` group).
fn reaches(code: &str) -> Vec<Reach<'_>> {
    let tests = test_ranges(code);
    let mut found = Vec::new();
    for via in ["crate", "slabscope"] {
        for (at, _) in code.match_indices(&format!("{via}::")) {
            let before = code[..at].chars().next_back();
            if before.is_some_and(|c| is_ident(c) || c == ':') {
                continue;
            }
            let in_test = tests.iter().any(|&(s, e)| s <= at && at < e);
            let rest = &code[at + via.len() + 2..];
            for name in first_names(rest) {
                found.push(Reach { via, name, in_test });
            }
        }
    }
    found
}

/// The name `text` starts with (after any space).
fn ident(text: &str) -> &str {
    let t = text.trim_start();
    &t[..t.find(|c: char| !is_ident(c)).unwrap_or(t.len())]
}

/// The first name of the path that `rest` starts with, or of each path of a `{…}` group.
fn first_names(rest: &str) -> Vec<&str> {
    let Some(group) = rest.strip_prefix('{') else {
        return vec![ident(rest)];
    };
    let (mut depth, mut start, mut names) = (0usize, 0, Vec::new());
    for (k, c) in group.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => {
                names.push(ident(&group[start..k]));
                break;
            }
            '}' => depth -= 1,
            ',' if depth == 0 => {
                names.push(ident(&group[start..k]));
                start = k + 1;
            }
            _ => {}
        }
    }
    names.retain(|n| !n.is_empty() && *n != "self");
    names
}

impl Rules {
    /// The rules for `sources`, the layer order being `line`.
    fn new(sources: &[Source], line: BTreeMap<String, usize>) -> Self {
        let declared = |root: &str| -> BTreeSet<String> {
            sources
                .iter()
                .filter(|s| s.path == root)
                .flat_map(|s| declared_modules(&s.code))
                .map(|(name, _)| name)
                .collect()
        };
        Self {
            library: declared("lib.rs"),
            binary: declared("main.rs"),
            line,
            test_files: test_only(sources),
        }
    }

    /// Whether the file at `path` is compiled only for tests.
    fn is_test_file(&self, path: &str) -> bool {
        self.test_files
            .iter()
            .any(|t| path == t || (t.ends_with('/') && path.starts_with(t.as_str())))
    }

    /// What is wrong with `reach` from module `from` of the file at `path`, if anything.
    fn broken(&self, path: &str, from: &str, reach: &Reach) -> Option<String> {
        let (via, to) = (reach.via, reach.name);
        let in_binary = self.binary.contains(from);
        let modules = if in_binary && via == "crate" {
            &self.binary
        } else {
            &self.library
        };
        let what = format!("{path} (module {from}) imports {via}::{to}");
        let in_test = reach.in_test || self.is_test_file(path);
        if !modules.contains(to) {
            return match (in_binary, via) {
                // The library's facade, from the binary: all of it lies below the binary.
                (true, "slabscope") => None,
                // A test of the binary may reach its root: the argument parser lives there.
                (true, _) if in_test => None,
                (true, _) => Some(format!(
                    "{what}: an item of main.rs, the binary's root, which is above every module"
                )),
                _ => Some(format!(
                    "{what}: the crate's root facade; name the module's path instead \
                     (crate::MODULE::{to})"
                )),
            };
        }
        self.order_broken(&what, from, to, in_test)
    }

    /// What is wrong with module `from` importing module `to` by the layer order, if anything.
    fn order_broken(&self, what: &str, from: &str, to: &str, in_test: bool) -> Option<String> {
        if from == to {
            return None;
        }
        let (Some(&low), Some(&high)) = (self.line.get(to), self.line.get(from)) else {
            return Some(format!(
                "{what}: {} is not in the layer order of docs/design.md",
                if self.line.contains_key(from) {
                    to
                } else {
                    from
                }
            ));
        };
        if to == "testing" {
            return (!in_test)
                .then(|| format!("{what}: only #[cfg(test)] code may import testing"));
        }
        match low.cmp(&high) {
            std::cmp::Ordering::Equal => Some(format!(
                "{what}: {to} is on the same line of the layer order as {from}, and modules on \
                 one line import nothing of each other"
            )),
            std::cmp::Ordering::Greater => Some(format!(
                "{what}: {to} is on a later line of the layer order than {from}, and a module \
                 imports only modules on earlier lines"
            )),
            std::cmp::Ordering::Less => None,
        }
    }
}

/// Every rule `sources` break, one line each, and the number of paths read.
fn violations(sources: &[Source], line: BTreeMap<String, usize>) -> (BTreeSet<String>, usize) {
    let rules = Rules::new(sources, line);
    let mut broken = BTreeSet::new();
    for module in rules.library.iter().chain(&rules.binary) {
        if !rules.line.contains_key(module) {
            broken.insert(format!(
                "module {module} is not in the layer order of docs/design.md"
            ));
        }
    }
    let mut read = 0;
    for s in sources {
        let Some(from) = top_module(&s.path) else {
            continue;
        };
        for reach in reaches(&s.code) {
            read += 1;
            broken.extend(rules.broken(&s.path, from, &reach));
        }
    }
    (broken, read)
}

/// Every `.rs` file under `dir`, its path relative to `root`, sorted.
pub(super) fn rust_files(root: &Path, dir: &Path, out: &mut Vec<Source>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .expect("src/ is readable")
        .map(|e| e.expect("src/ is readable").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            rust_files(root, &path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&path).expect("a source file is UTF-8");
            let relative = path.strip_prefix(root).expect("under src/");
            out.push(Source {
                path: relative.to_string_lossy().replace('\\', "/"),
                code: code_only(&text),
            });
        }
    }
}

#[test]
fn every_import_follows_the_layer_order_of_the_design() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let design = std::fs::read_to_string(manifest.join("docs/design.md"))
        .expect("docs/design.md holds the layer order");
    let line = layer_lines(&design).expect("docs/design.md has a ```text block after ## Layers");
    assert!(
        line.len() >= 10,
        "the layer order names {} modules",
        line.len()
    );
    let src = manifest.join("src");
    let mut sources = Vec::new();
    rust_files(&src, &src, &mut sources);
    let (broken, read) = violations(&sources, line);
    assert!(read > 300, "only {read} paths to our modules were read");
    assert!(
        broken.is_empty(),
        "{} imports break the layers:\n{}",
        broken.len(),
        broken.into_iter().collect::<Vec<_>>().join("\n")
    );
}

#[test]
fn the_checker_finds_each_broken_rule_and_reads_only_code() {
    let source = |path: &str, text: &str| Source {
        path: path.into(),
        code: code_only(text),
    };
    let sources = [
        source(
            "lib.rs",
            "pub mod low;\npub mod high;\npub mod side;\n#[cfg(test)]\nmod testing;",
        ),
        source("main.rs", "mod front;"),
        source(
            "low/mod.rs",
            "use crate::high::X; // crate::side::Y in a comment\nconst S: &str = \"crate::side\";\n\
             #[cfg(test)]\nmod tests { use crate::testing::Lcg; }\nuse crate::{side::Z, Volume};",
        ),
        source(
            "high.rs",
            "fn f() { crate::low::g(); crate::testing::h(); }",
        ),
        source("side.rs", "#[cfg(test)]\nmod tests;\nuse crate::low::A;"),
        source("side/tests.rs", "use crate::testing::Lcg;"),
        source(
            "front/x.rs",
            "use slabscope::{Volume, high::H};\nuse crate::Cli;",
        ),
    ];
    let line = layer_lines("## Layers\n\ntext\n\n```text\ntesting\nlow\nhigh side\nfront\n```\n")
        .expect("a layer block");
    let (broken, read) = violations(&sources, line);
    let broken: Vec<String> = broken.into_iter().collect();
    let expected = [
        "front/x.rs (module front) imports crate::Cli: an item of main.rs",
        "high.rs (module high) imports crate::testing: only #[cfg(test)]",
        "low/mod.rs (module low) imports crate::Volume: the crate's root facade",
        "low/mod.rs (module low) imports crate::high: high is on a later line",
        "low/mod.rs (module low) imports crate::side: side is on a later line",
    ];
    assert_eq!(broken.len(), expected.len(), "{broken:#?}");
    for (got, want) in broken.iter().zip(expected) {
        assert!(got.starts_with(want), "{got}\ndoes not start with\n{want}");
    }
    assert_eq!(read, 11);
}
