//! The store a Zarr array is read from: the files of a local folder, each opened as every input
//! file is (never blocking, regular files only: a FIFO named like a chunk cannot hang the
//! read), inside the store's tree (a symbolic link that leads out of it refused, with no window
//! between a check and the open for a link swapped in to slip through) and weighed before it
//! is read (a file larger than the budget is an error, not an allocation).

use std::collections::VecDeque;
use std::ffi::OsString;
use std::os::unix::fs::FileExt;
use std::path::{Component, Path, PathBuf};

use zarrs::storage::byte_range::{ByteRange, ByteRangeIterator};
use zarrs::storage::{Bytes, MaybeBytesIterator, ReadableStorageTraits, StorageError, StoreKey};

use super::failure::Failure;
use super::guard::Guard;
use crate::error::human_bytes;

/// The store's tree: the folder given, canonical (its symbolic links resolved), that every file
/// read must lie in.
pub fn tree(dir: &Path) -> crate::error::Result<PathBuf> {
    dir.canonicalize()
        .map_err(|e| crate::error::Error::io(dir, e))
}

/// The most symbolic links followed on the way to one file (Linux's own limit).
const MAX_LINKS: usize = 40;

/// The error of a path that leads out of the store's tree (of kind `PermissionDenied`, naming
/// nothing of where it leads).
fn out_of_the_store() -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::PermissionDenied,
        "a symbolic link that leads out of the store: slabscope reads only the files inside it",
    )
}

/// The names of `path`'s components (`..` kept, `.` dropped); an error for an absolute path.
fn names(path: &Path) -> std::io::Result<VecDeque<OsString>> {
    let mut out = VecDeque::new();
    for c in path.components() {
        match c {
            Component::Normal(name) => out.push_back(name.to_os_string()),
            Component::ParentDir => out.push_back("..".into()),
            Component::CurDir => {}
            Component::RootDir | Component::Prefix(_) => return Err(out_of_the_store()),
        }
    }
    Ok(out)
}

/// Where in the tree `tree` the absolute link target `target` leads, from the tree's root: an
/// error when outside it. (Its name only: the walk then opens it from the tree's root, each
/// folder on the way checked again.)
fn beneath(tree: &Path, target: &Path) -> std::io::Result<PathBuf> {
    if let Ok(rest) = target.strip_prefix(tree) {
        return Ok(rest.to_path_buf());
    }
    // Named through a link to the tree (the store's folder as the user named it).
    let real = target.canonicalize()?;
    real.strip_prefix(tree)
        .map(Path::to_path_buf)
        .map_err(|_| out_of_the_store())
}

/// The file `relative` (a path inside the store) of the store whose tree is `tree` ([`tree`]),
/// opened as every input is (never blocking, a regular file only): an error of kind
/// `PermissionDenied`, naming nothing of the file, when it or a folder on its way is a symbolic
/// link that leads out of the tree; `NotFound` when there is none.
///
/// The path is walked one name at a time from the tree's root, each folder opened relative to
/// the one before it and nothing opened through a link (`O_NOFOLLOW`): a link on the way is read
/// and its target walked the same way, `..` never above the root. What is opened is what was
/// checked, so a link swapped in meanwhile cannot lead the read out of the tree. (The library
/// reads on Unix alone: `FileExt` above.)
pub fn open_inside(tree: &Path, relative: &Path) -> std::io::Result<std::fs::File> {
    use std::os::unix::ffi::OsStringExt;

    use rustix::fs::{CWD, Mode, OFlags, openat, readlinkat};
    use rustix::io::Errno;
    // A folder is opened only to look names up in: where there is `O_PATH`, without the right
    // to list it, which a path's lookup never needed.
    #[cfg(any(target_os = "linux", target_os = "android"))]
    let folder = OFlags::PATH | OFlags::DIRECTORY | OFlags::CLOEXEC;
    #[cfg(not(any(target_os = "linux", target_os = "android")))]
    let folder = OFlags::RDONLY | OFlags::DIRECTORY | OFlags::CLOEXEC;
    let file = OFlags::RDONLY | OFlags::NONBLOCK | OFlags::NOCTTY | OFlags::CLOEXEC;
    // The folders on the way, the tree's root first.
    let mut dirs = vec![openat(CWD, tree, folder, Mode::empty())?];
    let mut todo = names(relative)?;
    let mut links = 0;
    while let Some(name) = todo.pop_front() {
        if name == ".." {
            if dirs.len() == 1 {
                return Err(out_of_the_store());
            }
            dirs.pop();
            continue;
        }
        let Some(at) = dirs.last() else { break };
        match readlinkat(at, name.as_os_str(), Vec::new()) {
            Ok(target) => {
                links += 1;
                if links > MAX_LINKS {
                    return Err(Errno::LOOP.into());
                }
                let target = PathBuf::from(OsString::from_vec(target.into_bytes()));
                let rest = if target.is_absolute() {
                    dirs.truncate(1);
                    beneath(tree, &target)?
                } else {
                    target
                };
                for name in names(&rest)?.into_iter().rev() {
                    todo.push_front(name);
                }
                continue;
            }
            Err(Errno::INVAL) => {} // not a link
            Err(e) => return Err(e.into()),
        }
        let last = todo.is_empty();
        let flags = OFlags::NOFOLLOW | if last { file } else { folder };
        match openat(at, name.as_os_str(), flags, Mode::empty()) {
            Ok(fd) if last => return crate::formats::regular(std::fs::File::from(fd)),
            Ok(fd) => dirs.push(fd),
            // Made a link since it was read: looked at again, as a link.
            Err(Errno::LOOP) if links < MAX_LINKS => {
                links += 1;
                todo.push_front(name);
            }
            Err(e) => return Err(e.into()),
        }
    }
    // The tree itself, or a folder in it: refused as a folder.
    match dirs.pop() {
        Some(fd) => crate::formats::regular(std::fs::File::from(fd)),
        None => Err(out_of_the_store()),
    }
}

/// A read-only Zarr store over the folder `node` of a store's tree, whose files all lie in the
/// tree.
#[derive(Debug)]
pub struct LocalStore {
    /// The store's tree ([`tree`]): no file outside it is read.
    tree: PathBuf,
    /// The folder read, in the tree (`""` for its root).
    node: PathBuf,
    /// The most bytes one file of the store may hold.
    max_file: u64,
    /// What the chunks of the array read may decode to.
    guard: Option<Guard>,
}

impl LocalStore {
    /// The store of the folder `node` (a path in the tree, `""` for its root) of the store's
    /// tree `tree`, whose files may each hold at most `max_file` bytes.
    pub fn new(tree: &Path, node: &Path, max_file: u64) -> Self {
        Self {
            tree: tree.to_path_buf(),
            node: node.to_path_buf(),
            max_file,
            guard: None,
        }
    }

    /// This store, each chunk of the array `guard` describes weighed before it is decoded.
    pub fn with_guard(mut self, guard: Guard) -> Self {
        self.guard = Some(guard);
        self
    }

    /// The file of `key` in the tree, which must stay inside the store's folder.
    fn path(&self, key: &StoreKey) -> Result<PathBuf, StorageError> {
        let relative = Path::new(key.as_str());
        if !relative
            .components()
            .all(|c| matches!(c, Component::Normal(_)))
        {
            return Err(StorageError::Other(format!(
                "key {key} leaves the store's folder"
            )));
        }
        Ok(self.node.join(relative))
    }

    /// The file of `key` opened with its size; `None` when there is none.
    fn open(&self, key: &StoreKey) -> Result<Option<(std::fs::File, u64)>, StorageError> {
        let path = self.path(key)?;
        let file = match open_inside(&self.tree, &path) {
            Ok(file) => file,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(unread(key, &e)),
        };
        let size = file.metadata().map_err(|e| unread(key, &e))?.len();
        if size > self.max_file {
            return Err(StorageError::Other(format!(
                "{key} holds {}, more than the memory limit of {}",
                human_bytes(size),
                human_bytes(self.max_file)
            )));
        }
        Ok(Some((file, size)))
    }
}

impl ReadableStorageTraits for LocalStore {
    fn get_partial_many<'a>(
        &'a self,
        key: &StoreKey,
        byte_ranges: ByteRangeIterator<'a>,
    ) -> Result<MaybeBytesIterator<'a>, StorageError> {
        let Some((file, size)) = self.open(key)? else {
            return Ok(None);
        };
        let out: Vec<Result<Bytes, StorageError>> = byte_ranges
            .map(|range| {
                let (bytes, span) = read_range(&file, size, key, range)?;
                if let Some(guard) = &self.guard {
                    guard
                        .check(key.as_str(), span, size, &bytes)
                        .map_err(Failure::Refused)?;
                }
                Ok(bytes)
            })
            .collect();
        Ok(Some(Box::new(out.into_iter())))
    }

    fn size_key(&self, key: &StoreKey) -> Result<Option<u64>, StorageError> {
        Ok(self.open(key)?.map(|(_, size)| size))
    }

    fn supports_get_partial(&self) -> bool {
        true
    }
}

/// The failure to read the file of `key`: `problem`.
fn unread(key: &StoreKey, problem: &dyn std::fmt::Display) -> StorageError {
    Failure::Unread {
        key: key.to_string(),
        problem: problem.to_string(),
    }
    .into()
}

/// The bytes of `range` of `file` (of `size` bytes), which must lie within it, with where they
/// lie.
fn read_range(
    file: &std::fs::File,
    size: u64,
    key: &StoreKey,
    range: ByteRange,
) -> Result<(Bytes, (u64, u64)), StorageError> {
    let (start, end) = match range {
        ByteRange::FromStart(start, None) => (start, size),
        ByteRange::FromStart(start, Some(length)) => (start, start.saturating_add(length)),
        ByteRange::Suffix(length) => (size.saturating_sub(length), size),
    };
    if start > end || end > size {
        // The range may come from a shard's index: its numbers are the file's bytes, not quoted.
        return Err(unread(
            key,
            &format!("a range of bytes asked that the file of {size} bytes does not hold"),
        ));
    }
    // Within the file, which is within the budget.
    let mut buffer = vec![0u8; (end - start) as usize];
    file.read_exact_at(&mut buffer, start)
        .map_err(|e| unread(key, &e))?;
    Ok((Bytes::from(buffer), (start, end)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The file opened is the one named inside the tree (a hard link is the file); a link out
    /// of the tree, at the end or on the way, is refused before anything behind it is opened.
    #[cfg(unix)]
    #[test]
    fn the_open_handle_is_the_file_named_inside_the_tree() {
        use std::os::unix::fs::{MetadataExt, symlink};
        let dir = tempfile::tempdir().unwrap();
        let store = dir.path().join("s.zarr");
        std::fs::create_dir_all(store.join("sub")).unwrap();
        std::fs::write(store.join("sub/a"), b"same").unwrap();
        std::fs::hard_link(store.join("sub/a"), store.join("a2")).unwrap();
        let tree = tree(&store).unwrap();
        let inode = |f: &std::fs::File| f.metadata().unwrap().ino();
        let a = open_inside(&tree, Path::new("sub/a")).unwrap();
        assert_eq!(
            inode(&a),
            std::fs::metadata(store.join("a2")).unwrap().ino()
        );
        assert_eq!(
            inode(&open_inside(&tree, Path::new("a2")).unwrap()),
            inode(&a)
        );
        std::fs::create_dir(dir.path().join("elsewhere")).unwrap();
        std::fs::write(dir.path().join("elsewhere/a"), b"x").unwrap();
        symlink(dir.path().join("elsewhere/a"), store.join("out")).unwrap();
        symlink(dir.path().join("elsewhere"), store.join("away")).unwrap();
        symlink("../elsewhere", store.join("up")).unwrap();
        symlink("sub/../../elsewhere/a", store.join("climb")).unwrap();
        for name in [
            "out",
            "away/a",
            "away/absent",
            "up/a",
            "climb",
            "../elsewhere/a",
        ] {
            let e = open_inside(&tree, Path::new(name)).unwrap_err();
            assert_eq!(e.kind(), std::io::ErrorKind::PermissionDenied, "{name}");
            assert_eq!(e.to_string(), out_of_the_store().to_string(), "{name}");
        }
        // `..` inside the tree, and the tree itself (a folder).
        let back = open_inside(&tree, Path::new("sub/../sub/a")).unwrap();
        assert_eq!(inode(&back), inode(&a));
        let e = open_inside(&tree, Path::new("")).unwrap_err();
        assert_eq!(e.to_string(), "a folder, where a file was expected");
        assert_eq!(
            open_inside(&tree, Path::new("sub/absent"))
                .unwrap_err()
                .kind(),
            std::io::ErrorKind::NotFound
        );
    }

    /// A loop of links ends in an error, and a FIFO named like a chunk is refused without
    /// blocking.
    #[cfg(unix)]
    #[test]
    fn loops_and_fifos_end_in_an_error() {
        use std::os::unix::fs::symlink;
        let dir = tempfile::tempdir().unwrap();
        symlink("b", dir.path().join("a")).unwrap();
        symlink("a", dir.path().join("b")).unwrap();
        let tree = tree(dir.path()).unwrap();
        let e = open_inside(&tree, Path::new("a")).unwrap_err();
        assert_eq!(e.raw_os_error(), Some(libc::ELOOP), "{e}");
        let fifo =
            std::ffi::CString::new(dir.path().join("f").into_os_string().into_encoded_bytes())
                .unwrap();
        rustix::fs::mknodat(
            rustix::fs::CWD,
            fifo.as_c_str(),
            rustix::fs::FileType::Fifo,
            rustix::fs::Mode::RUSR | rustix::fs::Mode::WUSR,
            0,
        )
        .unwrap();
        let e = open_inside(&tree, Path::new("f")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a FIFO (named pipe): slabscope reads regular files and folders"
        );
    }

    #[test]
    fn keys_stay_in_the_folder_and_files_within_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("n")).unwrap();
        std::fs::write(dir.path().join("n/small"), b"0123456789").unwrap();
        let tree = tree(dir.path()).unwrap();
        let store = LocalStore::new(&tree, Path::new("n"), 16);
        let key = |k: &str| StoreKey::new(k).unwrap();
        let got = store.get(&key("small")).unwrap().unwrap();
        assert_eq!(&got[..], b"0123456789");
        let tail = store
            .get_partial(&key("small"), ByteRange::Suffix(3))
            .unwrap()
            .unwrap();
        assert_eq!(&tail[..], b"789");
        assert!(store.get(&key("absent")).unwrap().is_none());
        let past = store
            .get_partial(&key("small"), ByteRange::FromStart(8, Some(5)))
            .unwrap_err();
        assert_eq!(
            past.to_string(),
            "small: a range of bytes asked that the file of 10 bytes does not hold"
        );
        let zarrs = zarrs::array::ArrayError::StorageError(past);
        assert_eq!(
            super::super::failure::find(&zarrs),
            Some(&Failure::Unread {
                key: "small".into(),
                problem: "a range of bytes asked that the file of 10 bytes does not hold".into()
            })
        );
        std::fs::write(dir.path().join("n/big"), [0u8; 17]).unwrap();
        let err = store.get(&key("big")).unwrap_err().to_string();
        assert_eq!(
            err,
            "big holds 17 bytes, more than the memory limit of 16 bytes"
        );
        assert!(store.path(&key("a/../../etc")).is_err());
    }

    #[cfg(unix)]
    #[test]
    fn links_inside_the_tree_are_read_and_links_out_of_it_refused() {
        use std::os::unix::fs::symlink;
        let outside = tempfile::tempdir().unwrap();
        std::fs::write(outside.path().join("secret"), b"ABCDEFGH").unwrap();
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("store");
        std::fs::create_dir_all(root.join("sub")).unwrap();
        std::fs::write(root.join("sub/real"), b"0123").unwrap();
        symlink(root.join("sub/real"), root.join("inside")).unwrap();
        symlink(outside.path().join("secret"), root.join("out")).unwrap();
        symlink(outside.path(), root.join("folder")).unwrap();
        symlink(root.join("sub"), root.join("alias")).unwrap();
        let store = LocalStore::new(&tree(&root).unwrap(), Path::new(""), 64);
        let key = |k: &str| StoreKey::new(k).unwrap();
        assert_eq!(&store.get(&key("inside")).unwrap().unwrap()[..], b"0123");
        assert_eq!(
            &store.get(&key("alias/real")).unwrap().unwrap()[..],
            b"0123"
        );
        for k in ["out", "folder/secret"] {
            let e = store.get(&key(k)).unwrap_err().to_string();
            assert!(e.contains(k) && e.contains("leads out of the store"), "{e}");
            assert!(!e.contains("ABCD"), "{e}");
        }
        // Nothing behind a link out of the store is looked at, not even whether it exists.
        let e = store.get(&key("folder/absent")).unwrap_err().to_string();
        assert!(e.contains("leads out of the store"), "{e}");
    }
}
