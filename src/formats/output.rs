//! Writing files so that nothing is half-written, replaced unasked, or left behind: each output
//! is staged in a temporary file beside its target and renamed into place when complete; only
//! regular files are ever replaced, and only when asked; a front end's signal handler removes
//! the staged files of an interrupted run.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use tempfile::NamedTempFile;

use crate::error::{Error, Result};

/// The temporary files staged and not yet put in place or dropped.
static STAGED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every staged file: for a signal handler, before the process ends without running
/// destructors.
pub fn remove_staged() {
    let staged = STAGED
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    for path in staged.iter() {
        let _ = std::fs::remove_file(path);
    }
}

/// Fails unless `path` may be written: it must not exist unless `force` is set, and then it must
/// be a regular file (never a device, a FIFO or a folder); its folder must exist and take new
/// files. Call it before any work, so that a run does not fail at its end.
pub fn check_output(path: &Path, force: bool) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(meta) if !meta.is_file() => {
            return Err(Error::NotRegularFile {
                path: path.to_path_buf(),
            });
        }
        Ok(_) if !force => {
            return Err(Error::Exists {
                path: path.to_path_buf(),
            });
        }
        _ => {}
    }
    let dir = folder(path);
    if !dir.is_dir() {
        return Err(Error::format(
            path,
            format!("folder {} does not exist", crate::error::shown(dir)),
        ));
    }
    // A file made and removed at once: the folder takes new files.
    temporary(path).map(drop)
}

/// Whether `a` and `b` are the same file (the same device and inode; the same canonical path
/// where there are no inodes). A path that does not exist is no file.
pub fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ma.dev() == mb.dev() && ma.ino() == mb.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (ma, mb);
        a.canonicalize().ok() == b.canonicalize().ok()
    }
}

fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// What the staging files of `path` are named before their process id: `.NAME.slabscope-`
/// (`.slabscope-` alone for a name too long to carry).
fn staging_prefix(path: &Path) -> std::ffi::OsString {
    let mut prefix = std::ffi::OsString::from(".");
    match path.file_name() {
        Some(name) if name.len() <= 200 => {
            prefix.push(name);
            prefix.push(".slabscope-");
        }
        _ => prefix = ".slabscope-".into(),
    }
    prefix
}

/// Removes the staging files of `path` that a killed run left beside it: named after it, by a
/// process that no longer runs (`/proc/PID` is gone; where there is no `/proc` nothing is
/// removed), and regular files. A run still writing the same target keeps its own.
#[cfg(unix)]
fn remove_stale(path: &Path) {
    use std::os::unix::ffi::OsStrExt;
    let prefix = staging_prefix(path);
    let prefix = prefix.as_bytes();
    if prefix == b".slabscope-" || !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(folder(path)) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(rest) = name.as_bytes().strip_prefix(prefix) else {
            continue;
        };
        let pid = rest.split(|&b| b == b'-').next().unwrap_or_default();
        let Some(pid) = std::str::from_utf8(pid)
            .ok()
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        let regular = entry.file_type().is_ok_and(|t| t.is_file());
        let gone = pid != std::process::id() && !Path::new("/proc").join(pid.to_string()).exists();
        if regular && gone && name.as_bytes().ends_with(b".tmp") {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// A new temporary file beside `path`, named after it and this process
/// (`.NAME.slabscope-PID-XXXXXX.tmp`), with the usual permissions (0644 on Unix); the staging
/// files of `path` a killed run left are removed first.
fn temporary(path: &Path) -> Result<NamedTempFile> {
    #[cfg(unix)]
    remove_stale(path);
    let mut prefix = staging_prefix(path);
    prefix.push(format!("{}-", std::process::id()));
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o644));
    }
    builder
        .tempfile_in(folder(path))
        .map_err(|e| Error::io(path, e))
}

/// An output written to a temporary file beside its target, not yet in place. Dropped, it is
/// removed.
pub struct Staged {
    /// The temporary file; taken when it is put in place.
    file: Option<NamedTempFile>,
    path: PathBuf,
}

/// Writes what `write` writes to a temporary file beside `path` and flushes it to disk.
pub fn stage(path: &Path, write: impl FnOnce(&File) -> std::io::Result<()>) -> Result<Staged> {
    let file = temporary(path)?;
    STAGED
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
        .push(file.path().to_path_buf());
    write(file.as_file())
        .and_then(|()| file.as_file().sync_all())
        .map_err(|e| {
            unregister(file.path());
            Error::io(path, e)
        })?;
    Ok(Staged {
        file: Some(file),
        path: path.to_path_buf(),
    })
}

impl Staged {
    /// The file it will become.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Puts the file in place: an existing regular file is replaced only when `force` is set;
    /// anything else is never replaced.
    pub fn persist(mut self, force: bool) -> Result<()> {
        let path = self.path.clone();
        if let Ok(meta) = std::fs::metadata(&path)
            && !meta.is_file()
        {
            return Err(Error::NotRegularFile { path });
        }
        let Some(file) = self.file.take() else {
            return Ok(());
        };
        unregister(file.path());
        let persisted = if force {
            file.persist(&path)
        } else {
            file.persist_noclobber(&path)
        };
        persisted.map_err(|e| {
            if e.error.kind() == std::io::ErrorKind::AlreadyExists {
                Error::Exists { path: path.clone() }
            } else {
                Error::io(&path, e.error)
            }
        })?;
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(file) = &self.file {
            unregister(file.path());
        }
    }
}

fn unregister(temp: &Path) {
    STAGED
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
        .retain(|p| p != temp);
}

/// Writes a file through a temporary file beside `path`, renamed into place when complete, so a
/// reader never sees half a file; an existing `path` is replaced only when `force` is set and it
/// is a regular file.
pub fn write_atomic(
    path: &Path,
    force: bool,
    write: impl FnOnce(&File) -> std::io::Result<()>,
) -> Result<()> {
    check_output(path, force)?;
    stage(path, write)?.persist(force)
}
