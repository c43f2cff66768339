//! Triage of many single-image DICOM series in one folder (issue #28: "2,000 single-image DICOM
//! series in one folder triaged within 10 s on 2 cores"): N files of 64×64 i16, each its own
//! series (its own `SeriesInstanceUID` and number), and one localizer, written to a temporary
//! folder, then walked, loaded and analysed as `slabscope triage` does (two at a time). Prints
//! the walk's time and the whole run's, and the rows' count.
//!
//! `cargo bench --bench triage_series [-- N [DIR]]` (N default 2000; with DIR the files are
//! written there and kept, for timing `slabscope triage DIR` itself)

use std::path::Path;
use std::time::{Duration, Instant};

use slabscope::AnalysisParams;
use slabscope::triage::{TriagePlan, discover, look_all};
use slabscope::{Error, LoadOptions};

mod common;

use common::element;

const SIDE: usize = 64;

/// Image `k`: explicit VR little endian, elements in tag order, series `k + 1` of its own
/// (a localizer when `localizer`).
fn image(k: usize, localizer: bool) -> Vec<u8> {
    let mut b = vec![0u8; 128];
    b.extend(b"DICM");
    element(2, 0x10, *b"UI", b"1.2.840.10008.1.2.1", &mut b);
    let kind: &[u8] = if localizer {
        b"ORIGINAL\\PRIMARY\\LOCALIZER"
    } else {
        b"ORIGINAL\\PRIMARY\\AXIAL"
    };
    element(8, 0x08, *b"CS", kind, &mut b);
    element(8, 0x16, *b"UI", b"1.2.840.10008.5.1.4.1.1.2", &mut b);
    element(8, 0x18, *b"UI", format!("2.25.9{k}").as_bytes(), &mut b);
    element(8, 0x60, *b"CS", b"CT", &mut b);
    element(0x20, 0x0E, *b"UI", format!("2.25.7{k}").as_bytes(), &mut b);
    element(0x20, 0x11, *b"IS", format!("{}", k + 1).as_bytes(), &mut b);
    element(0x20, 0x13, *b"IS", b"1", &mut b);
    let z = format!("-100\\-100\\{:.2}", 2.5 * k as f64);
    element(0x20, 0x32, *b"DS", z.as_bytes(), &mut b);
    element(0x20, 0x37, *b"DS", b"1\\0\\0\\0\\1\\0", &mut b);
    element(0x28, 0x02, *b"US", &1u16.to_le_bytes(), &mut b);
    element(0x28, 0x04, *b"CS", b"MONOCHROME2", &mut b);
    element(0x28, 0x10, *b"US", &(SIDE as u16).to_le_bytes(), &mut b);
    element(0x28, 0x11, *b"US", &(SIDE as u16).to_le_bytes(), &mut b);
    element(0x28, 0x30, *b"DS", b"0.7\\0.7", &mut b);
    element(0x28, 0x100, *b"US", &16u16.to_le_bytes(), &mut b);
    element(0x28, 0x101, *b"US", &16u16.to_le_bytes(), &mut b);
    element(0x28, 0x102, *b"US", &15u16.to_le_bytes(), &mut b);
    element(0x28, 0x103, *b"US", &1u16.to_le_bytes(), &mut b);
    let pixels: Vec<u8> = (0..SIDE * SIDE)
        .flat_map(|p| (((p * 7 + k * 13) % 2000) as i16).to_le_bytes())
        .collect();
    element(0x7FE0, 0x10, *b"OW", &pixels, &mut b);
    b
}

/// Writes `count` single-image series and a localizer into `dir`.
fn write(dir: &Path, count: usize) -> std::io::Result<()> {
    for k in 0..count {
        std::fs::write(dir.join(format!("IM{k:05}.dcm")), image(k, false))?;
    }
    std::fs::write(dir.join("LOCALIZER.dcm"), image(count, true))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let count = args.first().and_then(|a| a.parse().ok()).unwrap_or(2000);
    let temp = tempfile::tempdir()?;
    let dir = args.get(1).map_or(temp.path(), Path::new);
    std::fs::create_dir_all(dir)?;
    write(dir, count)?;
    let opts = LoadOptions::default();
    let t = Instant::now();
    let volumes = discover(&[dir.to_path_buf()], &opts)?;
    let walked = t.elapsed().as_secs_f64();
    let how = TriagePlan {
        load: opts,
        params: AnalysisParams::default(),
        timeout: Duration::from_secs(60),
        fast: true,
        tile: None,
    };
    let describe = |_: &Path, e: Error| e.to_string();
    let (mut rows, mut failed, mut noted) = (0, 0, 0);
    look_all(&volumes, &how, 2, None, &describe, |_, looked| {
        rows += 1;
        failed += usize::from(looked.row.error.is_some());
        noted += looked
            .row
            .problems
            .iter()
            .filter(|p| p.contains("localizer"))
            .count();
        true
    });
    let took = t.elapsed().as_secs_f64();
    println!(
        "{count} single-image series of {SIDE}x{SIDE} and a localizer in one folder: \
         walked in {walked:.2} s, triaged in {took:.2} s ({rows} rows, {failed} failed, \
         the localizer noted {noted} times)"
    );
    Ok(())
}
