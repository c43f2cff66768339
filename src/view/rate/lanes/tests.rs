//! The eight-lane walk on every voxel type: its corners gathered (or read one by one where a
//! gather could leave the volume) give the scalar walk's counts.

use super::super::tests::awkward_volume_of;
use super::super::{AxisEntropy, BinSampler, RaySubset, Vector, Walk, counts_with};
use crate::geometry::lattice::Lattice;
use crate::progress::Monitor;
use crate::volume::{Volume, Voxel, VoxelType, Voxels, with_voxels};

/// The walks' test volume (`awkward_volume_of`) held in `voxel_type` itself, its values
/// stretched over the type's range so that the sign bit and the high byte are used (negative
/// values for the signed types, values above the signed range for the unsigned ones); f32 as it
/// is, with its missing voxels.
fn held_as(dims: [usize; 3], voxel_type: VoxelType, seed: u64) -> Volume {
    let (scale, offset) = match voxel_type {
        VoxelType::U8 => (3.0, 40.0),
        VoxelType::I8 => (3.0, -110.0),
        VoxelType::U16 => (900.0, 2000.0),
        VoxelType::I16 => (900.0, -30000.0),
        _ => (1.0, 0.0),
    };
    let v = awkward_volume_of(dims, [1.0; 3], voxel_type, seed);
    let data = v
        .data()
        .to_f32_vec()
        .iter()
        .map(|&x| x * scale + offset)
        .collect();
    let held = Voxels::narrowed(data, voxel_type);
    let v = Volume::from_voxels(dims, [1.0; 3], voxel_type, held).unwrap();
    assert_eq!(v.data().held(), voxel_type, "voxels held in their own type");
    v
}

/// Whether the eight-lane walks of `voxels` (those of `v`) count what the walk one ray at a
/// time counts, along a few oblique axes; returns the samples compared.
fn lanes_agree<T: Voxel>(voxels: &[T], v: &Volume) -> u64 {
    let dims = v.dims();
    let sampler = BinSampler::over(voxels, v, v.quantizer(32).unwrap());
    let mut samples = 0;
    for (axis, phase) in [
        ([0.3, -0.5, 0.81], [0.31, 0.77, 0.5]),
        ([1.0, 1.0, 1.0], [0.0; 3]),
        ([-0.9, 0.2, 0.1], [0.5, 0.25, 0.0]),
    ] {
        let lattice = Lattice::new(dims, [1.0; 3], axis, 1.0, 0.9, phase).unwrap();
        let none = Monitor::none();
        let walk = |vector| {
            let walk = (Walk::Tiles { vector }, RaySubset::ALL);
            let (counts, rays) = counts_with(&sampler, &lattice, 3, (&none, 1), walk)?;
            Ok::<_, crate::error::Error>(AxisEntropy::new(lattice.d, &counts, rays))
        };
        let one_by_one = walk(Vector::Off).unwrap();
        for vector in [Vector::Avx2, Vector::Widest] {
            let at = format!("{:?} {dims:?} {axis:?} {vector:?}", T::TYPE);
            assert_eq!(walk(vector).unwrap(), one_by_one, "{at}");
        }
        samples += one_by_one.samples;
    }
    samples
}

#[test]
fn every_voxel_type_walked_eight_rays_at_a_time_counts_what_one_at_a_time_counts() {
    let mut samples = 0;
    for voxel_type in [
        VoxelType::U8,
        VoxelType::I8,
        VoxelType::U16,
        VoxelType::I16,
        VoxelType::F32,
    ] {
        // One voxel thick along x (whose corners along x are one voxel: read one by one), two
        // thick, and one whose first and last cells are mixed and met by oblique rays.
        for dims in [[1, 17, 15], [2, 13, 11], [25, 21, 19]] {
            let v = held_as(dims, voxel_type, 5);
            samples += with_voxels!(v.data(), |d| lanes_agree(d, &v));
        }
    }
    assert!(samples > 100_000, "{samples} samples compared");
}
