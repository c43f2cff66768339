//! The mutation harness: valid files of every reader, mutated at random (bytes flipped, header
//! numbers made extreme, files cut short or lengthened, fields of binary headers overwritten),
//! each run through the real binary as a subprocess, as a user's file would be, under an
//! address-space limit (`prlimit`, where it exists) and a 10-second timeout. No mutant may
//! panic, abort, hang, print more than one line of error, or peak above four times the budgeted
//! size of the volume it loads (the budget, 64 MiB, for one that fails) plus the program's own
//! 24 MiB.
//!
//! `SLABSCOPE_MUTANTS=N` sets the mutants per reader (default 40; `.ci/run` runs 400, and
//! `SLABSCOPE_MUTANTS=10000 cargo test --release --test slow mutants` is the full run the README
//! reports).

use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::common::{bounded, data, dicom, prlimit_available};

/// The budget every mutant is loaded under.
const BUDGET: u64 = 64 << 20;

/// The program's own resident memory, whatever it loads.
const BASE: u64 = 24 << 20;

/// Seeds, per reader: a file of `tests/data` and the name a mutant takes.
const READERS: &[(&str, &[(&str, &str)])] = &[
    (
        "nifti",
        &[
            ("ramp_u8.nii", "m.nii"),
            ("ramp_f32_be.nii", "m.nii"),
            ("ramp_i16_scaled.nii.gz", "m.nii.gz"),
            ("ramp_4d_um.nii.gz", "m.nii.gz"),
        ],
    ),
    (
        "nifti2",
        &[
            ("nifti2/ramp_i16_oblique.nii", "m.nii"),
            ("nifti2/ramp_f32_be.nii.gz", "m.nii.gz"),
            ("nifti2/ramp_4d_um.nii", "m.nii"),
        ],
    ),
    (
        "nrrd",
        &[
            ("ramp_u16_be.nrrd", "m.nrrd"),
            ("ramp_f32_gzip.nrrd", "m.nrrd"),
            ("ramp_u8_ascii.nrrd", "m.nrrd"),
            ("ramp_i16_detached.nhdr", "m.nhdr"),
        ],
    ),
    (
        "metaimage",
        &[
            ("ramp_i16.mha", "m.mha"),
            ("ramp_f32_zlib.mha", "m.mha"),
            ("ramp_u8.mhd", "m.mhd"),
        ],
    ),
    (
        "tiff",
        &[
            ("ramp_u16_stack.tif", "m.tif"),
            ("ramp_f32_stack.tif", "m.tif"),
            ("ome/zct.ome.tif", "m.ome.tif"),
        ],
    ),
    ("volumeshop", &[("", "m.dat")]),
    (
        "dicom",
        &[
            ("dicom/enhanced.dcm", "m.dcm"),
            ("dicom/jpegll/j1.dcm", "m.dcm"),
            ("dicom/gap/slice00.dcm", "m.dcm"),
            ("dicom/deflated.dcm", "m.dcm"),
            ("dicom/j2k-lossy/s0.dcm", "m.dcm"),
            ("dicom/jxl-lossy/s0.dcm", "m.dcm"),
        ],
    ),
    // Siemens mosaics: their CSA image headers among the header bytes mutated.
    (
        "mosaic",
        &[
            ("dicom/mosaic/asc/t0.dcm", "m.dcm"),
            ("dicom/mosaic/desc/t0.dcm", "m.dcm"),
        ],
    ),
    ("raw", &[("ramp_u8.raw", "m_5x4x3_uint8.raw")]),
    // A folder format: the store is copied whole and one of its files (after `//`) mutated.
    (
        "zarr",
        &[
            ("zarr/v04_blosc.ome.zarr//.zattrs", "m.ome.zarr"),
            ("zarr/v04_blosc.ome.zarr//s0/.zarray", "m.ome.zarr"),
            ("zarr/v04_blosc.ome.zarr//s0/1/1/1", "m.ome.zarr"),
            ("zarr/v05_sharded.ome.zarr//zarr.json", "m.ome.zarr"),
            ("zarr/v05_sharded.ome.zarr//s0/zarr.json", "m.ome.zarr"),
            ("zarr/v05_sharded.ome.zarr//s0/c/1/1/1", "m.ome.zarr"),
            ("zarr/v05_tczyx.ome.zarr//s0/zarr.json", "m.ome.zarr"),
            ("zarr/v05_tczyx.ome.zarr//s0/c/1/2/1/1/1", "m.ome.zarr"),
        ],
    ),
    // Readers added later come last: each mutant's random stream follows its place in the
    // list, and the earlier readers' mutants stay the ones CI has always run.
    (
        "mrc",
        &[
            ("mrc/ramp_i16.mrc", "m.mrc"),
            ("mrc/ramp_f16.mrc", "m.mrc"),
            ("mrc/ramp_zyx.mrc", "m.mrc"),
            ("mrc/ramp_ext.mrc", "m.rec"),
        ],
    ),
    (
        "vtk",
        &[
            ("vtk/ramp_i16.vtk", "m.vtk"),
            ("vtk/ramp_u8_ascii.vtk", "m.vtk"),
            ("vtk/ramp_f64_cells.vtk", "m.vtk"),
        ],
    ),
    (
        "vti",
        &[
            ("vti/ramp_i16_ascii.vti", "m.vti"),
            ("vti/ramp_f32_binary.vti", "m.vti"),
            ("vti/ramp_u8_raw.vti", "m.vti"),
            ("vti/ramp_u16_zlib.vti", "m.vti"),
            ("vti/ramp_i32_zlib_binary.vti", "m.vti"),
            ("vti/ramp_f64_base64.vti", "m.vti"),
        ],
    ),
    // Issue #47's hostile stores: a codec chain (gzip inside gzip), a shard inside a shard, and
    // 4096 chunks of 4³ (a header number made extreme makes a flood of them).
    (
        "zarr-hostile",
        &[
            ("zarr/hostile/gzip_gzip.zarr//zarr.json", "m.zarr"),
            ("zarr/hostile/gzip_gzip.zarr//c/0/0/0", "m.zarr"),
            ("zarr/hostile/nested_shard.zarr//zarr.json", "m.zarr"),
            ("zarr/hostile/nested_shard.zarr//c/0/0/0", "m.zarr"),
            ("zarr/hostile/small_chunks.zarr//zarr.json", "m.zarr"),
        ],
    ),
    (
        "hdf5",
        &[
            ("hdf5/ramp_u16_contiguous.h5", "m.h5"),
            ("hdf5/ramp_f32_gzip_shuffle.h5", "m.h5"),
            ("hdf5/ramp_i16_gzip_latest.h5", "m.h5"),
            ("hdf5/ramp_4d_i8.h5", "m.h5"),
            ("hdf5/imaris.ims", "m.ims"),
        ],
    ),
    // Issue #49's DICOM paths, written by `common::dicom` (`gen:` seeds): a mosaic of three
    // frames, a mosaic whose CSA series header holds an ASCCONV protocol setting
    // `sSliceArray.ucImageNumb`, and 32-bit samples beyond 2^24 over four frames.
    (
        "dicom-49",
        &[
            ("gen:mosaic_frames", "m.dcm"),
            ("gen:mosaic_protocol", "m.dcm"),
            ("gen:dicom32", "m.dcm"),
        ],
    ),
];

/// xorshift64*: the mutants of a seed are the same on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Numbers a header should never be trusted with.
const EXTREMES: [&str; 16] = [
    "0",
    "-1",
    "1",
    "2147483647",
    "2147483648",
    "4294967296",
    "18446744073709551617",
    "99999999999999999999999",
    "1e308",
    "-1e308",
    "1e-300",
    "nan",
    "inf",
    "65535",
    "-32768",
    "3.5",
];

/// The header's length: the text before the blank line (NRRD), before `ElementDataFile`'s line's
/// end (MetaImage), DICOM's elements before the pixel data, the 352 bytes of NIfTI.
fn header_len(bytes: &[u8]) -> usize {
    // JSON metadata (Zarr's) is all header.
    if bytes.first() == Some(&b'{') {
        return bytes.len();
    }
    // HDF5's metadata is spread through the file (these fixtures are a few kilobytes).
    if bytes.starts_with(b"\x89HDF") {
        return bytes.len();
    }
    if bytes.get(128..132) == Some(b"DICM") {
        return bytes
            .windows(4)
            .position(|w| w == [0xE0, 0x7F, 0x10, 0x00])
            .unwrap_or(bytes.len());
    }
    let text = &bytes[..bytes.len().min(4096)];
    if let Some(i) = text.windows(2).position(|w| w == b"\n\n") {
        return i + 2;
    }
    if let Some(i) = text.windows(15).position(|w| w == b"ElementDataFile") {
        return text[i..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(text.len(), |j| i + j + 1);
    }
    bytes.len().min(352)
}

/// Makes a number of the text header (its first `head` bytes) extreme.
fn extreme_number(b: &mut Vec<u8>, head: usize, rng: &mut Rng) {
    let text = &b[..head.min(b.len())];
    let numbers: Vec<(usize, usize)> = text
        .iter()
        .enumerate()
        .filter(|&(i, c)| c.is_ascii_digit() && (i == 0 || !text[i - 1].is_ascii_alphanumeric()))
        .map(|(i, _)| {
            let len = text[i..]
                .iter()
                .take_while(|c| c.is_ascii_digit() || **c == b'.' || **c == b'e')
                .count();
            (i, len)
        })
        .collect();
    if !numbers.is_empty() {
        let (at, len) = numbers[rng.below(numbers.len())];
        let value = EXTREMES[rng.below(EXTREMES.len())].as_bytes();
        b.splice(at..at + len, value.iter().copied());
    }
}

/// Overwrites an aligned field of the binary header (its first `head` bytes) with an extreme.
fn extreme_field(b: &mut [u8], head: usize, rng: &mut Rng) {
    let at = rng.below(head.min(b.len()) / 2) * 2;
    let values: [&[u8]; 8] = [
        &[0xff, 0xff],
        &[0xff, 0x7f],
        &[0x00, 0x80],
        &[0, 0],
        &[0xff, 0xff, 0xff, 0x7f],
        &[0x00, 0x00, 0xc0, 0x7f],
        &[0x00, 0x00, 0x80, 0x7f],
        &[0x01, 0x00, 0x00, 0x00],
    ];
    let v = values[rng.below(values.len())];
    for (k, &x) in v.iter().enumerate() {
        if at + k < b.len() {
            b[at + k] = x;
        }
    }
}

/// Repeats a line of the text header (its first `head` bytes).
fn repeat_line(b: &mut Vec<u8>, head: usize, rng: &mut Rng) {
    let text = &b[..head.min(b.len())];
    let starts: Vec<usize> = std::iter::once(0)
        .chain(
            text.iter()
                .enumerate()
                .filter(|(_, c)| **c == b'\n')
                .map(|(i, _)| i + 1),
        )
        .filter(|&i| i < text.len())
        .collect();
    if !starts.is_empty() {
        let s = starts[rng.below(starts.len())];
        let e = text[s..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(text.len(), |j| s + j + 1);
        let line = b[s..e].to_vec();
        b.splice(e..e, line);
    }
}

/// One mutant of `seed`.
fn mutate(seed: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut b = seed.to_vec();
    let head = header_len(&b).max(1);
    for _ in 0..=rng.below(3) {
        match rng.below(7) {
            // Flip bytes, mostly in the header.
            0 => {
                for _ in 0..=rng.below(8) {
                    let at = if rng.below(4) > 0 {
                        rng.below(head)
                    } else {
                        rng.below(b.len())
                    };
                    if at < b.len() {
                        b[at] ^= 1 << rng.below(8);
                    }
                }
            }
            // Make a number of a text header extreme.
            1 => extreme_number(&mut b, head, rng),
            // Overwrite an aligned field of a binary header with an extreme.
            2 => extreme_field(&mut b, head, rng),
            // Cut short.
            3 => b.truncate(rng.below(b.len() + 1)),
            // Lengthen with zeros or noise.
            4 => {
                let n = 1 + rng.below(4096);
                let noise = rng.below(2) == 0;
                for _ in 0..n {
                    b.push(if noise { rng.next() as u8 } else { 0 });
                }
            }
            // Repeat a header line.
            5 => repeat_line(&mut b, head, rng),
            // Drop a header line.
            _ => {
                let text = &b[..head.min(b.len())];
                if let Some(s) = text.iter().position(|&c| c == b'\n') {
                    let from = s + 1;
                    if let Some(len) = text[from..].iter().position(|&c| c == b'\n') {
                        b.drain(from..=from + len);
                    }
                }
            }
        }
    }
    b
}

/// A valid VolumeShop `.dat`: three u16 dims, then u16 voxels.
fn volumeshop_seed() -> Vec<u8> {
    let mut b = Vec::new();
    for d in [5u16, 4, 3] {
        b.extend(d.to_le_bytes());
    }
    for i in 0..60u16 {
        b.extend((i * 7).to_le_bytes());
    }
    b
}

/// The bytes of `seed`: a file of `tests/data`, a member of a store (`STORE//MEMBER`), or
/// (empty) the VolumeShop seed.
fn seed_bytes(seed: &str) -> Vec<u8> {
    match seed.split_once("//") {
        _ if seed.is_empty() => volumeshop_seed(),
        _ if seed.starts_with("gen:") => generated(&seed[4..]),
        Some((store, member)) => std::fs::read(data(store).join(member)).unwrap(),
        None => std::fs::read(data(seed)).unwrap(),
    }
}

/// The seed `common::dicom` writes for `name`.
fn generated(name: &str) -> Vec<u8> {
    match name {
        "mosaic_frames" => dicom::mosaic_frames(),
        "mosaic_protocol" => {
            dicom::mosaic_protocol(&dicom::ascconv("sSliceArray.ucImageNumb = 0x1\n"))
        }
        "dicom32" => dicom::dicom32(&[0, 7, 1 << 24, (1 << 24) + 1], 4, false, None),
        _ => panic!("no generated seed {name}"),
    }
}

/// Copies the folder `from` to `to`, whole.
fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_dir() {
            copy_tree(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

/// Writes the mutant `bytes` of `seed` as `name` in `dir` (for a seed inside a folder store,
/// `STORE//MEMBER`, a fresh copy of the store with that member replaced) and runs it.
fn run_one(dir: &Path, seed: &str, name: &str, bytes: &[u8]) -> (Option<String>, bool) {
    let path = dir.join(name);
    if let Some((store, member)) = seed.split_once("//") {
        let _ = std::fs::remove_dir_all(&path);
        copy_tree(&data(store), &path);
        std::fs::write(path.join(member), bytes).unwrap();
    } else {
        std::fs::write(&path, bytes).unwrap();
    }
    let out = bounded(10, 4 * BUDGET + (768 << 20))
        .args(["info", "--json", "--max-memory", "64M"])
        .arg(&path)
        .env("SLABSCOPE_REPORT_PEAK", "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let peak = stderr
        .lines()
        .find_map(|l| l.strip_prefix("slabscope: peak memory: "))
        .and_then(|l| l.trim_end_matches(" KiB").parse::<u64>().ok())
        .map(|k| k * 1024);
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("slabscope: error"))
        .collect();
    let others = stderr
        .lines()
        .filter(|l| !l.starts_with("slabscope: "))
        .collect::<Vec<_>>();
    let budgeted = match out.status.code() {
        Some(0) => serde_json::from_slice::<serde_json::Value>(&out.stdout)
            .ok()
            .and_then(|v| v["memory_bytes"].as_u64())
            .unwrap_or(BUDGET),
        _ => BUDGET,
    };
    let problem = match out.status.code() {
        None => Some("killed by a signal".to_string()),
        Some(124) => Some("hung (10 s)".to_string()),
        Some(0) if errors.is_empty() => None,
        Some(1) if errors.len() == 1 && errors[0].contains(name) => None,
        Some(c) => Some(format!("exit {c} with {} error lines", errors.len())),
    }
    .or_else(|| (!others.is_empty()).then(|| format!("stray output: {others:?}")))
    .or_else(|| match peak {
        None => Some("no peak reported".into()),
        Some(p) if p > 4 * budgeted + BASE => Some(format!(
            "peak {} MiB for {} MiB budgeted",
            p >> 20,
            budgeted >> 20
        )),
        Some(_) => None,
    });
    (
        problem.map(|p| format!("{p}: {}", stderr.trim())),
        out.status.success(),
    )
}

#[test]
fn mutants_of_every_reader_fail_cleanly_within_their_budget() {
    let _alone = crate::one_at_a_time();
    let per_reader: usize = std::env::var("SLABSCOPE_MUTANTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40);
    if !prlimit_available() {
        eprintln!("note: prlimit not found; mutants run without an address-space limit");
    }
    let dir = tempfile::tempdir().unwrap();
    // The detached seeds' data files, beside every mutant.
    std::fs::copy(
        data("ramp_i16_detached.raw"),
        dir.path().join("ramp_i16_detached.raw"),
    )
    .unwrap();
    std::fs::copy(data("ramp_u8.raw"), dir.path().join("ramp_u8.raw")).unwrap();
    let mut jobs = Vec::new();
    for (reader, seeds) in READERS {
        for i in 0..per_reader {
            let (seed, name) = seeds[i % seeds.len()];
            jobs.push((*reader, seed, name, i));
        }
    }
    let next = AtomicUsize::new(0);
    let loaded = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    let threads = std::thread::available_parallelism().map_or(2, std::num::NonZero::get);
    std::thread::scope(|s| {
        for t in 0..threads {
            let (jobs, next, failures, loaded) = (&jobs, &next, &failures, &loaded);
            let dir = dir.path().join(format!("t{t}"));
            std::fs::create_dir(&dir).unwrap();
            for f in ["ramp_i16_detached.raw", "ramp_u8.raw"] {
                std::fs::copy(data(f), dir.join(f)).unwrap();
            }
            s.spawn(move || {
                loop {
                    let j = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&(reader, seed, name, i)) = jobs.get(j) else {
                        break;
                    };
                    let bytes = seed_bytes(seed);
                    let mut rng =
                        Rng(0x9E37_79B9_7F4A_7C15
                            ^ (j as u64 + 1).wrapping_mul(0xD1B5_4A32_D192_ED03));
                    let mutant = mutate(&bytes, &mut rng);
                    let (problem, ok) = run_one(&dir, seed, name, &mutant);
                    if ok {
                        loaded.fetch_add(1, Ordering::Relaxed);
                    }
                    if let Some(problem) = problem {
                        let kept = dir.join(format!("failed-{reader}-{i}-{name}"));
                        if seed.contains("//") {
                            std::fs::rename(dir.join(name), &kept).unwrap();
                        } else {
                            std::fs::write(&kept, &mutant).unwrap();
                        }
                        failures
                            .lock()
                            .unwrap()
                            .push(format!("{reader} #{i} ({seed}): {problem}"));
                    }
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(
        failures.is_empty(),
        "{} of {} mutants failed:\n{}",
        failures.len(),
        jobs.len(),
        failures.join("\n")
    );
    eprintln!(
        "{} mutants ({per_reader} per reader): {} loaded, the others failed cleanly",
        jobs.len(),
        loaded.into_inner()
    );
}
