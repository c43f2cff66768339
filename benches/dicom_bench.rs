//! Loading a DICOM series against reading the same pixels as raw: a 512×512×400 CT-like series
//! (one file a slice, i16, rescaled, shuffled names) written to a temporary folder, and the same
//! voxels as one headerless raw file. Prints the best of three loads of each (warm page cache).
//!
//! `cargo bench --bench dicom_bench [-- NX NY NZ]`

use std::path::Path;
use std::time::Instant;

use slabscope::formats::RawOptions;
use slabscope::volume::{Endian, VoxelType};
use slabscope::{Error, LoadOptions};

mod common;

use common::element;

/// One CT slice: explicit VR little endian, elements in tag order.
fn slice(k: usize, dims: [usize; 3], pixels: &[u8]) -> Vec<u8> {
    let mut b = vec![0u8; 128];
    b.extend(b"DICM");
    element(2, 0x10, *b"UI", b"1.2.840.10008.1.2.1", &mut b);
    element(8, 0x16, *b"UI", b"1.2.840.10008.5.1.4.1.1.2", &mut b);
    element(
        8,
        0x18,
        *b"UI",
        format!("2.25.{}", 1000 + k).as_bytes(),
        &mut b,
    );
    element(8, 0x60, *b"CS", b"CT", &mut b);
    element(0x20, 0x0E, *b"UI", b"2.25.77", &mut b);
    element(0x20, 0x11, *b"IS", b"2", &mut b);
    element(0x20, 0x13, *b"IS", format!("{}", k + 1).as_bytes(), &mut b);
    let z = format!("-100\\-100\\{:.2}", 0.625 * k as f64);
    element(0x20, 0x32, *b"DS", z.as_bytes(), &mut b);
    element(0x20, 0x37, *b"DS", b"1\\0\\0\\0\\1\\0", &mut b);
    element(0x28, 0x02, *b"US", &1u16.to_le_bytes(), &mut b);
    element(0x28, 0x04, *b"CS", b"MONOCHROME2", &mut b);
    element(0x28, 0x10, *b"US", &(dims[1] as u16).to_le_bytes(), &mut b);
    element(0x28, 0x11, *b"US", &(dims[0] as u16).to_le_bytes(), &mut b);
    element(0x28, 0x30, *b"DS", b"0.7\\0.7", &mut b);
    element(0x28, 0x100, *b"US", &16u16.to_le_bytes(), &mut b);
    element(0x28, 0x101, *b"US", &16u16.to_le_bytes(), &mut b);
    element(0x28, 0x102, *b"US", &15u16.to_le_bytes(), &mut b);
    element(0x28, 0x103, *b"US", &1u16.to_le_bytes(), &mut b);
    element(0x28, 0x1052, *b"DS", b"-1024", &mut b);
    element(0x28, 0x1053, *b"DS", b"1", &mut b);
    element(0x7FE0, 0x10, *b"OW", pixels, &mut b);
    b
}

fn best_of_three(what: &str, mut f: impl FnMut() -> Result<(), Error>) -> Result<f64, Error> {
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        f()?;
        best = best.min(start.elapsed().as_secs_f64());
    }
    println!("{what:<34} {best:>8.3} s");
    Ok(best)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let dims = match args[..] {
        [x, y, z] => [x, y, z],
        _ => [512, 512, 400],
    };
    let dir = tempfile::tempdir()?;
    let series = dir.path().join("series");
    std::fs::create_dir(&series)?;
    let plane = dims[0] * dims[1];
    let mut raw = Vec::with_capacity(plane * dims[2] * 2);
    for k in 0..dims[2] {
        let pixels: Vec<u8> = (0..plane)
            .flat_map(|p| (((p * 7 + k * 13) % 2000) as i16).to_le_bytes())
            .collect();
        // Names that do not sort in slice order.
        let name = format!("IM{:08X}", (k * 2_654_435_761) % 0xFFFF_FFFF);
        std::fs::write(series.join(name), slice(k, dims, &pixels))?;
        raw.extend(&pixels);
    }
    let raw_path = dir.path().join("same.raw");
    std::fs::write(&raw_path, &raw)?;
    drop(raw);
    println!(
        "{}x{}x{} i16, {} files ({} MB of pixels)",
        dims[0],
        dims[1],
        dims[2],
        dims[2],
        (plane * dims[2] * 2) >> 20
    );
    let raw_opts = LoadOptions {
        raw: RawOptions {
            dims: Some(dims),
            voxel_type: Some(VoxelType::I16),
            spacing: Some([0.7, 0.7, 0.625]),
            endian: Some(Endian::Little),
            offset: None,
        },
        ..LoadOptions::default()
    };
    let check = |p: &Path, o: &LoadOptions| {
        slabscope::load(p, o).map(|l| assert_eq!(l.volume.dims(), dims))
    };
    let raw_s = best_of_three("raw (the same voxels, one file)", || {
        check(&raw_path, &raw_opts)
    })?;
    let dicom_s = best_of_three("DICOM series (one file a slice)", || {
        check(&series, &LoadOptions::default())
    })?;
    println!("DICOM / raw: {:.2}x", dicom_s / raw_s);
    Ok(())
}
