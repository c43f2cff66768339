//! What the benchmarks share: timed whole-process runs, medians, and the body phantoms they
//! write once as uncompressed i16 NIfTI after checking the free disk space.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use slabscope::formats::{NrrdEncoding, write_phantom};
use slabscope::volume::phantom::Recipe;

/// The value after `name` among the process's arguments, if given (for the benchmarks that time
/// work in process and take flags of their own).
pub fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

/// The command line the whole-process benchmarks share: `--runs N`, `--dir DIR` (where their
/// volumes are written), any number of `--bin PATH` (the builds compared in turns; the release
/// build when none), and flags of their own read by [`Args::value`].
pub struct Args(Vec<String>);

impl Args {
    /// The process's arguments.
    pub fn from_env() -> Self {
        Self(std::env::args().skip(1).collect())
    }

    /// The value after `flag`, if given.
    pub fn value(&self, flag: &str) -> Option<&str> {
        let i = self.0.iter().position(|a| a == flag)?;
        self.0.get(i + 1).map(String::as_str)
    }

    /// `--runs`, 3 by default.
    pub fn runs(&self) -> Result<usize, Box<dyn std::error::Error>> {
        Ok(self.value("--runs").map_or(Ok(3), str::parse)?)
    }

    /// `--dir`, `target/bench-volumes` by default.
    pub fn dir(&self) -> PathBuf {
        PathBuf::from(self.value("--dir").unwrap_or("target/bench-volumes"))
    }

    /// Every `--bin`, or the release build.
    pub fn bins(&self) -> Vec<PathBuf> {
        let bins: Vec<PathBuf> = self
            .0
            .windows(2)
            .filter(|w| w[0] == "--bin")
            .map(|w| PathBuf::from(&w[1]))
            .collect();
        if bins.is_empty() {
            vec![PathBuf::from("target/release/slabscope")]
        } else {
            bins
        }
    }
}

/// One timed run: seconds from start to exit, and the peak anonymous memory in MiB.
pub fn run(bin: &Path, args: &[&str]) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let start = Instant::now();
    let mut child = Command::new(bin)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()?;
    let status = format!("/proc/{}/status", child.id());
    let mut peak_kib = 0u64;
    loop {
        if let Some(exit) = child.try_wait()? {
            if !exit.success() {
                return Err(format!("{} {args:?} failed: {exit}", bin.display()).into());
            }
            break;
        }
        if let Ok(text) = std::fs::read_to_string(&status)
            && let Some(kib) = text
                .lines()
                .find(|l| l.starts_with("RssAnon:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        {
            peak_kib = peak_kib.max(kib);
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    Ok((start.elapsed().as_secs_f64(), peak_kib as f64 / 1024.0))
}

pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Free bytes on the file system holding `dir`.
pub fn free_bytes(dir: &Path) -> Option<u64> {
    let out = Command::new("df")
        .args(["--output=avail", "-B1"])
        .arg(dir)
        .output()
        .ok()?;
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .nth(1)?
        .trim()
        .parse()
        .ok()
}

/// The body phantom of `dims` as i16 NIfTI in `dir`, written unless it is there (a chunk of
/// voxels at a time: never held whole).
pub fn volume(dir: &Path, dims: [usize; 3]) -> Result<PathBuf, Box<dyn std::error::Error>> {
    let path = dir.join(format!("body_{}x{}x{}.nii", dims[0], dims[1], dims[2]));
    if path.exists() {
        return Ok(path);
    }
    let bytes = dims.iter().product::<usize>() as u64 * 2 + 352;
    if free_bytes(dir).is_some_and(|free| free < bytes + (1 << 30)) {
        return Err(format!("{}: not enough free disk for {bytes} bytes", dir.display()).into());
    }
    let t = Instant::now();
    // Made and written a chunk at a time, never held: 2048³ (16 GiB) as well as 256³.
    write_phantom(&path, &Recipe::body(dims, 1)?, NrrdEncoding::Raw, false)?;
    println!(
        "wrote {} in {:.1} s",
        path.display(),
        t.elapsed().as_secs_f64()
    );
    Ok(path)
}

pub fn parse_dims(text: &str) -> Option<[usize; 3]> {
    let mut it = text.split('x').map(|n| n.parse().ok());
    let dims = [it.next()??, it.next()??, it.next()??];
    it.next().is_none().then_some(dims)
}

/// Appends one DICOM data element, explicit VR little endian, its value padded to an even
/// length (UIDs with a NUL, text with a space): the DICOM files the benchmarks write.
pub fn element(group: u16, elem: u16, vr: [u8; 2], value: &[u8], out: &mut Vec<u8>) {
    let mut value = value.to_vec();
    if value.len() % 2 == 1 {
        value.push(if &vr == b"UI" { 0 } else { b' ' });
    }
    out.extend(group.to_le_bytes());
    out.extend(elem.to_le_bytes());
    out.extend(vr);
    if matches!(&vr, b"OB" | b"OW" | b"SQ" | b"UN" | b"UT") {
        out.extend([0, 0]);
        out.extend((value.len() as u32).to_le_bytes());
    } else {
        out.extend((value.len() as u16).to_le_bytes());
    }
    out.extend(value);
}
