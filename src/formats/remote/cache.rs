//! The caches of a remote store's chunks, so that a chunk is fetched once: in memory for the
//! process ([`Memory`], a share of the budget, the oldest answers dropped past it), and on disk
//! when asked (`--cache DIR`: [`Disk`], the oldest files dropped past [`DISK_CAP`]), so that
//! reading the store again fetches nothing it holds. Both key an answer by its URL and range; the
//! disk's file names are the SHA-256 of that key, so no URL reaches a path, each written
//! whole to a temporary file in the folder and renamed into place. Metadata files are not
//! cached (a store's metadata is read fresh each time); a store's chunks are taken not to change.

use std::collections::{HashMap, VecDeque};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

use sha2::{Digest, Sha256};

use super::Span;

/// The most bytes an on-disk cache holds: past it, its oldest files are removed.
pub const DISK_CAP: u64 = 1 << 30;

/// The share of the memory budget the answers kept in memory may take (1/16).
pub const MEMORY_SHARE: u64 = 16;

/// The key of the answer to `span` of `url`.
fn key(url: &str, span: Span) -> String {
    match span {
        Span::All => url.to_string(),
        Span::From(start, None) => format!("{url} bytes={start}-"),
        Span::From(start, Some(n)) => format!("{url} bytes={start}+{n}"),
        Span::Suffix(n) => format!("{url} bytes=-{n}"),
    }
}

/// The SHA-256 of `text`, in lower-case hexadecimal.
fn sha256_hex(text: &str) -> String {
    let mut hex = String::with_capacity(64);
    for b in Sha256::digest(text.as_bytes()) {
        let _ = write!(hex, "{b:02x}");
    }
    hex
}

/// Answers kept in memory, the oldest dropped first past the capacity.
#[derive(Debug, Default)]
pub struct Memory {
    held: Mutex<Held>,
}

#[derive(Debug, Default)]
struct Held {
    answers: HashMap<String, std::sync::Arc<[u8]>>,
    order: VecDeque<String>,
    bytes: u64,
}

impl Memory {
    /// The answer to `span` of `url`, when kept.
    pub fn get(&self, url: &str, span: Span) -> Option<Vec<u8>> {
        let held = self.held.lock().unwrap_or_else(PoisonError::into_inner);
        held.answers.get(&key(url, span)).map(|b| b.to_vec())
    }

    /// Keeps `bytes`, the answer to `span` of `url`, within `capacity` bytes in all (an answer
    /// larger than that is not kept).
    pub fn put(&self, url: &str, span: Span, bytes: &[u8], capacity: u64) {
        let n = bytes.len() as u64;
        if n > capacity {
            return;
        }
        let mut held = self.held.lock().unwrap_or_else(PoisonError::into_inner);
        let key = key(url, span);
        if held.answers.contains_key(&key) {
            return;
        }
        while held.bytes + n > capacity {
            let Some(old) = held.order.pop_front() else {
                break;
            };
            if let Some(b) = held.answers.remove(&old) {
                held.bytes -= b.len() as u64;
            }
        }
        held.answers.insert(key.clone(), bytes.into());
        held.order.push_back(key);
        held.bytes += n;
    }
}

/// The answers kept in memory by every store of this process.
pub static MEMORY: std::sync::LazyLock<Memory> = std::sync::LazyLock::new(Memory::default);

/// A folder of answers kept on disk.
#[derive(Debug)]
pub struct Disk {
    dir: PathBuf,
    cap: u64,
    /// The bytes of its entries, as far as known (counted at opening, then kept).
    bytes: AtomicU64,
}

impl Disk {
    /// The cache in the folder `dir`, made when missing (its parent must exist), holding at most
    /// `cap` bytes; an error in words when it is no folder or cannot be made.
    pub fn open(dir: &Path, cap: u64) -> Result<Self, String> {
        match std::fs::symlink_metadata(dir) {
            Ok(m) if m.is_dir() => {}
            Ok(_) => return Err("the cache is not a folder".into()),
            Err(_) => std::fs::create_dir(dir).map_err(|e| format!("the cache folder: {e}"))?,
        }
        let cache = Self {
            dir: dir.to_path_buf(),
            cap,
            bytes: AtomicU64::new(0),
        };
        let held: u64 = cache.entries().iter().map(|(_, n, _)| n).sum();
        cache.bytes.store(held, Ordering::Relaxed);
        Ok(cache)
    }

    /// The file of the answer to `span` of `url`: the SHA-256 of its key, in hexadecimal.
    fn path(&self, url: &str, span: Span) -> PathBuf {
        self.dir.join(sha256_hex(&key(url, span)))
    }

    /// The answer to `span` of `url` when the cache holds it in a regular file of at most
    /// `limit` bytes.
    pub fn get(&self, url: &str, span: Span, limit: u64) -> Option<Vec<u8>> {
        let path = self.path(url, span);
        let meta = std::fs::symlink_metadata(&path).ok()?;
        if !meta.is_file() || meta.len() > limit {
            return None;
        }
        std::fs::read(&path).ok()
    }

    /// Keeps `bytes`, the answer to `span` of `url`: written whole to a temporary file of the
    /// folder, then renamed to its name; the oldest entries removed past the cap. A failure
    /// (a full disk) leaves the cache as it was: it is no error of the read.
    pub fn put(&self, url: &str, span: Span, bytes: &[u8]) {
        let n = bytes.len() as u64;
        if n > self.cap {
            return;
        }
        let path = self.path(url, span);
        let Ok(mut file) = tempfile::Builder::new()
            .prefix(".partial-")
            .tempfile_in(&self.dir)
        else {
            return;
        };
        if file.write_all(bytes).is_err() || file.persist(&path).is_err() {
            return;
        }
        if self.bytes.fetch_add(n, Ordering::Relaxed) + n > self.cap {
            self.trim();
        }
    }

    /// The cache's entries (files named by 64 hexadecimal digits; nothing else in the folder is
    /// touched): path, size and time of last change.
    fn entries(&self) -> Vec<(PathBuf, u64, std::time::SystemTime)> {
        let Ok(list) = std::fs::read_dir(&self.dir) else {
            return Vec::new();
        };
        list.flatten()
            .filter(|e| {
                let name = e.file_name();
                let name = name.to_string_lossy();
                name.len() == 64 && name.bytes().all(|b| b.is_ascii_hexdigit())
            })
            .filter_map(|e| {
                let m = e.metadata().ok().filter(std::fs::Metadata::is_file)?;
                Some((e.path(), m.len(), m.modified().ok()?))
            })
            .collect()
    }

    /// Removes the oldest entries until the cache holds at most nine tenths of its cap.
    fn trim(&self) {
        let mut entries = self.entries();
        entries.sort_by_key(|(_, _, t)| *t);
        let mut held: u64 = entries.iter().map(|(_, n, _)| n).sum();
        for (path, n, _) in entries {
            if held <= self.cap / 10 * 9 {
                break;
            }
            if std::fs::remove_file(&path).is_ok() {
                held -= n;
            }
        }
        self.bytes.store(held, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_keeps_answers_within_its_capacity() {
        let memory = Memory::default();
        memory.put("u/a", Span::All, &[1; 6], 10);
        assert_eq!(memory.get("u/a", Span::All), Some(vec![1; 6]));
        assert_eq!(memory.get("u/a", Span::Suffix(6)), None, "another range");
        memory.put("u/b", Span::All, &[2; 6], 10);
        assert_eq!(memory.get("u/a", Span::All), None, "the oldest dropped");
        assert_eq!(memory.get("u/b", Span::All), Some(vec![2; 6]));
        memory.put("u/c", Span::All, &[3; 11], 10);
        assert_eq!(
            memory.get("u/c", Span::All),
            None,
            "larger than the capacity"
        );
    }

    #[test]
    fn disk_entries_are_hashed_whole_and_trimmed_oldest_first() {
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join("cache");
        let cache = Disk::open(&folder, 100).unwrap();
        std::fs::write(folder.join("notes.txt"), "mine").unwrap();
        let url = "http://h/s.zarr/0/../../etc";
        cache.put(url, Span::From(4, Some(8)), &[7; 40]);
        assert_eq!(
            cache.get(url, Span::From(4, Some(8)), 100),
            Some(vec![7; 40])
        );
        assert_eq!(
            cache.get(url, Span::From(4, Some(8)), 39),
            None,
            "over the limit"
        );
        assert_eq!(cache.get(url, Span::All, 100), None);
        // The entry's name is the key's SHA-256: the URL reaches no path.
        let names: Vec<String> = std::fs::read_dir(&folder)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        let hex = sha256_hex("http://h/s.zarr/0/../../etc bytes=4+8");
        assert!(names.contains(&hex), "{names:?}");
        // SHA-256 itself, against FIPS 180-2's example.
        assert_eq!(
            sha256_hex("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        // Past the cap, the oldest go (not the user's own file), down to 90 bytes at most.
        std::thread::sleep(std::time::Duration::from_millis(20));
        cache.put("http://h/b", Span::All, &[1; 40]);
        std::thread::sleep(std::time::Duration::from_millis(20));
        cache.put("http://h/c", Span::All, &[2; 40]);
        assert_eq!(
            cache.get(url, Span::From(4, Some(8)), 100),
            None,
            "the oldest"
        );
        assert!(cache.get("http://h/c", Span::All, 100).is_some());
        assert!(folder.join("notes.txt").is_file());
        // Reopened, it finds what it holds.
        let again = Disk::open(&folder, 100).unwrap();
        assert_eq!(again.bytes.load(Ordering::Relaxed), 80);
        assert!(Disk::open(&folder.join("notes.txt"), 100).is_err());
    }
}
