//! Manifests: the volumes a walk found, one a line, read back instead of walking. `--list`
//! writes the escaped form: a header line, then each path escaped by the one rule of
//! [`crate::error::names`] (so a line never holds a raw tab or line break), for a DICOM series a
//! tab and its key. A file without the header is read in the plain form older lists and `find`
//! write: each line a path as it is (any bytes but a line feed), maybe a tab and a series UID.

use std::path::{Path, PathBuf};

use super::Entry;
use crate::error::{Error, Result, names};

/// The first line of a manifest in the escaped form.
pub const MANIFEST_HEADER: &str =
    "# slabscope manifest 2: names escaped as docs/formats.md#names says, a tab before a series";

/// What marks the escaped form: the header's first words.
const MARK: &str = "# slabscope manifest 2";

/// The longest manifest line read, bytes (a path of 4096 bytes, each escaped as `\xHH`, and a
/// series key fit).
pub const MAX_LINE: usize = 1 << 15;

impl Entry {
    /// The entry as a line of an escaped manifest: the path escaped, and for DICOM a tab and the
    /// series key, escaped too.
    pub fn line(&self) -> String {
        let path = names::path(&self.path);
        match &self.series {
            Some(key) => format!("{path}\t{}", names::text(key)),
            None => path,
        }
    }
}

/// The lines of the manifest of `entries`: the header, then one line an entry.
pub fn manifest_lines(entries: &[Entry]) -> impl Iterator<Item = String> + '_ {
    std::iter::once(MANIFEST_HEADER.to_string()).chain(entries.iter().map(Entry::line))
}

/// The entries of the manifest `text`, read from `path` (which errors name, with the line):
/// the escaped form after the header, else the plain form; blank lines skipped.
pub fn parse_manifest(path: &Path, text: &[u8]) -> Result<Vec<Entry>> {
    let mut lines = text.split(|&b| b == b'\n').enumerate().peekable();
    let escaped = lines
        .peek()
        .is_some_and(|(_, first)| first.starts_with(MARK.as_bytes()));
    if escaped {
        lines.next();
    }
    let mut entries = Vec::new();
    for (i, line) in lines {
        let bad = |what: String| Error::format(path, format!("line {}: {what}", i + 1));
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line.len() > MAX_LINE {
            return Err(bad(format!("longer than {MAX_LINE} bytes")));
        }
        if line.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        entries.push(if escaped {
            escaped_entry(line).map_err(bad)?
        } else {
            plain_entry(line)
        });
    }
    Ok(entries)
}

/// A line of the escaped form.
fn escaped_entry(line: &[u8]) -> std::result::Result<Entry, String> {
    let line = std::str::from_utf8(line).map_err(|_| "not UTF-8 (an escaped name is)")?;
    let (path, key) = match line.split_once('\t') {
        Some((path, key)) => (path, Some(key)),
        None => (line, None),
    };
    let series = match key {
        Some(key) => Some(
            String::from_utf8(names::unescape(key)?)
                .map_err(|_| "a series key that is not UTF-8".to_string())?,
        ),
        None => None,
    };
    Ok(Entry {
        series,
        ..Entry::file(names::unescape_path(path)?)
    })
}

/// A line of the plain form: a path as it is, and a tab and a series key when the text after
/// the last tab is one.
fn plain_entry(line: &[u8]) -> Entry {
    if let Some(tab) = line.iter().rposition(|&b| b == b'\t') {
        let key = std::str::from_utf8(&line[tab + 1..]).unwrap_or_default();
        if is_series_key(key) {
            return Entry {
                series: Some(key.to_string()),
                ..Entry::file(raw_path(&line[..tab]))
            };
        }
    }
    Entry::file(raw_path(line))
}

/// The path of `bytes` as they are.
fn raw_path(bytes: &[u8]) -> PathBuf {
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        PathBuf::from(std::ffi::OsStr::from_bytes(bytes))
    }
    #[cfg(not(unix))]
    {
        PathBuf::from(String::from_utf8_lossy(bytes).into_owned())
    }
}

/// Whether `text` is a series key (a UID, digits and dots, maybe with `#N` after it: the
/// reader's to say).
fn is_series_key(text: &str) -> bool {
    crate::formats::group::is_key(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_forms_read_and_the_escaped_one_keeps_everything() {
        let hostile = Entry::file(names::unescape_path("a\\tb\\n\\xff\\u{1b}\t1.2").unwrap());
        let series = Entry {
            series: Some("1.2.3#2".into()),
            ..Entry::file("dir\\x")
        };
        let text = manifest_lines(&[hostile.clone(), series.clone()])
            .collect::<Vec<_>>()
            .join("\n");
        assert_eq!(text.lines().count(), 3, "{text}");
        let read = parse_manifest(Path::new("m"), text.as_bytes()).unwrap();
        assert_eq!(read, [hostile, series.clone()]);
        let plain = b"dir\\x\t1.2.3#2\r\n\n  \nsome/a\tb.nii\nx\xff.nii\n";
        let read = parse_manifest(Path::new("m"), plain).unwrap();
        assert_eq!(read[0], series, "a backslash is itself in the plain form");
        assert_eq!(read[1], Entry::file("some/a\tb.nii"));
        assert_eq!(read[2].path, raw_path(b"x\xff.nii"));
        let bad = format!("{MANIFEST_HEADER}\nok\nbad\\q\n");
        let e = parse_manifest(Path::new("m"), bad.as_bytes()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "m: line 3: unknown escape \\q at character 4"
        );
    }
}
