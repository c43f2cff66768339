//! The store a Zarr array is read from: the files of a local folder, each opened as every input
//! file is (never blocking, regular files only: a FIFO named like a chunk cannot hang the
//! read) and weighed before it is read (a file larger than the budget is an error, not an
//! allocation).

use std::os::unix::fs::FileExt;
use std::path::{Component, Path, PathBuf};

use zarrs::storage::byte_range::{ByteRange, ByteRangeIterator};
use zarrs::storage::{Bytes, MaybeBytesIterator, ReadableStorageTraits, StorageError, StoreKey};

use super::guard::Guard;
use crate::error::human_bytes;

/// The store's tree: the folder given, canonical (its symbolic links resolved), that every file
/// read must lie in.
pub fn tree(dir: &Path) -> crate::error::Result<PathBuf> {
    dir.canonicalize()
        .map_err(|e| crate::error::Error::io(dir, e))
}

/// The file `path` of the store whose tree is `tree` ([`tree`]), opened as every input is: an
/// error (of kind `PermissionDenied`, naming nothing of the file) when it, or a folder on its
/// way, is a symbolic link that leads out of the tree; `NotFound` when there is none.
///
/// Nothing outside the tree is opened, and the open handle is checked after: its name's real
/// place must still lie in the tree and be the very file opened (the same device and inode),
/// so a link swapped in between the check and the open cannot lead the read out of the tree.
pub fn open_inside(tree: &Path, path: &Path) -> std::io::Result<std::fs::File> {
    let inside = |p: &Path| {
        let real = p.canonicalize()?;
        if real.starts_with(tree) {
            Ok(real)
        } else {
            Err(std::io::Error::new(
                std::io::ErrorKind::PermissionDenied,
                "a symbolic link that leads out of the store: slabscope reads only the files \
                 inside it",
            ))
        }
    };
    let real = inside(path)?;
    let file = crate::formats::open_regular(&real)?;
    let again = inside(&real)?;
    if !same_file(&file.metadata()?, &std::fs::metadata(&again)?) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::PermissionDenied,
            "a file of the store replaced while it was opened: slabscope reads only the files \
             inside it",
        ));
    }
    Ok(file)
}

/// Whether two files' metadata are of one file (the same device and inode).
#[cfg(unix)]
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    (a.dev(), a.ino()) == (b.dev(), b.ino())
}

/// Whether two files' metadata are of one file: where there are no inodes to compare, their
/// sizes and times.
#[cfg(not(unix))]
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    a.len() == b.len() && a.modified().ok() == b.modified().ok()
}

/// A read-only Zarr store over the folder `root`, whose files all lie in the store's tree.
#[derive(Debug)]
pub struct LocalStore {
    root: PathBuf,
    /// The store's tree ([`tree`]): no file outside it is read.
    tree: PathBuf,
    /// The most bytes one file of the store may hold.
    max_file: u64,
    /// What the chunks of the array read may decode to.
    guard: Option<Guard>,
}

impl LocalStore {
    /// The store of the folder `root`, inside the store's tree `tree`, whose files may each hold
    /// at most `max_file` bytes.
    pub fn new(root: &Path, tree: &Path, max_file: u64) -> Self {
        Self {
            root: root.to_path_buf(),
            tree: tree.to_path_buf(),
            max_file,
            guard: None,
        }
    }

    /// This store, each chunk of the array `guard` describes weighed before it is decoded.
    pub fn with_guard(mut self, guard: Guard) -> Self {
        self.guard = Some(guard);
        self
    }

    /// The file of `key`, which must stay inside the store's folder.
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
        Ok(self.root.join(relative))
    }

    /// The file of `key` opened with its size; `None` when there is none.
    fn open(&self, key: &StoreKey) -> Result<Option<(std::fs::File, u64)>, StorageError> {
        let path = self.path(key)?;
        let file = match open_inside(&self.tree, &path) {
            Ok(file) => file,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(StorageError::Other(format!("{key}: {e}"))),
        };
        let size = file
            .metadata()
            .map_err(|e| StorageError::Other(format!("{key}: {e}")))?
            .len();
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
                        .map_err(StorageError::Other)?;
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
        return Err(StorageError::Other(format!(
            "{key}: a range of bytes asked that the file of {size} bytes does not hold"
        )));
    }
    // Within the file, which is within the budget.
    let mut buffer = vec![0u8; (end - start) as usize];
    file.read_exact_at(&mut buffer, start)
        .map_err(|e| StorageError::Other(format!("{key}: {e}")))?;
    Ok((Bytes::from(buffer), (start, end)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The handle is compared with the name's file by device and inode: a hard link is the file,
    /// another file of the same bytes is not; a link out of the tree is refused before opening.
    #[cfg(unix)]
    #[test]
    fn the_open_handle_is_the_file_named_inside_the_tree() {
        let dir = tempfile::tempdir().unwrap();
        let store = dir.path().join("s.zarr");
        std::fs::create_dir(&store).unwrap();
        let (a, b) = (store.join("a"), store.join("b"));
        std::fs::write(&a, b"same").unwrap();
        std::fs::write(&b, b"same").unwrap();
        std::fs::hard_link(&a, store.join("a2")).unwrap();
        let meta = |p: &Path| std::fs::metadata(p).unwrap();
        assert!(same_file(&meta(&a), &meta(&store.join("a2"))));
        assert!(!same_file(&meta(&a), &meta(&b)));
        let tree = tree(&store).unwrap();
        let opened = open_inside(&tree, &a).unwrap();
        assert!(same_file(&opened.metadata().unwrap(), &meta(&a)));
        std::fs::write(dir.path().join("secret"), b"x").unwrap();
        std::os::unix::fs::symlink(dir.path().join("secret"), store.join("out")).unwrap();
        let e = open_inside(&tree, &store.join("out")).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::PermissionDenied);
    }

    #[test]
    fn keys_stay_in_the_folder_and_files_within_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("small"), b"0123456789").unwrap();
        let tree = tree(dir.path()).unwrap();
        let store = LocalStore::new(dir.path(), &tree, 16);
        let key = |k: &str| StoreKey::new(k).unwrap();
        let got = store.get(&key("small")).unwrap().unwrap();
        assert_eq!(&got[..], b"0123456789");
        let tail = store
            .get_partial(&key("small"), ByteRange::Suffix(3))
            .unwrap()
            .unwrap();
        assert_eq!(&tail[..], b"789");
        assert!(store.get(&key("absent")).unwrap().is_none());
        assert!(
            store
                .get_partial(&key("small"), ByteRange::FromStart(8, Some(5)))
                .is_err(),
            "past the end"
        );
        std::fs::write(dir.path().join("big"), [0u8; 17]).unwrap();
        let err = store.get(&key("big")).unwrap_err().to_string();
        assert!(err.contains("more than the memory limit"), "{err}");
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
        let store = LocalStore::new(&root, &tree(&root).unwrap(), 64);
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
        assert!(store.get(&key("folder/absent")).unwrap().is_none());
    }
}
