//! The label volume of a partition written to a file (`analyze --export-labels`, the TUI's
//! export, Python's `Analysis.write_labels`): streamed a few planes at a time
//! ([`Labeller`]), so a label volume beyond the memory budget (a 2048³ one is 8 GiB) is
//! written, never held whole; the file's bytes are those of
//! [`label_volume`](crate::partition::label_volume) written whole.

use std::path::Path;

use crate::error::{Error, Result};
use crate::formats::{Staged, VolumeHeader, stage_streamed};
use crate::partition::{LabelRoom, Labeller, MaskHome, Partition};
use crate::progress::Monitor;
use crate::volume::Volume;

/// The label volume of `p` at `volume`'s shape and world geometry (`partitioned` the level `p`
/// partitions, as for [`label_volume`](crate::partition::label_volume)), in the format the
/// extension of `path` names, to a temporary file beside it that [`Staged::persist`] puts in
/// place. Holds a found background's mask, in memory or in a mapped scratch file beside `path`
/// as `room` says ([`MaskHome`]), and one chunk of planes within `room`'s bytes (at least one
/// plane; [`Budget::labels`](crate::budget::Budget::labels) gives the room a budget leaves,
/// [`LABEL_CHUNK_BYTES`](crate::partition::LABEL_CHUNK_BYTES) is the most used); stops when
/// `monitor` is cancelled, whose progress counts the planes written.
pub fn stage_labels(
    path: &Path,
    volume: &Volume,
    partitioned: &Volume,
    p: &Partition,
    room: LabelRoom,
    monitor: &Monitor,
) -> Result<Staged> {
    let home = if room.mask_in_memory {
        MaskHome::Memory
    } else {
        MaskHome::Scratch(path)
    };
    let labeller = Labeller::new(volume, partitioned, p, home, monitor)?;
    let step = labeller.chunk_planes(room.chunk);
    stage_in_chunks(path, volume, &labeller, step, monitor)
}

/// [`stage_labels`] by `labeller`, `step` planes at a time.
fn stage_in_chunks(
    path: &Path,
    volume: &Volume,
    labeller: &Labeller<'_>,
    step: usize,
    monitor: &Monitor,
) -> Result<Staged> {
    let header = VolumeHeader {
        voxel_type: labeller.voxel_type(),
        ..VolumeHeader::of(volume)
    };
    let nz = volume.dims()[2];
    monitor.start("writing labels", nz as u64);
    let mut bytes = Vec::new();
    let mut cancelled = false;
    let staged = stage_streamed(path, &header, &mut |out| {
        for z in (0..nz).step_by(step) {
            if monitor.is_cancelled() {
                cancelled = true;
                return Err(std::io::Error::other("cancelled"));
            }
            let end = (z + step).min(nz);
            labeller.planes_le(z..end, &mut bytes);
            out.write_all(&bytes)?;
            // A cancellation raised meanwhile is seen at the next chunk.
            let _ = monitor.advance((end - z) as u64);
        }
        Ok(())
    });
    if cancelled {
        return Err(Error::Cancelled);
    }
    staged
}

/// [`stage_labels`] put in place at `path`: an existing `path` is replaced only when `force`
/// is set, and only when it is a regular file.
pub fn write_labels(
    path: &Path,
    (volume, partitioned, p): (&Volume, &Volume, &Partition),
    room: LabelRoom,
    force: bool,
    monitor: &Monitor,
) -> Result<()> {
    crate::formats::check_output(path, force)?;
    stage_labels(path, volume, partitioned, p, room, monitor)?.persist(force)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::stage_volume;
    use crate::partition::{PartitionParams, Stop, label_volume, partition};
    use crate::volume::VoxelType;
    use crate::volume::background::BackgroundRule;

    /// A volume of `dims` whose value rises with z, one step a slice, dark (0) on the x = 0 face
    /// and missing at one voxel, with a transform.
    fn ramp(dims: [usize; 3]) -> Volume {
        let [nx, ny, nz] = dims;
        let v: Vec<f32> = (0..nx * ny * nz)
            .map(|i| match (i % nx, i / (nx * ny)) {
                _ if i == nx + 1 => f32::NAN,
                (0, _) => 0.0,
                (_, z) => 10.0 + z as f32 * 7.0,
            })
            .collect();
        let t = crate::geometry::WorldTransform::ras(
            [[0.0, -1.5, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 0.5]],
            [3.0, -4.0, 5.0],
        );
        Volume::new(dims, [2.0, 1.5, 0.5], VoxelType::F32, v)
            .unwrap()
            .with_transform(t)
    }

    fn labelled(partitioned: &Volume, slabs: usize) -> Partition {
        let mut params = PartitionParams {
            stop: Stop::Slabs(slabs),
            ..PartitionParams::default()
        };
        params.stack.background = BackgroundRule::Below(1.0);
        partition(partitioned, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap()
    }

    /// The bytes written by `stage`, put in place in `dir` as `name`.
    fn written(dir: &Path, name: &str, stage: impl FnOnce(&Path) -> Result<Staged>) -> Vec<u8> {
        let path = dir.join(name);
        stage(&path).unwrap().persist(false).unwrap();
        std::fs::read(&path).unwrap()
    }

    /// Streamed a plane, three planes and a whole chunk at a time, in every format, the file is
    /// byte for byte the label volume written whole: u8 labels, an analysis of a coarser level,
    /// and u16 labels (300 slabs).
    #[test]
    fn streamed_labels_are_the_label_volume_written_whole() {
        let dir = tempfile::tempdir().unwrap();
        let fine = ramp([6, 5, 20]);
        let coarse = fine.coarser(1);
        let wide = ramp([3, 2, 600]);
        let cases: [(&Volume, &Volume, usize, VoxelType); 3] = [
            (&fine, &fine, 4, VoxelType::U8),
            (&fine, &coarse, 3, VoxelType::U8),
            (&wide, &wide, 300, VoxelType::U16),
        ];
        let none = Monitor::none();
        for (k, (v, level, slabs, ty)) in cases.into_iter().enumerate() {
            let p = labelled(level, slabs);
            assert_eq!(p.slabs.len(), slabs);
            let whole = label_volume(v, level, &p, &none).unwrap();
            assert_eq!(whole.voxel_type(), ty);
            let labeller = Labeller::new(v, level, &p, MaskHome::Memory, &none).unwrap();
            for ext in ["nrrd", "nii", "nii.gz"] {
                let want = written(dir.path(), &format!("{k}-whole.{ext}"), |path| {
                    stage_volume(path, &whole)
                });
                let all = labeller.chunk_planes(crate::partition::LABEL_CHUNK_BYTES);
                assert_eq!(all, v.dims()[2], "a small volume in one chunk");
                assert_eq!(labeller.chunk_planes(0), 1, "at least a plane");
                for step in [1, 3, all] {
                    let got = written(dir.path(), &format!("{k}-{step}.{ext}"), |path| {
                        stage_in_chunks(path, v, &labeller, step, &none)
                    });
                    assert!(got == want, "case {k}, .{ext}, {step} planes at a time");
                }
                for mask_in_memory in [true, false] {
                    let room = LabelRoom {
                        chunk: 100,
                        mask_in_memory,
                    };
                    let got = written(
                        dir.path(),
                        &format!("{k}-public-{mask_in_memory}.{ext}"),
                        |path| stage_labels(path, v, level, &p, room, &none),
                    );
                    assert!(got == want, "case {k}, .{ext}, stage_labels, {room:?}");
                }
            }
        }
    }

    /// With a found background's mask held in a scratch file beside the labels (the room a
    /// budget below the mask gives: `Budget::labels`), the labels written are byte for byte
    /// the label volume computed in memory and written whole, in every format, and the scratch
    /// file leaves no name behind.
    #[test]
    fn labels_with_the_mask_in_a_scratch_file_are_those_in_memory() {
        let volume = crate::volume::phantom::body([48, 40, 36], 5).unwrap();
        let params = PartitionParams {
            stop: Stop::Slabs(3),
            ..PartitionParams::default()
        };
        let none = Monitor::none();
        let p = partition(&volume, [0.0, 0.0, 1.0], &params, &none).unwrap();
        assert_eq!(p.background.rule, BackgroundRule::Auto);
        let room = LabelRoom {
            chunk: 48 * 40 + 10,
            mask_in_memory: false,
        };
        let whole = label_volume(&volume, &volume, &p, &none).unwrap();
        let dir = tempfile::tempdir().unwrap();
        for ext in ["nrrd", "nii", "nii.gz"] {
            let want = written(dir.path(), &format!("whole.{ext}"), |path| {
                stage_volume(path, &whole)
            });
            let got = written(dir.path(), &format!("streamed.{ext}"), |path| {
                stage_labels(path, &volume, &volume, &p, room, &none)
            });
            assert!(want == got, ".{ext}");
        }
        let crate::volume::Voxels::U8(l) = whole.data() else {
            panic!("u8 labels")
        };
        let labelled = l.as_slice().iter().filter(|&&x| x > 0).count();
        let zeros = 48 * 40 * 36 - labelled;
        assert!(
            zeros > 48 * 40 * 36 / 5,
            "air left out by the mask: {zeros}"
        );
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 6);
    }

    #[test]
    fn a_cancelled_write_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let v = ramp([6, 5, 20]);
        let p = labelled(&v, 2);
        let flag = std::sync::atomic::AtomicBool::new(true);
        let monitor = Monitor::new(Some(&flag), None);
        let labeller = Labeller::new(&v, &v, &p, MaskHome::Memory, &Monitor::none()).unwrap();
        let path = dir.path().join("l.nrrd");
        let e = stage_in_chunks(&path, &v, &labeller, 1, &monitor).err();
        assert!(matches!(e, Some(Error::Cancelled)), "{e:?}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
