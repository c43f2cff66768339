//! `slabscope triage DIR|FILES...`: every volume under the paths, one row each (a table, JSON
//! Lines or CSV), a broken file a row with its error; shards for clusters, and a manifest so that
//! shards need not walk the folders again.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;
use slabscope::Error;
use slabscope::error::names::controls;
use slabscope::params::{Given, Terms, table};
use slabscope::render::{ImageOutput, encode, sheet};
use slabscope::triage::{
    Entry, Source, TriageOutcome, TriagePlan, TriageRow, manifest_lines, select,
};

use super::args::{AnalysisArgs, LoadArgs};
use super::params::{self, Flags};
use super::progress::Bar;

/// Arguments of `slabscope triage`.
#[derive(Debug, Args)]
pub struct TriageArgs {
    /// Folders (walked recursively; a folder of TIFF slices is one volume) and files.
    #[arg(required_unless_present = "manifest")]
    pub paths: Vec<PathBuf>,
    /// One JSON object per volume and line (JSON Lines).
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// Comma-separated values, with a header line.
    #[arg(long)]
    pub csv: bool,
    /// Print the sorted list of volumes and stop: a manifest for --manifest (a header line, then
    /// one volume a line, names escaped).
    #[arg(long, conflicts_with_all = ["json", "csv"])]
    pub list: bool,
    /// Read the list of volumes from FILE (as --list writes it, or one path a line as it is)
    /// instead of walking folders.
    #[arg(long, value_name = "FILE", conflicts_with = "paths")]
    pub manifest: Option<PathBuf>,
    /// `--shard` and `--full`.
    #[command(flatten)]
    pub shard: Flags<params::Shard>,
    /// Also write a contact sheet: per volume, numbered in row order, its exploded view and its
    /// three orthogonal mid slices.
    #[arg(long, value_name = "OUT.png")]
    pub sheet: Option<PathBuf>,
    #[command(flatten)]
    pub tile: Flags<params::Tile>,
    /// Overwrite the sheet if it exists.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub timeout: Flags<params::TriageTimeout>,
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    #[command(flatten)]
    pub load: LoadArgs,
}

impl TriageArgs {
    /// `--tile`: the size of the sheet's pictures.
    fn tile(&self) -> slabscope::Result<u32> {
        self.tile.given.number(&table::TILE)
    }

    /// The values of triage's own flags given.
    fn own(&self) -> Given {
        let mut own = self.shard.given.clone();
        own.extend(&self.tile.given);
        own.extend(&self.timeout.given);
        own
    }
}

/// Runs triage; the exit status: 0 when every volume was looked at, 1 when some failed (their
/// rows printed), 2 for an error before any row.
pub fn run(args: &TriageArgs) -> Result<u8> {
    let volumes = match volumes(args).and_then(|v| check_sheet(args, &v).map(|()| v)) {
        Ok(v) => v,
        Err(e) => {
            eprintln!("slabscope: error: {}", super::error_message(&e));
            return Ok(2);
        }
    };
    if args.list {
        for line in manifest_lines(&volumes) {
            outln!("{line}");
        }
        return Ok(0);
    }
    if volumes.is_empty() {
        return Ok(0);
    }
    if args.csv {
        outln!("{}", CSV_HEADER.join(","));
    } else if !args.json {
        outln!(
            "   {:<11} {:<13} {:<19} {:<4} {:<5} {:<22} {:>2} path  (problems)",
            "format",
            "dims",
            "spacing mm",
            "orient",
            "type",
            "best axis (? uncertain)",
            "K"
        );
    }
    let bar = Bar::volumes(volumes.len());
    let mut failed = 0;
    let mut cells = Vec::new();
    let mut result = Ok(());
    look_all(&volumes, args, |i, TriageOutcome { row, cell }| {
        bar.set_done(i + 1);
        failed += usize::from(row.error.is_some());
        if args.sheet.is_some() {
            cells.push(cell);
        }
        let line = if args.json {
            slabscope::report::to_json_line(&row).map_err(anyhow::Error::from)
        } else if args.csv {
            Ok(csv_line(&row))
        } else {
            Ok(table_line(&row))
        };
        match line {
            Ok(line) => {
                bar.suspend(|| outln!("{line}"));
                true
            }
            Err(e) => {
                result = Err(e);
                false
            }
        }
    })?;
    result?;
    drop(bar);
    if let Some(out) = &args.sheet {
        let picture = sheet::sheet(&cells, args.tile()?, sheet_columns(cells.len()))?;
        super::write_new(
            out,
            &encode(&picture, ImageOutput::for_path(out)?)?,
            args.force,
        )?;
    }
    Ok(u8::from(failed > 0))
}

/// Columns of the sheet: about as many as rows (cells are twice as wide as high).
fn sheet_columns(count: usize) -> usize {
    ((count as f64 / 2.0).sqrt().ceil() as usize).max(1)
}

/// Before any work: the sheet can be written (a new picture, not an input) and will fit.
fn check_sheet(args: &TriageArgs, volumes: &[Entry]) -> Result<()> {
    if let Some(out) = &args.sheet {
        ImageOutput::for_path(out)?;
        let inputs: Vec<PathBuf> = volumes.iter().map(|v| v.path.clone()).collect();
        super::check_outputs(&[out], &inputs, args.force)?;
        sheet::check_sheet(volumes.len(), args.tile()?, sheet_columns(volumes.len()))?;
    }
    Ok(())
}

/// The volumes a run takes (see `slabscope::triage::select`); an empty shard is said in a note.
fn volumes(args: &TriageArgs) -> Result<Vec<Entry>> {
    let source = match &args.manifest {
        Some(m) => Source::Manifest(m),
        None => Source::Paths(&args.paths),
    };
    let selection = select(source, &args.load.options()?, args.shard.given.shard()?)?;
    if let Some(note) = selection.note {
        eprintln!("slabscope: note: {}", controls(&note));
    }
    Ok(selection.volumes)
}

/// Every volume's row (and cell), looked at as `slabscope::triage::look_all` does, errors worded
/// in the CLI's terms and without the path the row names; handed to `emit` in order.
fn look_all(
    volumes: &[Entry],
    args: &TriageArgs,
    emit: impl FnMut(usize, TriageOutcome) -> bool,
) -> Result<()> {
    let how = TriagePlan::given(
        &args.own(),
        args.load.options()?,
        args.analysis.params(false)?,
        args.sheet.is_some(),
    )?;
    // A row names its file: its error need not (told by the error's path, not its words).
    let describe = |path: &Path, e: Error| match e {
        Error::Cancelled => super::error_message(&e.into()),
        e => controls(&e.in_terms_within(Terms::Flags, path)).into_owned(),
    };
    slabscope::triage::look_all(volumes, &how, WORKERS, None, &describe, emit);
    Ok(())
}

/// Volumes looked at at once, on this machine's two cores.
const WORKERS: usize = 2;

const CSV_HEADER: [&str; 15] = [
    "path",
    "series",
    "format",
    "dims",
    "spacing",
    "orientation",
    "type",
    "min",
    "max",
    "missing",
    "best_axis",
    "entropy_rate",
    "uncertain",
    "slabs",
    "problems",
];

fn triple<T: std::fmt::Display>(v: &[T; 3], sep: &str) -> String {
    format!("{}{sep}{}{sep}{}", v[0], v[1], v[2])
}

fn axis_text(a: &[f64; 3]) -> String {
    format!("{:.3},{:.3},{:.3}", a[0], a[1], a[2])
}

fn slabs_text(slabs: &[[usize; 2]]) -> String {
    slabs
        .iter()
        .map(|s| format!("{}-{}", s[0], s[1].saturating_sub(1)))
        .collect::<Vec<_>>()
        .join(" ")
}

/// What is wrong: the error, else the problems (control characters escaped, whatever they quote).
fn problems(row: &TriageRow) -> String {
    let text = match &row.error {
        Some(e) => format!("error: {e}"),
        None => row.problems.join("; "),
    };
    controls(&text).into_owned()
}

/// A CSV field as RFC 4180 writes it: quoted when it holds a comma, a quote or a line break
/// (its quotes doubled), control characters escaped first (names are escaped already), so that
/// none reaches the file raw.
fn field(s: &str) -> String {
    let s = controls(s);
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.into_owned()
    }
}

fn csv_line(row: &TriageRow) -> String {
    let opt = |v: Option<String>| v.unwrap_or_default();
    [
        row.path.clone(),
        opt(row.series.clone()),
        opt(row.format.clone()),
        opt(row.dims.map(|d| triple(&d, "x"))),
        opt(row.spacing.map(|s| triple(&s, "x"))),
        opt(row.orientation.clone()),
        opt(row.voxel_type.clone()),
        opt(row.range.map(|r| r[0].to_string())),
        opt(row.range.map(|r| r[1].to_string())),
        opt(row.missing.map(|m| m.to_string())),
        opt(row.best_axis.as_ref().map(axis_text)),
        opt(row.entropy_rate.map(|h| format!("{h:.4}"))),
        opt(row.uncertain.map(|u| u.to_string())),
        opt(row.slabs.as_deref().map(slabs_text)),
        problems(row),
    ]
    .iter()
    .map(|s| field(s))
    .collect::<Vec<_>>()
    .join(",")
}

/// A row of the table: fixed-width columns, then the path and what is wrong.
fn table_line(row: &TriageRow) -> String {
    let dims = row.dims.map(|d| triple(&d, "x")).unwrap_or_default();
    let spacing = row
        .spacing
        .map(|s| format!("{:.3}x{:.3}x{:.3}", s[0], s[1], s[2]))
        .unwrap_or_default();
    let axis = row.axis_name().unwrap_or_default();
    let verdict = match row.uncertain {
        Some(true) => "?",
        _ => "",
    };
    let slabs = row.slabs.as_ref().map_or(0, Vec::len);
    let status = if row.error.is_some() { "!!" } else { "ok" };
    let wrong = problems(row);
    format!(
        "{status} {:<11} {:<13} {:<19} {:<4} {:<5} {:<22} {:>2} {}{}",
        row.format.as_deref().unwrap_or("-"),
        dims,
        spacing,
        row.orientation.as_deref().unwrap_or("-"),
        row.voxel_type.as_deref().unwrap_or("-"),
        format!("{axis}{verdict}"),
        slabs,
        row.name(),
        if wrong.is_empty() {
            String::new()
        } else {
            format!("  ({wrong})")
        }
    )
}
