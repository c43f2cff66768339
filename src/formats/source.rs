//! What a reader reads: a [`Source`] of bytes, and the checks that keep every input a regular
//! file or a folder (never a FIFO or a device, which would block or never end).

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::{Error, Result};
use crate::volume::mapped::{self, MappedFile};

/// The bytes a reader reads: today a regular file (or, for the folder formats, a folder) named
/// by its path; a remote store can be one later. Readers take a source rather than a path, and
/// reach its bytes through it ([`open`](Self::open), [`map`](Self::map), [`head`](Self::head),
/// [`len`](Self::len)) and the files a header names beside it through
/// [`sibling`](Self::sibling); the shared voxel reader (`data.rs`) reads the source its header
/// names; TIFF decodes the source's map, and DICOM reads each of a series' files through a
/// source of its own. What still takes [`path`](Self::path): the folder formats, whose volume is
/// many files (a folder of TIFF slices or of DICOM files walked by its path, a Zarr store read
/// by key from its folder or URL), and messages, which name the path.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Source {
    path: PathBuf,
}

impl Source {
    /// The file or folder at `path`.
    #[must_use]
    pub fn new(path: &Path) -> Self {
        Self {
            path: path.to_path_buf(),
        }
    }

    /// Its path, for the readers whose parsers still need one (a remote source will have none).
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Its name (the last component of its path), as given.
    #[must_use]
    pub fn name(&self) -> String {
        self.path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    }

    /// How messages show it.
    #[must_use]
    pub fn shown(&self) -> String {
        crate::error::shown(&self.path)
    }

    /// Opens it for reading ([`open_regular`]: only a regular file, never blocking).
    pub fn open(&self) -> Result<File> {
        open_regular(&self.path).map_err(|e| Error::io(&self.path, e))
    }

    /// Its length in bytes.
    pub fn len(&self) -> Result<u64> {
        let file = self.open()?;
        Ok(file.metadata().map_err(|e| Error::io(&self.path, e))?.len())
    }

    /// Whether it holds no bytes.
    pub fn is_empty(&self) -> Result<bool> {
        Ok(self.len()? == 0)
    }

    /// Its first `n` bytes (all of them when it is shorter).
    pub fn head(&self, n: usize) -> Result<Vec<u8>> {
        let mut head = Vec::with_capacity(n);
        self.open()?
            .take(n as u64)
            .read_to_end(&mut head)
            .map_err(|e| Error::io(&self.path, e))?;
        Ok(head)
    }

    /// Its bytes, mapped read-only (a truncation by another process while mapped is reported by
    /// [`mapped`]'s fault handler).
    pub fn map(&self) -> Result<Arc<MappedFile>> {
        mapped::map(&self.open()?, &self.path).map_err(|e| Error::io(&self.path, e))
    }

    /// The data file its header names (`name`, relative to its folder unless absolute); it must
    /// be a regular file that exists, else the error names this source.
    pub fn sibling(&self, name: &str) -> Result<Source> {
        let p = Path::new(name);
        let file = if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.path.parent().unwrap_or(Path::new(".")).join(p)
        };
        match std::fs::metadata(&file) {
            Ok(meta) if meta.is_file() => Ok(Self { path: file }),
            Ok(meta) => Err(Error::format(
                &self.path,
                format!(
                    "its data file {} is {}",
                    crate::error::shown(&file),
                    kind(&meta).unwrap_or("a folder")
                ),
            )),
            Err(e) => Err(Error::format(
                &self.path,
                format!("its data file {}: {e}", crate::error::shown(&file)),
            )),
        }
    }
}

/// Fails unless `path` is a regular file or a folder (or a URL, [`super::remote::is_url`], read
/// by its reader): a FIFO would block forever and a device would never end.
pub fn check_input(path: &Path) -> Result<()> {
    if super::remote::is_url(path) {
        return Ok(());
    }
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    match kind(&meta) {
        None => Ok(()),
        Some(kind) => Err(Error::unsupported(
            path,
            format!("{kind}: slabscope reads regular files and folders"),
        )),
    }
}

/// Opens `path` for reading, only if it is a regular file, without ever blocking: the open does
/// not wait (`O_NONBLOCK`: a FIFO or a device, even one mounted over a file's name, opens at once
/// instead of waiting for a writer) and the opened handle's own type is checked (not the name's,
/// which a directory listing or an earlier `stat` may have seen differently). Every input file
/// is opened through it.
pub fn open_regular(path: &Path) -> std::io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY);
    }
    regular(options.open(path)?)
}

/// `file`, opened without blocking, when its handle is of a regular file: else an error (of kind
/// `InvalidInput`) saying what it is.
pub fn regular(file: File) -> std::io::Result<File> {
    let meta = file.metadata()?;
    match kind(&meta) {
        None if meta.is_file() => Ok(file),
        None => Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "a folder, where a file was expected",
        )),
        Some(kind) => Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{kind}: slabscope reads regular files and folders"),
        )),
    }
}

/// What a path that is neither a regular file nor a folder is, in words.
fn kind(meta: &std::fs::Metadata) -> Option<&'static str> {
    if meta.is_file() || meta.is_dir() {
        return None;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if t.is_char_device() || t.is_block_device() {
            return Some("a device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A FIFO opens at once and is refused by its handle's own type, never waiting for a writer
    /// (a plain `File::open` would wait forever); a folder is refused too.
    #[test]
    #[cfg(unix)]
    fn only_regular_files_open_and_a_fifo_never_blocks() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("scan0001");
        if !std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success())
        {
            eprintln!("skipped: no mkfifo");
            return;
        }
        let (tx, rx) = std::sync::mpsc::channel();
        let path = fifo.clone();
        std::thread::spawn(move || {
            let _ = tx.send(open_regular(&path).map(drop).map_err(|e| e.to_string()));
        });
        let opened = rx
            .recv_timeout(std::time::Duration::from_secs(10))
            .expect("the open returned at once");
        let e = opened.unwrap_err();
        assert!(e.contains("a FIFO"), "{e}");
        let e = open_regular(dir.path()).unwrap_err().to_string();
        assert!(e.contains("a folder"), "{e}");
        let file = dir.path().join("a.nii");
        std::fs::write(&file, b"x").unwrap();
        assert!(open_regular(&file).is_ok());
    }

    /// A source gives its bytes, its head and its length, and finds the data file beside it.
    #[test]
    fn a_source_reads_its_bytes_and_finds_its_sibling() {
        let dir = tempfile::tempdir().unwrap();
        let header = dir.path().join("a.nhdr");
        std::fs::write(&header, b"NRRD0004\n").unwrap();
        std::fs::write(dir.path().join("a.raw"), [1u8, 2, 3]).unwrap();
        let source = Source::new(&header);
        assert_eq!(source.name(), "a.nhdr");
        assert_eq!(source.len().unwrap(), 9);
        assert!(!source.is_empty().unwrap());
        assert_eq!(source.head(4).unwrap(), b"NRRD");
        assert_eq!(source.map().unwrap().bytes(), b"NRRD0004\n");
        let data = source.sibling("a.raw").unwrap();
        assert_eq!(data.path(), dir.path().join("a.raw"));
        let e = source.sibling("missing.raw").unwrap_err().to_string();
        assert!(e.contains("a.nhdr") && e.contains("missing.raw"), "{e}");
        let e = source.sibling(".").unwrap_err().to_string();
        assert!(e.contains("is a folder"), "{e}");
    }
}
