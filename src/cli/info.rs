//! `slabscope info FILE`: what a volume is, in a few lines or as JSON.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use slabscope::error::{human_bytes, shown};
use slabscope::formats::{Details, Loaded};
use slabscope::report::{FolderReport, GeometryReport, InfoReport, ListedVolume, to_json};
use slabscope::triage::{Entry, Folder, discover, folder_kind, picks_in_folder};
use slabscope::volume::dims_string;

use super::LoadArgs;

/// Bins of the histogram `info` shows.
const HISTOGRAM_BINS: usize = 32;

/// Arguments of `slabscope info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The volume: a file, a folder of TIFF slices or DICOM files, or an OME-Zarr store (a
    /// folder of volumes is listed).
    pub file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// For a store at a URL, take the statistics (range, mean, missing, histogram) from every
    /// voxel of level 0 rather than from the store's coarsest dataset, which is all `info` reads
    /// of a remote store otherwise
    #[arg(long)]
    pub exact: bool,
    #[command(flatten)]
    pub load: LoadArgs,
}

pub fn run(args: &InfoArgs) -> Result<()> {
    // A folder of volumes, or of several DICOM series, is listed, one a line (what `triage`
    // would look at).
    let dir = &args.file;
    let opts = args.load.options()?;
    let listed = if dir.is_dir() && !picks_in_folder(&opts) {
        match folder_kind(dir)? {
            Folder::Collection => Some(discover(std::slice::from_ref(dir), &opts)?),
            Folder::Series => {
                Some(discover(std::slice::from_ref(dir), &opts)?).filter(|series| series.len() > 1)
            }
            Folder::Slices | Folder::Store | Folder::Empty => None,
        }
    } else {
        None
    };
    if let Some(volumes) = listed {
        if args.json {
            let listed = volumes.iter().map(listed_volume).collect();
            outln!("{}", to_json(&FolderReport::new(dir, listed))?);
        } else {
            outln!("folder      {}", shown(dir));
            outln!(
                "volumes     {} (a collection: `slabscope triage` looks at them all; --series \
                 N|UID picks a DICOM series)",
                volumes.len()
            );
            let positions = slabscope::triage::series_positions(&volumes, &args.load.options()?);
            for (v, at) in volumes.iter().zip(positions) {
                match at {
                    Some(n) => outln!("            {}  (--series {n})", v.name()),
                    None => outln!("            {}", v.name()),
                }
            }
        }
        return Ok(());
    }
    // A remote store's statistics from its coarsest dataset: a few requests, not level 0.
    let coarsest = if slabscope::formats::remote::is_url(&args.file) && !args.exact {
        super::progress::while_reading(&args.file, || {
            slabscope::formats::load_preview(&args.file, &opts, 0)
        })?
    } else {
        None
    };
    let loaded = match coarsest {
        Some(loaded) => {
            for n in &loaded.notes {
                super::note(&args.file, n);
            }
            loaded
        }
        None => super::load(&args.file, &args.load)?,
    };
    print(&shown(&args.file), &loaded, args.json)
}

/// A volume of a folder as the folder's report lists it.
fn listed_volume(entry: &Entry) -> ListedVolume {
    ListedVolume {
        path: shown(&entry.path),
        series: entry.series.clone(),
        label: entry.label.clone(),
    }
}

fn print(name: &str, loaded: &Loaded, json: bool) -> Result<()> {
    let report = InfoReport::new(name, loaded, HISTOGRAM_BINS)?;
    if json {
        outln!("{}", to_json(&report)?);
        return Ok(());
    }
    let (format, v) = (loaded.format, &loaded.volume);
    let s = v.stats();
    let (hist, geometry) = (&report.histogram, &report.geometry);
    let [nx, ny, nz] = report.dims;
    let [sx, sy, sz] = report.spacing;
    outln!("file        {name}");
    let details = loaded.details.as_deref();
    match (
        details.and_then(Details::format_words),
        &loaded.format_version,
    ) {
        (Some(words), _) => outln!("format      {} ({words})", format.name()),
        (None, Some(version)) => outln!("format      {} (version {version})", format.name()),
        (None, None) => outln!("format      {}", format.name()),
    }
    for (label, text) in details.map(Details::lines).unwrap_or_default() {
        outln!("{label:<11} {text}");
    }
    outln!(
        "dims        {}  ({} voxels)",
        dims_string(report.dims),
        report.voxels
    );
    let (unit, per_mm) = slabscope::geometry::length_unit(sx.max(sy).max(sz));
    outln!(
        "spacing     {} x {} x {} {unit}  (extent {} x {} x {} {unit})",
        significant(sx * per_mm),
        significant(sy * per_mm),
        significant(sz * per_mm),
        extent(sx * per_mm * nx as f64),
        extent(sy * per_mm * ny as f64),
        extent(sz * per_mm * nz as f64)
    );
    print_geometry(geometry);
    outln!("type        {}", v.voxel_type());
    if let Some(from) = &report.statistics_from {
        outln!(
            "statistics  from pyramid level {} ({}, a voxel for {} of level 0's), the store's \
             coarsest: --exact reads every voxel",
            from.pyramid_level,
            dims_string(from.dims),
            dims_string(from.factor)
        );
    }
    if s.finite == 0 {
        outln!("range       none: every voxel is NaN or infinite");
    } else {
        outln!("range       {} .. {}", s.min, s.max);
        outln!("mean        {:.6}", s.mean);
    }
    if s.missing > 0 {
        outln!("missing     {} NaN/Inf voxels", s.missing);
    }
    print_memory(v);
    outln!(
        "histogram   {}  ({HISTOGRAM_BINS} bins, log scale)",
        sparkline(hist)
    );
    Ok(())
}

/// Where the voxels are held: memory, the file mapped, or a scratch file mapped.
fn print_memory(v: &slabscope::Volume) {
    let held = v.data().held();
    if v.scratch_bytes() > 0 {
        let bytes = human_bytes(v.scratch_bytes());
        outln!("memory      none: {bytes} of {held} decoded into a scratch file on disk (mapped)");
    } else if v.mapped_bytes() > 0 {
        let bytes = human_bytes(v.mapped_bytes());
        outln!("memory      none: {bytes} of {held} read in place from the file (mapped)");
    } else {
        outln!("memory      {} as {held}", human_bytes(v.memory_bytes()));
    }
}

/// The orientation, the transform and the world box.
fn print_geometry(g: &GeometryReport) {
    let Some(codes) = &g.orientation else {
        outln!("orientation unknown: the file states none (no anatomical directions are named)");
        return;
    };
    let axes: Vec<String> = ["x", "y", "z"]
        .iter()
        .zip(codes.chars())
        .map(|(a, c)| format!("{a} to {}", side(c)))
        .collect();
    let shear = if g.orthogonal {
        String::new()
    } else {
        "; sheared: the voxel axes are not perpendicular".into()
    };
    outln!("orientation {codes}  ({}{shear})", axes.join(", "));
    for (r, row) in g.affine.iter().take(3).enumerate() {
        let label = if r == 0 { "affine" } else { "" };
        let cells: Vec<String> = row.iter().map(|x| format!("{:>9}", number(*x))).collect();
        outln!("{label:<11} [{} ]  {}", cells.join(" "), ["R", "A", "S"][r]);
    }
    let [lo, hi] = g.world_bounds;
    outln!(
        "world box   R {} .. {}, A {} .. {}, S {} .. {} mm",
        number(lo[0]),
        number(hi[0]),
        number(lo[1]),
        number(hi[1]),
        number(lo[2]),
        number(hi[2])
    );
}

/// The anatomical side a code letter names.
fn side(code: char) -> &'static str {
    match code {
        'R' => "right",
        'L' => "left",
        'A' => "anterior",
        'P' => "posterior",
        'S' => "superior",
        _ => "inferior",
    }
}

/// `x` with at most 4 decimals and no trailing zeros.
/// `x` to 12 significant digits, as short as that allows: a spacing computed from positions
/// (3.3000000000000007) reads as it was meant (3.3).
fn significant(x: f64) -> String {
    let rounded: f64 = format!("{x:.11e}").parse().unwrap_or(x);
    format!("{rounded}")
}

fn number(x: f64) -> String {
    let s = format!("{:.4}", x + 0.0);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// One character per bin, heights by log(1 + count); empty bins are blank.
pub fn sparkline(counts: &[u64]) -> String {
    const BARS: [char; 8] = ['▁', '▂', '▃', '▄', '▅', '▆', '▇', '█'];
    let top = counts
        .iter()
        .map(|&c| (c as f64).ln_1p())
        .fold(0.0, f64::max);
    counts
        .iter()
        .map(|&c| {
            if c == 0 || top == 0.0 {
                ' '
            } else {
                let level = ((c as f64).ln_1p() / top * 7.0).round() as usize;
                BARS[level.min(7)]
            }
        })
        .collect()
}

/// An extent in mm: to a tenth of a millimetre, or to three significant digits below that
/// (a microscope's stack is micrometres across).
fn extent(mm: f64) -> String {
    if mm >= 0.1 || mm <= 0.0 {
        format!("{mm:.1}")
    } else {
        let digits = (2 - mm.log10().floor() as i32).max(0) as usize;
        format!("{mm:.digits$}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sparkline_scales_by_log() {
        assert_eq!(sparkline(&[0, 1, 1_000_000]), " ▁█");
        assert_eq!(sparkline(&[100, 1_000_000]), "▃█");
        assert_eq!(sparkline(&[0, 0]), "  ");
    }

    #[test]
    fn spacings_keep_twelve_significant_digits() {
        assert_eq!(significant(3.300_000_000_000_000_7), "3.3");
        assert_eq!(significant(0.000_25), "0.00025");
        assert_eq!(significant(0.781_25), "0.78125");
    }

    #[test]
    fn extents_keep_three_digits_below_a_tenth_of_a_millimetre() {
        assert_eq!(super::extent(181.0), "181.0");
        assert_eq!(super::extent(0.1), "0.1");
        assert_eq!(super::extent(0.0025), "0.00250");
        assert_eq!(super::extent(0.06), "0.0600");
    }
}
