//! `slabscope tour --export DIR`: the tour's pages for slides, without a terminal. Each page's
//! title, paragraph and numbers go into `tour.md` and `tour.json`; its pictures (the exploded
//! view, the paper's Fig. 1a and 1b) are drawn by the library's renderer as PNG beside them.
//! Every number is the library's: the same analysis, lessons and worked examples the tour shows.

use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde_json::{Value, json};
use slabscope::explain::figure::{View, rays_figure, sphere_figure};
use slabscope::explain::{self, StepsShown, text, worked};
use slabscope::geometry::AxisChoice;
use slabscope::partition::Method;
use slabscope::render::{DEFAULT_SPREAD, Gap, Layout, RenderParams, Renderer, draw_figure};
use slabscope::{Analysis, AnalysisParams, LoadOptions, Monitor, Stop, Volume};

use super::app::tour::{Board, PAGES};

mod charts;
mod examples;

use charts::{CURVES, MERGE, MERGE_BEST, SPLIT, WORKED_JS, WORKED_NMI};

/// What to export and how.
pub struct ExportOptions {
    /// The folder written (made when it does not exist).
    pub dir: PathBuf,
    /// Write over the tour's files in a folder that is not empty.
    pub force: bool,
    /// The volume (None: the built-in dataset).
    pub file: Option<PathBuf>,
    /// How to read it.
    pub load: LoadOptions,
    /// How to analyse it (paper mode already applied).
    pub analysis: AnalysisParams,
    /// Whether the tour runs in paper mode.
    pub paper: bool,
}

/// Everything the pages show, computed once.
struct Numbers {
    name: String,
    volume: Volume,
    /// Top-down along the chosen axis at the given analysis's slab count, every split explained.
    top: Analysis,
    /// Bottom-up along the same axis at the same slab count.
    bottom: Analysis,
    /// The given analysis's partition when its method is not top-down (else `top`'s).
    chosen: Option<slabscope::Partition>,
    /// Bottom-up where its history shows structure: the merge page's count and examples.
    merges: examples::Merges,
    modes: explain::ModeLesson,
}

impl Numbers {
    /// The slab count of the given analysis, which every page shows.
    fn slabs(&self) -> usize {
        self.top.partition.slabs.len()
    }

    /// The partition the given analysis found, drawn as the exploded view.
    fn shown(&self) -> &slabscope::Partition {
        self.chosen.as_ref().unwrap_or(&self.top.partition)
    }
}

/// One page as exported.
struct Exported {
    numbers: Value,
    lines: Vec<String>,
    pictures: Vec<&'static str>,
}

/// The pictures' files.
const EXPLODED: &str = "exploded-view.png";
const FIG_1A: &str = "fig-1a-viewpoint-sphere.png";
const FIG_1B: &str = "fig-1b-rays.png";

/// Writes the tour's pages into `options.dir`.
pub fn export(options: &ExportOptions) -> Result<()> {
    check_folder(&options.dir, options.force)?;
    check_files(&options.dir, options.file.as_deref(), options.force)?;
    let numbers = compute(options)?;
    let pages: Vec<Exported> = (0..PAGES.len()).map(|i| page(i, &numbers)).collect();
    let mode = if options.paper {
        "paper mode"
    } else {
        "defaults"
    };
    let json = json!({
        "volume": numbers.name,
        "mode": mode,
        "pages": PAGES.iter().zip(&pages).enumerate().map(|(i, (p, e))| json!({
            "page": i + 1,
            "title": p.title,
            "text": p.text,
            "numbers": e.numbers,
            "lines": e.lines,
            "pictures": e.pictures,
        })).collect::<Vec<_>>(),
    });
    let mut files = pictures(&numbers)?;
    files.push((
        "tour.json",
        serde_json::to_string_pretty(&json)?.into_bytes(),
    ));
    files.push((
        "tour.md",
        markdown(&numbers.name, mode, &pages).into_bytes(),
    ));
    // Every file written in full beside its place first, then all put in place together.
    let staged = files
        .iter()
        .map(|(name, bytes)| {
            slabscope::formats::stage(&options.dir.join(name), |mut f| f.write_all(bytes))
        })
        .collect::<slabscope::Result<Vec<_>>>()?;
    for s in staged {
        s.persist(options.force)?;
    }
    Ok(())
}

/// The files the export writes (a chart only where its page has one).
const FILES: [&str; 11] = [
    EXPLODED,
    FIG_1A,
    FIG_1B,
    CURVES,
    SPLIT,
    MERGE,
    MERGE_BEST,
    WORKED_JS,
    WORKED_NMI,
    "tour.json",
    "tour.md",
];

/// Fails unless every file of the export may be written into `dir`: none is the volume read,
/// and none exists unless `force` (checked before any work).
fn check_files(dir: &Path, input: Option<&Path>, force: bool) -> Result<()> {
    for name in FILES {
        let path = dir.join(name);
        if input.is_some_and(|i| slabscope::formats::same_file(&path, i)) {
            bail!(
                "{}: is the volume read: the tour is not written over it",
                path.display()
            );
        }
        slabscope::formats::check_output(&path, force)?;
    }
    Ok(())
}

/// Fails unless `dir` is a folder to write the tour into: a new one (its parent must exist), an
/// empty one, or with `force` one holding files already.
fn check_folder(dir: &Path, force: bool) -> Result<()> {
    let shown = dir.display();
    match std::fs::metadata(dir) {
        Ok(m) if !m.is_dir() => bail!("{shown}: not a folder"),
        Ok(_) => {
            let full = std::fs::read_dir(dir)
                .with_context(|| format!("{shown}: cannot read the folder"))?
                .next()
                .is_some();
            if full && !force {
                bail!(
                    "{shown}: the folder is not empty (use --force to write the tour's files over those in it)"
                );
            }
            Ok(())
        }
        Err(_) => {
            std::fs::create_dir(dir).with_context(|| format!("{shown}: cannot make the folder"))
        }
    }
}

/// The analyses behind the pages: the given one (its method, its stop: `--slabs` or
/// `--threshold`, as `analyze` runs it), top-down along its axis with every split explained,
/// bottom-up along the same axis at the same slab count and where its history shows structure
/// ([`examples::merges`]), and the modes' numbers.
fn compute(o: &ExportOptions) -> Result<Numbers> {
    let (name, volume) = match &o.file {
        Some(path) => (
            slabscope::error::shown(path),
            slabscope::load(path, &o.load)?.volume,
        ),
        None => (
            slabscope::BUILTIN_NAME.to_string(),
            slabscope::builtin_dataset()?,
        ),
    };
    let monitor = Monitor::none();
    let run = |params: &AnalysisParams| {
        slabscope::analyze(&volume, params, &monitor)
            .with_context(|| format!("{name}: the analysis failed"))
    };
    let top_down = o.analysis.method == Method::TopDown;
    let given = run(&AnalysisParams {
        explain: Some(if top_down {
            StepsShown::All
        } else {
            StepsShown::Last(1)
        }),
        search_views: true,
        ..o.analysis.clone()
    })?;
    let slabs = given.partition.slabs.len();
    let along = AxisChoice::Along(slabscope::Axis::new(given.axis())?);
    let (top, chosen) = if top_down {
        (given, None)
    } else {
        // The view search again, for the lesson's worst axis; the axis stays the given one's.
        let top = run(&AnalysisParams {
            method: Method::TopDown,
            stop: Stop::Slabs(slabs),
            axis: along,
            explain: Some(StepsShown::All),
            search_views: true,
            ..o.analysis.clone()
        })?;
        (top, Some(given.partition))
    };
    let bottom = run(&AnalysisParams {
        method: Method::BottomUp,
        stop: Stop::Slabs(slabs),
        axis: along,
        explain: None,
        // The axis is the given analysis's: no second view search.
        search_views: false,
        ..o.analysis.clone()
    })?;
    let modes = explain::mode_lesson(&volume, top.axis(), &o.analysis.view, &monitor)?;
    let merges = examples::merges(&volume, top.axis(), &o.analysis, slabs, &monitor)?;
    Ok(Numbers {
        name,
        volume,
        top,
        bottom,
        chosen,
        merges,
        modes,
    })
}

/// An axis as the tour names it: `z` or `[ 0.000, 0.526, 0.851]`.
fn axis_name(axis: [f64; 3]) -> String {
    slabscope::Axis::new(axis).map_or_else(|_| format!("{axis:?}"), slabscope::Axis::labelled)
}

/// The physical size of `volume`, mm.
fn size(volume: &Volume) -> [f64; 3] {
    let (d, s) = (volume.dims(), volume.spacing());
    std::array::from_fn(|k| d[k] as f64 * s[k])
}

/// The pictures: the exploded view, Fig. 1a and Fig. 1b, as PNG.
fn pictures(n: &Numbers) -> Result<Vec<(&'static str, Vec<u8>)>> {
    let axis = n.top.axis();
    let level = n.top.views.as_ref().map_or(1, |v| v.params.level);
    let sphere = sphere_figure(level, axis, &View::default());
    let across = View::across(axis).unwrap_or_default();
    let rays = rays_figure(size(&n.volume), axis, 4, 5, &across)?;
    let layout = Layout::exploded(n.shown(), Gap::Similarity, DEFAULT_SPREAD);
    let params = RenderParams {
        width: 960,
        height: 720,
        ..RenderParams::default()
    };
    let exploded = Renderer::new(&n.volume)?.render(&layout, &params, &Monitor::none())?;
    let w = worked();
    let mut out = vec![
        (EXPLODED, exploded.png()?),
        (FIG_1A, png(&draw_figure(&sphere.drawing, 800, 800)?)?),
        (FIG_1B, png(&draw_figure(&rays.drawing, 1000, 640)?)?),
        (CURVES, png(&charts::curves(&n.top.partition, 1000, 700)?)?),
        (WORKED_JS, png(&charts::worked_js(&w.js, 800, 450)?)?),
        (WORKED_NMI, png(&charts::worked_nmi(&w.nmi, 640, 520)?)?),
    ];
    if let Some(s) = first_split(n) {
        out.push((SPLIT, png(&charts::split(s, 1000, 760)?)?));
    }
    if let Some(m) = last_merge(n) {
        out.push((MERGE, png(&charts::merge(m, 800, 640)?)?));
    }
    if let Some(m) = &n.merges.best {
        out.push((MERGE_BEST, png(&charts::merge(m, 800, 640)?)?));
    }
    Ok(out)
}

/// Top-down's first split, explained.
fn first_split(n: &Numbers) -> Option<&explain::SplitLesson> {
    n.top.explain.as_ref().and_then(|e| e.splits.first())
}

/// Bottom-up's merge that leaves the merge page's slab count, explained.
fn last_merge(n: &Numbers) -> Option<&explain::MergeLesson> {
    n.merges.last.as_ref()
}

/// The charts a page of the volume's own numbers shows, by its title.
fn charts_of(title: &str, n: &Numbers) -> Vec<&'static str> {
    match title {
        "Slicing along the best axis" | "Further splits and the gain curve" => vec![CURVES],
        "The first split" if first_split(n).is_some() => vec![SPLIT],
        "A merge" => [
            (MERGE_BEST, n.merges.best.is_some()),
            (MERGE, last_merge(n).is_some()),
        ]
        .into_iter()
        .filter_map(|(file, drawn)| drawn.then_some(file))
        .collect(),
        _ => Vec::new(),
    }
}

fn png(p: &tiny_skia::Pixmap) -> Result<Vec<u8>> {
    Ok(slabscope::render::encode(
        p,
        slabscope::render::ImageOutput::Png,
    )?)
}

/// Page `i`'s numbers, the lines that say them, and its pictures.
fn page(i: usize, n: &Numbers) -> Exported {
    let w = worked();
    let one = |numbers: Value, lines: Vec<String>, pictures: Vec<&'static str>| Exported {
        numbers,
        lines,
        pictures,
    };
    match PAGES[i].board {
        Some(Board::Blocks) => return one(json!(w.ray), w.ray.lines(), Vec::new()),
        Some(Board::Js) => return one(json!(w.js), w.js.lines(), vec![WORKED_JS]),
        Some(Board::Nmi) => return one(json!(w.nmi), w.nmi.lines(), vec![WORKED_NMI]),
        Some(Board::Sphere) => return sphere_page(n),
        Some(Board::Rays) => return rays_page(n),
        None => {}
    }
    volume_page(i, n)
}

fn sphere_page(n: &Numbers) -> Exported {
    let views = n.top.views.as_ref();
    let h = |v: Option<&slabscope::view::AxisEntropy>| v.map(slabscope::view::score);
    let level = views.map_or(1, |v| v.params.level);
    let points = slabscope::view::icosphere::icosphere(level).len();
    Exported {
        numbers: json!({
            "level": level,
            "viewpoints": points,
            "axes": points / 2,
            "best_axis": n.top.axis(),
            "best_h": h(views.and_then(|v| v.views.first())),
            "worst_h": h(views.and_then(|v| v.views.iter().rev().find(|a| a.measured()))),
        }),
        lines: vec![format!(
            "{points} viewpoints, {} axes; the best axis {}",
            points / 2,
            axis_name(n.top.axis())
        )],
        pictures: vec![FIG_1A],
    }
}

fn rays_page(n: &Numbers) -> Exported {
    let lesson = n
        .top
        .explain
        .as_ref()
        .and_then(|e| e.axes.first())
        .map(|a| &a.lesson);
    Exported {
        numbers: json!({
            "bins": lesson.map(|l| l.bins),
            "block": lesson.map(|l| l.block),
            "rays": lesson.map(|l| l.rays),
            "samples": lesson.map(|l| l.samples),
        }),
        lines: lesson
            .map(|l| {
                vec![format!(
                    "{} rays, {} samples, {} bins, blocks of {}",
                    text::grouped(l.rays),
                    text::grouped(l.samples),
                    l.bins,
                    l.block
                )]
            })
            .unwrap_or_default(),
        pictures: vec![FIG_1B],
    }
}

/// A page of the volume's own numbers.
fn volume_page(i: usize, n: &Numbers) -> Exported {
    let part = &n.top.partition;
    let title = PAGES[i].title;
    let (numbers, lines) = match title {
        "The volume and the question" | "The exploded view" => {
            let shown = n.shown();
            let slabs: Vec<String> = shown
                .slabs
                .iter()
                .map(|&(a, b)| format!("{a}–{}", b.saturating_sub(1)))
                .collect();
            let line = format!(
                "{} slabs {} along {}, slices {}",
                shown.slabs.len(),
                shown.method.name(),
                axis_name(shown.axis),
                slabs.join(", ")
            );
            let numbers = json!({
                "dims": n.volume.dims(),
                "spacing": n.volume.spacing(),
                "axis": shown.axis,
                "method": shown.method.name(),
                "slabs": shown.slabs,
            });
            return Exported {
                numbers,
                lines: vec![line],
                pictures: vec![EXPLODED],
            };
        }
        "Blocks and H(X^L)" | "The entropy rate of the best and the worst axis" => {
            axis_page(title, n)
        }
        "The paper and this tool's defaults" => (json!(n.modes), text::mode_lines(&n.modes)),
        "Slicing along the best axis" => (
            json!({"slices": part.slices, "thickness": part.thickness}),
            vec![format!(
                "{} slices of {:.3} mm",
                part.slices, part.thickness
            )],
        ),
        _ => step_page(title, n),
    };
    Exported {
        numbers,
        lines,
        pictures: charts_of(title, n),
    }
}

/// The numbers and lines of the pages on the best (and worst) axis.
fn axis_page(title: &str, n: &Numbers) -> (Value, Vec<String>) {
    let axes: Vec<&explain::AxisLesson> = n
        .top
        .explain
        .as_ref()
        .map(|e| e.axes.iter().map(|a| &a.lesson).collect())
        .unwrap_or_default();
    match (title, axes.as_slice()) {
        ("Blocks and H(X^L)", [best, ..]) => (
            axis_numbers(best),
            text::axis_lines("the best axis", best, 8),
        ),
        (_, [best, worst, ..]) => (
            json!({"best": axis_numbers(best), "worst": axis_numbers(worst)}),
            vec![text::rate_sentence(
                "the best axis",
                best,
                "the worst",
                worst,
            )],
        ),
        _ => (Value::Null, Vec::new()),
    }
}

/// The numbers and lines of the pages on the partition's steps.
fn step_page(title: &str, n: &Numbers) -> (Value, Vec<String>) {
    let (part, bottom) = (&n.top.partition, &n.bottom.partition);
    let e = n.top.explain.as_ref();
    let splits = e.map(|e| e.splits.as_slice()).unwrap_or_default();
    let none = || (Value::Null, Vec::new());
    match title {
        "The first split" => splits
            .first()
            .map_or_else(none, |s| (json!(s), text::split_lines(s, n.slabs() - 1))),
        "Further splits and the gain curve" => (
            json!({
                "information": splits.iter().map(|s| s.information).collect::<Vec<_>>(),
                "entropy": part.entropy,
            }),
            splits
                .iter()
                .map(|s| {
                    format!(
                        "after split {}: I = {:.4} bits of H = {:.4}",
                        s.step, s.information, part.entropy
                    )
                })
                .collect(),
        ),
        "A merge" => n.merges.page(),
        "Top-down against bottom-up" => (
            json!({
                "top_down": part.information,
                "bottom_up": bottom.information,
                "entropy": part.entropy,
                "top_down_slabs": part.slabs,
                "bottom_up_slabs": bottom.slabs,
            }),
            [format!(
                "Here {} slabs keep {:.4} bits top-down and {:.4} bits bottom-up, of H = {:.4}.",
                n.slabs(),
                part.information,
                bottom.information,
                part.entropy
            )]
            .into_iter()
            .chain(n.merges.given.as_ref().map(explain::boundaries_sentence))
            .collect(),
        ),
        "The optimum" => match e.and_then(|e| e.optimal.as_ref()) {
            Some(o) => (json!(o), text::optimal_lines(o)),
            None => (
                Value::Null,
                vec!["the optimum was not computed for this stack".into()],
            ),
        },
        _ => none(),
    }
}

/// An axis lesson's numbers without its full block tables (the ten most frequent blocks).
fn axis_numbers(a: &explain::AxisLesson) -> Value {
    json!({
        "axis": a.axis,
        "bins": a.bins,
        "block": a.block,
        "rays": a.rays,
        "samples": a.samples,
        "block_entropies": a.block_entropies,
        "entropy_rate": a.entropy_rate,
        "top_blocks": a.blocks.iter().take(10).collect::<Vec<_>>(),
    })
}

/// The pages as Markdown: a section each, its paragraph, its pictures and its numbers' lines.
fn markdown(name: &str, mode: &str, pages: &[Exported]) -> String {
    let mut out = format!("# The paper in {} pages: {name} ({mode})\n", PAGES.len());
    for (i, (p, e)) in PAGES.iter().zip(pages).enumerate() {
        let _ = write!(out, "\n## {}. {}\n\n{}\n", i + 1, p.title, p.text);
        for picture in &e.pictures {
            let _ = write!(out, "\n![{}]({picture})\n", p.title);
        }
        if !e.lines.is_empty() {
            out.push_str("\n```text\n");
            for l in &e.lines {
                out.push_str(l);
                out.push('\n');
            }
            out.push_str("```\n");
        }
    }
    out
}
