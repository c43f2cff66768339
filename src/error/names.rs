//! One rule for every name and every value that comes from a file, in every output (tables, CSV,
//! JSON, listings, problems, notes and errors): nothing a file holds reaches a terminal raw.
//!
//! A name is written as its bytes: printable UTF-8 as it is; a backslash as `\\`; a line feed,
//! tab and carriage return as `\n`, `\t` and `\r`; every other control character (U+0000–U+001F,
//! U+007F–U+009F), every bidirectional formatting character (U+061C, U+200E, U+200F,
//! U+202A–U+202E, U+2066–U+2069) and the line and paragraph separators (U+2028, U+2029) as
//! `\u{HEX}`; and each byte that is not part of valid UTF-8 as `\xHH` (two lowercase hex
//! digits). The escaped form is reversible ([`unescape`]), so two names never print the same and
//! a name printed can be read back to the same bytes.
//!
//! Text read from a file's metadata (an axis name, a unit, a label name, a dataset path, a
//! note or an error quoting one) is written by the same rule in text ([`text`] for a value,
//! [`controls`] for a message); JSON keeps the text itself and [`json`] writes those characters
//! as JSON's own `\uXXXX` escapes, so that it reads back to the same text.

use std::borrow::Cow;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Whether `c` is never written raw: a control or a bidirectional formatting character, or a
/// line or paragraph separator.
fn hidden(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{061c}'
                | '\u{200e}'
                | '\u{200f}'
                | '\u{2028}'..='\u{202e}'
                | '\u{2066}'..='\u{2069}'
        )
}

/// Appends `c` as the rule writes it; a backslash doubled when `backslash` is set.
fn push(c: char, backslash: bool, out: &mut String) {
    match c {
        '\\' if backslash => out.push_str("\\\\"),
        '\n' => out.push_str("\\n"),
        '\t' => out.push_str("\\t"),
        '\r' => out.push_str("\\r"),
        c if hidden(c) => {
            let _ = write!(out, "\\u{{{:x}}}", c as u32);
        }
        c => out.push(c),
    }
}

/// `bytes` escaped by the rule: the lossless form of a name.
pub fn bytes(bytes: &[u8]) -> String {
    let mut out = String::with_capacity(bytes.len());
    for chunk in bytes.utf8_chunks() {
        for c in chunk.valid().chars() {
            push(c, true, &mut out);
        }
        for b in chunk.invalid() {
            let _ = write!(out, "\\x{b:02x}");
        }
    }
    out
}

/// A path as every output shows it: escaped by the rule, losslessly (non-UTF-8 bytes as `\xHH`).
pub fn path(path: &Path) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        bytes(path.as_os_str().as_bytes())
    }
    #[cfg(not(unix))]
    {
        bytes(path.to_string_lossy().as_bytes())
    }
}

/// A value read from a file (a series description, a UID) as every output shows it.
pub fn text(text: &str) -> String {
    bytes(text.as_bytes())
}

/// `text` with its control and bidirectional characters escaped as the rule writes them, its
/// backslashes left as they are: for a message whose names are escaped already (it is unchanged
/// then), so that nothing raw reaches a terminal whatever the message quotes.
pub fn controls(text: &str) -> Cow<'_, str> {
    escape_hidden(text, false)
}

/// JSON text (as `serde_json` writes it) with every control and bidirectional character that is
/// not its own layout written as a JSON `\uXXXX` escape: `serde_json` escapes U+0000–U+001F
/// inside strings by itself, not DEL, the C1 controls (U+0080–U+009F) nor the bidirectional
/// formatting characters, which can only stand inside strings. The JSON stays valid and reads
/// back to the same text; nothing raw reaches a terminal. The line feeds of pretty JSON stay.
pub fn json(text: &str) -> Cow<'_, str> {
    escape_hidden(text, true)
}

/// The one pass of [`controls`] and [`json`]: `text` with every character the rule hides
/// escaped, as the rule writes it or (`json`) as JSON does, `\n` of JSON's layout kept.
fn escape_hidden(text: &str, json: bool) -> Cow<'_, str> {
    let escaped = |c: char| hidden(c) && !(json && c == '\n');
    if !text.chars().any(escaped) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if json && escaped(c) {
            // Every hidden character is in the Basic Multilingual Plane: one escape each.
            let _ = write!(out, "\\u{:04x}", c as u32);
        } else if json {
            out.push(c);
        } else {
            push(c, false, &mut out);
        }
    }
    Cow::Owned(out)
}

/// The bytes a name escaped by the rule stands for; an error names what cannot be read (a lone
/// backslash, an unknown escape, a bad hex number). Also accepts `\xHH` for any byte and
/// `\u{HEX}` for any character, so that a hand-written name reads too.
pub fn unescape(text: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(text.len());
    let mut chars = text.char_indices();
    while let Some((at, c)) = chars.next() {
        if c != '\\' {
            let mut buf = [0; 4];
            out.extend_from_slice(c.encode_utf8(&mut buf).as_bytes());
            continue;
        }
        let bad = |what: &str| format!("{what} at character {}", text[..at].chars().count() + 1);
        match chars.next().map(|(_, c)| c) {
            Some('\\') => out.push(b'\\'),
            Some('n') => out.push(b'\n'),
            Some('t') => out.push(b'\t'),
            Some('r') => out.push(b'\r'),
            Some('x') => {
                let hex: String = chars.by_ref().take(2).map(|(_, c)| c).collect();
                let byte = (hex.len() == 2)
                    .then(|| u8::from_str_radix(&hex, 16).ok())
                    .flatten()
                    .ok_or_else(|| bad("\\x without two hex digits"))?;
                out.push(byte);
            }
            Some('u') => {
                let rest = &text[at + 2..];
                let end = rest
                    .strip_prefix('{')
                    .and_then(|r| r.find('}'))
                    .ok_or_else(|| bad("\\u without {HEX}"))?;
                let c = u32::from_str_radix(&rest[1..=end], 16)
                    .ok()
                    .and_then(char::from_u32)
                    .ok_or_else(|| bad("\\u{…} that is no character"))?;
                let mut buf = [0; 4];
                out.extend_from_slice(c.encode_utf8(&mut buf).as_bytes());
                for _ in 0..end + 2 {
                    chars.next();
                }
            }
            Some(other) => return Err(bad(&format!("unknown escape \\{other}"))),
            None => return Err(bad("a lone backslash")),
        }
    }
    Ok(out)
}

/// The path a name escaped by the rule stands for ([`path`] read back).
pub fn unescape_path(text: &str) -> Result<PathBuf, String> {
    let bytes = unescape(text)?;
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStringExt;
        Ok(PathBuf::from(std::ffi::OsString::from_vec(bytes)))
    }
    #[cfg(not(unix))]
    {
        Ok(PathBuf::from(String::from_utf8_lossy(&bytes).into_owned()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_escaped_by_one_rule() {
        assert_eq!(bytes(b"plain/name.nii.gz"), "plain/name.nii.gz");
        assert_eq!(bytes("é→ü".as_bytes()), "é→ü", "printable text stays");
        assert_eq!(
            bytes(b"esc\x1b[31mRED\x1b[0m\x07.nii"),
            "esc\\u{1b}[31mRED\\u{1b}[0m\\u{7}.nii"
        );
        assert_eq!(bytes(b"a\nb\tc\rd\\e"), "a\\nb\\tc\\rd\\\\e");
        assert_eq!(bytes(b"p\xff.nii.gz"), "p\\xff.nii.gz");
        assert_eq!(bytes(b"p\xfe.nii.gz"), "p\\xfe.nii.gz");
        assert_eq!(bytes("\u{202e}txt\u{85}".as_bytes()), "\\u{202e}txt\\u{85}");
        assert_eq!(text("ok"), "ok");
    }

    #[test]
    fn controls_leave_escaped_text_unchanged() {
        let once = bytes(b"a\\b\x1bc\n");
        assert_eq!(controls(&once), once);
        assert_eq!(controls("x\x1by\\z"), "x\\u{1b}y\\z");
    }

    #[test]
    fn json_escapes_what_serde_json_leaves_raw_and_reads_back() {
        let hostile =
            "a\u{1b}[2J\u{7}\u{1b}]0;pwned\u{7}\u{7f}\u{9b}\u{85}\u{202e}\u{2066}\u{200e}\\\"z";
        let value = serde_json::json!({ "name": hostile, "list": [hostile] });
        for text in [
            serde_json::to_string(&value).unwrap(),
            serde_json::to_string_pretty(&value).unwrap(),
        ] {
            let out = json(&text);
            assert!(
                !out.chars().any(|c| hidden(c) && c != '\n'),
                "nothing raw: {out}"
            );
            assert!(out.contains("\\u007f") && out.contains("\\u202e"), "{out}");
            let back: serde_json::Value = serde_json::from_str(&out).unwrap();
            assert_eq!(back, value, "the same text read back");
        }
        assert!(matches!(json("{\n  \"a\": 1\n}"), Cow::Borrowed(_)));
        assert_eq!(controls("\u{9b}\u{2066}"), "\\u{9b}\\u{2066}");
    }

    #[test]
    fn escaping_reads_back_to_the_same_bytes() {
        let names: [&[u8]; 9] = [
            b"",
            b"a",
            b"\\",
            b"\\x41",
            b"\\u{41}",
            b"-lead\tTAB\nNL\x1b\x7f\xc2\x85",
            b"\xff\xfe\xc3",
            "é\u{202e}".as_bytes(),
            b"\x00",
        ];
        for name in names {
            assert_eq!(unescape(&bytes(name)).unwrap(), name, "{name:?}");
        }
        assert_eq!(unescape("\\x41\\u{e9}").unwrap(), "Aé".as_bytes());
        for bad in ["\\", "a\\q", "\\x4", "\\xzz", "\\u{d800}", "\\u41"] {
            assert!(unescape(bad).is_err(), "{bad}");
        }
    }

    #[cfg(unix)]
    #[test]
    fn paths_read_back() {
        use std::os::unix::ffi::OsStrExt;
        let p = Path::new(std::ffi::OsStr::from_bytes(b"dir/p\xff\n.nii"));
        assert_eq!(path(p), "dir/p\\xff\\n.nii");
        assert_eq!(unescape_path(&path(p)).unwrap(), p);
    }
}
