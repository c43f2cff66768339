//! The entries of one command's own: what a render draws instead of the exploded view, a slice's
//! letters, how long a run may take, and triage's shard, lattice and sheet.
#![allow(missing_docs)]

use super::{count, named, param};
use crate::params::{Param, Takes, text};

/// Seconds a run may take, from a tenth of a second to a day.
const fn seconds(default: Option<f64>) -> Takes {
    Takes::Number {
        min: 0.1,
        max: 86400.0,
        default,
    }
}

pub const FACES: Param = param(
    "faces",
    "faces",
    "Instead of the exploded view, the faces of every slab: its last slice above its first, a \
     column a slab, fit into the size",
    Takes::Switch,
);
pub const NO_LETTERS: Param = param(
    "no_letters",
    "no-letters",
    "No orientation letters on the edges",
    Takes::Switch,
);
/// `analyze`'s and `render`'s bound on the whole run (none by default).
pub const TIMEOUT: Param = named(
    "timeout",
    "timeout",
    "SECONDS",
    "Stop after this many seconds, with an error saying so",
    seconds(None),
);

/// A command's own entries (each its own, for the help lists them apart).
pub const COMMANDS: &[&Param] = &[&FACES, &NO_LETTERS, &TIMEOUT];

// Triage's own.

pub const SHARD: Param = named(
    "shard",
    "shard",
    "K/N",
    "Take the K-th of N contiguous blocks of the sorted volumes (K from 1), e.g. `--shard \
     $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`",
    Takes::Text {
        valid: |s| text::shard(s).is_some(),
        expected: "K/N with 1 <= K <= N, e.g. 3/10",
        default: None,
        hyphens: false,
    },
);
pub const FULL: Param = param(
    "full",
    "full",
    "The view search on the voxels' own lattice over every phase, not the fast path's twice \
     coarser lattice over 4 phases (used unless --ray-spacing or --sample-spacing is given, on \
     volumes of 32 voxels a side or more)",
    Takes::Switch,
);
pub const TILE: Param = named(
    "tile",
    "tile",
    "PIXELS",
    "Size of the sheet's pictures, pixels",
    count(32, 1024, Some(160)),
);
/// Triage's bound on each volume (a minute by default).
pub const TRIAGE_TIMEOUT: Param = named(
    "timeout",
    "timeout",
    "SECONDS",
    "Stop the loading and analysis of a volume after this many seconds (its row says so)",
    seconds(Some(60.0)),
);

/// Triage's own entries.
pub const TRIAGE: &[&Param] = &[&SHARD, &FULL, &TILE, &TRIAGE_TIMEOUT];
