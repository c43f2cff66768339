//! A loopback HTTP server written for the tests (no server from outside): it serves a folder
//! (a fixture store) on 127.0.0.1 with single-range support (`Range: bytes=a-b`, `a-`, `-n`),
//! GET and HEAD, keep-alive, counts the requests it answers, and can misbehave on the paths that
//! hold a given text: stall, answer slowly, truncate the body, answer a status, redirect in a
//! loop, or send an HTML page.

use std::collections::HashSet;
use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How the server misbehaves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// It serves the folder as it is.
    Normal,
    /// It reads the request and never answers (until the connection is closed by the client).
    Stall,
    /// It waits this many milliseconds before each answer, then serves the folder: a load that
    /// takes as long as its requests make it, whatever the machine.
    Slow(u64),
    /// It states the file's length but sends half of it, then closes the connection.
    Truncate,
    /// It states half the file's length but sends all of it, keeping the connection open: the
    /// rest is what a client reusing the connection reads as its next answer.
    Overlong,
    /// It sends each file whole as stated, then a few more bytes that belong to no answer,
    /// keeping the connection open.
    Trailing,
    /// It answers this status, with an empty body.
    Status(u16),
    /// It redirects every request to itself.
    RedirectLoop,
    /// It answers 200 with an HTML page, whatever was asked.
    Html,
    /// It ignores `Range` and sends whole files (as Python's `http.server` does).
    NoRange,
    /// It answers 500 the first time each path is asked, then serves it.
    Flaky,
}

/// A running server.
pub struct Server {
    /// Its base URL, `http://127.0.0.1:PORT`.
    pub base: String,
    /// Each request answered: method, path and range, one string each.
    pub log: Arc<Mutex<Vec<String>>>,
    /// The `Authorization` header of each request that had one.
    pub authorizations: Arc<Mutex<Vec<String>>>,
}

impl Server {
    /// The requests answered so far.
    pub fn requests(&self) -> Vec<String> {
        self.log.lock().unwrap().clone()
    }

    /// The URL of `path` on the server.
    pub fn url(&self, path: &str) -> String {
        format!("{}/{}", self.base, path.trim_start_matches('/'))
    }
}

/// Serves the folder `root`, misbehaving as `mode` says on the paths that hold `only` (every
/// path when `only` is empty).
pub fn serve(root: &Path, mode: Mode, only: &str) -> Server {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let base = format!("http://{}", listener.local_addr().unwrap());
    let log = Arc::new(Mutex::new(Vec::new()));
    let authorizations = Arc::new(Mutex::new(Vec::new()));
    let auth = Arc::clone(&authorizations);
    let (root, only, shared) = (root.to_path_buf(), only.to_string(), Arc::clone(&log));
    let seen = Arc::new(Mutex::new(HashSet::new()));
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let (root, only, log) = (root.clone(), only.clone(), Arc::clone(&shared));
            let (seen, auth) = (Arc::clone(&seen), Arc::clone(&auth));
            std::thread::spawn(move || {
                let _ = connection(stream, &root, mode, &only, (&log, &auth), &seen);
            });
        }
    });
    Server {
        base,
        log,
        authorizations,
    }
}

/// A port on 127.0.0.1 that nothing listens on (bound, then let go).
pub fn closed_port() -> u16 {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    listener.local_addr().unwrap().port()
}

/// Answers the requests of one connection until it closes.
fn connection(
    stream: TcpStream,
    root: &Path,
    mode: Mode,
    only: &str,
    (log, auth): (&Mutex<Vec<String>>, &Mutex<Vec<String>>),
    seen: &Mutex<HashSet<String>>,
) -> std::io::Result<()> {
    // A response goes out as two writes (its head, then its body): with Nagle's algorithm the
    // second waited for the client's delayed acknowledgement, 40 ms a request on keep-alive.
    stream.set_nodelay(true)?;
    let mut reader = BufReader::new(stream.try_clone()?);
    let mut out = stream;
    loop {
        let mut line = String::new();
        if reader.read_line(&mut line)? == 0 {
            return Ok(());
        }
        let mut parts = line.split_whitespace();
        let method = parts.next().unwrap_or_default().to_string();
        let path = parts.next().unwrap_or_default().to_string();
        let mut range = None;
        loop {
            let mut header = String::new();
            if reader.read_line(&mut header)? == 0 {
                return Ok(());
            }
            let header = header.trim_end();
            if header.is_empty() {
                break;
            }
            if let Some((name, value)) = header.split_once(':') {
                if name.eq_ignore_ascii_case("range") {
                    range = Some(value.trim().to_string());
                } else if name.eq_ignore_ascii_case("authorization") {
                    auth.lock().unwrap().push(value.trim().to_string());
                }
            }
        }
        log.lock().unwrap().push(format!(
            "{method} {path} {}",
            range.as_deref().unwrap_or("-")
        ));
        let mode = match mode {
            _ if !(only.is_empty() || path.contains(only)) => Mode::Normal,
            Mode::Flaky if seen.lock().unwrap().insert(path.clone()) => Mode::Status(500),
            Mode::Flaky => Mode::Normal,
            other => other,
        };
        if !answer(&mut out, root, mode, &method, &path, range.as_deref())? {
            return Ok(());
        }
    }
}

/// Answers one request; whether the connection stays open.
fn answer(
    out: &mut TcpStream,
    root: &Path,
    mode: Mode,
    method: &str,
    path: &str,
    range: Option<&str>,
) -> std::io::Result<bool> {
    match mode {
        Mode::Stall => {
            std::thread::sleep(Duration::from_secs(60));
            return Ok(false);
        }
        Mode::Slow(ms) => {
            std::thread::sleep(Duration::from_millis(ms));
            return answer(out, root, Mode::Normal, method, path, range);
        }
        Mode::Status(code) => {
            write!(out, "HTTP/1.1 {code} Nope\r\nContent-Length: 0\r\n\r\n")?;
            return Ok(true);
        }
        Mode::RedirectLoop => {
            write!(
                out,
                "HTTP/1.1 302 Found\r\nLocation: {path}\r\nContent-Length: 0\r\n\r\n"
            )?;
            return Ok(true);
        }
        Mode::Html => {
            let body = b"<!DOCTYPE html><html><body>Welcome</body></html>";
            write!(
                out,
                "HTTP/1.1 200 OK\r\nContent-Type: text/html\r\nContent-Length: {}\r\n\r\n",
                body.len()
            )?;
            out.write_all(body)?;
            return Ok(true);
        }
        _ => {}
    }
    let Some(file) = local(root, path) else {
        write!(out, "HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\n\r\n")?;
        return Ok(true);
    };
    let bytes = std::fs::read(&file)?;
    let n = bytes.len() as u64;
    let span = range
        .filter(|_| mode != Mode::NoRange)
        .and_then(|r| parse_range(r, n));
    let (status, start, end) = match span {
        Some((a, b)) => ("206 Partial Content", a, b),
        None => ("200 OK", 0, n),
    };
    let body = &bytes[start as usize..end as usize];
    let range = if span.is_some() {
        format!("Content-Range: bytes {start}-{}/{n}\r\n", end - 1)
    } else {
        String::new()
    };
    let stated = if mode == Mode::Overlong {
        body.len() / 2
    } else {
        body.len()
    };
    let head = format!("HTTP/1.1 {status}\r\nContent-Length: {stated}\r\n{range}\r\n");
    out.write_all(head.as_bytes())?;
    if method == "HEAD" {
        return Ok(true);
    }
    if mode == Mode::Truncate {
        out.write_all(&body[..body.len() / 2])?;
        out.flush()?;
        return Ok(false);
    }
    out.write_all(body)?;
    if mode == Mode::Trailing {
        out.write_all(b"HTTP/1.1 200 OK\r\nContent-Length: 5\r\n\r\nextra")?;
    }
    Ok(true)
}

/// The file of `path` under `root`, when there is one (nothing outside `root`).
fn local(root: &Path, path: &str) -> Option<PathBuf> {
    let relative = path.trim_start_matches('/');
    if relative.split('/').any(|s| s == "..") {
        return None;
    }
    let file = root.join(relative);
    file.is_file().then_some(file)
}

/// The bytes `[start, end)` a `Range` header asks of an object of `n` bytes.
fn parse_range(range: &str, n: u64) -> Option<(u64, u64)> {
    let spec = range.strip_prefix("bytes=")?;
    let (a, b) = spec.split_once('-')?;
    let (start, end) = if a.is_empty() {
        (n.saturating_sub(b.parse().ok()?), n)
    } else {
        let start: u64 = a.parse().ok()?;
        let end = if b.is_empty() {
            n
        } else {
            (b.parse::<u64>().ok()? + 1).min(n)
        };
        (start, end)
    };
    (start < end).then_some((start, end))
}
