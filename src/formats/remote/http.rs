//! The HTTP client of remote stores (`ureq`, synchronous, rustls): GET of a key or a range of
//! its bytes and HEAD for its size, each request with a timeout on every read (a stalled
//! server), at most [`MAX_IN_FLIGHT`] at once, retried [`TRIES`] times in all on a 5xx answer or
//! a connection reset, every body held to the limit the caller gives (the budget) before it is
//! read. 404 is "no such key" (a Zarr chunk not written is its fill value); every other failure
//! is one line of words, naming the key (the caller names the store's URL).

use std::io::Read;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;

use ureq::unversioned::resolver::{DefaultResolver, ResolvedSocketAddrs, Resolver};
use ureq::unversioned::transport::{DefaultConnector, NextTimeout};

use super::{Failed, Url, cache, sigv4};
use crate::error::human_bytes;

/// The most requests in flight at once, over all threads.
pub const MAX_IN_FLIGHT: usize = 8;

/// The tries of one request on a 5xx answer or a connection reset, the first included.
pub const TRIES: u32 = 3;

/// The seconds a read may wait for the server (`SLABSCOPE_HTTP_TIMEOUT` sets others).
pub const TIMEOUT_S: f64 = 30.0;

/// The most redirects followed for one request.
const MAX_REDIRECTS: u32 = 8;

pub use super::Span;

/// A store's HTTP client.
#[derive(Debug)]
pub struct Client {
    url: Url,
    agent: ureq::Agent,
    timeout: Duration,
    slots: Slots,
    requests: AtomicU64,
    fetched: AtomicU64,
    /// Whether a chunk answered 403 is missing (the fill value) rather than an error.
    forbidden_missing: bool,
    /// The on-disk cache of chunks (`--cache DIR`), when asked.
    disk: Option<std::sync::Arc<cache::Disk>>,
    /// The credentials an `s3://` store's requests are signed with, when the environment
    /// holds some.
    creds: Option<sigv4::Credentials>,
}

impl Client {
    /// The client of the store at `url`, its timeout `SLABSCOPE_HTTP_TIMEOUT` seconds when set
    /// (else [`TIMEOUT_S`]).
    pub fn new(url: Url) -> Result<Self, String> {
        let timeout = match std::env::var("SLABSCOPE_HTTP_TIMEOUT") {
            Ok(text) => text
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|s| s.is_finite() && *s > 0.0 && *s <= 86_400.0)
                .ok_or_else(|| {
                    format!("SLABSCOPE_HTTP_TIMEOUT {text:?}: expected seconds, above 0")
                })?,
            Err(_) => TIMEOUT_S,
        };
        let timeout = Duration::from_secs_f64(timeout);
        let config = ureq::Agent::config_builder()
            .http_status_as_error(false)
            .max_redirects(MAX_REDIRECTS)
            .timeout_resolve(Some(timeout))
            .timeout_connect(Some(timeout))
            .timeout_per_read(Some(timeout))
            .timeout_send_request(Some(timeout))
            .user_agent(concat!("slabscope/", env!("CARGO_PKG_VERSION")))
            .build();
        let agent = ureq::Agent::with_parts(config, DefaultConnector::default(), Lookup::default());
        Ok(Self {
            agent,
            timeout,
            slots: Slots::new(MAX_IN_FLIGHT),
            requests: AtomicU64::new(0),
            fetched: AtomicU64::new(0),
            forbidden_missing: false,
            disk: None,
            creds: url
                .region
                .as_ref()
                .and_then(|_| sigv4::Credentials::from_env(|n| std::env::var(n).ok())),
            url,
        })
    }

    /// This client, taking a chunk the server refuses (403) as missing when `missing`
    /// (`--missing-as-fill`), as a chunk it does not have (404).
    #[must_use]
    pub fn forbidden_as_missing(self, missing: bool) -> Self {
        Self {
            forbidden_missing: missing,
            ..self
        }
    }

    /// This client, keeping the chunks it fetches in `disk` and reading them from there.
    #[must_use]
    pub fn cached(self, disk: Option<std::sync::Arc<cache::Disk>>) -> Self {
        Self { disk, ..self }
    }

    /// The store's URL.
    pub fn url(&self) -> &Url {
        &self.url
    }

    /// The requests made so far, and the bytes of the bodies fetched.
    pub fn counts(&self) -> (u64, u64) {
        (
            self.requests.load(Ordering::Relaxed),
            self.fetched.load(Ordering::Relaxed),
        )
    }

    /// The bytes `span` of `key`, at most `limit` of them (more is an error, not read);
    /// `None` when the server has no such key (404). A server that ignores the range and sends
    /// the whole object has the range cut from it (within the limit). A chunk's bytes are
    /// fetched once: kept in memory (at most `limit` / [`cache::MEMORY_SHARE`] bytes of answers
    /// in all) and on disk when the client has a cache.
    pub fn get(&self, key: &str, span: Span, limit: u64) -> Result<Option<Vec<u8>>, Failed> {
        let url = self.url.key(key).map_err(Failed::Refused)?;
        let chunk = !super::is_metadata(key);
        if chunk {
            let kept = (cache::MEMORY.get(&url, span)).or_else(|| {
                let bytes = self.disk.as_ref()?.get(&url, span, limit)?;
                cache::MEMORY.put(&url, span, &bytes, limit / cache::MEMORY_SHARE);
                Some(bytes)
            });
            if let Some(bytes) = kept.filter(|b| b.len() as u64 <= limit) {
                return check_span(key, span, bytes).map(Some);
            }
        }
        let fetched = self.fetch(key, &url, span, limit)?;
        if let (true, Some(bytes)) = (chunk, &fetched) {
            cache::MEMORY.put(&url, span, bytes, limit / cache::MEMORY_SHARE);
            if let Some(disk) = &self.disk {
                disk.put(&url, span, bytes);
            }
        }
        Ok(fetched)
    }

    /// [`get`](Self::get) from the server, `url` the key's.
    fn fetch(
        &self,
        key: &str,
        url: &str,
        span: Span,
        limit: u64,
    ) -> Result<Option<Vec<u8>>, Failed> {
        let range = match span {
            Span::All => None,
            Span::From(start, None) => Some(format!("bytes={start}-")),
            Span::From(_, Some(0)) | Span::Suffix(0) => return Ok(Some(Vec::new())),
            Span::From(start, Some(n)) => {
                Some(format!("bytes={start}-{}", start.saturating_add(n - 1)))
            }
            Span::Suffix(n) => Some(format!("bytes=-{n}")),
        };
        let fetched = self.retried(key, || {
            let mut request = self.agent.get(url);
            for (name, value) in self.signed("GET", url) {
                request = request.header(name, value);
            }
            if let Some(range) = &range {
                request = request.header("Range", range);
            }
            let mut response = request.call()?;
            let status = response.status().as_u16();
            if !(200..300).contains(&status) {
                return Ok(Answer::Status(status));
            }
            let partial = status == 206;
            let stated = response.body().content_length();
            // (A server that ignores the range sends the whole object: held to the limit too.)
            if stated.is_some_and(|n| n > limit) {
                return Ok(Answer::TooLarge(stated.unwrap_or(0)));
            }
            let mut body = Vec::new();
            let read = response
                .body_mut()
                .with_config()
                .limit(limit)
                .reader()
                .read_to_end(&mut body);
            if let Err(e) = read {
                return Ok(Answer::Broken(e));
            }
            if let Some(n) = stated
                && (body.len() as u64) < n
            {
                return Ok(Answer::Short(body.len() as u64, n));
            }
            self.fetched.fetch_add(body.len() as u64, Ordering::Relaxed);
            super::count_fetched(body.len() as u64);
            Ok(Answer::Body(if partial { body } else { cut(body, span) }))
        })?;
        match fetched {
            Some(Fetched::Bytes(bytes)) => check_span(key, span, bytes).map(Some),
            _ => Ok(None),
        }
    }

    /// The size in bytes of `key` (a HEAD request); `None` when there is none.
    pub fn size(&self, key: &str) -> Result<Option<u64>, Failed> {
        let url = self.url.key(key).map_err(Failed::Refused)?;
        let fetched = self.retried(key, || {
            let mut request = self.agent.head(&url);
            for (name, value) in self.signed("HEAD", &url) {
                request = request.header(name, value);
            }
            let response = request.call()?;
            let status = response.status().as_u16();
            if !(200..300).contains(&status) {
                return Ok(Answer::Status(status));
            }
            // A HEAD answer has no body to ask: its size is the header's.
            let length = response
                .headers()
                .get("content-length")
                .and_then(|v| v.to_str().ok()?.trim().parse().ok());
            Ok(Answer::Size(length))
        })?;
        Ok(match fetched {
            Some(Fetched::Size(n)) => Some(n),
            _ => None,
        })
    }

    /// The headers that sign `method` of `url` (an `s3://` store's, with credentials), now.
    fn signed(&self, method: &str, url: &str) -> Vec<(&'static str, String)> {
        let (Some(creds), Some(region)) = (&self.creds, &self.url.region) else {
            return Vec::new();
        };
        let origin = format!("{}://{}", self.url.scheme, self.url.host);
        let path = url.strip_prefix(&origin).unwrap_or(url);
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        sigv4::s3_headers(creds, method, &self.url.host, path, region, now)
    }

    /// Runs `call` until it answers, at most [`TRIES`] times on a 5xx answer or a connection
    /// reset, in one of the slots; the answer in words.
    fn retried(
        &self,
        key: &str,
        call: impl Fn() -> Result<Answer, ureq::Error>,
    ) -> Result<Option<Fetched>, Failed> {
        let mut last = String::new();
        for attempt in 0..TRIES {
            if attempt > 0 {
                std::thread::sleep(Duration::from_millis(100 << (2 * attempt)));
            }
            let answer = {
                let _slot = self.slots.take();
                self.requests.fetch_add(1, Ordering::Relaxed);
                call()
            };
            match answer {
                Ok(Answer::Body(bytes)) => return Ok(Some(Fetched::Bytes(bytes))),
                Ok(Answer::Size(size)) => {
                    return size
                        .map(|n| Some(Fetched::Size(n)))
                        .ok_or_else(|| Failed::at(key, "the server gives no size"));
                }
                Ok(Answer::Status(404)) => return Ok(None),
                // S3 answers 403 for a key it does not have when listing is not allowed: a
                // metadata file probed for (zarr.json of a v2 store) is then absent.
                Ok(Answer::Status(403)) if self.url.s3.is_some() && super::is_metadata(key) => {
                    return Ok(None);
                }
                // A chunk refused, taken as missing when asked (`--missing-as-fill`).
                Ok(Answer::Status(403)) if self.forbidden_missing && !super::is_metadata(key) => {
                    return Ok(None);
                }
                Ok(Answer::Status(403)) if !super::is_metadata(key) => {
                    return Err(Failed::at(
                        key,
                        "HTTP 403 Forbidden (--missing-as-fill reads a chunk refused as the fill \
                         value, as public S3 refuses a chunk never written)",
                    ));
                }
                Ok(Answer::Status(status)) if status >= 500 => {
                    last = format!("HTTP {status} {}", reason(status));
                }
                Ok(Answer::Status(status)) => {
                    return Err(Failed::at(
                        key,
                        format!("HTTP {status} {}{}", reason(status), advice(status)),
                    ));
                }
                Ok(Answer::TooLarge(n)) => {
                    return Err(Failed::at(
                        key,
                        format!(
                            "the server sends {}, more than the memory limit allows",
                            human_bytes(n)
                        ),
                    ));
                }
                Ok(Answer::Short(got, stated)) => {
                    return Err(Failed::at(
                        key,
                        format!(
                            "the answer ended after {got} of the {stated} bytes its \
                         Content-Length says"
                        ),
                    ));
                }
                Ok(Answer::Broken(e)) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
                    return Err(Failed::at(
                        key,
                        "the answer ended before the bytes its Content-Length says",
                    ));
                }
                Ok(Answer::Broken(e)) => {
                    // ureq's own errors (a body past its limit) come back out of the wrapping.
                    let e = ureq::Error::from(e);
                    if !retry(&e) {
                        return Err(Failed::at(key, self.words(&e)));
                    }
                    last = self.words(&e);
                }
                Err(e) if retry(&e) => last = self.words(&e),
                Err(e) => return Err(Failed::at(key, self.words(&e))),
            }
        }
        Err(Failed::at(key, format!("{last}, after {TRIES} tries")))
    }

    /// A failure of the client in words.
    fn words(&self, e: &ureq::Error) -> String {
        let host = &self.url.host;
        let s = self.timeout.as_secs_f64();
        match e {
            ureq::Error::HostNotFound => format!("unknown host {host}"),
            ureq::Error::Timeout(_) => format!(
                "the server did not answer within {s} s (a stalled server; \
                 SLABSCOPE_HTTP_TIMEOUT sets the seconds)"
            ),
            ureq::Error::TooManyRedirects => {
                format!("more than {MAX_REDIRECTS} redirects (a redirect loop)")
            }
            ureq::Error::BodyExceedsLimit(_) => {
                "the server sends more than the memory limit allows".into()
            }
            ureq::Error::Tls(m) => format!("TLS failure with {host}: {m}"),
            ureq::Error::Rustls(e) => format!("TLS failure with {host}: {e}"),
            ureq::Error::Io(io) => match io.kind() {
                std::io::ErrorKind::ConnectionRefused => format!("connection refused by {host}"),
                std::io::ErrorKind::ConnectionReset | std::io::ErrorKind::ConnectionAborted => {
                    format!("the connection to {host} was reset")
                }
                std::io::ErrorKind::UnexpectedEof if self.url.scheme == "https" => format!(
                    "TLS failure with {host}: the connection closed before an answer (does \
                     the server speak HTTPS?)"
                ),
                std::io::ErrorKind::UnexpectedEof => {
                    format!("the connection to {host} closed before an answer")
                }
                std::io::ErrorKind::TimedOut | std::io::ErrorKind::WouldBlock => format!(
                    "the server did not answer within {s} s (a stalled server; \
                     SLABSCOPE_HTTP_TIMEOUT sets the seconds)"
                ),
                _ => format!("{host}: {io}"),
            },
            other => other.to_string(),
        }
    }
}

/// ureq's resolver, whose failures are all [`ureq::Error::HostNotFound`]: the standard library
/// reports a name that does not resolve as an I/O error of no kind of its own (its message
/// alone says so), and an I/O error out of the resolver is one, whatever its words.
#[derive(Debug, Default)]
struct Lookup(DefaultResolver);

impl Resolver for Lookup {
    fn resolve(
        &self,
        uri: &ureq::http::Uri,
        config: &ureq::config::Config,
        timeout: NextTimeout,
    ) -> Result<ResolvedSocketAddrs, ureq::Error> {
        match self.0.resolve(uri, config, timeout) {
            Err(ureq::Error::Io(_)) => Err(ureq::Error::HostNotFound),
            other => other,
        }
    }
}

/// What one try of a request came to.
enum Answer {
    /// The bytes asked.
    Body(Vec<u8>),
    /// The size a HEAD answer states.
    Size(Option<u64>),
    /// Another status than 2xx.
    Status(u16),
    /// A body stated larger than the limit, not read.
    TooLarge(u64),
    /// A body shorter than its Content-Length: got, stated.
    Short(u64, u64),
    /// A body whose reading failed.
    Broken(std::io::Error),
}

/// What a request fetched.
enum Fetched {
    Bytes(Vec<u8>),
    Size(u64),
}

/// The bytes `span` of a whole object `body` (a server that ignored the range).
fn cut(mut body: Vec<u8>, span: Span) -> Vec<u8> {
    let len = body.len() as u64;
    let (start, end) = match span {
        Span::All => (0, len),
        Span::From(start, None) => (start.min(len), len),
        Span::From(start, Some(n)) => (start.min(len), start.saturating_add(n).min(len)),
        Span::Suffix(n) => (len.saturating_sub(n), len),
    };
    body.truncate(end as usize);
    body.drain(..start as usize);
    body
}

/// `bytes` when they are as many as `span` asks: a server that answers a range with fewer bytes
/// (past the object's end, or a lying `Content-Range`) is an error, never read as the chunk.
fn check_span(key: &str, span: Span, bytes: Vec<u8>) -> Result<Vec<u8>, Failed> {
    let wanted = match span {
        Span::From(_, Some(n)) | Span::Suffix(n) => Some(n),
        _ => None,
    };
    match wanted {
        Some(n) if bytes.len() as u64 != n => Err(Failed::at(
            key,
            format!(
                "{n} bytes asked, {} answered (a range the object does not hold)",
                bytes.len()
            ),
        )),
        _ => Ok(bytes),
    }
}

/// Whether a failure may pass when the request is made again: a connection reset or closed.
fn retry(e: &ureq::Error) -> bool {
    matches!(e, ureq::Error::Io(io) if matches!(
        io.kind(),
        std::io::ErrorKind::ConnectionReset
            | std::io::ErrorKind::ConnectionAborted
            | std::io::ErrorKind::BrokenPipe
    )) || matches!(e, ureq::Error::ConnectionFailed)
}

/// The reason phrase of an HTTP status.
fn reason(status: u16) -> &'static str {
    match status {
        400 => "Bad Request",
        401 => "Unauthorized",
        403 => "Forbidden",
        405 => "Method Not Allowed",
        410 => "Gone",
        416 => "Range Not Satisfiable",
        429 => "Too Many Requests",
        500 => "Internal Server Error",
        502 => "Bad Gateway",
        503 => "Service Unavailable",
        504 => "Gateway Timeout",
        _ => "",
    }
}

/// What a user can do about a 4xx status.
fn advice(status: u16) -> &'static str {
    match status {
        401 | 403 => {
            " (is the URL the store's, and public? an s3:// store's requests are signed when \
             AWS_ACCESS_KEY_ID and AWS_SECRET_ACCESS_KEY are set)"
        }
        _ => "",
    }
}

/// A counting semaphore: at most its count of requests in flight.
#[derive(Debug)]
struct Slots {
    free: Mutex<usize>,
    freed: Condvar,
}

/// A slot taken, given back when dropped.
struct Slot<'a>(&'a Slots);

impl Slots {
    fn new(n: usize) -> Self {
        Self {
            free: Mutex::new(n),
            freed: Condvar::new(),
        }
    }

    fn take(&self) -> Slot<'_> {
        let mut free = self
            .free
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        while *free == 0 {
            free = self
                .freed
                .wait(free)
                .unwrap_or_else(std::sync::PoisonError::into_inner);
        }
        *free -= 1;
        Slot(self)
    }
}

impl Drop for Slot<'_> {
    fn drop(&mut self) {
        let mut free = self
            .0
            .free
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        *free += 1;
        self.0.freed.notify_one();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_cut_from_whole_objects() {
        let body = b"0123456789".to_vec();
        assert_eq!(cut(body.clone(), Span::From(2, Some(3))), b"234");
        assert_eq!(cut(body.clone(), Span::Suffix(4)), b"6789");
        assert_eq!(cut(body.clone(), Span::From(8, None)), b"89");
        assert_eq!(cut(body.clone(), Span::From(12, Some(2))), b"");
        assert!(check_span("k", Span::From(8, Some(5)), b"89".to_vec()).is_err());
        assert_eq!(check_span("k", Span::All, body.clone()).unwrap(), body);
    }

    /// A name that does not resolve (`.invalid` never does, RFC 6761) is an unknown host, told
    /// by the resolver's failing, in the words the CLI has always printed.
    #[test]
    fn a_host_that_does_not_resolve_is_unknown() {
        let client =
            Client::new(Url::parse("http://nonexistent.invalid/store.zarr").unwrap()).unwrap();
        let e = client.size("zarr.json").unwrap_err();
        if e.to_string().contains("did not answer") {
            eprintln!("skipped: this machine's resolver does not answer ({e})");
            return;
        }
        assert_eq!(
            e,
            Failed::at("zarr.json", "unknown host nonexistent.invalid")
        );
        assert_eq!(e.to_string(), "zarr.json: unknown host nonexistent.invalid");
    }
}
