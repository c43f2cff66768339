//! Where decoded voxels go: memory within the budget, else a scratch file on disk, mapped.
//!
//! Voxels stored as they are held are read in place from a map of their file, so the budget
//! never weighs them (their pages are the kernel's to drop). Compressed or converted voxels
//! (`.nii.gz`, a zlib MetaImage, scaled or big-endian data, a Zarr chunk) must be decoded
//! somewhere. Within the budget that is memory. Beyond it, when the user gives a scratch folder
//! (`--scratch DIR`), rather than refuse, they are decoded once into an unnamed file there and
//! then mapped read-only: from there on the volume is a mapped one like any other, so its pyramid
//! levels, the view search slab by slab and the partition strip by strip read it as they read a
//! mapped file, with no second decode (docs/design.md, "Volumes of any size"). The file has no
//! name where the file system allows (`O_TMPFILE`: gone however the process ends) and its blocks
//! are reserved on disk before it is mapped, so a full disk is an error before decoding. A scratch folder in memory
//! (tmpfs) would hold the voxels in memory after all, so it is refused, and so is one without
//! room for the voxels with a margin to spare.

#![allow(unsafe_code)]

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::volume::mapped;
use crate::volume::scratch::scratch_map;
use crate::volume::{Voxel, Voxels};

/// Decoded voxels of type `T` on their way to a volume: a vector in memory, or the map of a
/// scratch file, filled in any order ([`all`](Self::all)) or in memory order a stretch at a time
/// ([`room`](Self::room) then [`commit`](Self::commit)).
pub(crate) struct VoxelOut<T> {
    count: usize,
    done: usize,
    to: To<T>,
}

enum To<T> {
    Memory(Vec<T>),
    /// The scratch file's map, its room reserved on disk (so that writing through the map can
    /// never find the disk full), and the file the voxels are of.
    Scratch {
        map: memmap2::MmapMut,
        path: PathBuf,
        dir: PathBuf,
        _voxels: std::marker::PhantomData<T>,
    },
}

/// Where decoded voxels may go: memory within `max_memory`, beyond it a file in the `scratch`
/// folder when one is given.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Room<'a> {
    /// The memory budget.
    pub max_memory: u64,
    /// The folder for voxels beyond it (`LoadOptions::scratch`).
    pub scratch: Option<&'a Path>,
}

impl Room<'_> {
    /// Checks `dims` voxels held as f32 against the budget before anything is decoded: an
    /// error when they do not fit and there is no scratch folder to take them (whether the
    /// folder can is [`VoxelOut::new`]'s to find out, when the room is made).
    pub(crate) fn check(&self, path: &Path, dims: [usize; 3]) -> Result<()> {
        match super::data::budget::check_budget(path, dims, self.max_memory) {
            Err(Error::TooLarge { .. }) if self.scratch.is_some() => Ok(()),
            Err(e @ Error::TooLarge { .. }) => Err(refusal(e, None)),
            checked => checked.map(drop),
        }
    }

    /// Room for `dims` voxels held as f32: memory within the budget, else the scratch folder.
    pub(crate) fn f32_voxels(&self, path: &Path, dims: [usize; 3]) -> Result<VoxelOut<f32>> {
        VoxelOut::new(path, dims, self.scratch, || {
            super::data::budget::voxel_buffer(path, dims, self.max_memory)
        })
    }
}

impl<T: Voxel> VoxelOut<T> {
    /// Room for the `dims` voxels of `path`: memory when `memory` (the budget's check, an
    /// error when they do not fit) allows it, else a file in the `scratch` folder when it can
    /// hold them, else `memory`'s error (with the reason the scratch could not).
    pub(crate) fn new(
        path: &Path,
        dims: [usize; 3],
        scratch: Option<&Path>,
        memory: impl FnOnce() -> Result<Vec<T>>,
    ) -> Result<Self> {
        let refused = match memory() {
            Ok(v) => {
                return Ok(Self {
                    count: v.len(),
                    done: 0,
                    to: To::Memory(v),
                });
            }
            Err(e @ Error::TooLarge { .. }) => e,
            Err(e) => return Err(e),
        };
        let Some(dir) = scratch else {
            return Err(refusal(refused, None));
        };
        let Some(count) = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d)) else {
            return Err(refused);
        };
        let bytes = (count as u64).saturating_mul(T::TYPE.size() as u64);
        match scratch_map(dir, bytes) {
            Ok(map) => Ok(Self {
                count,
                done: 0,
                to: To::Scratch {
                    map,
                    path: path.to_path_buf(),
                    dir: dir.to_path_buf(),
                    _voxels: std::marker::PhantomData,
                },
            }),
            Err(why) => Err(refusal(refused, Some(&why))),
        }
    }

    /// The voxels still to come in memory order.
    pub(crate) fn left(&self) -> usize {
        self.count - self.done
    }

    /// Every voxel, to fill in any order (then [`finish`](Self::finish)).
    pub(crate) fn all(&mut self) -> &mut [T] {
        self.done = self.count;
        self.voxels()
    }

    /// The next `n` voxels in memory order, to fill and then [`commit`](Self::commit).
    pub(crate) fn room(&mut self, n: usize) -> &mut [T] {
        let (from, to) = (self.done, self.done + n.min(self.left()));
        &mut self.voxels()[from..to]
    }

    fn voxels(&mut self) -> &mut [T] {
        match &mut self.to {
            To::Memory(v) => v,
            To::Scratch { map, .. } => bytemuck::cast_slice_mut(&mut map[..]),
        }
    }

    /// Takes the next `n` voxels as filled.
    pub(crate) fn commit(&mut self, n: usize) {
        self.done += n.min(self.left());
    }

    /// The volume's voxels, once every one is filled: in memory, or the scratch file mapped
    /// read-only.
    pub(crate) fn finish(self) -> Result<Voxels> {
        debug_assert_eq!(self.done, self.count);
        match self.to {
            To::Memory(v) => Ok(Voxels::owned(v)),
            To::Scratch { map, path, dir, .. } => {
                // Written out before it is read back, so that a disk that fails is an error here.
                let failed = |e: std::io::Error| {
                    Error::format(
                        &path,
                        format!(
                            "its scratch file in {} could not be written: {e}",
                            crate::error::shown(&dir)
                        ),
                    )
                };
                map.flush().map_err(failed)?;
                let map = map.make_read_only().map_err(failed)?;
                Voxels::mapped(mapped::scratch(map, &path, &dir), T::TYPE, 0, self.count)
                    .ok_or_else(|| Error::format(&path, "the scratch file is shorter than written"))
            }
        }
    }
}

/// The budget's refusal: without a scratch folder (`why` `None`), saying that one would do;
/// else saying why the voxels could not go to a scratch file there.
fn refusal(refused: Error, why: Option<&str>) -> Error {
    match refused {
        Error::TooLarge {
            path,
            what,
            needed,
            limit,
            machine,
            ..
        } => Error::TooLarge {
            path,
            what: match why {
                Some(why) => format!("{what} (not decoded to disk instead: {why})"),
                None => what,
            },
            needed,
            limit,
            machine,
            disk: why.is_none(),
        },
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refuse<T>() -> Result<Vec<T>> {
        Err(Error::TooLarge {
            path: PathBuf::from("big.nii.gz"),
            what: "a volume".into(),
            needed: 1 << 40,
            limit: 1,
            machine: false,
            disk: false,
        })
    }

    #[test]
    fn beyond_the_budget_voxels_go_to_a_mapped_scratch_file_in_order() {
        let dims = [300, 200, 150];
        let dir = tempfile::tempdir().unwrap();
        let mut out =
            VoxelOut::<i16>::new(Path::new("big.nii.gz"), dims, Some(dir.path()), refuse).unwrap();
        let mut next = 0i32;
        while out.left() > 0 {
            let n = 1 << 20;
            for v in out.room(n) {
                *v = (next % 30_000) as i16;
                next += 1;
            }
            out.commit(n);
        }
        let voxels = out.finish().unwrap();
        let Voxels::I16(store) = &voxels else {
            panic!("held as i16");
        };
        assert!(store.is_mapped());
        let got = store.as_slice();
        assert_eq!(got.len(), 300 * 200 * 150);
        assert!(
            got.iter()
                .enumerate()
                .all(|(i, &v)| v == (i % 30_000) as i16)
        );
    }

    #[test]
    fn within_the_budget_voxels_stay_in_memory() {
        let dir = tempfile::tempdir().unwrap();
        let mut out = VoxelOut::<u8>::new(
            Path::new("small.nii.gz"),
            [4, 3, 2],
            Some(dir.path()),
            || Ok(vec![0; 24]),
        )
        .unwrap();
        out.room(24).copy_from_slice(&[7; 24]);
        out.commit(24);
        let Voxels::U8(store) = out.finish().unwrap() else {
            panic!("held as u8");
        };
        assert!(!store.is_mapped());
        assert_eq!(store.as_slice(), &[7; 24]);
    }

    #[test]
    fn a_scratch_too_small_keeps_the_budget_error_with_its_reason() {
        // 2⁶³ bytes fit on no disk.
        let dir = tempfile::tempdir().unwrap();
        let e = VoxelOut::<u8>::new(
            Path::new("big.nii.gz"),
            [1 << 21, 1 << 21, 1 << 21],
            Some(dir.path()),
            refuse,
        )
        .err()
        .unwrap()
        .to_string();
        assert!(e.starts_with("big.nii.gz: a volume (not decoded to disk instead: the scratch"));
        assert!(e.contains("free, not"), "{e}");
        assert!(!e.contains('\n'));
    }

    #[test]
    fn without_a_scratch_folder_the_budget_error_says_a_disk_would_do() {
        let e = VoxelOut::<u8>::new(Path::new("big.nii.gz"), [8, 8, 8], None, refuse)
            .err()
            .unwrap();
        assert!(matches!(e, Error::TooLarge { disk: true, .. }), "{e:?}");
    }

    #[test]
    fn a_scratch_folder_in_memory_is_refused() {
        use crate::volume::scratch::room_of;
        let shm = Path::new("/dev/shm");
        let Ok(file) = tempfile::tempfile_in(shm) else {
            return; // no /dev/shm here: nothing to test
        };
        if !room_of(&file).is_ok_and(|r| r.in_memory) {
            return;
        }
        let e = VoxelOut::<u8>::new(Path::new("big.nii.gz"), [8, 8, 8], Some(shm), refuse)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("is in memory (tmpfs), not on disk"), "{e}");
    }

    #[test]
    fn other_errors_pass_through() {
        let e = VoxelOut::<u8>::new(Path::new("x"), [1, 1, 1], None, || {
            Err(Error::format(Path::new("x"), "dimensions contain a zero"))
        })
        .err()
        .unwrap();
        assert_eq!(e.to_string(), "x: dimensions contain a zero");
    }
}
