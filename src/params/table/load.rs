//! The entries of how to read the input: every reader's options, the budget and the threads.
#![allow(missing_docs)]

use super::{count, named, param};
use crate::params::{Param, Takes, text};

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

pub const CACHE: Param = named(
    "cache",
    "cache",
    "DIR",
    "A folder where the chunks of a store at a URL are kept once fetched (made when missing; at \
     most 1 GiB, the oldest dropped past it), so that reading the store again fetches none it \
     holds",
    Takes::Text {
        valid: |s| !s.is_empty(),
        expected: "a folder",
        default: None,
        hyphens: false,
    },
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
    &CACHE,
];
