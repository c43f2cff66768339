//! The entries: every parameter the CLI and Python share, in the order the CLI's help lists
//! them, and the sets each command takes. The library's own `Default`s agree with the defaults
//! here (a test holds them together). Each entry's `help` is its documentation.
#![allow(missing_docs)]

use super::{Param, Takes, text};
use crate::analysis::AxisBy;
use crate::partition::Method;
use crate::render::{Colormap, Gap, Mode, Preset};

/// A parameter with what every entry shares filled in: flag and keyword from the name.
const fn param(name: &'static str, flag: &'static str, help: &'static str, takes: Takes) -> Param {
    Param {
        name,
        flag,
        keyword: name,
        value_name: None,
        help,
        takes,
        conflicts: &[],
        requires: None,
    }
}

/// A parameter with a placeholder for its value in the help.
const fn named(
    name: &'static str,
    flag: &'static str,
    value_name: &'static str,
    help: &'static str,
    takes: Takes,
) -> Param {
    Param {
        value_name: Some(value_name),
        ..param(name, flag, help, takes)
    }
}

const fn count(min: u64, max: u64, default: Option<u64>) -> Takes {
    Takes::Count { min, max, default }
}

const fn number(min: f64, max: f64, default: f64) -> Takes {
    Takes::Number {
        min,
        max,
        default: Some(default),
    }
}

// The analysis: view search and partition.

pub const BINS: Param = param("bins", "bins", "Quantization bins", count(2, 255, Some(32)));
pub const BLOCK: Param = param(
    "block",
    "block",
    "Block length L of the entropy rate H(X^L) - H(X^(L-1))",
    count(2, 4, Some(3)),
);
pub const LEVEL: Param = param(
    "level",
    "level",
    "Icosphere level: 0, 1, 2, 3 or 4 for 12, 42, 162, 642 or 2562 viewpoints",
    count(0, 4, Some(1)),
);
pub const RAY_SPACING: Param = named(
    "ray_spacing",
    "ray-spacing",
    "MM",
    "Distance between rays in mm (default: the smallest voxel spacing)",
    Takes::Positive,
);
pub const SAMPLE_SPACING: Param = named(
    "sample_spacing",
    "sample-spacing",
    "MM",
    "Distance between samples along a ray in mm (default: the smallest voxel spacing)",
    Takes::Positive,
);
pub const PHASES: Param = named(
    "phases",
    "phases",
    "N",
    "Rank axes by the mean of h over N lattice phases, the paper's lattice among them (0: by \
     the paper's single lattice, as the paper does)",
    count(0, 64, Some(crate::view::DEFAULT_PHASES as u64)),
);
pub const PHASE_SUBSET: Param = named(
    "phase_subset",
    "phase-subset",
    "K",
    "Each shifted lattice walks one block of rays in K, spread over the volume (1: every ray)",
    count(1, 64, Some(crate::view::DEFAULT_PHASE_SUBSET)),
);
pub const REFINE: Param = param(
    "refine",
    "refine",
    "Refine the best axes on a finer local search, to within 2 degrees",
    Takes::Switch,
);
pub const AXIS: Param = param(
    "axis",
    "axis",
    "The axis: best (the view search's), x, y, z, a direction DX,DY,DZ, or axial, coronal, \
     sagittal (the volume axis nearest that plane's normal; needs a stated orientation)",
    Takes::Text {
        valid: |s| text::axis(s).is_some(),
        expected: "best, x, y, z, axial, coronal, sagittal or a direction DX,DY,DZ",
        default: Some("best"),
        hyphens: false,
    },
);
pub const AXIS_BY: Param = param(
    "axis_by",
    "axis-by",
    "Which ranking picks the axis: entropy (the lowest entropy rate, the paper's most \
     structured view) or gain (the axes ranked by the information their top-down slabs keep)",
    Takes::Words {
        words: super::choices::words::<AxisBy>,
        default: "entropy",
    },
);
pub const GAIN: Param = param(
    "gain",
    "gain",
    "Rank the axes by partition gain too, without changing which ranking picks the axis",
    Takes::Switch,
);
pub const METHOD: Param = param(
    "method",
    "method",
    "How to find the slabs",
    Takes::Words {
        words: super::choices::words::<Method>,
        default: "topdown",
    },
);
pub const SLABS: Param = Param {
    conflicts: &["threshold"],
    ..named(
        "slabs",
        "slabs",
        "K",
        "Number of slabs",
        count(0, u64::MAX, Some(4)),
    )
};
pub const THRESHOLD: Param = Param {
    conflicts: &["slabs"],
    ..named(
        "threshold",
        "threshold",
        "T",
        "Stop when the best ΔI (topdown), the largest NMI (bottomup), or the gain of one more \
         slab (optimal) falls below T",
        Takes::Number {
            min: 0.0,
            max: 1e6,
            default: None,
        },
    )
};
pub const BACKGROUND: Param = named(
    "background",
    "background",
    "auto|none|VALUE",
    "The background left out of slab histograms: auto (the region connected to the border at or \
     below a threshold from the border voxels), none (every voxel, as the paper), or VALUE \
     (every voxel at or below it)",
    Takes::Text {
        valid: |s| text::background(s).is_some(),
        expected: "auto, none or a number",
        default: Some("auto"),
        hyphens: true,
    },
);

/// The analysis's parameters, in the help's order.
pub const ANALYSIS: &[&Param] = &[
    &BINS,
    &BLOCK,
    &LEVEL,
    &RAY_SPACING,
    &SAMPLE_SPACING,
    &PHASES,
    &PHASE_SUBSET,
    &REFINE,
    &AXIS,
    &AXIS_BY,
    &GAIN,
    &METHOD,
    &SLABS,
    &THRESHOLD,
    &BACKGROUND,
];

// How values become colours.

pub const TF: Param = named(
    "tf",
    "tf",
    "PRESET",
    "Transfer function (auto: windowed on what is not background, CT in a soft-tissue window, \
     label volumes in distinct colours)",
    Takes::Words {
        words: super::choices::words::<Preset>,
        default: "auto",
    },
);
pub const COLORMAP: Param = param(
    "colormap",
    "colormap",
    "Colour map",
    Takes::Words {
        words: super::choices::words::<Colormap>,
        default: "grey",
    },
);
pub const WINDOW: Param = named(
    "window",
    "window",
    "LO,HI",
    "Window LO,HI: grey from LO to HI and opacity rising across it (replaces the preset's)",
    Takes::Text {
        valid: |s| text::window(s).is_some(),
        expected: "LO,HI with LO below HI, e.g. -200,1500",
        default: None,
        hyphens: true,
    },
);

/// The look's parameters.
pub const LOOK: &[&Param] = &[&TF, &COLORMAP, &WINDOW];

// The scene: what the render shows and how (the look comes second in the help).

pub const MODE: Param = param(
    "mode",
    "mode",
    "Cut faces (the cross-section at every cut, the volume rendered behind), plain direct volume \
     rendering, or maximum intensity projection",
    Takes::Words {
        words: super::choices::words::<Mode>,
        default: "cut",
    },
);
pub const AZIMUTH: Param = param(
    "azimuth",
    "azimuth",
    "Camera angle around the slab axis, degrees",
    number(-360.0, 360.0, 30.0),
);
pub const ELEVATION: Param = param(
    "elevation",
    "elevation",
    "Camera angle above the slab planes, degrees",
    number(-90.0, 90.0, 20.0),
);
pub const ZOOM: Param = param(
    "zoom",
    "zoom",
    "Magnification (1 fits the scene)",
    number(0.05, 50.0, 1.0),
);
pub const PERSPECTIVE: Param = param(
    "perspective",
    "perspective",
    "Perspective projection instead of orthographic",
    Takes::Switch,
);
pub const GAP: Param = param(
    "gap",
    "gap",
    "Gaps between slabs: all equal, or wider where neighbouring slabs are less alike",
    Takes::Words {
        words: super::choices::words::<Gap>,
        default: "similarity",
    },
);
pub const SPREAD: Param = param(
    "spread",
    "spread",
    "Total gap as a fraction of the stack's length",
    number(0.0, 10.0, crate::render::DEFAULT_SPREAD),
);
pub const HIGHLIGHT: Param = named(
    "highlight",
    "highlight",
    "SLAB",
    "Show this slab normally and the others faint",
    count(0, u64::MAX, None),
);
pub const SOLO: Param = Param {
    requires: Some("highlight"),
    ..param(
        "solo",
        "solo",
        "Show only the highlighted slab",
        Takes::Switch,
    )
};
pub const STEP: Param = param(
    "step",
    "step",
    "Sample distance along rays, in smallest voxel spacings",
    number(0.05, 10.0, 1.0),
);
pub const NO_SHADING: Param = param(
    "no_shading",
    "no-shading",
    "No gradient shading",
    Takes::Switch,
);
pub const NO_OUTLINES: Param = param(
    "no_outlines",
    "no-outlines",
    "No slab outlines",
    Takes::Switch,
);
pub const NO_LABELS: Param = param("no_labels", "no-labels", "No slab numbers", Takes::Switch);

/// The scene's parameters before the look (the mode).
pub const SCENE_FIRST: &[&Param] = &[&MODE];
/// The scene's parameters after the look.
pub const SCENE: &[&Param] = &[
    &AZIMUTH,
    &ELEVATION,
    &ZOOM,
    &PERSPECTIVE,
    &GAP,
    &SPREAD,
    &HIGHLIGHT,
    &SOLO,
    &STEP,
    &NO_SHADING,
    &NO_OUTLINES,
    &NO_LABELS,
];

// What `analyze` computes on, beyond the analysis's own parameters.

pub const VIEWS: Param = param(
    "views",
    "views",
    "Also run the view search when --axis names an axis",
    Takes::Switch,
);
pub const RESOLUTION: Param = named(
    "resolution",
    "resolution",
    "auto|full|K",
    "The pyramid level to compute on: full (every voxel, the paper's method), auto (the coarsest \
     level with at least 128 voxels along every axis), or a level number K (each level halves \
     every axis, averaging 2x2x2 blocks; for an OME-Zarr store, K names the store's K-th dataset \
     when its datasets make the pyramid, halving y and x only if they do)",
    Takes::Text {
        valid: |s| text::resolution(s).is_some(),
        expected: "auto, full or a pyramid level number",
        default: Some("full"),
        hyphens: false,
    },
);

// Pictures and slices.

/// A picture's size, `WxH`, with its default.
const fn size(help: &'static str, default: &'static str) -> Param {
    named(
        "size",
        "size",
        "WxH",
        help,
        Takes::Text {
            valid: |s| text::size(s).is_some(),
            expected: "a size WxH between 1x1 and 8192x8192, e.g. 640x480",
            default: Some(default),
            hyphens: false,
        },
    )
}

pub const RENDER_SIZE: Param = size("Image size", "640x480");
pub const SLICE_SIZE: Param = size(
    "The size the slice is scaled to fit, keeping its shape",
    "512x512",
);
pub const INDEX: Param = named(
    "index",
    "index",
    "I",
    "The slice, counted from 0 along the axis (default: the middle one)",
    count(0, u64::MAX, None),
);

// How to read the input.

pub const DIMS: Param = named(
    "dims",
    "dims",
    "NXxNYxNZ",
    "Dimensions of a headerless raw file, NXxNYxNZ (makes any file load as raw)",
    Takes::Text {
        valid: |s| text::dims(s).is_some(),
        expected: "NXxNYxNZ, e.g. 256x256x113",
        default: None,
        hyphens: false,
    },
);
pub const TYPE: Param = Param {
    keyword: "dtype",
    ..named(
        "type",
        "type",
        "TYPE",
        "Voxel type of a raw file: u8, i8, u16, i16, u32, i32, f32 or f64",
        Takes::Text {
            valid: |s| text::voxel_type(s).is_some(),
            expected: "one of u8, i8, u16, i16, u32, i32, f32, f64",
            default: None,
            hyphens: false,
        },
    )
};
pub const SPACING: Param = named(
    "spacing",
    "spacing",
    "SX,SY,SZ",
    "Voxel spacing of a raw file in mm, SX,SY,SZ",
    Takes::Text {
        valid: |s| text::spacing(s).is_some(),
        expected: "three positive numbers SX,SY,SZ",
        default: None,
        hyphens: false,
    },
);
pub const ENDIAN: Param = named(
    "endian",
    "endian",
    "little|big",
    "Byte order of a raw file",
    Takes::Text {
        valid: |s| text::endian(s).is_some(),
        expected: "little or big",
        default: None,
        hyphens: false,
    },
);
pub const OFFSET: Param = named(
    "offset",
    "offset",
    "BYTES",
    "Bytes to skip at the start of a raw file",
    count(0, u64::MAX, None),
);
pub const MAX_MEMORY: Param = named(
    "max_memory",
    "max-memory",
    "BYTES",
    "The most memory the volume and its analysis may take, e.g. 8G (default: half the physical \
     memory); a file read in place (mapped) is not counted, and an analysis that would not fit \
     runs on the finest pyramid level that does",
    Takes::Text {
        valid: |s| text::bytes(s).is_some(),
        expected: "a size such as 512M or 8G",
        default: None,
        hyphens: false,
    },
);
pub const SCRATCH: Param = named(
    "scratch",
    "scratch",
    "DIR",
    "A folder on disk to decode compressed or converted voxels into when they do not fit in \
     --max-memory (an unnamed file, gone when slabscope ends), read from there as a mapped file; \
     without it such a volume is refused",
    Takes::Text {
        valid: |s| !s.is_empty(),
        expected: "a folder",
        default: None,
        hyphens: false,
    },
);
pub const THREADS: Param = named(
    "threads",
    "threads",
    "N",
    "The most threads the work runs on (default: one a core)",
    count(1, 4096, None),
);
pub const VOLUME: Param = named(
    "volume",
    "volume",
    "N",
    "Which volume of a 4D file (NIfTI, NRRD, MetaImage, DICOM, HDF5; an OME-TIFF's, OME-Zarr's or \
     Imaris file's time point) to read, from 0",
    count(0, u32::MAX as u64, Some(0)),
);
pub const CHANNEL: Param = named(
    "channel",
    "channel",
    "N",
    "Which channel of a multichannel file (OME-TIFF, OME-Zarr, Imaris), from 0",
    count(0, u32::MAX as u64, Some(0)),
);
pub const ARRAY: Param = named(
    "array",
    "array",
    "NAME",
    "Which array of a file holding several: a VTK XML image data array by its name, an HDF5 \
     dataset by its path (default: the active scalars; DXchange's /exchange/data, else the only \
     dataset of three or four dimensions)",
    Takes::Text {
        valid: |_| true,
        expected: "an array's name or a dataset's path",
        default: None,
        hyphens: false,
    },
);
pub const SERIES: Param = named(
    "series",
    "series",
    "N|UID",
    "Which series of a DICOM folder: its position in the folder's list `info` gives (from 1, \
     shown as `--series N` there), or its `SeriesInstanceUID`; `triage` then gives that series' \
     rows only",
    Takes::Text {
        valid: |_| true,
        expected: "a series' position or UID",
        default: None,
        hyphens: false,
    },
);
pub const INCLUDE_LOCALIZERS: Param = param(
    "include_localizers",
    "include-localizers",
    "Keep DICOM localizer (scout) and derived images, left out by default",
    Takes::Switch,
);
pub const RESAMPLE: Param = param(
    "resample",
    "resample",
    "Resample a DICOM series with gaps, uneven spacing or gantry tilt to an even, orthogonal grid \
     (otherwise kept as it is, with a warning; tilt as a sheared transform)",
    Takes::Switch,
);
pub const SHOW_PHI: Param = param(
    "show_phi",
    "show-phi",
    "Show patient-identifying DICOM fields (name, ID, birth date, ...), hidden by default",
    Takes::Switch,
);
pub const LABEL_IMAGE: Param = named(
    "label_image",
    "label-image",
    "NAME",
    "Read the label image NAME of an OME-Zarr store (its `labels/NAME`) instead of its image",
    Takes::Text {
        valid: |_| true,
        expected: "a label image's name",
        default: None,
        hyphens: false,
    },
);

pub const ENDPOINT: Param = named(
    "endpoint",
    "endpoint",
    "URL",
    "The S3 endpoint an s3:// store is read at, path-style (MinIO, Ceph, a local S3 server), \
     before AWS_ENDPOINT_URL_S3 and AWS_ENDPOINT_URL",
    Takes::Text {
        valid: |s| s.starts_with("http://") || s.starts_with("https://"),
        expected: "an http:// or https:// URL",
        default: None,
        hyphens: false,
    },
);

pub const MISSING_AS_FILL: Param = param(
    "missing_as_fill",
    "missing-as-fill",
    "Read a chunk of a store at a URL that the server refuses (HTTP 403, as public S3 answers for \
     a chunk never written) as the fill value, as a chunk not written, rather than an error",
    Takes::Switch,
);

/// How to read the input.
pub const LOAD: &[&Param] = &[
    &DIMS,
    &TYPE,
    &SPACING,
    &ENDIAN,
    &OFFSET,
    &MAX_MEMORY,
    &SCRATCH,
    &THREADS,
    &VOLUME,
    &CHANNEL,
    &ARRAY,
    &SERIES,
    &INCLUDE_LOCALIZERS,
    &RESAMPLE,
    &SHOW_PHI,
    &LABEL_IMAGE,
    &ENDPOINT,
    &MISSING_AS_FILL,
];

/// The pictures' and slices' own entries.
pub const PICTURES: &[&Param] = &[&VIEWS, &RESOLUTION, &RENDER_SIZE, &SLICE_SIZE, &INDEX];

// The tour's own.

pub const PAPER: Param = Param {
    conflicts: &["phases", "background"],
    ..param(
        "paper",
        "paper",
        "Follow the paper exactly: rank by its single lattice and count every voxel (the named \
         form of --phases 0 --background none)",
        Takes::Switch,
    )
};

/// The tour's parameters.
pub const TOUR: &[&Param] = &[&PAPER];

/// Every entry, for looking one up by name.
pub fn all() -> impl Iterator<Item = &'static Param> {
    [ANALYSIS, LOOK, SCENE_FIRST, SCENE, PICTURES, LOAD, TOUR]
        .into_iter()
        .flatten()
        .copied()
}
