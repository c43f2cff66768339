//! `slabscope tour --export DIR`: the pages written for slides, their numbers the lesson's (the
//! same as `analyze --explain` gives), their pictures PNG, and a folder with files in it left
//! alone unless `--force`.

use serde_json::Value;

use crate::common::{Ran, run, s};

/// The JSON `analyze` prints for `args`.
fn analyzed(args: &[&str]) -> Value {
    let Ran {
        ok, stdout, stderr, ..
    } = run(args);
    assert!(ok, "{stderr}");
    serde_json::from_str(&stdout).unwrap()
}

#[test]
fn the_exported_pages_hold_the_lessons_numbers_and_pictures() {
    let dir = tempfile::tempdir().unwrap();
    let body = dir.path().join("body.nrrd");
    let made = run(&["phantom", "body", "-o", s(&body), "--dims", "24x24x40"]);
    assert!(made.ok, "{}", made.stderr);
    for paper in [false, true] {
        let out = dir.path().join(if paper { "paper" } else { "defaults" });
        let mut args = vec!["tour", s(&body), "--export", s(&out)];
        let mut explain = vec![
            "analyze",
            s(&body),
            "--json",
            "--slabs",
            "4",
            "--explain",
            "all",
        ];
        if paper {
            args.push("--paper");
            explain.extend(["--phases", "0", "--background", "none"]);
        }
        let ran = run(&args);
        assert!(ran.ok, "{}", ran.stderr);
        for name in [
            "tour.md",
            "tour.json",
            "exploded-view.png",
            "fig-1a-viewpoint-sphere.png",
            "fig-1b-rays.png",
            "curves.png",
            "first-split.png",
            "merge-joint-histogram.png",
            "merge-highest-nmi.png",
            "worked-js-histograms.png",
            "worked-nmi-joint-table.png",
        ] {
            let bytes = std::fs::read(out.join(name)).unwrap();
            if std::path::Path::new(name).extension() == Some("png".as_ref()) {
                assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{name}");
            }
        }
        let tour: Value =
            serde_json::from_slice(&std::fs::read(out.join("tour.json")).unwrap()).unwrap();
        let pages = tour["pages"].as_array().unwrap();
        assert_eq!(pages.len(), 16);
        assert_eq!(tour["mode"], if paper { "paper mode" } else { "defaults" });
        let page = |title: &str| {
            pages
                .iter()
                .find(|p| p["title"] == title)
                .unwrap_or_else(|| panic!("no page {title}"))["numbers"]
                .clone()
        };
        check_lessons(&page, &explain, &body, paper);
        // The worked examples by hand: h = log2 3 - 1.5 of the five-sample ray.
        let ray = page("A worked example: blocks along one ray");
        let h = ray["entropy_rate"].as_f64().unwrap();
        assert!((h - (3f64.log2() - 1.5)).abs() < 1e-12, "{h}");
        assert_eq!(page("The viewpoint sphere")["viewpoints"], 42);
        let md = std::fs::read_to_string(out.join("tour.md")).unwrap();
        assert!(
            md.contains("![The viewpoint sphere](fig-1a-viewpoint-sphere.png)"),
            "{md}"
        );
        assert!(md.contains("## 16. The exploded view"), "{md}");
        check_pictures(&out, pages);
    }
}

#[test]
fn a_folder_with_files_is_written_over_only_with_force() {
    let dir = tempfile::tempdir().unwrap();
    let body = dir.path().join("body.nrrd");
    let made = run(&["phantom", "body", "-o", s(&body), "--dims", "16x16x24"]);
    assert!(made.ok, "{}", made.stderr);
    let out = dir.path().join("slides");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("tour.md"), "mine").unwrap();
    let ran = run(&["tour", s(&body), "--export", s(&out)]);
    assert!(!ran.ok);
    assert!(
        ran.stderr.contains("the folder is not empty (use --force"),
        "{}",
        ran.stderr
    );
    assert_eq!(
        std::fs::read_to_string(out.join("tour.md")).unwrap(),
        "mine"
    );
    let ran = run(&["tour", s(&body), "--export", s(&out), "--force"]);
    assert!(ran.ok, "{}", ran.stderr);
    assert!(
        std::fs::read_to_string(out.join("tour.md"))
            .unwrap()
            .starts_with("# The paper")
    );
    // The files are checked before any work: a folder holding a file where the tour writes
    // one is refused even with --force.
    std::fs::remove_file(out.join("tour.md")).unwrap();
    std::fs::create_dir(out.join("tour.md")).unwrap();
    let ran = run(&["tour", s(&body), "--export", s(&out), "--force"]);
    assert!(
        !ran.ok && ran.stderr.contains("not a regular file"),
        "{}",
        ran.stderr
    );
    // A file is no folder; a folder whose parent is missing is not made.
    let ran = run(&["tour", s(&body), "--export", s(&body)]);
    assert!(ran.stderr.contains("not a folder"), "{}", ran.stderr);
    let deep = dir.path().join("no/such");
    let ran = run(&["tour", s(&body), "--export", s(&deep)]);
    assert!(
        !ran.ok && ran.stderr.contains("cannot make the folder"),
        "{}",
        ran.stderr
    );
    // --force alone asks for --export.
    assert!(!run(&["tour", s(&body), "--force"]).ok);
}

/// The exported pages' numbers against `analyze --explain`'s (`explain` its arguments).
fn check_lessons(
    page: &dyn Fn(&str) -> Value,
    explain: &[&str],
    body: &std::path::Path,
    paper: bool,
) {
    let lesson = analyzed(explain)["explain"].clone();
    // The axis's block entropies and rate, the first split, the optimum: the lesson's.
    let blocks = page("Blocks and H(X^L)");
    let chosen = &lesson["axes"][0];
    for key in ["block_entropies", "entropy_rate", "rays", "samples", "axis"] {
        assert_eq!(blocks[key], chosen[key], "{key}");
    }
    let rates = page("The entropy rate of the best and the worst axis");
    assert_eq!(
        rates["worst"]["entropy_rate"],
        lesson["axes"][1]["entropy_rate"]
    );
    let split = page("The first split");
    for key in ["at", "js", "gain", "weights", "entropies", "information"] {
        assert_eq!(split[key], lesson["splits"][0][key], "{key}");
    }
    assert_eq!(page("The optimum"), lesson["optimal"]);
    // The merge page shows bottom-up where the NMI of its merges falls furthest, between 3 and
    // 8 slabs, counted here from the whole history `analyze --method bottomup` gives.
    let merge = page("A merge");
    let bottom_up = |slabs: &str| {
        let mut args = vec![
            "analyze",
            s(body),
            "--json",
            "--method",
            "bottomup",
            "--explain",
            "all",
            "--slabs",
        ];
        args.push(slabs);
        if paper {
            args.extend(["--phases", "0", "--background", "none"]);
        }
        analyzed(&args)
    };
    let whole = bottom_up("1");
    let nmis: Vec<f64> = whole["partition"]["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["nmi"].as_f64().unwrap())
        .collect();
    let slices = nmis.len() + 1;
    let fall = |k: usize| nmis[slices - k - 1] - nmis[slices - k];
    let structured = (3..=8)
        .filter(|&k| fall(k) > 0.0)
        .fold(None, |best: Option<usize>, k| match best {
            Some(b) if fall(b) >= fall(k) => best,
            _ => Some(k),
        })
        .unwrap();
    assert_eq!(merge["slabs"], structured, "{merge}");
    assert_eq!(merge["structure"]["at"]["slabs"], structured);
    assert_eq!(
        merge["structure"]["at"]["next_nmi"],
        nmis[slices - structured]
    );
    let shown = structured.to_string();
    let merges = bottom_up(&shown);
    let explained = merges["explain"]["merges"].as_array().unwrap();
    let last = explained.last().unwrap();
    for key in ["nmi", "mi", "h_xy", "merge"] {
        assert_eq!(merge[key], last[key], "{key}");
    }
    // Beside it, the merge of the highest NMI below 1 bottom-up took (the first on ties): the
    // first merges join slices whose paired samples are each of one bin, a joint histogram of
    // one cell, NMI 1 by convention.
    let below_one = explained.iter().filter(|m| m["nmi"].as_f64() < Some(1.0));
    let highest = below_one.fold(None, |best: Option<&Value>, m| match best {
        Some(b) if b["nmi"].as_f64() >= m["nmi"].as_f64() => best,
        _ => Some(m),
    });
    let highest = highest.unwrap();
    assert!(highest["h_xy"].as_f64() > Some(0.0), "{highest}");
    if !paper {
        let one = explained
            .iter()
            .find(|m| m["nmi"].as_f64() == Some(1.0))
            .unwrap();
        assert_eq!(one["h_xy"].as_f64(), Some(0.0), "{one}");
    }
    for key in ["step", "nmi", "merge", "h_xy"] {
        assert_eq!(merge["highest_nmi"][key], highest[key], "{key}");
    }
}

#[test]
fn the_export_follows_the_given_analysis() {
    let dir = tempfile::tempdir().unwrap();
    let body = dir.path().join("body.nrrd");
    let made = run(&["phantom", "body", "-o", s(&body), "--dims", "24x24x40"]);
    assert!(made.ok, "{}", made.stderr);
    let given: [&[&str]; 2] = [
        &["--slabs", "6", "--method", "bottomup"],
        &["--threshold", "0.05"],
    ];
    for (i, flags) in given.iter().enumerate() {
        let out = dir.path().join(format!("slides-{i}"));
        let mut args = vec!["tour", s(&body), "--export", s(&out)];
        args.extend_from_slice(flags);
        let ran = run(&args);
        assert!(ran.ok, "{}", ran.stderr);
        let mut analyze = vec!["analyze", s(&body), "--json"];
        analyze.extend_from_slice(flags);
        let partition = analyzed(&analyze)["partition"].clone();
        let tour: Value =
            serde_json::from_slice(&std::fs::read(out.join("tour.json")).unwrap()).unwrap();
        let pages = tour["pages"].as_array().unwrap();
        let slabs = partition["slabs"].as_array().unwrap().len();
        // The first and the last page show the given analysis's slabs, by its method.
        for page in [&pages[0], &pages[15]] {
            assert_eq!(page["numbers"]["slabs"], partition["slabs"]);
            assert_eq!(page["numbers"]["method"], partition["method"]);
        }
        // Top-down and bottom-up are compared at its slab count.
        let compared = &pages[13]["numbers"];
        assert_eq!(compared["top_down_slabs"].as_array().unwrap().len(), slabs);
        assert_eq!(compared["bottom_up_slabs"].as_array().unwrap().len(), slabs);
        let lines = pages[13]["lines"][0].as_str().unwrap();
        assert!(
            lines.starts_with(&format!("Here {slabs} slabs keep")),
            "{lines}"
        );
    }
}

/// Every picture a page names is written, the charts stand on their pages, at their sizes.
fn check_pictures(out: &std::path::Path, pages: &[Value]) {
    // Every picture a page names is written, and the charts stand on their pages.
    for p in pages {
        for picture in p["pictures"].as_array().unwrap() {
            assert!(out.join(picture.as_str().unwrap()).is_file(), "{picture}");
        }
    }
    let pictures = |title: &str| {
        let p = pages.iter().find(|p| p["title"] == title).unwrap();
        p["pictures"].clone()
    };
    assert_eq!(pictures("The first split")[0], "first-split.png");
    assert_eq!(
        pictures("A merge"),
        serde_json::json!(["merge-highest-nmi.png", "merge-joint-histogram.png"])
    );
    assert_eq!(pictures("Slicing along the best axis")[0], "curves.png");
    // The charts are drawn at their sizes (width and height from the PNG's header).
    let size = |name: &str| {
        let b = std::fs::read(out.join(name)).unwrap();
        let be = |k: usize| u32::from_be_bytes(b[k..k + 4].try_into().unwrap());
        (be(16), be(20))
    };
    assert_eq!(size("curves.png"), (1000, 700));
    assert_eq!(size("merge-joint-histogram.png"), (800, 640));
}
