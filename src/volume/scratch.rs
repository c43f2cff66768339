//! Unnamed scratch files on disk, mapped: room for data beyond the memory budget that lives in
//! the kernel's page cache (written out and dropped under pressure) rather than the process's
//! memory. Decoded voxels beyond the budget (`formats/scratch.rs`, `--scratch DIR`) and a found
//! background's mask beside labels streamed to a file (`partition::Labeller`) are made in one.
//! The file has no name where the file system allows (`O_TMPFILE`: gone however the process
//! ends) and its blocks are reserved on disk before it is mapped, so that writing through the
//! map never meets a full disk; a folder in memory (tmpfs) is refused (the data would be in
//! memory after all), and so is one without room for the data with a margin to spare.

#![allow(unsafe_code)]

use std::fs::File;
use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};

/// Free space a scratch file must leave on its file system: this fraction of it (capped at
/// [`MARGIN_MAX`]), so that decoding never fills a disk others use.
const MARGIN_FRACTION: u64 = 20;
const MARGIN_MAX: u64 = 1 << 30;

/// The writable map of an unnamed scratch file of `bytes`, their room reserved on disk, in the
/// first of `dirs` that can hold one (not in memory, with room to spare), or why none could:
/// each folder's reason, joined.
pub(crate) fn scratch_in_any(
    dirs: &[PathBuf],
    bytes: u64,
) -> std::result::Result<memmap2::MmapMut, String> {
    let mut why = Vec::new();
    for dir in dirs {
        match scratch_map(dir, bytes) {
            Ok(map) => return Ok(map),
            Err(e) => why.push(e),
        }
    }
    Err(why.join("; "))
}

/// The writable map of an unnamed file in the scratch folder with `bytes` reserved on disk,
/// or why there is none.
pub(crate) fn scratch_map(dir: &Path, bytes: u64) -> std::result::Result<memmap2::MmapMut, String> {
    let shown = crate::error::shown(dir);
    let file = tempfile::tempfile_in(dir)
        .map_err(|e| format!("no scratch file could be made in {shown} ({e})"))?;
    let room = room_of(&file).map_err(|e| format!("the scratch folder {shown}: {e}"))?;
    if room.in_memory {
        return Err(format!(
            "the scratch folder {shown} is in memory (tmpfs), not on disk"
        ));
    }
    let margin = (room.total / MARGIN_FRACTION).min(MARGIN_MAX);
    if bytes.saturating_add(margin) > room.free {
        return Err(format!(
            "the scratch folder {shown} has {} free, not {} with a margin",
            mib(room.free),
            mib(bytes.saturating_add(margin))
        ));
    }
    reserve(&file, bytes).map_err(|e| format!("the scratch folder {shown}: {e}"))?;
    // SAFETY: the file has no name, so no other process can open, write or truncate it; its
    // blocks are reserved, so writing through the map cannot meet a full disk.
    unsafe { memmap2::MmapMut::map_mut(&file) }
        .map_err(|e| format!("the scratch file in {shown} could not be mapped ({e})"))
}

/// Sets `file`'s length to `bytes` with every block allocated on disk: `fallocate(2)` itself,
/// not glibc's `posix_fallocate`, which on a file system without it writes every block in turn;
/// such a file system is refused instead.
#[cfg(target_os = "linux")]
fn reserve(file: &File, bytes: u64) -> std::io::Result<()> {
    let len = libc::off_t::try_from(bytes).map_err(std::io::Error::other)?;
    // SAFETY: a plain system call on a descriptor `file` keeps open.
    if unsafe { libc::fallocate(file.as_raw_fd(), 0, 0, len) } == 0 {
        return Ok(());
    }
    let e = std::io::Error::last_os_error();
    if e.raw_os_error() == Some(libc::EOPNOTSUPP) {
        return Err(std::io::Error::other(
            "its file system cannot reserve room for a file (no fallocate)",
        ));
    }
    Err(e)
}

#[cfg(not(target_os = "linux"))]
fn reserve(_file: &File, _bytes: u64) -> std::io::Result<()> {
    Err(std::io::Error::other(
        "decoding to disk is built for Linux only",
    ))
}

fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / f64::from(1u32 << 20))
}

/// The file system a file is on: its size and free bytes, and whether it lives in memory.
pub(crate) struct FileSystem {
    total: u64,
    pub(crate) free: u64,
    /// Whether it lives in memory (tmpfs, ramfs).
    pub(crate) in_memory: bool,
}

#[allow(clippy::useless_conversion)] // the fields are wider or narrower elsewhere
pub(crate) fn room_of(file: &File) -> std::io::Result<FileSystem> {
    let fd = file.as_raw_fd();
    // SAFETY: `fstatvfs` writes one `statvfs` into the zeroed struct it is given, for an open
    // descriptor that `file` keeps alive.
    let mut vfs: libc::statvfs = unsafe { std::mem::zeroed() };
    if unsafe { libc::fstatvfs(fd, &raw mut vfs) } != 0 {
        return Err(std::io::Error::last_os_error());
    }
    let block = u64::from(vfs.f_frsize);
    Ok(FileSystem {
        total: u64::from(vfs.f_blocks).saturating_mul(block),
        free: u64::from(vfs.f_bavail).saturating_mul(block),
        in_memory: in_memory(fd)?,
    })
}

#[cfg(target_os = "linux")]
fn in_memory(fd: std::os::fd::RawFd) -> std::io::Result<bool> {
    const TMPFS_MAGIC: i64 = 0x0102_1994;
    const RAMFS_MAGIC: i64 = 0x8584_58f6;
    // SAFETY: as for `fstatvfs` above: one `statfs` written into the zeroed struct.
    let mut fs: libc::statfs = unsafe { std::mem::zeroed() };
    if unsafe { libc::fstatfs(fd, &raw mut fs) } != 0 {
        return Err(std::io::Error::last_os_error());
    }
    #[allow(clippy::useless_conversion)]
    let kind = i64::from(fs.f_type);
    Ok(kind == TMPFS_MAGIC || kind == RAMFS_MAGIC)
}

#[cfg(not(target_os = "linux"))]
fn in_memory(_fd: std::os::fd::RawFd) -> std::io::Result<bool> {
    Ok(false)
}
