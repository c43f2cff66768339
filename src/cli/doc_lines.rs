//! Docs that cannot rot: every `slabscope` command line in `README.md` and `docs/*.md` is parsed
//! by the real argument parser, so a flag renamed in the code fails this test until the docs
//! follow. The conventions (placeholders, synopsis blocks) are written in `docs/testing.md`.

use std::path::{Path, PathBuf};

use clap::{CommandFactory, Parser};

use crate::Cli;

/// The marker that makes the next fenced block (or, outside one, the next paragraph) a
/// synopsis: a usage pattern such as `slabscope [FILE]`, not a command line to run.
const SYNOPSIS: &str = "<!-- synopsis -->";

/// Placeholders a command line may hold, whole arguments, and what they stand for: a value the
/// parser accepts wherever the placeholder is used.
const PLACEHOLDERS: &[(&str, &str)] = &[
    ("FILE", "body.nrrd"),
    ("FILES...", "a.nii"),
    ("DIR", "archive"),
    ("FOLDER", "archive"),
    ("KIND", "body"),
    ("K/N", "2/5"),
    ("WxH", "640x480"),
    ("NXxNYxNZ", "64x64x96"),
    ("SX,SY,SZ", "1,1,2"),
    ("DX,DY,DZ", "1,1,0"),
    ("LO,HI", "-200,300"),
    ("MM", "1.5"),
    ("BYTES", "0"),
    ("PIXELS", "160"),
    ("SLAB", "1"),
    ("VALUE", "-500"),
    ("UID", "1.2.840.1"),
    ("SECONDS", "60"),
    ("I", "10"),
    ("N", "2"),
    ("K", "4"),
    ("B", "32"),
    ("L", "3"),
    ("T", "0.05"),
    ("S", "0.5"),
    ("A", "30"),
    ("E", "20"),
    ("Z", "1.5"),
    ("F", "body.nrrd"),
];

/// Shell variables, replaced wherever they stand inside an argument.
const VARIABLES: &[(&str, &str)] = &[
    ("$SLURM_ARRAY_TASK_ID", "3"),
    ("$SLURM_ARRAY_TASK_COUNT", "50"),
];

/// Arguments that end an invocation: shell operators and redirections.
const ENDS: &[&str] = &["|", "||", "&&", ";", "&", ">", ">>", "<", "#"];

/// One `slabscope` invocation found in a page.
#[derive(Debug)]
struct Invocation {
    /// Where it was found, `docs/cli.md:12`.
    place: String,
    /// Its arguments as written, after the program's name.
    args: Vec<String>,
}

/// The pages whose command lines are checked: the README and every `docs/*.md`.
fn pages() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut pages: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .expect("docs/ is readable")
        .map(|entry| entry.expect("docs/ lists").path())
        .filter(|path| path.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    pages.insert(0, root.join("README.md"));
    pages
}

/// A piece of a page to search for invocations: a command line of a code block (continuations
/// joined) or a paragraph of prose, with the line it starts on.
struct Piece {
    line: usize,
    text: String,
    code: bool,
}

/// How far a page's reading is into a synopsis that its marker announced.
#[derive(Clone, Copy, PartialEq)]
enum Synopsis {
    /// No synopsis: lines are read.
    No,
    /// The marker was seen; the next fence or paragraph is the synopsis.
    Announced,
    /// Inside the synopsis: lines are skipped until its fence closes or its paragraph ends.
    Inside,
}

/// The page cut into code lines and prose paragraphs, synopsis blocks left out.
fn pieces(page: &str) -> Vec<Piece> {
    let mut pieces = Vec::new();
    let mut fence = false;
    let mut synopsis = Synopsis::No;
    let mut current: Option<Piece> = None;
    for (n, line) in page.lines().enumerate() {
        let trimmed = line.trim();
        // A heading ends a paragraph and is no command line: `## `slabscope info`` names one.
        let blank = !fence && (trimmed.is_empty() || trimmed.starts_with('#'));
        let fence_line = trimmed.starts_with("```");
        if fence_line || blank || trimmed == SYNOPSIS {
            pieces.extend(current.take());
        }
        synopsis = match (synopsis, fence_line, blank) {
            _ if trimmed == SYNOPSIS => Synopsis::Announced,
            (Synopsis::Inside, true, _) if fence => Synopsis::No,
            (Synopsis::Inside, false, true) if !fence => Synopsis::No,
            (Synopsis::Announced, _, false) => Synopsis::Inside,
            (state, _, _) => state,
        };
        if fence_line {
            fence = !fence;
        }
        if fence_line || blank || synopsis != Synopsis::No {
            continue;
        }
        let piece = current.get_or_insert_with(|| Piece {
            line: n + 1,
            text: String::new(),
            code: fence,
        });
        piece.text.push_str(trimmed.trim_end_matches('\\'));
        piece.text.push(' ');
        if fence && !trimmed.ends_with('\\') {
            pieces.extend(current.take());
        }
    }
    pieces.extend(current);
    pieces
}

/// The texts of a piece that may hold command lines: a code line whole, a paragraph's inline
/// code spans.
fn spans(piece: &Piece) -> Vec<String> {
    if piece.code {
        return vec![piece.text.clone()];
    }
    inline_code(&piece.text)
        .into_iter()
        .map(|span| span.replace("\\|", "|"))
        .collect()
}

/// The inline code spans of a paragraph: a run of backticks opens one, and the next run of as
/// many closes it (so that ``` `` `x` `` ``` holds `` `x` ``).
fn inline_code(text: &str) -> Vec<String> {
    let mut spans = Vec::new();
    let mut rest = text;
    while let Some(open) = rest.find('`') {
        let ticks = rest[open..].len() - rest[open..].trim_start_matches('`').len();
        let fence = &rest[open..open + ticks];
        let body = &rest[open + ticks..];
        let Some(close) = find_run(body, fence) else {
            break;
        };
        spans.push(body[..close].trim().to_string());
        rest = &body[close + ticks..];
    }
    spans
}

/// Where in `text` a run of exactly `fence`'s backticks starts.
fn find_run(text: &str, fence: &str) -> Option<usize> {
    let mut from = 0;
    while let Some(at) = text[from..].find(fence) {
        let start = from + at;
        let end = start + fence.len();
        let longer = text[end..].starts_with('`') || (start > 0 && text[..start].ends_with('`'));
        if !longer {
            return Some(start);
        }
        from = end + text[end..].len() - text[end..].trim_start_matches('`').len();
    }
    None
}

/// The words of `text`, split at white space outside quotes, quotes removed.
fn words(text: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut word = String::new();
    let mut quote = None;
    for c in text.chars() {
        match (quote, c) {
            (None, '\'' | '"') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            (None, c) if c.is_whitespace() => {
                if !word.is_empty() {
                    words.push(std::mem::take(&mut word));
                }
            }
            _ => word.push(c),
        }
    }
    if !word.is_empty() {
        words.push(word);
    }
    words
}

/// Where an invocation starts in `words`: the index of its first argument, after `slabscope`
/// (or a path ending in `/slabscope`, but not the target of `cargo test --bin slabscope` nor
/// Python's `from slabscope import *`) or `cargo run --release --`.
fn starts(words: &[String]) -> Vec<usize> {
    let mut starts = Vec::new();
    for i in 0..words.len() {
        let w = words[i].as_str();
        let named = i > 0
            && matches!(
                words[i - 1].as_str(),
                "--bin" | "-p" | "--package" | "from" | "import"
            );
        if (w == "slabscope" || w.ends_with("/slabscope")) && !named {
            starts.push(i + 1);
        } else if words[i..].starts_with(&["cargo", "run", "--release", "--"].map(String::from)) {
            starts.push(i + 4);
        }
    }
    starts
}

/// Whether `word` ends the invocation it follows: a shell operator or a redirection.
fn ends(word: &str) -> bool {
    ENDS.contains(&word)
        || word.starts_with('>')
        || word.starts_with("2>")
        || word.starts_with("1>")
        || word.starts_with('#')
}

/// Every invocation of a page, its arguments as written; one with no arguments (the program's
/// name in prose) is left out.
fn invocations(name: &str, page: &str) -> Vec<Invocation> {
    let mut found = Vec::new();
    for piece in pieces(page) {
        for span in spans(&piece) {
            for words in commands(&span) {
                for start in starts(&words) {
                    let args: Vec<String> = words[start..]
                        .iter()
                        .take_while(|w| !ends(w))
                        .cloned()
                        .collect();
                    if !args.is_empty() {
                        found.push(Invocation {
                            place: format!("{name}:{}", piece.line),
                            args,
                        });
                    }
                }
            }
        }
    }
    found
}

/// The words of `text`, and the words of each quoted command inside it (`sbatch --wrap
/// 'slabscope triage …'`).
fn commands(text: &str) -> Vec<Vec<String>> {
    let outer = words(text);
    let inner: Vec<Vec<String>> = outer
        .iter()
        .filter(|w| w.contains(char::is_whitespace))
        .flat_map(|w| commands(w))
        .collect();
    std::iter::once(outer).chain(inner).collect()
}

/// An argument with its placeholders filled in: `x|y|z` becomes `x`, `[--force]` `--force`,
/// `OUT.png` `out.png`, and whole placeholders and shell variables their table's value.
fn filled(arg: &str) -> String {
    let arg = arg.trim_matches(['[', ']']);
    let arg = arg.split('|').next().unwrap_or(arg);
    if let Some((_, value)) = PLACEHOLDERS.iter().find(|(p, _)| *p == arg) {
        return (*value).to_string();
    }
    if let Some(rest) = arg.strip_prefix("OUT.") {
        return format!("out.{rest}");
    }
    let mut arg = arg.to_string();
    for (variable, value) in VARIABLES {
        arg = arg.replace(variable, value);
    }
    arg
}

/// Whether an argument, once filled, still looks like a placeholder: a word of capitals the
/// table does not know, or an ellipsis.
fn unfilled(arg: &str) -> bool {
    let capitals = arg.len() > 1
        && arg.starts_with(|c: char| c.is_ascii_uppercase())
        && arg
            .chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_');
    capitals || arg.contains('…') || arg.contains("...") || arg.contains('$')
}

/// Parses one invocation with the real parser; the problem, if any, in words.
fn check(invocation: &Invocation) -> Result<Vec<String>, String> {
    let args: Vec<String> = invocation
        .args
        .iter()
        .map(|a| filled(a))
        .filter(|a| !a.is_empty())
        .collect();
    if let Some(bad) = args.iter().find(|a| unfilled(a)) {
        return Err(format!(
            "{}: `{bad}` is no placeholder docs/testing.md lists (mark a usage pattern as a synopsis)",
            invocation.place
        ));
    }
    let argv = std::iter::once("slabscope".to_string()).chain(args.iter().cloned());
    match Cli::try_parse_from(argv) {
        Ok(_) => Ok(args),
        Err(e)
            if matches!(
                e.kind(),
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
            ) =>
        {
            Ok(args)
        }
        Err(e) => Err(format!(
            "{}: `slabscope {}`: {}",
            invocation.place,
            args.join(" "),
            e.render().to_string().lines().next().unwrap_or_default()
        )),
    }
}

/// Every documented invocation, parsed: none may fail, at least 40 must be there, and every
/// subcommand must be shown at least once.
#[test]
fn every_documented_command_line_parses() {
    let mut parsed = Vec::new();
    let mut failures = Vec::new();
    for path in pages() {
        let page = std::fs::read_to_string(&path).expect("page is readable");
        let name = path
            .strip_prefix(env!("CARGO_MANIFEST_DIR"))
            .unwrap_or(&path)
            .display()
            .to_string();
        for invocation in invocations(name.trim_start_matches('/'), &page) {
            match check(&invocation) {
                Ok(args) => parsed.push(args),
                Err(problem) => failures.push(problem),
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        parsed.len() >= 40,
        "only {} command lines in the docs",
        parsed.len()
    );
    for sub in Cli::command().get_subcommands() {
        let name = sub.get_name();
        assert!(
            name == "help"
                || parsed
                    .iter()
                    .any(|args| args.first().is_some_and(|a| a == name)),
            "no documented command line runs `slabscope {name}`"
        );
    }
}

/// The extraction itself: continuations, pipes, `&&`, redirections, quotes and inline code.
#[test]
fn invocations_are_cut_out_of_shell_lines_and_prose() {
    let page = "```sh\nslabscope info a.nii 2>/dev/null | head -1 && \\\n  cargo run --release -- \
                analyze b.nrrd --json > x.json\nsbatch --wrap 'slabscope triage --list d'\n```\n\n\
                Run `slabscope render FILE -o OUT.png`, not the `slabscope` binary's name \
                (nor ``x `slabscope` y``).\n\n## `slabscope info`\n";
    let found: Vec<String> = invocations("t.md", page)
        .iter()
        .map(|i| i.args.join(" "))
        .collect();
    assert_eq!(
        found,
        [
            "info a.nii",
            "analyze b.nrrd --json",
            "triage --list d",
            "render FILE -o OUT.png"
        ]
    );
}

/// A synopsis block is left out, and the line after it is read again.
#[test]
fn synopsis_blocks_are_skipped() {
    let page = "<!-- synopsis -->\n```\nslabscope [FILE] [--json | --csv]\n```\n\n\
                `slabscope info FILE`\n\n<!-- synopsis -->\n`slabscope KIND...`\n\n`slabscope x`\n";
    let found: Vec<String> = invocations("t.md", page)
        .iter()
        .map(|i| i.args.join(" "))
        .collect();
    assert_eq!(found, ["info FILE", "x"]);
}

/// A renamed flag fails: the check is the real parser's, not a list of its own.
#[test]
fn a_renamed_flag_fails() {
    let invocation = |args: &[&str]| Invocation {
        place: "t.md:1".into(),
        args: args.iter().map(ToString::to_string).collect(),
    };
    assert!(check(&invocation(&["analyze", "FILE", "--slabs", "K"])).is_ok());
    assert!(check(&invocation(&["analyze", "FILE", "--slab-count", "K"])).is_err());
    assert!(check(&invocation(&["analyze", "FILE", "--slabs", "WHAT"])).is_err());
}
