//! The flags several commands share: how to read a file, and how to analyse it (view search and
//! partition). `slabscope [FILE]` takes the same analysis flags as `analyze`.

use clap::{Args, ValueEnum};
use slabscope::analysis::AxisBy;
use slabscope::geometry::AxisChoice;
use slabscope::volume::background::BackgroundRule;
use slabscope::volume::io::{RawOptions, default_max_memory, parse_bytes, parse_dims};
use slabscope::volume::{Endian, VoxelType};
use slabscope::{AnalysisParams, LoadOptions, Method, SamplingParams, Stop, ViewParams};

/// How to read the input: needed only for headerless raw files, and to change the memory limit.
#[derive(Debug, Args, Clone, Default)]
pub struct LoadArgs {
    /// Dimensions of a headerless raw file, NXxNYxNZ (makes any file load as raw).
    #[arg(long, value_name = "NXxNYxNZ", value_parser = parse_dims_arg)]
    pub dims: Option<[usize; 3]>,
    /// Voxel type of a raw file: u8, i8, u16, i16, u32, i32, f32 or f64.
    #[arg(long = "type", value_name = "TYPE", value_parser = parse_type_arg)]
    pub voxel_type: Option<VoxelType>,
    /// Voxel spacing of a raw file in mm, SX,SY,SZ.
    #[arg(long, value_name = "SX,SY,SZ", value_parser = parse_spacing_arg)]
    pub spacing: Option<[f64; 3]>,
    /// Byte order of a raw file.
    #[arg(long, value_name = "little|big", value_parser = parse_endian_arg)]
    pub endian: Option<Endian>,
    /// Bytes to skip at the start of a raw file.
    #[arg(long, value_name = "BYTES")]
    pub offset: Option<u64>,
    /// The most memory the volume and its analysis may take, e.g. 8G (default: half the physical
    /// memory); a file read in place (mapped) is not counted, and an analysis that would not fit
    /// runs on the finest pyramid level that does.
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes_arg)]
    pub max_memory: Option<u64>,
    /// Which volume of a 4D file (NIfTI, NRRD, MetaImage, DICOM; an OME-TIFF's or OME-Zarr's
    /// time point) to read, from 0.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub volume: usize,
    /// Which channel of a multichannel file (OME-TIFF, OME-Zarr), from 0.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub channel: usize,
    /// Which series of a DICOM folder: its position in the folder's list `info` gives (from 1,
    /// shown as `--series N` there), or its `SeriesInstanceUID`; `triage` then gives that
    /// series' rows only.
    #[arg(long, value_name = "N|UID")]
    pub series: Option<String>,
    /// Keep DICOM localizer (scout) and derived images, left out by default.
    #[arg(long)]
    pub include_localizers: bool,
    /// Resample a DICOM series with gaps, uneven spacing or gantry tilt to an even, orthogonal
    /// grid (otherwise kept as it is, with a warning; tilt as a sheared transform).
    #[arg(long)]
    pub resample: bool,
    /// Show patient-identifying DICOM fields (name, ID, birth date, ...), hidden by default.
    #[arg(long)]
    pub show_phi: bool,
    /// Read the label image NAME of an OME-Zarr store (its `labels/NAME`) instead of its image.
    #[arg(long, value_name = "NAME")]
    pub label_image: Option<String>,
}

impl LoadArgs {
    /// The library's load options.
    pub fn options(&self) -> LoadOptions {
        LoadOptions {
            max_memory: self.max_memory.unwrap_or_else(default_max_memory),
            raw: RawOptions {
                dims: self.dims,
                voxel_type: self.voxel_type,
                spacing: self.spacing,
                endian: self.endian,
                offset: self.offset,
            },
            volume: self.volume,
            channel: self.channel,
            series: self.series.clone(),
            include_localizers: self.include_localizers,
            resample: self.resample,
            show_phi: self.show_phi,
            label_image: self.label_image.clone(),
        }
    }
}

/// How to find the most structured view and the slabs along it.
#[derive(Debug, Args, Clone)]
pub struct AnalysisArgs {
    /// Quantization bins.
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u16).range(2..=255))]
    pub bins: u16,
    /// Block length L of the entropy rate H(X^L) - H(X^(L-1)).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(2..=4))]
    pub block: u8,
    /// Icosphere level: 0, 1, 2, 3 or 4 for 12, 42, 162, 642 or 2562 viewpoints.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=4))]
    pub level: u8,
    /// Distance between rays in mm (default: the smallest voxel spacing).
    #[arg(long, value_name = "MM", value_parser = positive)]
    pub ray_spacing: Option<f64>,
    /// Distance between samples along a ray in mm (default: the smallest voxel spacing).
    #[arg(long, value_name = "MM", value_parser = positive)]
    pub sample_spacing: Option<f64>,
    /// Rank axes by the mean of h over N lattice phases, the paper's lattice among them (0: by
    /// the paper's single lattice, as the paper does).
    #[arg(long, value_name = "N", default_value_t = 8, value_parser = clap::value_parser!(u8).range(0..=64))]
    pub phases: u8,
    /// Each shifted lattice walks one block of rays in K, spread over the volume (1: every ray).
    #[arg(long, value_name = "K", default_value_t = slabscope::view::DEFAULT_PHASE_SUBSET, value_parser = clap::value_parser!(u64).range(1..=64))]
    pub phase_subset: u64,
    /// Refine the best axes on a finer local search, to within 2 degrees.
    #[arg(long)]
    pub refine: bool,
    /// The axis: best (the view search's), x, y, z, a direction DX,DY,DZ, or axial, coronal,
    /// sagittal (the volume axis nearest that plane's normal; needs a stated orientation).
    #[arg(long, default_value = "best", value_parser = parse_axis)]
    pub axis: AxisChoice,
    /// Which ranking picks the axis: entropy (the lowest entropy rate, the paper's most
    /// structured view) or gain (the axes ranked by the information their top-down slabs keep).
    #[arg(long, value_enum, default_value_t = AxisByArg::Entropy)]
    pub axis_by: AxisByArg,
    /// Rank the axes by partition gain too, without changing which ranking picks the axis.
    #[arg(long)]
    pub gain: bool,
    /// How to find the slabs.
    #[arg(long, value_enum, default_value_t = MethodArg::Topdown)]
    pub method: MethodArg,
    /// Number of slabs.
    #[arg(long, value_name = "K", conflicts_with = "threshold")]
    pub slabs: Option<usize>,
    /// Stop when the best ΔI (topdown), the largest NMI (bottomup), or the gain of one more slab
    /// (optimal) falls below T.
    #[arg(long, value_name = "T", value_parser = within(0.0, 1e6))]
    pub threshold: Option<f64>,
    /// The background left out of slab histograms: auto (the region connected to the border at
    /// or below a threshold from the border voxels), none (every voxel, as the paper), or VALUE
    /// (every voxel at or below it).
    #[arg(long, value_name = "auto|none|VALUE", default_value = "auto", value_parser = parse_background, allow_hyphen_values = true)]
    pub background: BackgroundRule,
}

fn parse_axis(s: &str) -> Result<AxisChoice, String> {
    s.parse().map_err(|_| {
        format!("{s:?} is not best, x, y, z, axial, coronal, sagittal or a direction DX,DY,DZ")
    })
}

/// The rankings that can pick the axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AxisByArg {
    /// The lowest entropy rate (paper §4).
    Entropy,
    /// The most information kept by the axis's top-down slabs.
    Gain,
}

/// The partition methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Greedy splits by information gain (paper §5.1).
    Topdown,
    /// Greedy merges by normalized mutual information (paper §5.2).
    Bottomup,
    /// The partition that keeps the most information (dynamic programming).
    Optimal,
}

impl AnalysisArgs {
    /// Runs the analysis of `volume` (read from `name`) with a progress bar; an error names the
    /// file, and a slab count the user did not give is not blamed on `--slabs`.
    pub fn analyze(
        &self,
        name: &str,
        plan: &slabscope::Plan,
        search_views: bool,
    ) -> anyhow::Result<slabscope::Analysis> {
        self.analyze_with(name, plan, &self.params(search_views))
    }

    /// [`analyze`](Self::analyze) with these arguments' `params`, amended by the caller.
    pub fn analyze_with(
        &self,
        name: &str,
        plan: &slabscope::Plan,
        params: &AnalysisParams,
    ) -> anyhow::Result<slabscope::Analysis> {
        let views = plan.views.as_ref();
        if let Some(heavy) = params.heavy_work(views.dims(), views.spacing()) {
            eprintln!(
                "slabscope: note: {name}: {heavy}: it may take long; --timeout SECONDS bounds it"
            );
        }
        super::progress::with_bar(|monitor| slabscope::analyze_planned(plan, params, monitor))
            .map_err(|e| match (&e, self.slabs, self.threshold) {
                (
                    slabscope::Error::InvalidParameter {
                        parameter: "slabs",
                        expected,
                        ..
                    },
                    None,
                    None,
                ) => {
                    anyhow::anyhow!(
                        "the default of 4 slabs does not fit: {expected} (--slabs K asks for fewer)"
                    )
                }
                _ => e.into(),
            })
            .map_err(|e| e.context(name.to_string()))
    }

    /// The library's parameters; `search_views` runs the view search even for a named axis.
    pub fn params(&self, search_views: bool) -> AnalysisParams {
        AnalysisParams {
            view: ViewParams {
                sampling: SamplingParams {
                    bins: usize::from(self.bins),
                    ray_spacing: self.ray_spacing,
                    sample_spacing: self.sample_spacing,
                },
                block: usize::from(self.block),
                level: usize::from(self.level),
                phases: usize::from(self.phases),
                phase_subset: self.phase_subset,
                refine: self.refine,
                ..ViewParams::default()
            },
            axis: self.axis,
            search_views,
            method: match self.method {
                MethodArg::Topdown => Method::TopDown,
                MethodArg::Bottomup => Method::BottomUp,
                MethodArg::Optimal => Method::Optimal,
            },
            stop: match (self.slabs, self.threshold) {
                (_, Some(t)) => Stop::Threshold(t),
                (k, None) => Stop::Slabs(k.unwrap_or(4)),
            },
            background: self.background,
            axis_by: match self.axis_by {
                AxisByArg::Entropy => AxisBy::Entropy,
                AxisByArg::Gain => AxisBy::Gain,
            },
            gain: self.gain,
            explain: None,
        }
    }
}

fn parse_background(s: &str) -> Result<BackgroundRule, String> {
    match s.trim() {
        "auto" => Ok(BackgroundRule::Auto),
        "none" => Ok(BackgroundRule::None),
        t => finite(t)
            .map(|v| BackgroundRule::Below(v as f32))
            .map_err(|_| format!("{s:?} is not auto, none or a number")),
    }
}

fn finite(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{s:?} is not a number"))
}

/// A parser of numbers in `lo..=hi`, for float options.
pub fn within(lo: f64, hi: f64) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync {
    move |s: &str| match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!("{s:?} is not a number from {lo} to {hi}")),
    }
}

fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("{s:?} is not a positive number")),
    }
}

/// Parses `NXxNYxNZ`.
/// Two values written `A` then a separator then `B` (spaces around each allowed).
pub fn pair<T: std::str::FromStr>(s: &str, separators: &[char]) -> Option<(T, T)> {
    let (a, b) = s.split_once(separators)?;
    Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
}

pub fn parse_dims_arg(s: &str) -> Result<[usize; 3], String> {
    parse_dims(s).ok_or_else(|| format!("{s:?} is not NXxNYxNZ, e.g. 256x256x113"))
}

fn parse_type_arg(s: &str) -> Result<VoxelType, String> {
    VoxelType::parse(s)
        .ok_or_else(|| format!("{s:?} is not one of u8, i8, u16, i16, u32, i32, f32, f64"))
}

fn parse_spacing_arg(s: &str) -> Result<[f64; 3], String> {
    slabscope::geometry::parse_triple(s)
        .filter(|v| v.iter().all(|x| x.is_finite() && *x > 0.0))
        .ok_or_else(|| format!("{s:?} is not three positive numbers SX,SY,SZ"))
}

fn parse_endian_arg(s: &str) -> Result<Endian, String> {
    match s {
        "little" => Ok(Endian::Little),
        "big" => Ok(Endian::Big),
        _ => Err(format!("{s:?} is not little or big")),
    }
}

fn parse_bytes_arg(s: &str) -> Result<u64, String> {
    parse_bytes(s).ok_or_else(|| format!("{s:?} is not a size such as 512M or 8G"))
}
