//! The committed fixture stores served by real servers on 127.0.0.1, as users' stores are:
//! nginx (Range, multi-range too) over HTTP, and moto's S3 server (an anonymous bucket) over
//! `s3://`; `info --exact` and `analyze` of each equal the local store's. `.ci/run` installs
//! both (Debian's `nginx-light`, the `moto[server]` package); without `CI=true` a missing server skips
//! its test, saying so, and under it fails.

use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::http::closed_port;
use crate::common::{data, run, s};

const STORES: [&str; 2] = ["v04_blosc.ome.zarr", "v05_sharded.ome.zarr"];

/// A server process, stopped when dropped.
struct Running(Child);

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Whether `program` runs here; `false` skips the test with a message, unless under `CI=true`,
/// where a missing server fails it.
fn available(program: &str) -> bool {
    let found = Command::new(program)
        .arg(if program == "nginx" { "-v" } else { "--help" })
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !found {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "{program} is needed under CI=true (.ci/run installs it)"
        );
        eprintln!("skipped: {program} is not installed (.ci/run installs it; CI=true requires it)");
    }
    found
}

/// Waits until something listens on `port` (at most 20 s).
fn listening(port: u16, server: &mut Running) {
    let end = Instant::now() + Duration::from_secs(20);
    while TcpStream::connect(("127.0.0.1", port)).is_err() {
        assert!(server.0.try_wait().unwrap().is_none(), "the server ended");
        assert!(Instant::now() < end, "nothing listens on {port}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// `slabscope ARGS --json` with its `file` taken out.
fn json(args: &[&str]) -> serde_json::Value {
    let ran = run(args);
    assert!(ran.ok, "{args:?}: {}", ran.stderr);
    let mut json: serde_json::Value = serde_json::from_str(&ran.stdout).unwrap();
    json["file"] = serde_json::Value::Null;
    json
}

/// `info --exact` and `analyze` of `input` (with `extra` arguments) equal those of the local
/// store `name`.
fn same_reports(input: &str, name: &str, extra: &[&str]) {
    let local = data("zarr").join(name);
    for command in [
        &["info", "--json", "--exact"][..],
        &["analyze", "--json", "--slabs", "3"][..],
    ] {
        let remote = [command, &[input], extra].concat();
        assert_eq!(
            json(&remote),
            json(&[command, &[s(&local)]].concat()),
            "{command:?} {input}"
        );
    }
}

#[test]
fn nginx_serves_the_stores_as_the_folders_hold_them() {
    if !available("nginx") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let port = closed_port();
    let root = data("zarr");
    let conf = dir.path().join("nginx.conf");
    let tmp = s(dir.path());
    std::fs::write(
        &conf,
        format!(
            "daemon off; master_process off; pid {tmp}/nginx.pid; error_log {tmp}/error.log;
            events {{}}
            http {{
                access_log off; client_body_temp_path {tmp}; proxy_temp_path {tmp};
                fastcgi_temp_path {tmp}; uwsgi_temp_path {tmp}; scgi_temp_path {tmp};
                server {{ listen 127.0.0.1:{port}; root {}; }}
            }}",
            s(&root)
        ),
    )
    .unwrap();
    let mut server = Running(
        Command::new("nginx")
            .args(["-p", tmp, "-c", s(&conf)])
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    listening(port, &mut server);
    for name in STORES {
        same_reports(&format!("http://127.0.0.1:{port}/{name}"), name, &[]);
    }
}

/// Puts `body` at `path` of the S3 server at `port`, unsigned (moto's server takes requests
/// without credentials), readable by anyone (`public-read`); its status line.
fn put(port: u16, path: &str, body: &[u8]) -> String {
    use std::io::{BufRead, BufReader, Write};
    let mut stream = TcpStream::connect(("127.0.0.1", port)).unwrap();
    let head = format!(
        "PUT {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nContent-Length: {}\r\n\
         Content-Type: application/octet-stream\r\nx-amz-acl: public-read\r\n\
         Connection: close\r\n\r\n",
        body.len()
    );
    stream.write_all(head.as_bytes()).unwrap();
    stream.write_all(body).unwrap();
    let mut status = String::new();
    BufReader::new(stream).read_line(&mut status).unwrap();
    status
}

/// The files under `dir`, as paths relative to it.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(
                files(&path)
                    .into_iter()
                    .map(|p| Path::new(path.file_name().unwrap()).join(p)),
            );
        } else {
            out.push(PathBuf::from(path.file_name().unwrap()));
        }
    }
    out
}

#[test]
fn an_s3_server_serves_the_stores_from_an_anonymous_bucket() {
    if !available("moto_server") {
        return;
    }
    let port = closed_port();
    let mut server = Running(
        Command::new("moto_server")
            .args(["-H", "127.0.0.1", "-p", &port.to_string()])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    listening(port, &mut server);
    assert!(put(port, "/fixtures", b"").contains(" 200"), "the bucket");
    for name in STORES {
        let store = data("zarr").join(name);
        for file in files(&store) {
            let key = format!("/fixtures/{name}/{}", s(&file));
            let status = put(port, &key, &std::fs::read(store.join(&file)).unwrap());
            assert!(status.contains(" 200"), "{key}: {status}");
        }
    }
    let endpoint = format!("http://127.0.0.1:{port}");
    for name in STORES {
        let url = format!("s3://fixtures/{name}");
        same_reports(&url, name, &["--endpoint", &endpoint]);
    }
}
