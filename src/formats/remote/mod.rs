//! Volumes where they live: an `http://` or `https://` URL names a Zarr or OME-Zarr store read in
//! place (docs/design.md, "Remote stores"), and so does `s3://bucket/prefix`, read over HTTPS,
//! anonymously unless the environment holds credentials (then signed: `sigv4.rs`) (virtual-hosted, or path-style at the endpoint `AWS_ENDPOINT_URL_S3` or
//! `AWS_ENDPOINT_URL` names; the region from `AWS_REGION` or `AWS_DEFAULT_REGION`). This module knows URLs: which inputs are URLs
//! ([`is_url`]), their checked form ([`Url`]: no user name, password, query or fragment, so that
//! no credential is ever written in a message), and the keys of a store joined to them, confined
//! to the store ([`Url::key`]). Reading them, over HTTP, is `http.rs`, behind the `remote` cargo
//! feature (on by default); a build without it refuses URLs with a message saying so.

#[cfg(feature = "remote")]
pub mod cache;
#[cfg(feature = "remote")]
pub mod http;
#[cfg(feature = "remote")]
pub mod sigv4;

/// A range of a key's bytes, as zarrs asks them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Span {
    /// The whole object.
    All,
    /// From a byte, to the end or for a length.
    From(u64, Option<u64>),
    /// The last bytes.
    Suffix(u64),
}

/// Why a request gave no bytes, typed (a store over HTTP words it by what it is, reading no
/// text): shown as before, `key: problem`, or why no request was made.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Failed {
    /// The request for `key` (from the store's root) failed: `problem`.
    At {
        /// The key asked for.
        key: String,
        /// What went wrong, in words.
        problem: String,
    },
    /// No request was made (a key that would leave the store): why.
    Refused(String),
}

impl Failed {
    /// The failure of the request for `key`: `problem`.
    pub fn at(key: &str, problem: impl Into<String>) -> Self {
        Self::At {
            key: key.to_string(),
            problem: problem.into(),
        }
    }
}

impl std::fmt::Display for Failed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::At { key, problem } => write!(f, "{key}: {problem}"),
            Self::Refused(why) => f.write_str(why),
        }
    }
}

impl From<Failed> for String {
    fn from(failed: Failed) -> Self {
        failed.to_string()
    }
}

/// The bytes of every answer's body fetched by this process, over every store.
static FETCHED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// The bytes of the answers' bodies this process has fetched from remote stores so far (for a
/// progress line; 0 when none was read).
#[must_use]
pub fn bytes_fetched() -> u64 {
    FETCHED.load(std::sync::atomic::Ordering::Relaxed)
}

/// Counts `n` bytes fetched ([`bytes_fetched`]).
#[cfg(feature = "remote")]
fn count_fetched(n: u64) {
    FETCHED.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
}

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Whether `path`, as given, is a URL slabscope reads (`http://`, `https://` or `s3://`, any
/// case).
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
    } else if lower.starts_with("s3://") {
        Some("s3")
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
    /// The `s3://bucket/prefix` it was given as, which messages show.
    pub s3: Option<String>,
    /// The region of an `s3://` store (its requests are signed for it when the environment
    /// holds credentials).
    pub region: Option<String>,
}

impl Url {
    /// The URL `text`, checked; the error says what is wrong, naming the URL without what it
    /// must not show ([`shown_text`]).
    pub fn parse(text: &str) -> Result<Self, String> {
        Self::parse_at(text, None)
    }

    /// [`parse`](Self::parse), an `s3://` URL at `endpoint` when one is given (`--endpoint`),
    /// before the endpoint the environment names.
    pub fn parse_at(text: &str, endpoint: Option<&str>) -> Result<Self, String> {
        let scheme =
            scheme(text).ok_or_else(|| "not an http://, https:// or s3:// URL".to_string())?;
        if scheme == "s3" {
            return Self::s3(text, endpoint, |name| std::env::var(name).ok());
        }
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
            s3: None,
            region: None,
        })
    }

    /// The URL of `s3://bucket/prefix` (`text`), with `env` the environment: path-style at
    /// `endpoint` (`--endpoint`) or the endpoint `AWS_ENDPOINT_URL_S3` or `AWS_ENDPOINT_URL`
    /// names, else AWS's own (the region `AWS_REGION`, `AWS_DEFAULT_REGION` or us-east-1),
    /// virtual-hosted unless the bucket's name holds a dot. Errors name the setting they are
    /// about.
    fn s3(
        text: &str,
        endpoint: Option<&str>,
        env: impl Fn(&str) -> Option<String>,
    ) -> Result<Self, String> {
        let rest = &text[5..];
        if text.chars().any(|c| c.is_control() || c == ' ') {
            return Err("an s3:// URL with spaces or control characters".into());
        }
        if rest.contains(['@', '?', '#']) {
            return Err(
                "an s3:// URL with a user name, query or fragment: slabscope reads \
                        public buckets by their plain URL (credentials are never read from it, \
                        nor shown)"
                    .into(),
            );
        }
        let (bucket, prefix) = rest.split_at(rest.find('/').unwrap_or(rest.len()));
        let prefix = prefix.trim_end_matches('/');
        let valid = |c: char| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '.' || c == '-';
        if bucket.is_empty() || !bucket.chars().all(valid) {
            return Err(format!(
                "bucket {bucket:?}: a bucket's name is lower-case letters, digits, dots and hyphens"
            ));
        }
        let shown = format!("s3://{bucket}{prefix}");
        let set = |name: &'static str| {
            env(name)
                .filter(|v| !v.trim().is_empty())
                .map(|v| (name, v))
        };
        let endpoint = (endpoint.map(|e| ("--endpoint", e.to_string())))
            .or_else(|| set("AWS_ENDPOINT_URL_S3"))
            .or_else(|| set("AWS_ENDPOINT_URL"));
        let (name, region) = set("AWS_REGION")
            .or_else(|| set("AWS_DEFAULT_REGION"))
            .unwrap_or(("the default", "us-east-1".into()));
        if !region
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-')
        {
            return Err(format!("region {region:?} ({name}): not a region's name"));
        }
        if let Some((name, endpoint)) = endpoint {
            if !matches!(scheme(endpoint.trim()), Some("http" | "https")) {
                return Err(format!("the endpoint {name} names is not http(s)://"));
            }
            let base = Self::parse(endpoint.trim())
                .map_err(|e| format!("the endpoint {name} names: {e}"))?;
            return Ok(Self {
                path: format!("{}/{bucket}{prefix}", base.path),
                s3: Some(shown),
                region: Some(region),
                ..base
            });
        }
        let (host, path) = if bucket.contains('.') {
            (
                format!("s3.{region}.amazonaws.com"),
                format!("/{bucket}{prefix}"),
            )
        } else {
            (
                format!("{bucket}.s3.{region}.amazonaws.com"),
                prefix.to_string(),
            )
        };
        Ok(Self {
            scheme: "https",
            host,
            path,
            s3: Some(shown),
            region: Some(region),
        })
    }

    /// The URL requests go to (for S3, the bucket's HTTPS address).
    fn base(&self) -> String {
        format!("{}://{}{}", self.scheme, self.host, self.path)
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
        let mut url = self.base();
        if !key.is_empty() {
            url.push('/');
            url.push_str(&encode(key));
        }
        Ok(url)
    }
}

impl std::fmt::Display for Url {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.s3 {
            Some(s3) => f.write_str(s3),
            None => f.write_str(&self.base()),
        }
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
    let scheme = &text[..scheme.len()];
    let (authority, path) = rest.split_at(rest.find('/').unwrap_or(rest.len()));
    let host = authority.rsplit('@').next().unwrap_or_default();
    PathBuf::from(format!("{scheme}://{host}{path}"))
}

/// Whether the key names a Zarr metadata file.
#[must_use]
pub fn is_metadata(key: &str) -> bool {
    let name = key.rsplit('/').next().unwrap_or(key);
    matches!(name, "zarr.json" | ".zarray" | ".zattrs" | ".zgroup")
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
        assert!(is_url(Path::new("s3://bucket/a")));
        assert!(!is_url(Path::new("gs://bucket/a")));
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
    }

    #[test]
    fn s3_urls_are_virtual_hosted_or_path_style_at_an_endpoint() {
        let none = |_: &str| None;
        let url = Url::s3("s3://idr-public/zarr/1.ome.zarr/", None, none).unwrap();
        assert_eq!(
            url.base(),
            "https://idr-public.s3.us-east-1.amazonaws.com/zarr/1.ome.zarr"
        );
        assert_eq!(url.to_string(), "s3://idr-public/zarr/1.ome.zarr");
        assert_eq!(
            url.key("0/.zarray").unwrap(),
            "https://idr-public.s3.us-east-1.amazonaws.com/zarr/1.ome.zarr/0/.zarray"
        );
        let region = |n: &str| (n == "AWS_DEFAULT_REGION").then(|| "eu-west-2".to_string());
        let dotted = Url::s3("s3://my.bucket/a", None, region).unwrap();
        assert_eq!(
            dotted.base(),
            "https://s3.eu-west-2.amazonaws.com/my.bucket/a"
        );
        let local = |n: &str| (n == "AWS_ENDPOINT_URL").then(|| "http://127.0.0.1:9000/".into());
        let url = Url::s3("s3://bucket", None, local).unwrap();
        assert_eq!(url.base(), "http://127.0.0.1:9000/bucket");
        // --endpoint before the environment's.
        let flag = Url::s3("s3://bucket/p", Some("https://minio.example:9000"), local).unwrap();
        assert_eq!(flag.base(), "https://minio.example:9000/bucket/p");
        assert!(Url::s3("s3://Bad_Bucket/a", None, none).is_err());
        assert!(Url::s3("s3://b/a?x=1", None, none).is_err());
        let e = Url::s3("s3://b/a\u{7}b", None, none).unwrap_err();
        assert!(e.contains("control characters"), "{e}");
        // Each error names the setting it is about.
        let bad = |n: &str| (n == "AWS_ENDPOINT_URL").then(|| "ftp://x".to_string());
        let e = Url::s3("s3://b/a", None, bad).unwrap_err();
        assert_eq!(e, "the endpoint AWS_ENDPOINT_URL names is not http(s)://");
        let bad = |n: &str| (n == "AWS_ENDPOINT_URL_S3").then(|| "ftp://x".to_string());
        let e = Url::s3("s3://b/a", None, bad).unwrap_err();
        assert_eq!(
            e,
            "the endpoint AWS_ENDPOINT_URL_S3 names is not http(s)://"
        );
        let e = Url::s3("s3://b/a", Some("ftp://x"), none).unwrap_err();
        assert_eq!(e, "the endpoint --endpoint names is not http(s)://");
        let bad = |n: &str| (n == "AWS_DEFAULT_REGION").then(|| "eu west".to_string());
        let e = Url::s3("s3://b/a", None, bad).unwrap_err();
        assert!(e.contains("(AWS_DEFAULT_REGION)"), "{e}");
        assert_eq!(join("labels/a", "0"), "labels/a/0");
    }
}
