//! The entries: every parameter the CLI and Python share, in the order the CLI's help lists
//! them, and the sets each command takes. The library's own `Default`s agree with the defaults
//! here (a test holds them together). Each entry's `help` is its documentation.
#![allow(missing_docs)]

use super::{Param, Takes, text};
use crate::analysis::AxisBy;
use crate::partition::Method;
use crate::render::{Colormap, Gap, Mode, Preset};

/// A parameter with what every entry shares filled in: flag and keyword from the name.
pub(super) const fn param(
    name: &'static str,
    flag: &'static str,
    help: &'static str,
    takes: Takes,
) -> Param {
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
pub(super) const fn named(
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

pub(super) const fn count(min: u64, max: u64, default: Option<u64>) -> Takes {
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

// How to read the input: in `table/load.rs`; the commands' own: in `table/commands.rs`.

mod commands;
mod load;
pub use commands::*;
pub use load::*;

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
    [
        ANALYSIS,
        LOOK,
        SCENE_FIRST,
        SCENE,
        PICTURES,
        LOAD,
        TOUR,
        COMMANDS,
        TRIAGE,
    ]
    .into_iter()
    .flatten()
    .copied()
}
