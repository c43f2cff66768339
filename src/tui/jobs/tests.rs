//! The jobs' own tests: what they drop, stop and hold back, and a measurement of the pictures.

use std::sync::mpsc::channel;
use std::time::Instant;

use slabscope::params::{Given, Scene, table};
use slabscope::partition::Method;
use slabscope::request::RenderRequest;
use slabscope::{AnalysisParams, Histories, Partition, Renderer, Scope};

use super::worker::{picture, render};
use super::*;
use crate::term::{Caps, Graphics};
use crate::tui::event::PictureSettings;

/// The TUI's settings of the library's `scene`.
fn settings_of(scene: &Scene) -> PictureSettings {
    let p = &scene.params;
    PictureSettings {
        camera: p.camera,
        spread: scene.spread,
        gap: scene.gap,
        mode: p.mode,
        preset: p.preset,
        colormap: p.colormap,
        window: p.window,
        solo: p.solo,
    }
}

/// The library's scene of the values `given`, 96 × 128 pixels.
fn scene_of(given: &[(&'static slabscope::params::Param, &str)]) -> Scene {
    let given = given.iter().fold(Given::new(), |g, &(p, v)| g.with(p, v));
    given.scene(96, 128).unwrap()
}

/// The preview's exploded view of a partition's slabs, as the user steps to them, is pixel for
/// pixel the library's render request's picture of that partition with the same settings: the
/// similarity gaps of slabs whose NMI the histories count (top-down) or know (a bottom-up
/// step's), uniform gaps, and the whole volume before any partition.
#[test]
fn the_previews_picture_is_the_render_requests() {
    let volume = slabscope::volume::phantom::body([24, 24, 32], 1).unwrap();
    let renderer = Renderer::new(&volume).unwrap();
    let axis = [0.0, 0.0, 1.0];
    let h = Arc::new(
        Histories::new(
            &volume,
            axis,
            &AnalysisParams::default().stack(),
            Scope::ALL,
            &Monitor::none(),
        )
        .unwrap(),
    );
    let cases = [
        (
            Method::TopDown,
            3,
            scene_of(&[(&table::AZIMUTH, "-40"), (&table::ELEVATION, "35")]),
        ),
        (
            Method::BottomUp,
            28,
            scene_of(&[
                (&table::MODE, "dvr"),
                (&table::SPREAD, "1.5"),
                (&table::COLORMAP, "viridis"),
            ]),
        ),
        (
            Method::TopDown,
            5,
            scene_of(&[
                (&table::GAP, "uniform"),
                (&table::PERSPECTIVE, "true"),
                (&table::ZOOM, "1.4"),
            ]),
        ),
    ];
    for (method, position, scene) in cases {
        let part = Partition::new(&h, method, position, &Monitor::none()).unwrap();
        let nmi = h.known_nmi(method, position);
        assert_eq!(
            nmi.is_some(),
            method == Method::BottomUp,
            "known only bottom-up"
        );
        let request = RenderRequest {
            scene: scene.clone(),
            faces: false,
        };
        let expected = request.draw(&volume, &part, &Monitor::none()).unwrap();
        let job = PictureJob {
            slabs: part.slabs.clone(),
            histories: Some(Arc::clone(&h)),
            nmi,
            look: settings_of(&scene),
            ..PictureJob::whole((12, 8))
        };
        let (drawn, caption, window) =
            picture(&renderer, &job, (96, 128), &Monitor::none()).unwrap();
        assert!(part.slabs.len() > 2 && caption.is_none() && window.is_some());
        assert!(drawn.data() == expected.data(), "{method:?} at {position}");
    }
    // Nothing partitioned: the whole volume, as one slab.
    let scene = scene_of(&[]);
    let whole = PictureJob {
        look: settings_of(&scene),
        ..PictureJob::whole((12, 8))
    };
    let (drawn, ..) = picture(&renderer, &whole, (96, 128), &Monitor::none()).unwrap();
    let expected = renderer
        .render(
            &slabscope::Layout::whole(axis),
            &scene.params,
            &Monitor::none(),
        )
        .unwrap();
    assert!(drawn.data() == expected.pixmap.data());
}

/// The histories' request cuts the slices as the partitioning asked: its sampling and
/// background, nothing of the defaults.
#[test]
fn the_histories_request_cuts_as_asked() {
    let stack = StackParams {
        sampling: slabscope::geometry::lattice::SamplingParams {
            bins: 16,
            ray_spacing: Some(1.5),
            sample_spacing: Some(0.75),
        },
        background: slabscope::volume::background::BackgroundRule::Below(3.0),
    };
    assert_eq!(cutting(&stack).stack(), stack);
    assert_ne!(stack, StackParams::default());
}

#[test]
fn messages_of_a_volume_no_longer_open_are_dropped() {
    let (tx, _rx) = channel();
    let mut jobs = Jobs::new(tx, Caps::blocks(), None, LoadOptions::default());
    let done = |epoch| JobMsg::Epoch(epoch, Box::new(JobMsg::Exported(Ok("x".into()))));
    assert!(matches!(jobs.admit(done(0)), Some(JobMsg::Exported(_))));
    jobs.run(Effect::Open(slabscope::triage::Entry::file("next.nii")));
    assert!(jobs.admit(done(0)).is_none(), "the last volume's");
    assert!(matches!(jobs.admit(done(1)), Some(JobMsg::Exported(_))));
    // The folder's triage rows are for every volume: never dropped.
    let row = slabscope::triage::TriageRow::failed("a", "b".into());
    assert!(jobs.admit(JobMsg::Triaged(0, Box::new(row))).is_some());
}

/// Opening another volume stops the load under way (a Zarr store of 64,000 absent chunks:
/// seconds of reading), which ends cancelled rather than reading on.
#[test]
fn opening_another_volume_stops_the_load_under_way() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("slow.zarr");
    std::fs::create_dir(&store).unwrap();
    let meta = r#"{"zarr_format": 3, "node_type": "array", "shape": [320, 320, 320],
        "data_type": "uint8", "fill_value": 0,
        "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [8, 8, 8]}},
        "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
        "codecs": [{"name": "bytes", "configuration": {"endian": "little"}}]}"#;
    std::fs::write(store.join("zarr.json"), meta).unwrap();
    let (tx, rx) = channel();
    let entry = slabscope::triage::Entry::file(&store);
    let mut jobs = Jobs::new(tx, Caps::blocks(), Some(entry), LoadOptions::default());
    jobs.run(Effect::Load);
    jobs.run(Effect::Open(slabscope::triage::Entry::file("next.nii")));
    match rx.recv().unwrap() {
        Event::Job(JobMsg::Epoch(0, msg)) => match *msg {
            JobMsg::Loaded(Err(e)) => assert_eq!(e, slabscope::Error::Cancelled.to_string()),
            _ => panic!("not the load's end"),
        },
        _ => panic!("not the first volume's message"),
    }
}

#[test]
fn background_triage_waits_while_the_open_volume_works() {
    let (tx, rx) = channel();
    let mut jobs = Jobs::new(tx, Caps::blocks(), None, LoadOptions::default());
    jobs.run(Effect::PauseTriage(true));
    let unreadable = slabscope::triage::Entry::failed("gone.nii", "cannot be read");
    let params = Box::new(AnalysisParams::default());
    jobs.run(Effect::Triage(vec![unreadable], params));
    // Until the triage thread waits at the gate (no clock: it gets there or the test hangs).
    while jobs.triage_gate.waiting() == 0 {
        std::thread::yield_now();
    }
    assert!(rx.try_recv().is_err(), "held: no row");
    jobs.run(Effect::PauseTriage(false));
    match rx.recv().unwrap() {
        Event::Job(JobMsg::Triaged(0, row)) => {
            assert_eq!(row.error.as_deref(), Some("cannot be read"));
        }
        _ => panic!("not a row"),
    }
}

#[test]
fn a_file_preview_serves_its_level_until_forgotten() {
    let (tx, _rx) = channel();
    let mut jobs = Jobs::new(tx, Caps::blocks(), None, LoadOptions::default());
    assert!(jobs.open.level(1).is_none(), "nothing read yet");
    let full = Arc::new(slabscope::volume::phantom::body([8, 8, 8], 1).unwrap());
    let coarse = full.coarser(1);
    jobs.observe(&JobMsg::Preview(Arc::clone(&coarse), vec![]));
    assert!(matches!(jobs.open.level(1), Some(Source::Held(v)) if Arc::ptr_eq(&v, &coarse)));
    assert!(jobs.open.level(0).is_none() && jobs.open.level(2).is_none());
    jobs.observe(&JobMsg::Loaded(Ok((Arc::clone(&full), vec![]))));
    assert!(
        matches!(jobs.open.level(1), Some(Source::Held(_))),
        "kept for level 1"
    );
    assert!(matches!(jobs.open.level(2), Some(Source::Coarser(_, 2))));
    // Forgotten: level 1 comes from level 0, and what the jobs sent before is dropped.
    let done = |epoch| JobMsg::Epoch(epoch, Box::new(JobMsg::Exported(Ok("x".into()))));
    jobs.run(Effect::Forget);
    assert!(matches!(jobs.open.level(1), Some(Source::Coarser(_, 1))));
    assert!(jobs.admit(done(0)).is_none());
    assert!(jobs.admit(done(1)).is_some());
    assert_eq!(jobs.open.level(1).unwrap().get().dims(), coarse.dims());
}

/// The loopback server of the integration tests, serving a folder with a request log.
#[allow(dead_code, clippy::unwrap_used)]
#[path = "../../../tests/common/http.rs"]
mod http;

/// The next message of the load under way that is not its progress.
fn next_message(rx: &std::sync::mpsc::Receiver<Event>) -> JobMsg {
    loop {
        if let Event::Job(JobMsg::Epoch(0, msg)) = rx.recv().unwrap()
            && !matches!(*msg, JobMsg::Progress(..))
        {
            return *msg;
        }
    }
}

/// In `dir`, `big.ome.zarr`: a 256³ u8 level 0 over a 128³ level 1, no chunk written (each is
/// a request the server logs, answered 404: the fill value, 3).
fn two_level_store(dir: &std::path::Path) {
    let store = dir.join("big.ome.zarr");
    let array = |path: &str, n: usize| {
        std::fs::create_dir_all(store.join(path)).unwrap();
        let meta = format!(
            r#"{{"zarr_format": 2, "shape": [{n}, {n}, {n}], "chunks": [64, 64, 64],
                "dtype": "|u1", "compressor": null, "fill_value": 3, "order": "C",
                "filters": null}}"#
        );
        std::fs::write(store.join(path).join(".zarray"), meta).unwrap();
    };
    array("0", 256);
    array("1", 128);
    std::fs::write(store.join(".zgroup"), r#"{"zarr_format": 2}"#).unwrap();
    let dataset = |path: &str, s: f64| {
        let t = (s - 1.0) / 2.0;
        format!(
            r#"{{"path": "{path}", "coordinateTransformations": [{{"type": "scale", "scale": [{s}, {s}, {s}]}}, {{"type": "translation", "translation": [{t}, {t}, {t}]}}]}}"#
        )
    };
    let attrs = format!(
        r#"{{"multiscales": [{{"version": "0.4", "axes": [{{"name": "z", "type": "space"}},
            {{"name": "y", "type": "space"}}, {{"name": "x", "type": "space"}}],
            "datasets": [{}, {}]}}]}}"#,
        dataset("0", 1.0),
        dataset("1", 2.0)
    );
    std::fs::write(store.join(".zattrs"), attrs).unwrap();
}

/// How many chunks of `big.ome.zarr`'s level 0 the server was asked for.
fn level_0_chunks(server: &http::Server) -> usize {
    (server.requests().iter())
        .filter(|r| {
            r.contains("/big.ome.zarr/0/") && !r.contains("/.z") && !r.contains("zarr.json")
        })
        .count()
}

/// A remote store's first picture fetches no chunk of level 0: its preview level is sent, and
/// level 0 is read once the preview's first picture is drawn.
#[test]
fn a_remote_stores_level_0_waits_for_the_first_picture() {
    let dir = tempfile::tempdir().unwrap();
    two_level_store(dir.path());
    let server = http::serve(dir.path(), http::Mode::Normal, "");
    let level_0 = || level_0_chunks(&server);
    let (tx, rx) = channel();
    let entry = slabscope::triage::Entry::file(server.url("big.ome.zarr"));
    let mut jobs = Jobs::new(tx, Caps::blocks(), Some(entry), LoadOptions::default());
    jobs.run(Effect::Load);
    let JobMsg::Preview(preview, _) = next_message(&rx) else {
        panic!("not the preview first");
    };
    assert_eq!(preview.dims(), [128, 128, 128]);
    assert!(
        server
            .requests()
            .iter()
            .any(|r| r.contains("/big.ome.zarr/1/0.0.0"))
    );
    // Until a picture is drawn, level 0 waits: nothing of it is asked.
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(level_0(), 0, "{:?}", server.requests());
    jobs.admit(JobMsg::Rendered(1, Err("drawn".into())));
    let JobMsg::Loaded(Ok((full, _))) = next_message(&rx) else {
        panic!("not level 0 next");
    };
    assert_eq!(full.dims(), [256, 256, 256]);
    assert_eq!(
        level_0(),
        64,
        "each chunk of level 0 once, after the picture"
    );
}

/// A remote store whose level 0 is beyond `--max-memory` never has a chunk of level 0 fetched:
/// after the first picture, the level that fits is read from the store's dataset that serves it.
#[test]
fn a_remote_store_beyond_the_budget_opens_the_level_that_fits() {
    let dir = tempfile::tempdir().unwrap();
    two_level_store(dir.path());
    let server = http::serve(dir.path(), http::Mode::Normal, "");
    let (tx, rx) = channel();
    let entry = slabscope::triage::Entry::file(server.url("big.ome.zarr"));
    // Level 0's analysis needs 36 MiB (16 of voxels, 20 of slice stack), level 1's 4.5 MiB.
    let load = LoadOptions {
        max_memory: 16 << 20,
        ..LoadOptions::default()
    };
    let mut jobs = Jobs::new(tx, Caps::blocks(), Some(entry), load);
    jobs.run(Effect::Load);
    let JobMsg::Preview(preview, _) = next_message(&rx) else {
        panic!("not the preview first");
    };
    assert_eq!(preview.dims(), [128, 128, 128]);
    jobs.admit(JobMsg::Rendered(1, Err("drawn".into())));
    let JobMsg::Loaded(Ok((level, _))) = next_message(&rx) else {
        panic!("not the level that fits next");
    };
    assert_eq!((level.dims(), level.level().index), ([128; 3], 1));
    assert_eq!(level.unread_finest().map(|f| f.dims), Some([256; 3]));
    assert_eq!(level_0_chunks(&server), 0, "{:?}", server.requests());
    assert!(
        (server.requests().iter()).any(|r| r.contains("/big.ome.zarr/1/0.0.0")),
        "{:?}",
        server.requests()
    );
}

/// Not a test but a measurement: `cargo test --release --bin slabscope preview_timing --
/// --ignored --nocapture` prints, for the built-in dataset, the time to the first image
/// after start, and the time and bytes of an image after a step at 1000×600 pixels, per
/// protocol.
#[test]
#[ignore = "a benchmark: prints timings, asserts nothing about them"]
fn preview_timing() {
    let start = Instant::now();
    let volume = slabscope::builtin_dataset().unwrap();
    let renderer = Renderer::new(&volume).unwrap();
    let cells = (125, 37);
    let sixel = Caps {
        graphics: Graphics::Sixel,
        cell: (8, 16),
        ..Caps::blocks()
    };
    let whole = PictureJob::whole(cells);
    let first = render(&renderer, &sixel, &whole, &Monitor::none()).unwrap();
    println!(
        "first image (load, render, sixel) {:.0} ms after start, {} KB",
        start.elapsed().as_secs_f64() * 1e3,
        first.image.bytes / 1024
    );
    let params = AnalysisParams::default();
    let h = Arc::new(
        Histories::new(
            &volume,
            [0.0, 0.0, 1.0],
            &params.stack(),
            Scope::ALL,
            &Monitor::none(),
        )
        .unwrap(),
    );
    for (name, graphics) in [
        ("sixel", Graphics::Sixel),
        ("kitty", Graphics::Kitty),
        ("iTerm2", Graphics::Iterm),
        ("half-blocks", Graphics::Blocks),
    ] {
        let caps = Caps {
            graphics,
            ..sixel.clone()
        };
        let step = PictureJob {
            slabs: h.slabs(Method::TopDown, 4),
            histories: Some(Arc::clone(&h)),
            ..whole.clone()
        };
        let mut times = Vec::new();
        let mut bytes = 0;
        for _ in 0..5 {
            let t = Instant::now();
            bytes = render(&renderer, &caps, &step, &Monitor::none())
                .unwrap()
                .image
                .bytes;
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
        times.sort_by(f64::total_cmp);
        println!(
            "{name:>11}: an image after a step at 1000x592 px in {:.0} ms (median of 5), {} KB",
            times[2],
            bytes / 1024
        );
    }
}
