//! The failures of a remote store that take a timeout to show: a server that stalls (it reads
//! the request and never answers) and a host that does not resolve. Each is one line naming the
//! URL, within the timeout `SLABSCOPE_HTTP_TIMEOUT` sets, not retried.

use std::time::{Duration, Instant};

use crate::common::data;
use crate::common::http::{Mode, serve};
use crate::one_at_a_time;

/// `slabscope info URL` with a read timeout of 1 s: its error, and how long it took.
fn info(url: &str) -> (String, Duration) {
    let start = Instant::now();
    let out = crate::common::slabscope()
        .args(["info", url])
        .env("SLABSCOPE_HTTP_TIMEOUT", "1")
        .output()
        .unwrap();
    assert!(!out.status.success(), "{url}");
    (
        String::from_utf8_lossy(&out.stderr).into_owned(),
        start.elapsed(),
    )
}

#[test]
fn a_stalled_server_is_a_timeout_naming_the_url() {
    let _alone = one_at_a_time();
    // A chunk of the coarsest dataset, which `info` reads.
    for only in ["", "/s2/0"] {
        let server = serve(&data("zarr"), Mode::Stall, only);
        let url = server.url("v04_blosc.ome.zarr");
        let (e, took) = info(&url);
        assert_eq!(e.lines().count(), 1, "{e}");
        assert!(e.contains(&url), "{e}");
        assert!(e.contains("did not answer within 1 s"), "{e}");
        assert!(took < Duration::from_secs(20), "{took:?}");
    }
}

#[test]
fn an_unknown_host_is_named() {
    let _alone = one_at_a_time();
    let url = "http://no-such-host.invalid/data/image.ome.zarr";
    let (e, _) = info(url);
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(e.contains(url), "{e}");
    // A resolver that cannot be reached times out instead of saying the name is unknown.
    assert!(
        e.contains("unknown host no-such-host.invalid") || e.contains("did not answer"),
        "{e}"
    );
}
