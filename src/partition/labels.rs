//! Label volumes of a partition, by the medical-imaging convention: a voxel's label is its slab's
//! index + 1, and 0 marks the voxels the analysis left out (background, and missing values), so
//! that viewers which draw label 0 clear (napari, ITK-SNAP, 3D Slicer) and tools which skip it
//! (scikit-image's `regionprops`) see the slabs and nothing else. Slab indices stay as they are
//! everywhere else (JSON `slabs[].index`, `--highlight`, the TUI).

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::Partition;
use crate::error::{Error, Result};
use crate::geometry::dot;
use crate::progress::Monitor;
use crate::volume::background::{Background, MaskWords};
use crate::volume::{Volume, Voxel, VoxelType, Voxels};

/// The label volume of `p` at `volume`'s shape, spacing and world geometry: each voxel's slab
/// index + 1 (u8 up to 255 slabs, u16 beyond), 0 where the voxel is missing or background by
/// the rule the partition left background out by. `partitioned` is the pyramid level of
/// `volume` that `p` partitions (`volume` itself, or a coarser level): a voxel belongs to the
/// slice whose centre is nearest along the axis, measured in that level's frame, so the labels
/// of an analysis of a coarse level lie over every voxel of the volume.
pub fn label_volume(
    volume: &Volume,
    partitioned: &Volume,
    p: &Partition,
    monitor: &Monitor,
) -> Result<Volume> {
    let l = Labeller::new(volume, partitioned, p, MaskHome::Memory, monitor)?;
    let (frame, bg, slabs) = (&l.frame, &l.background, l.slab_of.as_slice());
    let (ty, data) = if l.wide {
        let labels = labels(volume, frame, bg, slabs, |l| l);
        (VoxelType::U16, Voxels::owned(labels))
    } else {
        let labels = labels(volume, frame, bg, slabs, |l| l as u8);
        (VoxelType::U8, Voxels::owned(labels))
    };
    Ok(
        Volume::from_voxels(volume.dims(), volume.spacing(), ty, data)?
            .with_transform(*volume.transform()),
    )
}

/// Bytes a voxel of [`label_volume`] takes for a partition of `slabs` slabs.
#[must_use]
pub fn label_bytes(slabs: usize) -> u64 {
    if slabs < 256 { 1 } else { 2 }
}

/// The memory [`label_volume`] takes for `volume` and a partition of `slabs` slabs, in bytes:
/// the labels, and a found background's mask (a bit a voxel).
#[must_use]
pub fn label_memory(volume: &Volume, slabs: usize) -> u64 {
    let n = volume.len() as u64;
    n * label_bytes(slabs) + n.div_ceil(64) * 8
}

/// Where a voxel of the labelled volume lies along the partition's axis.
struct Frame {
    axis: [f64; 3],
    spacing: [f64; 3],
    /// Voxel `i` lies at `(i - shift) · spacing` in the partitioned level's frame: its voxel 0
    /// sits at the centre of the block of voxels it averages.
    shift: [f64; 3],
    offset: f64,
    thickness: f64,
    last: f64,
}

impl Frame {
    fn of(volume: &Volume, partitioned: &Volume, p: &Partition) -> Self {
        let (fine, coarse) = (volume.spacing(), partitioned.spacing());
        Self {
            axis: p.axis,
            spacing: fine,
            shift: std::array::from_fn(|m| (coarse[m] / fine[m] - 1.0) / 2.0),
            offset: p.offset,
            thickness: p.thickness,
            last: p.slices as f64 - 1.0,
        }
    }

    /// The slice nearest to voxel `(x, y, z)`.
    #[inline]
    fn slice(&self, x: usize, y: usize, z: usize) -> usize {
        let c = [x as f64, y as f64, z as f64];
        let pos = std::array::from_fn(|m| (c[m] - self.shift[m]) * self.spacing[m]);
        let k = ((dot(pos, self.axis) - self.offset) / self.thickness).round();
        k.clamp(0.0, self.last) as usize
    }
}

/// The label of every voxel of `volume`: 0 where it is missing or `background`, else `slab_of`
/// its nearest slice, as `T`.
fn labels<T: Copy + Default + Send>(
    volume: &Volume,
    frame: &Frame,
    background: &Background,
    slab_of: &[u16],
    label: impl Fn(u16) -> T + Sync,
) -> Vec<T> {
    let mut out = vec![T::default(); volume.len()];
    fill(volume, 0, &mut out, frame, background, slab_of, &label);
    out
}

/// The labels of the planes of `volume` from `z0` on, as many as `out` holds, into `out`.
fn fill<T: Copy + Send>(
    volume: &Volume,
    z0: usize,
    out: &mut [T],
    frame: &Frame,
    background: &Background,
    slab_of: &[u16],
    label: &(impl Fn(u16) -> T + Sync),
) {
    crate::volume::with_voxels!(volume.data(), |v| {
        labels_of(v, volume.dims(), z0, out, frame, background, slab_of, label);
    });
}

/// [`labels`] of the planes from `z0` on of voxels `v` of dimensions `dims`, into `out`.
#[allow(clippy::too_many_arguments)] // the pieces of one rule, passed down once
fn labels_of<V: Voxel, T: Copy + Send>(
    v: &[V],
    [nx, ny, _]: [usize; 3],
    z0: usize,
    out: &mut [T],
    frame: &Frame,
    background: &Background,
    slab_of: &[u16],
    label: &(impl Fn(u16) -> T + Sync),
) {
    let background = background.test();
    out.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(dz, plane)| {
            let z = z0 + dz;
            let base = z * nx * ny;
            for (i, l) in plane.iter_mut().enumerate() {
                let value = v[base + i].to_f32();
                let left_out = !value.is_finite() || background.contains(base + i, value);
                *l = label(if left_out {
                    0
                } else {
                    slab_of[frame.slice(i % nx, i / nx, z)]
                });
            }
        });
}

/// The most bytes of labels [`Labeller`] computes at once, where the budget has room for them
/// (one plane when a plane is larger).
pub const LABEL_CHUNK_BYTES: u64 = 8 << 20;

/// The working memory a budget gives labels streamed to a file
/// ([`Budget::labels`](crate::budget::Budget::labels)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LabelRoom {
    /// Bytes for a chunk of planes (one plane is computed at once whatever it says).
    pub chunk: u64,
    /// Whether a found background's mask is held in memory; else in a mapped scratch file
    /// ([`MaskHome::Scratch`]).
    pub mask_in_memory: bool,
}

/// Where a [`Labeller`] holds a found background's mask (a bit a voxel: 1 GiB at 2048³).
#[derive(Clone, Copy, Debug)]
pub enum MaskHome<'a> {
    /// In memory.
    Memory,
    /// In an unnamed scratch file, mapped: in the folder of the labels' file given (where they
    /// are being written, so on a disk with room for them), else in the system's temporary
    /// folder; never in a folder in memory (tmpfs). Its pages are the kernel's page cache,
    /// which it writes out and drops under pressure, not the process's memory.
    Scratch(&'a Path),
}

/// The label volume of a partition ([`label_volume`]'s voxels, by the same rule) computed a few
/// planes at a time, for a writer that streams them to a file: a label volume larger than the
/// memory budget (a 2048³ one is 8 GiB) is never held whole. What it holds is a found
/// background's mask (a bit a voxel), in memory or in a mapped scratch file ([`MaskHome`]),
/// and one chunk of planes, as many as the room its caller gives holds
/// ([`label_stream_memory`]: at least one plane).
pub struct Labeller<'a> {
    volume: &'a Volume,
    frame: Frame,
    background: Background,
    slab_of: Vec<u16>,
    wide: bool,
}

impl<'a> Labeller<'a> {
    /// The labels of `p` at `volume`'s shape, `partitioned` being the level `p` partitions (as
    /// for [`label_volume`]); finds the background, its mask held in `home` (stops when
    /// `monitor` is cancelled).
    pub fn new(
        volume: &'a Volume,
        partitioned: &Volume,
        p: &Partition,
        home: MaskHome<'_>,
        monitor: &Monitor,
    ) -> Result<Self> {
        // By the analysis's rule, found on the voxels labelled: on the level analysed, the
        // threshold the analysis found; on a finer one, that level's own (its noise is wider
        // than the averaged level's, and a threshold from there would leave specks of air
        // labelled).
        let rule = p.background.rule;
        let background = match home {
            MaskHome::Memory => Background::find(volume, rule, monitor)?,
            MaskHome::Scratch(out) => {
                let folders = scratch_folders(out);
                Background::find_in(volume, rule, monitor, |words| {
                    mask_scratch(out, words, &folders)
                })?
            }
        };
        let mut slab_of = vec![0u16; p.slices];
        for (i, &(a, b)) in p.slabs.iter().enumerate() {
            slab_of[a..b].fill(i as u16 + 1);
        }
        Ok(Self {
            volume,
            frame: Frame::of(volume, partitioned, p),
            background,
            slab_of,
            wide: label_bytes(p.slabs.len()) == 2,
        })
    }

    /// The labels' voxel type: u8 up to 255 slabs, u16 beyond.
    #[must_use]
    pub fn voxel_type(&self) -> VoxelType {
        if self.wide {
            VoxelType::U16
        } else {
            VoxelType::U8
        }
    }

    /// The planes (along z) computed at once within `room` bytes: as many as `room` (at most
    /// [`LABEL_CHUNK_BYTES`]) holds, at least one, at most all of them.
    #[must_use]
    pub fn chunk_planes(&self, room: u64) -> usize {
        let plane = plane_memory(self.volume, self.wide);
        let planes = room.min(LABEL_CHUNK_BYTES) / plane.max(1);
        usize::try_from(planes)
            .unwrap_or(usize::MAX)
            .clamp(1, self.volume.dims()[2].max(1))
    }

    /// The labels of planes `z` (along z, x fastest) as little-endian bytes, into `out`
    /// (cleared first).
    pub fn planes_le(&self, z: std::ops::Range<usize>, out: &mut Vec<u8>) {
        let [nx, ny, _] = self.volume.dims();
        let n = z.len() * nx * ny;
        let (frame, bg, slabs) = (&self.frame, &self.background, self.slab_of.as_slice());
        out.clear();
        if self.wide {
            let mut l = vec![0u16; n];
            fill(self.volume, z.start, &mut l, frame, bg, slabs, &|l| l);
            out.extend(l.iter().flat_map(|x| x.to_le_bytes()));
        } else {
            out.resize(n, 0);
            fill(self.volume, z.start, out, frame, bg, slabs, &|l| l as u8);
        }
    }
}

/// Room for `words` words of a background's mask in an unnamed scratch file mapped
/// ([`MaskHome::Scratch`]), for the labels being written to `out`, in the first of
/// [`scratch_folders`] that can hold one; an error naming `out` when none can.
fn mask_scratch(out: &Path, words: usize, folders: &[PathBuf]) -> Result<MaskWords> {
    let bytes = (words as u64).saturating_mul(8);
    crate::volume::scratch::scratch_in_any(folders, bytes)
        .map(MaskWords::Mapped)
        .map_err(|why| {
            Error::io(
                out,
                std::io::Error::other(format!(
                    "the background's mask ({}) fits neither in the memory limit nor in a \
                     scratch file: {why}",
                    crate::error::short_bytes(bytes)
                )),
            )
        })
}

/// Where the scratch file of a background's mask for labels written to `out` goes: `out`'s
/// folder, then the system's temporary folder.
fn scratch_folders(out: &Path) -> Vec<PathBuf> {
    let here = match out.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut folders = vec![here];
    let temp = std::env::temp_dir();
    if !folders.contains(&temp) {
        folders.push(temp);
    }
    folders
}

/// The memory one plane of labels of `volume` takes while it is streamed: its labels, and for
/// u16 labels their bytes too.
fn plane_memory(volume: &Volume, wide: bool) -> u64 {
    let [nx, ny, _] = volume.dims();
    (nx * ny) as u64 * if wide { 4 } else { 1 }
}

/// The memory a [`Labeller`] of `volume` and a partition of `slabs` slabs takes while its
/// labels are streamed ([`label_stream_memory`]), in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamMemory {
    /// A found background's mask (a bit a voxel), when held in memory ([`MaskHome::Memory`]).
    pub mask: u64,
    /// One plane: the least chunk.
    pub plane: u64,
    /// The most a chunk of planes takes usefully (the volume's planes, at most
    /// [`LABEL_CHUNK_BYTES`]).
    pub most: u64,
}

/// The memory a [`Labeller`] of `volume` and a partition of `slabs` slabs takes while its
/// labels are streamed.
#[must_use]
pub fn label_stream_memory(volume: &Volume, slabs: usize) -> StreamMemory {
    let plane = plane_memory(volume, label_bytes(slabs) == 2);
    let all = plane * volume.dims()[2] as u64;
    StreamMemory {
        mask: (volume.len() as u64).div_ceil(64) * 8,
        plane,
        most: all.min(LABEL_CHUNK_BYTES.max(plane)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::partition::{PartitionParams, Stop, partition};
    use crate::volume::background::BackgroundRule;

    /// A volume of `dims` whose value rises with z in steps of 4 slices, dark (0) on the x = 0
    /// face and missing at one voxel.
    fn layered(dims: [usize; 3]) -> Volume {
        let [nx, ny, nz] = dims;
        let mut v = vec![0.0f32; nx * ny * nz];
        for (i, x) in v.iter_mut().enumerate() {
            let (xi, z) = (i % nx, i / (nx * ny));
            *x = if xi == 0 {
                0.0
            } else {
                10.0 + (z / 4) as f32 * 20.0
            };
        }
        v[nx + 1] = f32::NAN;
        Volume::new(dims, [1.0; 3], VoxelType::F32, v).unwrap()
    }

    fn params(slabs: usize) -> PartitionParams {
        let mut p = PartitionParams {
            stop: Stop::Slabs(slabs),
            ..PartitionParams::default()
        };
        p.stack.background = BackgroundRule::Below(1.0);
        p
    }

    #[test]
    fn a_voxel_is_its_slab_plus_one_and_left_out_voxels_are_zero() {
        let v = layered([6, 5, 16]);
        let p = partition(&v, [0.0, 0.0, 1.0], &params(3), &Monitor::none()).unwrap();
        let labels = label_volume(&v, &v, &p, &Monitor::none()).unwrap();
        assert_eq!(labels.dims(), v.dims());
        assert_eq!(labels.voxel_type(), VoxelType::U8);
        let Voxels::U8(l) = labels.data() else {
            panic!("u8 labels")
        };
        let mut seen = [false; 4];
        for (i, &label) in l.as_slice().iter().enumerate() {
            let (x, z) = (i % 6, i / 30);
            let expect = if x == 0 || i == 7 {
                0
            } else {
                1 + p
                    .slabs
                    .iter()
                    .position(|&(a, b)| (a..b).contains(&z))
                    .unwrap() as u8
            };
            assert_eq!(label, expect, "voxel {i}");
            seen[usize::from(label)] = true;
        }
        assert_eq!(seen, [true; 4], "the background and every slab");
    }

    #[test]
    fn labels_of_a_coarser_level_lie_over_every_voxel() {
        let v = layered([8, 6, 16]);
        let coarse = v.coarser(1);
        assert_eq!(coarse.dims(), [4, 3, 8]);
        let p = partition(&coarse, [0.0, 0.0, 1.0], &params(2), &Monitor::none()).unwrap();
        let labels = label_volume(&v, &coarse, &p, &Monitor::none()).unwrap();
        assert_eq!(labels.dims(), v.dims());
        let Voxels::U8(l) = labels.data() else {
            panic!("u8 labels")
        };
        // Coarse slice k averages full slices 2k and 2k + 1: the boundary between coarse
        // slices a - 1 and a falls between full slices 2a - 1 and 2a.
        let a = p.slabs[1].0;
        for (i, &label) in l.as_slice().iter().enumerate() {
            let (x, z) = (i % 8, i / 48);
            let expect = if x == 0 || i == 9 {
                0
            } else if z < 2 * a {
                1
            } else {
                2
            };
            assert_eq!(
                label, expect,
                "voxel {i} (z {z}, boundary at coarse slice {a})"
            );
        }
    }

    /// Air with noise, analysed on a coarser level (whose averaging narrows the noise): at full
    /// resolution no speck of air is labelled, and the body is.
    #[test]
    fn air_stays_zero_at_full_resolution_after_a_coarse_analysis() {
        let dims = [24, 24, 32];
        let mut lcg = crate::testing::Lcg::new(9);
        let v: Vec<f32> = (0..dims.iter().product::<usize>())
            .map(|i| {
                let (x, y) = (i % 24, (i / 24) % 24);
                let body = (6..18).contains(&x) && (6..18).contains(&y);
                // Four uniform draws: near normal, 0 to 80.
                let noise: f32 = (0..4).map(|_| (lcg.next_u64() % 21) as f32).sum();
                if body { 200.0 + noise } else { noise }
            })
            .collect();
        let v = Volume::new(dims, [1.0; 3], VoxelType::F32, v).unwrap();
        let coarse = v.coarser(1);
        let params = PartitionParams {
            stop: Stop::Slabs(2),
            ..PartitionParams::default()
        };
        let p = partition(&coarse, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap();
        assert_eq!(p.background.rule, BackgroundRule::Auto);
        let labels = label_volume(&v, &coarse, &p, &Monitor::none()).unwrap();
        let Voxels::U8(l) = labels.data() else {
            panic!("u8 labels")
        };
        for (i, &label) in l.as_slice().iter().enumerate() {
            let (x, y) = (i % 24, (i / 24) % 24);
            let body = (6..18).contains(&x) && (6..18).contains(&y);
            assert_eq!(label == 0, !body, "voxel {i}: label {label}");
        }
    }

    /// A found background's mask held in an unnamed scratch file beside the labels' file
    /// labels every voxel as the mask in memory does, holds no memory for it, and leaves no
    /// file behind.
    #[test]
    fn a_mask_in_a_scratch_file_labels_as_one_in_memory() {
        let v = crate::volume::phantom::body([40, 36, 30], 3).unwrap();
        let params = PartitionParams {
            stop: Stop::Slabs(3),
            ..PartitionParams::default()
        };
        let p = partition(&v, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap();
        assert_eq!(p.background.rule, BackgroundRule::Auto);
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("labels.nrrd");
        let none = Monitor::none();
        let memory = Labeller::new(&v, &v, &p, MaskHome::Memory, &none).unwrap();
        let mapped = Labeller::new(&v, &v, &p, MaskHome::Scratch(&out), &none).unwrap();
        let words = (40u64 * 36 * 30).div_ceil(64);
        assert_eq!(memory.background.memory_bytes(), 8 * words);
        assert_eq!(mapped.background.memory_bytes(), 0, "the page cache's");
        assert!(memory.background.fraction > 0.2, "air around the body");
        assert_eq!(mapped.background, memory.background);
        let (mut a, mut b) = (Vec::new(), Vec::new());
        memory.planes_le(0..30, &mut a);
        mapped.planes_le(0..30, &mut b);
        assert!(a == b, "the same labels");
        assert!(a.contains(&0) && a.contains(&3));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    /// The mask's scratch file goes beside the labels, else in the system's temporary folder;
    /// where no folder can hold it, the error is one line naming the labels' file and why.
    #[test]
    fn a_mask_with_no_room_anywhere_is_one_line_naming_the_file() {
        let temp = std::env::temp_dir();
        assert_eq!(
            scratch_folders(Path::new("labels.nrrd")),
            [PathBuf::from("."), temp.clone()]
        );
        assert_eq!(
            scratch_folders(&Path::new("/data/out").join("l.nii")),
            [PathBuf::from("/data/out"), temp.clone()]
        );
        assert_eq!(scratch_folders(&temp.join("l.nii")), [temp]);
        let out = Path::new("/nonexistent-slabscope/labels.nrrd");
        let folders = [PathBuf::from("/nonexistent-slabscope"), "/nowhere".into()];
        let Err(e) = mask_scratch(out, 1 << 20, &folders) else {
            panic!("no folder to hold it");
        };
        let text = e.to_string();
        assert!(
            text.starts_with(
                "/nonexistent-slabscope/labels.nrrd: the background's mask (8.0 MiB) fits \
                 neither in the memory limit nor in a scratch file: no scratch file could be \
                 made in /nonexistent-slabscope ("
            ),
            "{text}"
        );
        assert!(text.contains("; no scratch file could be made in /nowhere ("));
        assert!(!text.contains('\n'), "{text}");
    }

    #[test]
    fn a_label_takes_two_bytes_from_256_slabs() {
        assert_eq!(label_bytes(255), 1);
        assert_eq!(label_bytes(256), 2);
        let v = Volume::new([4, 4, 4], [1.0; 3], VoxelType::F32, vec![1.0; 64]).unwrap();
        assert_eq!(label_memory(&v, 3), 64 + 8);
        assert_eq!(label_memory(&v, 300), 128 + 8);
    }
}
