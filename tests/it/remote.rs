//! Zarr and OME-Zarr stores read in place over HTTP, from a loopback server written in the test
//! (`tests/common/http.rs`) serving the committed fixture stores: the voxels, levels, label
//! images and reports equal the local store's; `info` makes few requests; every failure of the
//! server is one line naming the URL, never a credential. The stalled server is in
//! `tests/slow/remote.rs`.

use std::path::{Path, PathBuf};

use slabscope::formats::{ZarrOptions, load_preview};
use slabscope::{LoadOptions, Loaded, load};

use crate::common::http::{Mode, Server, closed_port, serve};
use crate::common::{data, run, s};

const STORES: [&str; 4] = [
    "v04_blosc.ome.zarr",
    "v04_yx.ome.zarr",
    "v05_sharded.ome.zarr",
    "v05_tczyx.ome.zarr",
];

fn zarr() -> PathBuf {
    data("zarr")
}

fn loaded(path: &Path, opts: &LoadOptions) -> Loaded {
    load(path, opts).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every voxel and the geometry of `va` and `vb` are the same.
fn same_volume(va: &slabscope::Volume, vb: &slabscope::Volume, what: &str) {
    assert_eq!(va.dims(), vb.dims(), "{what}");
    assert_eq!(va.spacing(), vb.spacing(), "{what}");
    assert_eq!(va.voxel_type(), vb.voxel_type(), "{what}");
    assert_eq!(va.transform(), vb.transform(), "{what}");
    assert_eq!(va.level(), vb.level(), "{what}");
    let [nx, ny, nz] = va.dims();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let (p, q) = (va.value([x, y, z]), vb.value([x, y, z]));
                assert!(
                    p == q || (p.is_nan() && q.is_nan()),
                    "{what} at {x},{y},{z}"
                );
            }
        }
    }
}

/// Every voxel, the geometry, the details and the notes of `a` and `b` are the same.
fn same(a: &Loaded, b: &Loaded, what: &str) {
    same_volume(&a.volume, &b.volume, what);
    assert_eq!(a.format, b.format, "{what}");
    assert_eq!(a.details_json(), b.details_json(), "{what}");
    assert_eq!(a.notes, b.notes, "{what}");
}

#[test]
fn remote_stores_read_as_the_local_ones_voxel_for_voxel() {
    for mode in [Mode::Normal, Mode::NoRange] {
        let server = serve(&zarr(), mode, "");
        for name in STORES {
            let url = PathBuf::from(server.url(name));
            let local = zarr().join(name);
            let opts = LoadOptions::default();
            same(&loaded(&url, &opts), &loaded(&local, &opts), name);
        }
        // A time point and a channel, and a label image.
        let tczyx = LoadOptions {
            part: slabscope::formats::PartOptions {
                volume: 1,
                channel: 1,
                ..slabscope::formats::PartOptions::default()
            },
            ..LoadOptions::default()
        };
        let name = "v05_tczyx.ome.zarr";
        let (url, local) = (PathBuf::from(server.url(name)), zarr().join(name));
        same(&loaded(&url, &tczyx), &loaded(&local, &tczyx), "t1 c1");
        let cells = LoadOptions {
            zarr: ZarrOptions {
                label_image: Some("cells".into()),
                ..ZarrOptions::default()
            },
            ..LoadOptions::default()
        };
        let name = "v05_sharded.ome.zarr";
        let (url, local) = (PathBuf::from(server.url(name)), zarr().join(name));
        same(&loaded(&url, &cells), &loaded(&local, &cells), "labels");
        // The store's coarser levels, read from the server as from the folder.
        let name = "v04_blosc.ome.zarr";
        let opts = LoadOptions::default();
        let (url, local) = (PathBuf::from(server.url(name)), zarr().join(name));
        let (remote, local) = (loaded(&url, &opts), loaded(&local, &opts));
        for k in 1..3 {
            let a = remote.volume.asked_level(k).unwrap();
            let b = local.volume.asked_level(k).unwrap();
            same_volume(&a, &b, &format!("level {k}"));
        }
    }
}

#[test]
fn the_first_picture_comes_from_a_coarse_level_without_level_0() {
    let server = serve(&zarr(), Mode::Normal, "");
    let name = "v04_blosc.ome.zarr";
    let url = PathBuf::from(server.url(name));
    let opts = LoadOptions::default();
    let remote = load_preview(&url, &opts, 300).unwrap().unwrap();
    let local = load_preview(&zarr().join(name), &opts, 300)
        .unwrap()
        .unwrap();
    same(&remote, &local, "preview");
    let asked = server.requests();
    assert!(
        asked.iter().all(|r| !r.contains("/s0/0")),
        "a chunk of level 0: {asked:?}"
    );
}

/// `analyze --json` of the store over HTTP is the local store's report, its file aside.
#[test]
fn reports_equal_the_local_stores() {
    let server = serve(&zarr(), Mode::Normal, "");
    for name in ["v04_blosc.ome.zarr", "v05_sharded.ome.zarr"] {
        let url = server.url(name);
        let local = zarr().join(name);
        let report = |input: &str| {
            let ran = run(&["analyze", "--json", "--slabs", "3", input]);
            assert!(ran.ok, "{input}: {}", ran.stderr);
            let mut json: serde_json::Value = serde_json::from_str(&ran.stdout).unwrap();
            assert_eq!(json["file"], input);
            json["file"] = serde_json::Value::Null;
            json
        };
        assert_eq!(report(&url), report(s(&local)), "{name}");
        let info = |input: &str, exact: bool| {
            let mut args = vec!["info", "--json", input];
            if exact {
                args.push("--exact");
            }
            let ran = run(&args);
            assert!(ran.ok, "{input}: {}", ran.stderr);
            let mut json: serde_json::Value = serde_json::from_str(&ran.stdout).unwrap();
            json["file"] = serde_json::Value::Null;
            json
        };
        let local_info = info(s(&local), false);
        assert_eq!(info(&url, true), local_info, "{name}");
        assert!(local_info["statistics_from"].is_null());
        // Without --exact, the statistics of the store's coarsest dataset, the rest level 0's.
        let mut coarse = info(&url, false);
        let coarsest = loaded(&local.clone(), &LoadOptions::default()).volume;
        let top = if name == "v04_blosc.ome.zarr" { 2 } else { 0 };
        if top == 0 {
            assert_eq!(
                coarse, local_info,
                "{name}: no coarser dataset, level 0 read"
            );
            continue;
        }
        let level = coarsest.coarser(top);
        let from = &coarse["statistics_from"];
        assert_eq!(from["pyramid_level"], top, "{name}");
        assert_eq!(from["dims"], serde_json::json!(level.dims()), "{name}");
        let stats = level.stats();
        assert_eq!(
            coarse["range"],
            serde_json::json!([stats.min, stats.max]),
            "{name}"
        );
        assert_eq!(coarse["mean"], serde_json::json!(stats.mean), "{name}");
        for key in [
            "statistics_from",
            "range",
            "mean",
            "histogram",
            "memory_bytes",
        ] {
            coarse[key] = local_info[key].clone();
        }
        assert_eq!(
            coarse, local_info,
            "{name}: level 0's grid, type and details"
        );
    }
}

/// `info` of a remote store fetches the metadata once each and the chunks of the store's
/// coarsest dataset, no chunk of level 0; `--exact` the chunks of level 0 instead.
#[test]
fn info_reads_the_coarsest_level_and_exact_level_0() {
    let server = serve(&zarr(), Mode::Normal, "");
    let name = "v04_blosc.ome.zarr";
    let ran = run(&["info", &server.url(name)]);
    assert!(ran.ok, "{}", ran.stderr);
    assert!(
        ran.stdout
            .contains("statistics  from pyramid level 2 (4x3x3, a voxel for 4x4x4 of level 0's)"),
        "{}",
        ran.stdout
    );
    assert!(
        ran.stdout.contains("dims        14x12x10"),
        "{}",
        ran.stdout
    );
    let asked = server.requests();
    let chunks: Vec<&String> = asked.iter().filter(|r| !is_metadata(r)).collect();
    // Level 2 (4×3×3 in chunks of 4×5×6: one chunk), nothing of level 0 or 1.
    assert!(chunks.iter().all(|r| r.contains("/s2/")), "{chunks:#?}");
    assert_eq!(chunks.len(), 1, "{asked:#?}");
    // The metadata as for level 0 (below), each once.
    assert_eq!(asked.len() - chunks.len(), 12, "{asked:#?}");
    assert!(asked.len() <= 13, "{asked:#?}");
}

/// Whether the logged request `r` asks for a metadata file.
fn is_metadata(r: &str) -> bool {
    let name = r.split(' ').nth(1).unwrap().rsplit('/').next().unwrap();
    name.starts_with('.') || name == "zarr.json"
}

/// `info --exact` fetches the metadata once each and the chunks of level 0, nothing more.
#[test]
fn info_makes_few_requests() {
    let server = serve(&zarr(), Mode::Normal, "");
    let name = "v04_blosc.ome.zarr";
    let ran = run(&["info", "--exact", &server.url(name)]);
    assert!(ran.ok, "{}", ran.stderr);
    let asked = server.requests();
    let chunks: Vec<&String> = asked.iter().filter(|r| !is_metadata(r)).collect();
    assert!(chunks.iter().all(|r| r.contains("/s0/")), "{chunks:#?}");
    let metadata = asked.len() - chunks.len();
    // Each chunk file of level 0 once (there are 3x3x3), nothing of the other levels.
    assert_eq!(chunks.len(), 27, "{asked:#?}");
    // The store's zarr.json (absent), .zattrs and .zarray (absent: not a plain array), each
    // level's .zarray, the labels' four names (absent), and what zarrs asks when it opens level
    // 0 (its zarr.json, absent, and .zattrs): each once.
    assert_eq!(metadata, 12, "{asked:#?}");
    let mut unique = asked.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(
        unique.len(),
        asked.len(),
        "a request made twice: {asked:#?}"
    );
}

/// Runs `info URL` against a server misbehaving as `mode` on the paths holding `only`; its error.
fn failure(mode: Mode, only: &str) -> (String, String) {
    let server: Server = serve(&zarr(), mode, only);
    let url = server.url("v04_blosc.ome.zarr");
    let ran = run(&["info", &url]);
    assert!(!ran.ok, "{mode:?}: {}", ran.stdout);
    (url, ran.stderr)
}

/// One line, naming the URL, saying `words`.
fn says(error: &str, url: &str, words: &[&str]) {
    assert_eq!(error.lines().count(), 1, "{error}");
    assert!(error.contains(url), "{error}");
    for w in words {
        assert!(error.contains(w), "{w:?} in {error}");
    }
}

#[test]
fn each_failure_of_the_server_is_one_line_naming_the_url() {
    let (url, e) = failure(Mode::Status(404), "");
    says(&e, &url, &["no Zarr store at this URL"]);
    let (url, e) = failure(Mode::Status(403), "");
    says(&e, &url, &["zarr.json: HTTP 403 Forbidden", "public"]);
    let (url, e) = failure(Mode::Status(401), "");
    says(&e, &url, &["HTTP 401 Unauthorized"]);
    // `info` reads the coarsest dataset's chunk, s2/0/0/0.
    let (url, e) = failure(Mode::Status(403), "/s2/0");
    says(&e, &url, &["chunk s2/0/0/0: HTTP 403 Forbidden"]);
    let (url, e) = failure(Mode::Status(500), "/s2/0");
    says(&e, &url, &["HTTP 500 Internal Server Error, after 3 tries"]);
    let (url, e) = failure(Mode::Truncate, "/s2/0");
    says(&e, &url, &["ended", "Content-Length"]);
    let (url, e) = failure(Mode::Truncate, ".zattrs");
    says(&e, &url, &[".zattrs", "Content-Length"]);
    let (url, e) = failure(Mode::RedirectLoop, "");
    says(&e, &url, &["a redirect loop"]);
    let (url, e) = failure(Mode::Html, "");
    says(&e, &url, &["an HTML page where JSON was expected"]);
    let url = format!("http://127.0.0.1:{}/a.ome.zarr", closed_port());
    let ran = run(&["info", &url]);
    says(&ran.stderr, &url, &["connection refused"]);
    // TLS asked of a server that speaks plain HTTP.
    let server = serve(&zarr(), Mode::Normal, "");
    let url = server
        .url("v04_blosc.ome.zarr")
        .replace("http://", "https://");
    let ran = run(&["info", &url]);
    says(&ran.stderr, &url, &["TLS failure with 127.0.0.1"]);
}

/// A server that sends more than its Content-Length states: HTTP ends the answer at the stated
/// length, so what the client takes is cut short, and what follows on the connection belongs to
/// no request (ureq closes a connection with bytes waiting rather than reuse it). A metadata file
/// or a chunk so cut fails to parse or to decode: one line naming the URL and the key. A server
/// that sends a whole answer and then another nobody asked for never makes `info` say anything
/// but what the honest server's store says, or one line naming the URL.
#[test]
fn a_body_longer_than_its_content_length_is_never_taken_for_the_store() {
    let (url, e) = failure(Mode::Overlong, ".zattrs");
    says(&e, &url, &[".zattrs: not JSON"]);
    let (url, e) = failure(Mode::Overlong, ".zarray");
    says(&e, &url, &[".zarray: not JSON"]);
    let (url, e) = failure(Mode::Overlong, "/s2/0");
    says(&e, &url, &["chunk s2/0/0/0:"]);
    let honest = serve(&zarr(), Mode::Normal, "");
    let expected = run(&["info", "--json", &honest.url("v04_blosc.ome.zarr")]);
    assert!(expected.ok, "{}", expected.stderr);
    let server = serve(&zarr(), Mode::Trailing, "");
    let url = server.url("v04_blosc.ome.zarr");
    let ran = run(&["info", "--json", &url]);
    if ran.ok {
        let json = |out: &str| {
            let mut json: serde_json::Value = serde_json::from_str(out).unwrap();
            json["file"] = serde_json::Value::Null;
            json
        };
        assert_eq!(json(&ran.stdout), json(&expected.stdout));
    } else {
        assert_eq!(ran.stderr.lines().count(), 1, "{}", ran.stderr);
        assert!(ran.stderr.contains(&url), "{}", ran.stderr);
    }
}

#[test]
fn a_chunk_refused_is_the_fill_value_with_missing_as_fill() {
    let server = serve(&zarr(), Mode::Status(403), "/s2/0");
    let url = server.url("v04_blosc.ome.zarr");
    let refused = run(&["info", &url]);
    says(
        &refused.stderr,
        &url,
        &["chunk s2/0/0/0: HTTP 403 Forbidden", "--missing-as-fill"],
    );
    let filled = run(&["info", "--json", &url, "--missing-as-fill"]);
    assert!(filled.ok, "{}", filled.stderr);
    let json: serde_json::Value = serde_json::from_str(&filled.stdout).unwrap();
    // Level 2's one chunk, the fill value (0) throughout.
    assert_eq!(json["range"], serde_json::json!([0.0, 0.0]), "{json}");
    assert_eq!(json["statistics_from"]["pyramid_level"], 2);
    // A 403 is decided at once, never asked again: once by each run.
    let asked = server.requests();
    let refused = asked.iter().filter(|r| r.contains("/s2/0")).count();
    assert_eq!(refused, 2, "{asked:#?}");
}

#[test]
fn a_label_images_chunk_refused_is_named_once() {
    let server = serve(&zarr(), Mode::Status(403), "/labels/cells/s0/c");
    let url = server.url("v05_sharded.ome.zarr");
    let ran = run(&["info", "--exact", &url, "--label-image", "cells"]);
    says(&ran.stderr, &url, &["labels/cells", "HTTP 403 Forbidden"]);
    // The chunk's key once, as the array names it, not again from the store's root.
    assert_eq!(
        ran.stderr.matches("labels/cells").count(),
        1,
        "{}",
        ran.stderr
    );
}

#[test]
fn a_bioformats2raw_container_at_a_url_names_its_first_image() {
    let dir = tempfile::tempdir().unwrap();
    let container = dir.path().join("plate.zarr");
    crate::common::copy_tree(&zarr().join("v04_blosc.ome.zarr"), &container.join("0"));
    std::fs::write(container.join(".zgroup"), r#"{"zarr_format": 2}"#).unwrap();
    std::fs::write(container.join(".zattrs"), r#"{"bioformats2raw.layout": 3}"#).unwrap();
    let server = serve(dir.path(), Mode::Normal, "");
    let url = server.url("plate.zarr");
    let ran = run(&["info", &url]);
    says(
        &ran.stderr,
        &url,
        &[
            "bioformats2raw container",
            "cannot be listed",
            &format!("{url}/0 for the first"),
        ],
    );
    let image = run(&["info", "--exact", &format!("{url}/0")]);
    assert!(image.ok, "{}", image.stderr);
}

#[test]
fn a_500_that_passes_is_retried() {
    // The server answers 500 once for each path, then serves it: the read succeeds.
    let server = serve(&zarr(), Mode::Flaky, "");
    let ran = run(&["info", &server.url("v04_blosc.ome.zarr")]);
    assert!(ran.ok, "{}", ran.stderr);
    let asked = server.requests();
    assert!(asked.iter().any(|r| r.contains("/s2/0")), "{asked:?}");
}

#[test]
fn credentials_other_formats_and_tiny_chunks_are_refused() {
    let server = serve(&zarr(), Mode::Normal, "");
    let secret = server
        .url("v04_blosc.ome.zarr")
        .replace("http://", "http://user:hunter2@");
    for url in [secret, server.url("v04_blosc.ome.zarr?token=hunter2")] {
        let ran = run(&["info", &url]);
        assert!(!ran.ok);
        assert!(!ran.text().contains("hunter2"), "{}", ran.text());
        says(&ran.stderr, &server.base, &["credentials"]);
    }
    let url = server.url("scan.nii.gz");
    let ran = run(&["info", &url]);
    says(&ran.stderr, &url, &["download it"]);
    assert!(server.requests().is_empty(), "{:?}", server.requests());
    // A store of one-voxel chunks: refused before a chunk is asked.
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("tiny.zarr");
    std::fs::create_dir(&store).unwrap();
    std::fs::write(
        store.join(".zarray"),
        r#"{"zarr_format": 2, "shape": [64, 64, 32], "chunks": [1, 1, 1], "dtype": "<u1",
            "compressor": null, "fill_value": 0, "order": "C", "filters": null}"#,
    )
    .unwrap();
    let tiny = serve(dir.path(), Mode::Normal, "");
    let url = tiny.url("tiny.zarr");
    let ran = run(&["info", &url]);
    says(&ran.stderr, &url, &["131072 requests", "65536"]);
    let asked = tiny.requests();
    assert!(
        asked
            .iter()
            .all(|r| r.contains("/.z") || r.contains("zarr.json")),
        "{asked:?}"
    );
}

/// The URL goes wherever a path goes: a triage manifest, `render`, `slice`.
#[test]
fn urls_go_where_paths_go() {
    let server = serve(&zarr(), Mode::Normal, "");
    let url = server.url("v04_blosc.ome.zarr");
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("list.txt");
    std::fs::write(&manifest, format!("{url}\n")).unwrap();
    let ran = run(&["triage", "--json", "--manifest", s(&manifest)]);
    assert!(ran.ok, "{}", ran.text());
    let row: serde_json::Value = serde_json::from_str(ran.stdout.trim()).unwrap();
    assert_eq!(row["path"], url.as_str(), "{row}");
    assert_eq!(row["format"], "ome-zarr", "{row}");
    let png = dir.path().join("view.png");
    let ran = run(&["render", &url, "-o", s(&png), "--size", "64x48"]);
    assert!(ran.ok, "{}", ran.text());
    assert!(png.is_file());
}

/// `s3://bucket/prefix` at an endpoint (`AWS_ENDPOINT_URL`), path-style and anonymous: the
/// loopback server holds the bucket `zarr` (the fixtures' folder), and answers 403 for the
/// metadata a store does not have, as public S3 does when listing is not allowed.
#[test]
fn s3_stores_are_read_at_an_endpoint() {
    let server = serve(&data(""), Mode::Status(403), "zarr.json");
    let info = |input: &str, endpoint: Option<&str>| {
        let mut command = crate::common::slabscope();
        command.args(["info", "--json", "--exact", input]);
        command.env_remove("AWS_ENDPOINT_URL_S3");
        match endpoint {
            Some(e) => command.env("AWS_ENDPOINT_URL", e),
            None => command.env_remove("AWS_ENDPOINT_URL"),
        };
        let ran: crate::common::Ran = command.output().unwrap().into();
        assert!(ran.ok, "{input}: {}", ran.stderr);
        let mut json: serde_json::Value = serde_json::from_str(&ran.stdout).unwrap();
        json["file"] = serde_json::Value::Null;
        json
    };
    let s3 = "s3://zarr/v04_blosc.ome.zarr";
    let local = zarr().join("v04_blosc.ome.zarr");
    assert_eq!(info(s3, Some(&server.base)), info(s(&local), None));
    // --endpoint names it, before the environment's (here an endpoint with nothing there).
    let flagged: crate::common::Ran = crate::common::slabscope()
        .args(["info", "--json", "--exact", s3, "--endpoint", &server.base])
        .env(
            "AWS_ENDPOINT_URL",
            format!("http://127.0.0.1:{}", closed_port()),
        )
        .env_remove("AWS_ENDPOINT_URL_S3")
        .output()
        .unwrap()
        .into();
    assert!(flagged.ok, "{}", flagged.stderr);
    let mut json: serde_json::Value = serde_json::from_str(&flagged.stdout).unwrap();
    json["file"] = serde_json::Value::Null;
    assert_eq!(json, info(s(&local), None));
    let asked = server.requests();
    assert!(
        asked
            .iter()
            .all(|r| r.contains(" /zarr/v04_blosc.ome.zarr/")),
        "{asked:?}"
    );
    // With credentials in the environment, every request is signed (AWS SigV4, its scope the
    // key id, the day, the region and s3), and the secret shows nowhere.
    let signed: crate::common::Ran = crate::common::slabscope()
        .args(["info", "--json", "--exact", s3, "--endpoint", &server.base])
        .env("AWS_ACCESS_KEY_ID", "AKIDTEST")
        .env("AWS_SECRET_ACCESS_KEY", "hunter2secret")
        .env("AWS_REGION", "eu-west-2")
        .env_remove("AWS_SESSION_TOKEN")
        .output()
        .unwrap()
        .into();
    assert!(signed.ok, "{}", signed.stderr);
    assert!(!signed.text().contains("hunter2"), "{}", signed.text());
    let auths = server.authorizations.lock().unwrap().clone();
    let asked = server.requests().len();
    assert!(auths.len() >= 13 && auths.len() < asked, "{auths:?}");
    for auth in &auths {
        assert!(
            auth.starts_with("AWS4-HMAC-SHA256 Credential=AKIDTEST/")
                && auth.contains("/eu-west-2/s3/aws4_request, SignedHeaders=host;x-amz-content-sha256;x-amz-date, Signature="),
            "{auth}"
        );
        assert!(!auth.contains("hunter2"));
    }
    // Over plain HTTP the same 403 is an error.
    let (url, e) = failure(Mode::Status(403), "zarr.json");
    says(&e, &url, &["zarr.json: HTTP 403 Forbidden"]);
    // A chunk answered 403 is an error on S3 too, naming the s3:// URL.
    let server = serve(&data(""), Mode::Status(403), "/s2/0");
    let ran: crate::common::Ran = crate::common::slabscope()
        .args(["info", s3])
        .env("AWS_ENDPOINT_URL", &server.base)
        .output()
        .unwrap()
        .into();
    says(&ran.stderr, s3, &["chunk s2/0/0/0: HTTP 403 Forbidden"]);
}
