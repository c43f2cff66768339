//! Many volumes at once: what a set of paths holds (folders walked; a folder of TIFF slices is
//! one volume), in a stable order that shards split, and one row per volume with what a first
//! look needs: the format and geometry, the problems, the most structured axis and the slabs
//! along it.

mod look;
mod manifest;
mod row;
mod select;
mod series;
mod walk;

use std::path::{Path, PathBuf};

pub use self::look::{
    COARSE, COARSE_MIN_DIM, COARSE_PHASES, TriageOutcome, TriagePlan, look, look_all,
};
pub use self::manifest::{MANIFEST_HEADER, MAX_LINE, manifest_lines, parse_manifest};
pub use self::row::TriageRow;
pub use self::select::{MAX_MANIFEST, Selection, Source, read_manifest, select};
pub use self::series::resolve;
pub use self::walk::{discover, restrict_to_series, series_positions};
pub use crate::formats::{Folder, folder_kind, picks_in_folder};

/// The most volumes a walk collects: a bound on the memory a folder tree can claim.
pub const MAX_VOLUMES: usize = 1 << 20;

/// The deepest a walk goes below a folder it was given.
pub const MAX_DEPTH: usize = 64;

/// One volume triage looks at: a file or a folder, and for DICOM the series in it.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Entry {
    /// The file, or the folder.
    pub path: PathBuf,
    /// The DICOM series' key (its `SeriesInstanceUID`) in a folder of DICOM files.
    pub series: Option<String>,
    /// How a list names the series: number and description (not in manifests).
    pub label: Option<String>,
    /// Its position (from 1) in its folder's list of series, as the walk found it: what
    /// `--series N` takes (not in manifests).
    pub position: Option<usize>,
    /// Why the walk could not look inside it (a folder it cannot read, or past the depth
    /// limit): its row says so, and nothing is loaded.
    pub problem: Option<String>,
    /// The DICOM series' files, sorted, as the walk's scan found them: the series is read from
    /// them alone (empty: unknown, as in a manifest, which [`select`] then resolves).
    pub files: std::sync::Arc<[PathBuf]>,
    /// What its folder's scan left out (localizers, derived images, unreadable files), said
    /// once for the folder: on its first series' entry.
    pub notes: Vec<String>,
}

impl Entry {
    /// The entry of a file or folder that is one volume.
    pub fn file(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            series: None,
            label: None,
            position: None,
            problem: None,
            files: std::sync::Arc::default(),
            notes: Vec::new(),
        }
    }

    /// The entry of a path the walk could not look inside, and why.
    pub fn failed(path: impl Into<PathBuf>, problem: impl Into<String>) -> Self {
        Self {
            problem: Some(problem.into()),
            ..Self::file(path)
        }
    }

    /// The options that read this entry: `load`'s, with the entry's series (where it is one)
    /// in place of theirs.
    #[must_use]
    pub fn options(&self, load: &crate::formats::LoadOptions) -> crate::formats::LoadOptions {
        let mut opts = load.clone();
        if let Some(series) = &self.series {
            crate::formats::group::pick(&mut opts, series);
        }
        opts
    }

    /// The entry's name in messages and lists: the path, with the series after it.
    pub fn name(&self) -> String {
        self.name_under(Path::new(""))
    }

    /// [`Entry::name`] with the path relative to the folder `root`.
    pub fn name_under(&self, root: &Path) -> String {
        let path = crate::error::shown(self.path.strip_prefix(root).unwrap_or(&self.path));
        let series = match (&self.label, &self.series) {
            (Some(label), _) => format!("[{label}]"),
            (None, Some(key)) => format!("[series {key}]"),
            (None, None) => return path,
        };
        if path.is_empty() {
            series
        } else {
            format!("{path} {series}")
        }
    }
}

/// Block `k` (from 1) of `n` contiguous blocks of `items`: the volumes one machine of `n` takes,
/// so that the blocks of `k = 1..=n` are the whole list, each item in exactly one, for any `k`
/// and `n` up to `u64::MAX` (block `k` is `[(k-1)·len/n, k·len/n)`, computed in 128 bits, so
/// the last block ends at the last item). Empty when `k` is not in `1..=n`.
pub fn shard<T>(items: &[T], k: u64, n: u64) -> &[T] {
    if n == 0 || k == 0 || k > n {
        return &[];
    }
    let len = items.len() as u128;
    let at = |k: u64| (u128::from(k) * len / u128::from(n)) as usize;
    &items[at(k - 1)..at(k)]
}

/// `entries` sorted, with one entry per file however it was spelled (`DIR/a.nii`, `./DIR/a.nii`
/// and its absolute path are one file: the same device and inode), the first spelling in sorted
/// order kept. A path that cannot be looked up is told apart by its spelling.
pub fn dedupe(entries: &mut Vec<Entry>) {
    entries.sort();
    entries.dedup();
    let mut seen = std::collections::HashSet::new();
    entries.retain(|e| seen.insert((identity(&e.path), e.series.clone())));
}

/// What a file is, whatever its spelling: its device and inode (its canonical path where there
/// are no inodes), else its path as spelled.
fn identity(path: &Path) -> Result<(u64, u64), PathBuf> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        std::fs::metadata(path)
            .map(|m| (m.dev(), m.ino()))
            .map_err(|_| path.to_path_buf())
    }
    #[cfg(not(unix))]
    {
        Err(path.canonicalize().unwrap_or_else(|_| path.to_path_buf()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_are_named_in_few_characters() {
        let mut row = TriageRow::failed("a", String::new());
        assert_eq!(row.axis_name(), None);
        row.best_axis = Some([-0.0, 1.0, 0.0]);
        assert_eq!(row.axis_name().as_deref(), Some("y"));
        row.best_axis = Some([0.6, -0.0, 0.8]);
        assert_eq!(row.axis_name().as_deref(), Some("[0.60,0.00,0.80]"));
        row.anatomy = Some("I→S, axial".into());
        assert_eq!(row.axis_name().as_deref(), Some("I→S"));
    }

    #[test]
    fn shards_split_a_list_into_contiguous_blocks_that_cover_it_once() {
        let items: Vec<usize> = (0..10).collect();
        for n in 1..=12 {
            let joined: Vec<usize> = (1..=n).flat_map(|k| shard(&items, k, n).to_vec()).collect();
            assert_eq!(joined, items, "{n} shards");
        }
        assert!(shard(&items, 0, 3).is_empty() && shard(&items, 4, 3).is_empty());
        let big = 1 << 63;
        assert_eq!(
            shard(&items, big, big),
            &[9],
            "the last shard holds the last volume"
        );
        assert_eq!(shard(&items, u64::MAX, u64::MAX), &[9]);
        assert_eq!(shard(&items, 1, u64::MAX), &[] as &[usize]);
    }

    proptest::proptest! {
        /// Shard `k` begins where shard `k - 1` ends, the first at 0 and the last ends at the
        /// end, each holding ⌊len/n⌋ or ⌈len/n⌉ items: by induction, an exact partition of the
        /// set, for any `n` up to `u64::MAX`.
        #[test]
        fn shards_partition_the_set_for_any_k_and_n(
            len in 0usize..300,
            n in proptest::prop_oneof![1u64..40, 1u64..=u64::MAX],
            k in 1u64..=u64::MAX,
        ) {
            let items: Vec<usize> = (0..len).collect();
            let k = (k - 1) % n + 1;
            // Where a block lies in `items`, as [start, end).
            let span = |k: u64| {
                let block = shard(&items, k, n);
                let start = (block.as_ptr() as usize - items.as_ptr() as usize)
                    / std::mem::size_of::<usize>();
                (start, start + block.len())
            };
            let (start, end) = span(k);
            let (lo, hi) = (len as u64 / n, (len as u64).div_ceil(n));
            proptest::prop_assert!((lo..=hi).contains(&((end - start) as u64)));
            let before = if k == 1 { 0 } else { span(k - 1).1 };
            proptest::prop_assert_eq!(start, before);
            proptest::prop_assert_eq!(span(n).1, len);
            if n <= 40 {
                let joined: Vec<usize> =
                    (1..=n).flat_map(|k| shard(&items, k, n).to_vec()).collect();
                proptest::prop_assert_eq!(joined, items);
            }
        }
    }

    #[cfg(unix)]
    #[test]
    fn one_entry_per_file_however_spelled() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.nii");
        std::fs::write(&a, b"x").unwrap();
        std::os::unix::fs::symlink(dir.path(), dir.path().join("link")).unwrap();
        let linked = dir.path().join("link/a.nii");
        let mut entries = vec![
            Entry::file(&linked),
            Entry::file(&a),
            Entry::file(dir.path().join("./a.nii")),
            Entry::file(dir.path().join("gone.nii")),
            Entry::file(dir.path().join("gone2.nii")),
        ];
        dedupe(&mut entries);
        let names: Vec<&std::ffi::OsStr> = entries
            .iter()
            .map(|e| e.path.strip_prefix(dir.path()).unwrap().as_os_str())
            .collect();
        assert_eq!(names, ["a.nii", "gone.nii", "gone2.nii"]);
    }
}
