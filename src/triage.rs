//! Many volumes at once: what a set of paths holds (folders walked; a folder of TIFF slices is
//! one volume), in a stable order that shards split, and one row per volume with what a first
//! look needs: the format and geometry, the problems, the most structured axis and the slabs
//! along it.

mod look;
mod manifest;
mod row;
mod walk;

use std::path::{Path, PathBuf};

pub use self::look::{
    COARSE, COARSE_MIN_DIM, COARSE_PHASES, TriageOutcome, TriagePlan, look, look_all,
};
pub use self::manifest::{MANIFEST_HEADER, MAX_LINE, manifest_lines, parse_manifest};
pub use self::row::TriageRow;
pub use self::walk::discover;
pub use crate::volume::io::{Folder, folder_kind};

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
}

impl Entry {
    /// The entry of a file or folder that is one volume.
    pub fn file(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            series: None,
            label: None,
        }
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
/// so that the blocks of `k = 1..=n` are the whole list, each item in exactly one.
pub fn shard<T>(items: &[T], k: usize, n: usize) -> &[T] {
    if n == 0 || k == 0 || k > n {
        return &[];
    }
    let len = items.len();
    &items[(k - 1) * len / n..k * len / n]
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
    }
}
