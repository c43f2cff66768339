//! Small hostile files and options, each made here, through the real binary: every resource a
//! file can claim is checked before it is spent, nothing is written where it must not be, and
//! every failure is one clear line. Where `prlimit` is there, each run gets an address-space
//! limit, so that an allocation beyond the budget fails the test instead of passing unseen.

use std::io::Write;
use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use crate::common::{bounded, layers, s, slabscope};

/// Address space a run may take: the budget given with `--max-memory`, four times over, and
/// room for the program, its threads and their allocator arenas.
fn address_space(max_memory: u64) -> u64 {
    4 * max_memory + (768 << 20)
}

/// Runs slabscope with `args` under an address-space limit (where `prlimit` exists) and a
/// 20-second timeout; returns its output and how long it took.
fn run(args: &[&str], max_memory: u64) -> (Output, Duration) {
    let mut cmd = bounded(20, address_space(max_memory));
    cmd.args(args);
    let start = Instant::now();
    let out = cmd.output().unwrap();
    (out, start.elapsed())
}

/// Asserts a run failed in one line that names `file` and contains `phrase`, with nothing on
/// standard output, no crash and no timeout.
fn fails(out: &Output, file: &str, phrase: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.code().is_some(), "killed by a signal: {stderr}");
    assert_ne!(out.status.code(), Some(124), "timed out: {stderr}");
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        out.stdout.is_empty(),
        "stdout: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(stderr.contains(file), "does not name {file}: {stderr}");
    assert!(stderr.contains(phrase), "lacks {phrase:?}: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "not one line: {stderr}"
    );
    assert!(stderr.len() < 400, "{} bytes of error", stderr.len());
}

// --- TIFF -------------------------------------------------------------------------------------

/// One page of a hand-made little-endian TIFF: its size, bits, sample format (1 unsigned,
/// 2 signed, 3 float), compression (1 none, 8 deflate) and strip bytes.
struct Page {
    width: u32,
    height: u32,
    bits: u16,
    format: u16,
    compression: u16,
    strip: Vec<u8>,
}

impl Page {
    fn gray8(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            bits: 8,
            format: 1,
            compression: 1,
            strip: vec![7; (width * height) as usize],
        }
    }
}

/// A TIFF of `pages`, each one strip, written by hand so that its directories can say what no
/// encoder would write.
fn tiff(path: &Path, pages: &[Page]) {
    let mut out = b"II*\0".to_vec();
    out.extend(8u32.to_le_bytes());
    for (i, page) in pages.iter().enumerate() {
        let ifd_len = 2 + 10 * 12 + 4;
        let strip_at = out.len() + ifd_len;
        let next = if i + 1 < pages.len() {
            (strip_at + page.strip.len()) as u32
        } else {
            0
        };
        out.extend(10u16.to_le_bytes());
        let mut entry = |tag: u16, kind: u16, value: u32| {
            out.extend(tag.to_le_bytes());
            out.extend(kind.to_le_bytes());
            out.extend(1u32.to_le_bytes());
            out.extend(value.to_le_bytes());
        };
        let (short, long) = (3, 4);
        entry(256, long, page.width);
        entry(257, long, page.height);
        entry(258, short, u32::from(page.bits));
        entry(259, short, u32::from(page.compression));
        entry(262, short, 1);
        entry(273, long, strip_at as u32);
        entry(277, short, 1);
        entry(278, long, page.height);
        entry(279, long, page.strip.len() as u32);
        entry(339, short, u32::from(page.format));
        out.extend(next.to_le_bytes());
        out.extend(&page.strip);
    }
    std::fs::write(path, out).unwrap();
}

fn zlib(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

#[test]
fn a_huge_second_tiff_page_is_refused_before_it_is_decoded() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("stack.tif");
    // 30000² zeros compress to under a megabyte; decoded and widened they are 3.6 GB.
    let row = vec![0u8; 30000];
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    for _ in 0..30000 {
        e.write_all(&row).unwrap();
    }
    let huge = Page {
        compression: 8,
        strip: e.finish().unwrap(),
        ..Page::gray8(30000, 30000)
    };
    tiff(&path, &[Page::gray8(10, 10), huge]);
    let (out, took) = run(&["info", s(&path), "--max-memory", "256M"], 256 << 20);
    fails(
        &out,
        "stack.tif",
        "page 1 is 30000x30000 u8 but the first page is 10x10 u8",
    );
    assert!(took < Duration::from_secs(2), "decoded? {took:?}");
    // Pages alike but too many for the budget: refused before any is decoded.
    let big = dir.path().join("big.tif");
    let page = || Page {
        compression: 8,
        strip: zlib(&vec![0u8; 4000 * 4000]),
        ..Page::gray8(4000, 4000)
    };
    tiff(&big, &[page(), page(), page(), page(), page()]);
    let (out, _) = run(&["info", s(&big), "--max-memory", "200M"], 200 << 20);
    fails(&out, "big.tif", "over the memory limit of 200.0 MiB");
}

#[test]
fn tiff_directories_are_checked_before_the_decoder_reads_them() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("odd.tif");
    let patched = |at: usize, bytes: &[u8]| {
        tiff(&path, &[Page::gray8(4, 4)]);
        let mut b = std::fs::read(&path).unwrap();
        b[at..at + bytes.len()].copy_from_slice(bytes);
        std::fs::write(&path, b).unwrap();
    };
    // The first directory (at byte 8: 2 bytes of count, 10 entries of 12) points to itself.
    patched(130, &8u32.to_le_bytes());
    let (out, took) = run(&["info", s(&path)], 1 << 30);
    fails(
        &out,
        "odd.tif",
        "page 1: its directory loops back to an earlier one",
    );
    assert!(took < Duration::from_secs(2));
    // Its first tag made an ASCII value of 2³¹ bytes.
    patched(12, &[2, 0, 0xff, 0xff, 0xff, 0x7f]);
    let (out, _) = run(&["info", s(&path), "--max-memory", "64M"], 64 << 20);
    fails(
        &out,
        "odd.tif",
        "page 0: tag 256 claims 2147483647 values, more than the file holds",
    );
}

#[test]
fn tiff_samples_slabscope_does_not_read_are_named() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    for (name, bits, format, phrase) in [
        ("half.tif", 16, 3, "16-bit float samples"),
        ("long.tif", 64, 2, "64-bit integer samples"),
        ("bits.tif", 1, 1, "1-bit (black and white) samples"),
    ] {
        let path = dir.path().join(name);
        let bytes = (16 * 16 * u32::from(bits)).div_ceil(8) as usize;
        let page = Page {
            bits,
            format,
            strip: vec![0; bytes],
            ..Page::gray8(16, 16)
        };
        tiff(&path, &[page]);
        let (out, _) = run(&["info", s(&path)], 1 << 30);
        fails(&out, name, phrase);
    }
}

#[test]
fn a_tiff_folder_refuses_what_it_cannot_read() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    for i in 0..3 {
        tiff(&dir.path().join(format!("s_{i}.tif")), &[Page::gray8(8, 8)]);
    }
    let (out, _) = run(&["info", s(dir.path())], 1 << 30);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A folder named like a slice.
    std::fs::create_dir(dir.path().join("s_3.tif")).unwrap();
    let (out, _) = run(&["info", s(dir.path())], 1 << 30);
    fails(
        &out,
        "s_3.tif",
        "named like a slice, but not a regular file",
    );
    std::fs::remove_dir(dir.path().join("s_3.tif")).unwrap();
    // A link that leads nowhere.
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("s_9.tif", dir.path().join("s_9.tif")).unwrap();
        let (out, _) = run(&["info", s(dir.path())], 1 << 30);
        fails(&out, "s_9.tif", "");
    }
}

// --- spacing --------------------------------------------------------------------------------

/// A 32³ NRRD of noise with `spacings`.
fn nrrd_with_spacings(path: &Path, spacings: &str) {
    let mut bytes = format!(
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 32 32 32\nspacings: {spacings}\nencoding: raw\n\n"
    )
    .into_bytes();
    let mut x = 12345u32;
    bytes.extend((0..32 * 32 * 32).map(|_| {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        (x >> 24) as u8
    }));
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn absurd_spacings_are_refused_at_once() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let tiny = dir.path().join("tiny.nrrd");
    nrrd_with_spacings(&tiny, "1e-300 1 1");
    let (out, took) = run(&["analyze", s(&tiny)], 1 << 30);
    fails(&out, "tiny.nrrd", "within a factor of 10000 of each other");
    assert!(took < Duration::from_secs(5), "{took:?}");
    let thin = dir.path().join("thin.nrrd");
    nrrd_with_spacings(&thin, "0.0001 1 1");
    let (out, _) = run(&["analyze", s(&thin), "--axis", "1,1,0"], 1 << 30);
    assert!(out.status.success(), "a ratio of 1e4 is allowed");
    let ok = dir.path().join("ok.nrrd");
    nrrd_with_spacings(&ok, "1 1 1");
    for (flag, value) in [
        ("--ray-spacing", "0.00001"),
        ("--sample-spacing", "0.000001"),
    ] {
        let (out, took) = run(
            &["analyze", s(&ok), "--axis", "1,1,1", flag, value],
            1 << 30,
        );
        fails(
            &out,
            "ok.nrrd",
            &format!("{flag} {value}: expected a positive number of mm within a factor of 10000"),
        );
        assert!(took < Duration::from_secs(5), "{took:?}");
    }
}

// --- NRRD data ----------------------------------------------------------------------------------

#[test]
fn ascii_data_is_read_token_by_token() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nul.nrrd");
    let mut bytes =
        b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n\n".to_vec();
    bytes.resize(bytes.len() + (64 << 20), 0);
    std::fs::write(&path, bytes).unwrap();
    let (out, _) = run(&["info", s(&path), "--max-memory", "64M"], 64 << 20);
    fails(&out, "nul.nrrd", "is not a number");
    for (values, phrase) in [
        ("1 2 3 4 5 6 7 -5", "\"-5\" is not a u8 value (0 to 255)"),
        ("1 2 3 4 5 6 7 300", "\"300\" is not a u8 value"),
        ("1 2 3 4 5 6 7 1e9", "\"1e9\" is not a u8 value"),
        ("1 2 3 4 5 6 7 2.5", "\"2.5\" is not a u8 value"),
    ] {
        let path = dir.path().join("range.nrrd");
        std::fs::write(
            &path,
            format!(
                "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n\n{values}\n"
            ),
        )
        .unwrap();
        let (out, _) = run(&["info", s(&path)], 1 << 30);
        fails(&out, "range.nrrd", phrase);
    }
}

#[test]
fn skipped_lines_are_streamed() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("data.raw"), vec![b'x'; 96 << 20]).unwrap();
    let header = dir.path().join("skip.nhdr");
    std::fs::write(
        &header,
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\nline skip: 1\n\
         data file: data.raw\n",
    )
    .unwrap();
    let (out, _) = run(&["info", s(&header), "--max-memory", "16M"], 16 << 20);
    fails(&out, "skip.nhdr", "file ends after 0 of 1 lines to skip");
}

// --- outputs --------------------------------------------------------------------------------

/// The files of `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn force_never_replaces_an_input_or_a_file_that_is_not_regular() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let input = layers(dir.path(), 20);
    let before = std::fs::read(&input).unwrap();
    let (out, _) = run(
        &[
            "analyze",
            s(&input),
            "--export-labels",
            s(&input),
            "--force",
        ],
        1 << 30,
    );
    fails(
        &out,
        "layers.nrrd",
        "is an input of this command; slabscope never writes over its input",
    );
    assert_eq!(std::fs::read(&input).unwrap(), before);
    // A detached header's data file is an input too.
    let data = dir.path().join("data.nrrd");
    std::fs::write(&data, [1u8, 2, 3, 4, 5, 6, 7, 8]).unwrap();
    let header = dir.path().join("h.nhdr");
    std::fs::write(
        &header,
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: data.nrrd\n",
    )
    .unwrap();
    let (out, _) = run(
        &[
            "analyze",
            s(&header),
            "--axis",
            "z",
            "--slabs",
            "1",
            "--export-labels",
            s(&data),
            "--force",
        ],
        1 << 30,
    );
    fails(&out, "data.nrrd", "is an input of this command");
    assert_eq!(std::fs::read(&data).unwrap(), [1u8, 2, 3, 4, 5, 6, 7, 8]);
    #[cfg(unix)]
    {
        let fifo = dir.path().join("pipe.json");
        assert!(
            Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .unwrap()
                .success()
        );
        let (out, _) = run(
            &["analyze", s(&input), "--export-slabs", s(&fifo), "--force"],
            1 << 30,
        );
        fails(
            &out,
            "pipe.json",
            "not a regular file: slabscope writes only regular files",
        );
        assert!(std::os::unix::fs::FileTypeExt::is_fifo(
            &std::fs::metadata(&fifo).unwrap().file_type()
        ));
    }
}

#[test]
fn outputs_are_checked_before_any_work_and_written_together() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let input = layers(dir.path(), 20);
    let same = dir.path().join("out.json");
    let (out, _) = run(
        &[
            "analyze",
            s(&input),
            "--export-slabs",
            s(&same),
            "--curves",
            s(&same),
        ],
        1 << 30,
    );
    fails(&out, "out.json", "given for two outputs");
    let missing = dir.path().join("no/such/folder/labels.nrrd");
    let (out, _) = run(
        &["analyze", s(&input), "--export-labels", s(&missing)],
        1 << 30,
    );
    fails(&out, "labels.nrrd", "does not exist");
    // An analysis that fails writes nothing, though its first export could have been.
    let (out, _) = run(
        &[
            "analyze",
            s(&input),
            "--axis",
            "z",
            "--slabs",
            "99",
            "--export-slabs",
            s(&dir.path().join("a.json")),
            "--export-labels",
            s(&dir.path().join("b.nrrd")),
        ],
        1 << 30,
    );
    fails(&out, "layers.nrrd", "--slabs 99");
    assert_eq!(listing(dir.path()), ["layers.nrrd"]);
}

#[cfg(unix)]
#[test]
fn an_interrupted_write_leaves_nothing_behind() {
    let _alone = crate::one_at_a_time();
    for signal in ["INT", "TERM"] {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("big.nrrd");
        let mut child = slabscope()
            .args(["phantom", "body", "--dims", "256x256x600", "-o", s(&target)])
            .spawn()
            .unwrap();
        let start = Instant::now();
        let staged = loop {
            let names = listing(dir.path());
            if names.iter().any(|n| n.starts_with(".big.nrrd.slabscope-")) {
                // Wait for bytes, past the writability probe's empty file.
                let path = dir.path().join(&names[0]);
                if std::fs::metadata(&path).is_ok_and(|m| m.len() > 0) {
                    break true;
                }
            }
            if start.elapsed() > Duration::from_secs(60) || child.try_wait().unwrap().is_some() {
                break false;
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        assert!(staged, "the write was never seen under way");
        let killed = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        let status = child.wait().unwrap();
        assert!(!status.success());
        assert!(
            listing(dir.path()).is_empty(),
            "{signal}: {:?}",
            listing(dir.path())
        );
    }
}

#[test]
fn camera_values_are_checked() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let input = layers(dir.path(), 20);
    let png = dir.path().join("v.png");
    for (flag, value) in [
        ("--spread", "inf"),
        ("--spread", "1e308"),
        ("--spread", "NaN"),
        ("--zoom", "0"),
        ("--zoom", "NaN"),
        ("--zoom", "1e-300"),
        ("--azimuth", "inf"),
    ] {
        let (out, took) = run(&["render", s(&input), "-o", s(&png), flag, value], 1 << 30);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag} {value}: {stderr}");
        assert!(
            stderr.contains(&format!("'{value}' for '{flag}")),
            "{stderr}"
        );
        assert!(took < Duration::from_secs(5));
        assert!(!png.exists());
    }
}

// --- messages and inputs ------------------------------------------------------------------------

#[test]
fn messages_say_what_is_wrong_on_one_line() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    // A name with a newline is escaped.
    let odd = dir.path().join("two\nlines.nrrd");
    std::fs::write(&odd, "NRRD0004\ntype: uchar\n").unwrap();
    let (out, _) = run(&["info", s(&odd)], 1 << 30);
    fails(&out, "two\\nlines.nrrd", "");
    // NIfTI dims of -1 beyond the third.
    let nii = dir.path().join("neg.nii");
    let mut h = vec![0u8; 352 + 8];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (k, d) in [7i16, 2, 2, 2, -1, -1, -1, -1].iter().enumerate() {
        h[40 + 2 * k..42 + 2 * k].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&2i16.to_le_bytes());
    h[72..74].copy_from_slice(&8i16.to_le_bytes());
    for k in 0..8 {
        h[76 + 4 * k..80 + 4 * k].copy_from_slice(&1f32.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[344..348].copy_from_slice(b"n+1\0");
    std::fs::write(&nii, &h).unwrap();
    let (out, _) = run(&["info", s(&nii)], 1 << 30);
    fails(&out, "neg.nii", "dim[4] is -1");
    // A detached header's truncated data: the header first, then its data file.
    std::fs::write(dir.path().join("short.raw"), [1u8, 2, 3]).unwrap();
    let header = dir.path().join("short.nhdr");
    std::fs::write(
        &header,
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: short.raw\n",
    )
    .unwrap();
    let (out, _) = run(&["info", s(&header)], 1 << 30);
    fails(
        &out,
        "short.nhdr: ",
        "short.raw: truncated voxel data: expected 8 bytes, found 3",
    );
    // Data files that are no files.
    for (target, phrase) in [("/dev/zero", "is a device"), (".", "is a folder")] {
        let header = dir.path().join("odd.nhdr");
        std::fs::write(
            &header,
            format!(
                "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: {target}\n"
            ),
        )
        .unwrap();
        let (out, _) = run(&["info", s(&header)], 1 << 30);
        fails(&out, "odd.nhdr", phrase);
    }
    // The default slab count is not blamed on --slabs.
    let small = dir.path().join("small.nrrd");
    std::fs::write(
        &small,
        b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n\x01\x02\x03\x04\x05\x06\x07\x08",
    )
    .unwrap();
    let (out, _) = run(&["analyze", s(&small), "--axis", "z"], 1 << 30);
    fails(&out, "small.nrrd", "the default of 4 slabs does not fit");
}

#[cfg(unix)]
#[test]
fn fifos_are_refused_not_waited_on() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("scan.nii");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    for args in [vec!["info", s(&fifo)], vec![s(&fifo)]] {
        let (out, took) = run(&args, 1 << 30);
        fails(
            &out,
            "scan.nii",
            "a FIFO (named pipe): slabscope reads regular files and folders",
        );
        assert!(took < Duration::from_secs(5));
    }
}

#[test]
fn the_tui_starts_only_where_it_can() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nowhere.nrrd");
    let (out, _) = run(&[s(&missing)], 1 << 30);
    fails(&out, "nowhere.nrrd", "No such file or directory");
    // Without a terminal (as `ssh host slabscope f` runs it): what to run instead.
    let input = layers(dir.path(), 20);
    let (out, _) = run(&[s(&input)], 1 << 30);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr.contains("the TUI needs a terminal"), "{stderr}");
    assert!(
        stderr.contains("`slabscope analyze`, `render` and `preview`"),
        "{stderr}"
    );
}

// --- DICOM ------------------------------------------------------------------------------------

/// An explicit VR little endian element.
fn element(group: u16, elem: u16, vr: [u8; 2], value: &[u8]) -> Vec<u8> {
    let mut b = Vec::new();
    b.extend(group.to_le_bytes());
    b.extend(elem.to_le_bytes());
    b.extend(vr);
    if matches!(&vr, b"OB" | b"OW" | b"SQ" | b"UN" | b"UT") {
        b.extend([0, 0]);
        b.extend((value.len() as u32).to_le_bytes());
    } else {
        b.extend((value.len() as u16).to_le_bytes());
    }
    b.extend(value);
    b
}

/// A DICOM file: preamble, `DICM`, a meta group naming `syntax`, then `body`.
fn dicom(syntax: &str, body: &[u8]) -> Vec<u8> {
    let mut uid = syntax.as_bytes().to_vec();
    if uid.len() % 2 == 1 {
        uid.push(0);
    }
    let mut b = vec![0u8; 128];
    b.extend(b"DICM");
    b.extend(element(2, 0x10, *b"UI", &uid));
    b.extend(body);
    b
}

/// The image elements of a 4x4 u16 image with `frames` frames.
fn image_header(frames: &str) -> Vec<u8> {
    let mut b = Vec::new();
    b.extend(element(0x28, 0x02, *b"US", &1u16.to_le_bytes()));
    b.extend(element(0x28, 0x04, *b"CS", b"MONOCHROME2 "));
    b.extend(element(0x28, 0x08, *b"IS", frames.as_bytes()));
    b.extend(element(0x28, 0x10, *b"US", &4u16.to_le_bytes()));
    b.extend(element(0x28, 0x11, *b"US", &4u16.to_le_bytes()));
    b.extend(element(0x28, 0x100, *b"US", &16u16.to_le_bytes()));
    b.extend(element(0x28, 0x101, *b"US", &16u16.to_le_bytes()));
    b
}

const EXPLICIT: &str = "1.2.840.10008.1.2.1";

#[test]
fn dicom_lengths_are_checked_against_the_file_before_anything_is_kept() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    // A 4 GB value claimed by a file of a few hundred bytes.
    let mut body = image_header("1 ");
    body.extend([0x09, 0x00, 0x10, 0x10, b'O', b'B', 0, 0]);
    body.extend(0xFFFF_FFF0u32.to_le_bytes());
    body.extend([0u8; 16]);
    let huge = dir.path().join("huge.dcm");
    std::fs::write(&huge, dicom(EXPLICIT, &body)).unwrap();
    let (out, _) = run(&["info", s(&huge), "--max-memory", "64M"], 64 << 20);
    fails(
        &out,
        "huge.dcm",
        "claims 4294967280 bytes where 16 are left",
    );

    // Sequences nested 100,000 deep (undefined lengths: 12 bytes a level).
    let mut body = Vec::new();
    for _ in 0..100_000 {
        body.extend([
            0x09, 0x00, 0x10, 0x10, b'S', b'Q', 0, 0, 0xFF, 0xFF, 0xFF, 0xFF,
        ]);
        body.extend([0xFE, 0xFF, 0x00, 0xE0, 0xFF, 0xFF, 0xFF, 0xFF]);
    }
    let deep = dir.path().join("deep.dcm");
    std::fs::write(&deep, dicom(EXPLICIT, &body)).unwrap();
    let (out, _) = run(&["info", s(&deep)], 64 << 20);
    fails(&out, "deep.dcm", "sequences nest deeper than 32");

    // 40,000 small elements: their parsed form is charged to the budget.
    let mut body = Vec::new();
    for i in 0..40_000u32 {
        body.extend(element(0x0009, 0x1000 + (i % 0xE000) as u16, *b"LO", b"ab"));
    }
    let many = dir.path().join("many.dcm");
    std::fs::write(&many, dicom(EXPLICIT, &body)).unwrap();
    let (out, _) = run(&["info", s(&many), "--max-memory", "1M"], 1 << 20);
    fails(&out, "many.dcm", "over the memory limit");
}

#[test]
fn dicom_frames_and_compressed_sizes_are_checked_before_they_are_spent() {
    let _alone = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    // Two billion frames of native pixels in a 32-byte pixel data element.
    let mut body = image_header("2000000000");
    body.extend(element(0x7FE0, 0x10, *b"OW", &[0u8; 32]));
    let frames = dir.path().join("frames.dcm");
    std::fs::write(&frames, dicom(EXPLICIT, &body)).unwrap();
    let (out, _) = run(&["info", s(&frames), "--max-memory", "64M"], 64 << 20);
    fails(&out, "frames.dcm", "truncated voxel data");

    // A JPEG lossless fragment whose frame header claims 65535x65535 in a 4x4 image.
    let body = fragment([0xC3, 16, 0xFF, 0xFF, 0xFF, 0xFF]);
    let bomb = dir.path().join("bomb.dcm");
    std::fs::write(&bomb, dicom("1.2.840.10008.1.2.4.70", &body)).unwrap();
    let (out, _) = run(&["info", s(&bomb), "--max-memory", "64M"], 64 << 20);
    fails(&out, "bomb.dcm", "a compressed frame of 65535x65535 pixels");

    // 12-bit extended JPEG, which the pure-Rust decoder does not read: named, not attempted.
    let twelve = dicom("1.2.840.10008.1.2.4.51", &fragment([0xC1, 12, 0, 4, 0, 4]));
    let path = dir.path().join("twelve.dcm");
    std::fs::write(&path, twelve).unwrap();
    let (out, _) = run(&["info", s(&path)], 64 << 20);
    fails(&out, "twelve.dcm", "12-bit extended JPEG");
}

/// The image elements and encapsulated pixel data of one fragment: a JPEG stream whose frame
/// header is `sof` (marker, precision, height, width).
fn fragment(sof: [u8; 6]) -> Vec<u8> {
    let mut body = image_header("1 ");
    body.extend([
        0xE0, 0x7F, 0x10, 0x00, b'O', b'B', 0, 0, 0xFF, 0xFF, 0xFF, 0xFF,
    ]);
    body.extend([0xFE, 0xFF, 0x00, 0xE0, 0, 0, 0, 0]);
    let jpeg = [
        0xFF, 0xD8, 0xFF, sof[0], 0x00, 0x0B, sof[1], sof[2], sof[3], sof[4], sof[5], 1, 1, 0x11,
        0, 0,
    ];
    body.extend([0xFE, 0xFF, 0x00, 0xE0]);
    body.extend((jpeg.len() as u32).to_le_bytes());
    body.extend(jpeg);
    body.extend([0xFE, 0xFF, 0xDD, 0xE0, 0, 0, 0, 0]);
    body
}

#[test]
fn dicom_errors_quote_no_header_values() {
    let _alone = crate::one_at_a_time();
    // A transfer syntax whose length runs over the data set's first elements: the message
    // must not carry them (a patient's name among them) out.
    let dir = tempfile::tempdir().unwrap();
    let mut uid = b"1.2.840.10008.1.2.1\0".to_vec();
    uid.extend(element(0x10, 0x10, *b"PN", b"Secret^Patient"));
    let path = dir.path().join("leak.dcm");
    let mut bytes = vec![0u8; 128];
    bytes.extend(b"DICM");
    bytes.extend(element(2, 0x10, *b"UI", &uid));
    std::fs::write(&path, bytes).unwrap();
    let (out, _) = run(&["info", s(&path)], 64 << 20);
    fails(
        &out,
        "leak.dcm",
        "the transfer syntax in the file meta group is not a UID",
    );
    assert!(!String::from_utf8_lossy(&out.stderr).contains("Secret"));
}
