//! The fast integration tests, one binary for all of them (each test binary links the whole
//! crate, so one per subject would cost a link each): a module per subject, run in parallel.
//!
//! `cargo test --test it` runs them all; `cargo test --test it render::` one subject. The slow
//! process-level suites are in `tests/slow`.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

#[path = "../common/mod.rs"]
mod common;

mod bad_input;
mod cli;
mod contract;
mod dicom;
mod dicom_tree;
mod exact;
mod explain;
mod formats;
mod fuzz_headers;
mod gain;
mod geometry;
mod hdf5;
mod metadata;
mod mosaic;
mod mrc;
mod names;
mod native;
mod nifti2;
mod orientation;
mod partition;
#[cfg(feature = "remote")]
mod remote;
#[cfg(feature = "remote")]
mod remote_cache;
#[cfg(feature = "remote")]
mod remote_levels;
#[cfg(feature = "remote")]
mod remote_servers;
mod render;
mod size;
mod slice;
mod tour;
mod triage;
mod view;
mod vti;
mod vtk;
mod zarr;
mod zarr_bombs;
mod zarr_levels;
