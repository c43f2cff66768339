//! Volumes where they live: an `http://` or `https://` URL names a Zarr or OME-Zarr store read in
//! place (docs/design.md, "Remote stores"). This module knows URLs: which inputs are URLs
//! ([`is_url`]), their checked form ([`Url`]: no user name, password, query or fragment, so that
//! no credential is ever written in a message), and the keys of a store joined to them, confined
//! to the store ([`Url::key`]). Reading them, over HTTP, is `http.rs`, behind the `remote` cargo
//! feature (on by default); a build without it refuses URLs with a message saying so.

#[cfg(feature = "remote")]
pub mod http;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Whether `path`, as given, is a URL slabscope reads (`http://` or `https://`, any case).
#[must_use]
pub fn is_url(path: &Path) -> bool {
    path.to_str().is_some_and(|text| scheme(text).is_some())
}

/// The scheme `text` starts with, lower case, when it is one slabscope reads.
fn scheme(text: &str) -> Option<&'static str> {
    let lower = text.get(..8).unwrap_or(text).to_ascii_lowercase();
    if lower.starts_with("http://") {
        Some("http")
    } else if lower.starts_with("https://") {
        Some("https")
    } else {
        None
    }
}

/// A store's URL, checked: its scheme, host (with its port when given) and path, without a
/// trailing slash. It holds no user name, password, query or fragment (refused: a store read in
/// place is public, and no credential may reach a message).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Url {
    /// `http` or `https`.
    pub scheme: &'static str,
    /// The host, with `:port` when given.
    pub host: String,
    /// The path, from its `/` (empty for the server's root), without a trailing slash.
    pub path: String,
}

impl Url {
    /// The URL `text`, checked; the error says what is wrong, naming the URL without what it
    /// must not show ([`shown_text`]).
    pub fn parse(text: &str) -> Result<Self, String> {
        let scheme = scheme(text).ok_or_else(|| "not an http:// or https:// URL".to_string())?;
        let rest = &text[scheme.len() + 3..];
        let (authority, path) = rest.split_at(rest.find('/').unwrap_or(rest.len()));
        if authority.contains('@') || text.contains(['?', '#']) {
            return Err(
                "a URL with a user name, password, query or fragment: slabscope reads public \
                 stores by their plain URL (credentials are never read from it, nor shown)"
                    .into(),
            );
        }
        if authority.is_empty() {
            return Err("a URL without a host".into());
        }
        if text.chars().any(|c| c.is_control() || c == ' ') {
            return Err("a URL with spaces or control characters".into());
        }
        Ok(Self {
            scheme,
            host: authority.to_ascii_lowercase(),
            path: path.trim_end_matches('/').to_string(),
        })
    }

    /// The URL as messages show it, as a path (what every error names).
    #[must_use]
    pub fn shown(&self) -> PathBuf {
        PathBuf::from(self.to_string())
    }

    /// The URL of the store's `key` (a key of the store: `0/.zarray`, `labels/cells/zarr.json`):
    /// an error when the key would leave the store (an empty, `.` or `..` segment, a leading
    /// `/`), its bytes beyond the unreserved ones percent-encoded.
    pub fn key(&self, key: &str) -> Result<String, String> {
        check_key(key)?;
        let mut url = self.to_string();
        if !key.is_empty() {
            url.push('/');
            url.push_str(&encode(key));
        }
        Ok(url)
    }
}

impl std::fmt::Display for Url {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}://{}{}", self.scheme, self.host, self.path)
    }
}

/// What a message shows of the URL `text` that could not be read as a [`Url`]: its scheme, host
/// and path, never a user name, password, query or fragment.
#[must_use]
pub fn shown_text(text: &str) -> PathBuf {
    let Some(scheme) = scheme(text) else {
        return PathBuf::from(text);
    };
    let rest = &text[scheme.len() + 3..];
    let rest = rest.split(['?', '#']).next().unwrap_or_default();
    let (authority, path) = rest.split_at(rest.find('/').unwrap_or(rest.len()));
    let host = authority.rsplit('@').next().unwrap_or_default();
    PathBuf::from(format!("{scheme}://{host}{path}"))
}

/// Fails when the key `key` would leave its store.
pub fn check_key(key: &str) -> Result<(), String> {
    if key.is_empty() {
        return Ok(());
    }
    if key
        .split('/')
        .any(|s| s.is_empty() || s == "." || s == ".." || s.contains('\\'))
    {
        return Err(format!("key {key:?} leaves the store"));
    }
    Ok(())
}

/// `key` with every byte but the unreserved ones and `/` percent-encoded.
fn encode(key: &str) -> String {
    let mut out = String::with_capacity(key.len());
    for b in key.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            out.push(b as char);
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    out
}

/// The store key `name` inside the node `node` (`""` is the store's root).
#[must_use]
pub fn join(node: &str, name: &str) -> String {
    match (node.is_empty(), name.is_empty()) {
        (true, _) => name.to_string(),
        (_, true) => node.to_string(),
        _ => format!("{node}/{name}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_are_read_without_credentials() {
        assert!(is_url(Path::new("https://h/a.zarr")));
        assert!(is_url(Path::new("HTTP://h/a.zarr")));
        assert!(!is_url(Path::new("http:/h")));
        assert!(!is_url(Path::new("s3://bucket/a")));
        assert!(!is_url(Path::new("dir/https://x")));
        let url = Url::parse("https://Host.example:8443/data/img.ome.zarr/").unwrap();
        assert_eq!(
            url.to_string(),
            "https://host.example:8443/data/img.ome.zarr"
        );
        assert_eq!(
            url.key("0/c/1 2").unwrap(),
            "https://host.example:8443/data/img.ome.zarr/0/c/1%202"
        );
        for key in ["../x", "a/../../b", "/etc/passwd", "a//b", "./a"] {
            assert!(url.key(key).is_err(), "{key}");
        }
        for bad in [
            "https://user:secret@h/a",
            "https://h/a?X-Amz-Signature=s",
            "https://h/a#f",
        ] {
            let e = Url::parse(bad).unwrap_err();
            assert!(e.contains("credentials"), "{e}");
            let shown = shown_text(bad).display().to_string();
            assert!(
                !shown.contains("secret") && !shown.contains("Signature"),
                "{shown}"
            );
        }
        assert_eq!(
            shown_text("https://u:p@h/a?q").display().to_string(),
            "https://h/a"
        );
        assert!(Url::parse("http:///a").is_err());
        assert_eq!(join("", ".zattrs"), ".zattrs");
        assert_eq!(join("labels/a", "0"), "labels/a/0");
    }
}
