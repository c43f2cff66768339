//! Synthetic volumes with known answers: parallel material `layers` (the paper's synthetic model),
//! a CT-like `body` in Hounsfield-like units, and the 3D modified `shepp_logan` head.
//!
//! Noise is a hash of (seed, voxel index), so a phantom is identical for a given seed whatever the
//! thread count.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::{Volume, VoxelType};

/// The intensities of the six `layers` materials (u8).
pub const LAYER_VALUES: [f32; 6] = [30.0, 70.0, 110.0, 150.0, 190.0, 230.0];

/// Standard deviation of the `layers` noise, in intensity units: mild next to the gaps of 40.
pub const LAYER_NOISE: f64 = 3.0;

/// Standard deviation of the `body` noise, in HU.
pub const BODY_NOISE: f64 = 12.0;

/// A deterministic standard normal deviate for (seed, index): splitmix64 and Box-Muller.
fn gaussian(seed: u64, index: u64) -> f64 {
    let mix = |mut z: u64| {
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let a = mix(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ mix(index));
    let b = mix(a.wrapping_add(0x9e37_79b9_7f4a_7c15));
    let u1 = ((a >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let u2 = (b >> 11) as f64 / (1u64 << 53) as f64;
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

fn check_dims(dims: [usize; 3]) -> Result<usize> {
    let n = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    match n {
        Some(n) if n > 0 && dims.iter().all(|&d| d <= 65_536) => Ok(n),
        _ => Err(Error::invalid(
            "dims",
            crate::volume::dims_string(dims),
            "between 1 and 65536 voxels along each axis",
        )),
    }
}

/// A phantom's recipe: its grid, its voxel type, its place in the world and the value of every
/// voxel, a function of the voxel's place alone (the noise a hash of its index), so that it can
/// be made whole ([`Recipe::volume`]) or written a chunk of voxels at a time without ever being
/// held ([`Recipe::write_le`]): the same voxels either way.
pub struct Recipe {
    dims: [usize; 3],
    voxel_type: VoxelType,
    transform: Option<WorldTransform>,
    kind: Kind,
}

/// What a [`Recipe`] makes, with what its voxels' function needs.
enum Kind {
    /// The unit normal, the half extent along it, the seed.
    Layers([f64; 3], f64, u64),
    Body(u64),
    /// Each ellipsoid's rotation.
    SheppLogan(Vec<[[f64; 3]; 3]>),
}

/// Voxels made at a time by [`Recipe::write_le`]: 32 MiB of f32 and their encoding beside them,
/// whatever the phantom's size.
const WRITE_VOXELS: usize = 1 << 23;

impl Recipe {
    /// `[nx, ny, nz]`.
    #[must_use]
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The type its voxels are stored in.
    #[must_use]
    pub fn voxel_type(&self) -> VoxelType {
        self.voxel_type
    }

    /// Its voxel-to-world transform (1 mm voxels).
    #[must_use]
    pub fn transform(&self) -> WorldTransform {
        self.transform
            .unwrap_or_else(|| WorldTransform::unknown([1.0; 3]))
    }

    /// The value of voxel `(x, y, z)`, whose linear index is `i`.
    fn value(&self, x: usize, y: usize, z: usize, i: u64) -> f32 {
        let [nx, ny, nz] = self.dims;
        match &self.kind {
            Kind::Layers(n, extent, seed) => {
                let half = |k: usize| (self.dims[k] as f64 - 1.0) / 2.0;
                let t = n[0] * (x as f64 - half(0))
                    + n[1] * (y as f64 - half(1))
                    + n[2] * (z as f64 - half(2));
                let layer = (((t + extent) / (2.0 * extent) * 6.0).floor() as usize).min(5);
                let v = f64::from(LAYER_VALUES[layer]) + LAYER_NOISE * gaussian(*seed, i);
                v.round().clamp(0.0, 255.0) as f32
            }
            Kind::Body(seed) => {
                let p = [
                    (x as f64 + 0.5) / nx as f64 * 2.0 - 1.0,
                    (y as f64 + 0.5) / ny as f64 * 2.0 - 1.0,
                    (z as f64 + 0.5) / nz as f64,
                ];
                let v = body_hu(p) + BODY_NOISE * gaussian(*seed, i);
                v.round().clamp(-1024.0, 3071.0) as f32
            }
            Kind::SheppLogan(rotations) => shepp_logan_at([x, y, z], self.dims, rotations),
        }
    }

    /// Voxels `first..first + out.len()` in linear order (x fastest), in parallel.
    fn fill(&self, first: usize, out: &mut [f32]) {
        let [nx, ny, _] = self.dims;
        let part = nx.max(1 << 12);
        out.par_chunks_mut(part)
            .enumerate()
            .for_each(|(c, values)| {
                // The first voxel's place found once, the others' by stepping along x.
                let start = first + c * part;
                let (mut x, mut y, mut z) = (start % nx, start / nx % ny, start / (nx * ny));
                for (i, v) in (start as u64..).zip(values.iter_mut()) {
                    *v = self.value(x, y, z, i);
                    x += 1;
                    if x == nx {
                        x = 0;
                        y += 1;
                        if y == ny {
                            y = 0;
                            z += 1;
                        }
                    }
                }
            });
    }

    /// The phantom made whole, in memory (refused when that memory cannot be had).
    pub fn volume(&self) -> Result<Volume> {
        let n = self.dims.iter().product::<usize>();
        let mut data = Vec::new();
        data.try_reserve_exact(n).map_err(|_| {
            Error::invalid(
                "dims",
                crate::volume::dims_string(self.dims),
                "a phantom this machine can hold in memory (write it to a file instead)",
            )
        })?;
        data.resize(n, 0.0f32);
        let plane = self.dims[0] * self.dims[1];
        data.par_chunks_mut(plane)
            .enumerate()
            .for_each(|(z, slice)| self.fill(z * plane, slice));
        let volume = Volume::new(self.dims, [1.0; 3], self.voxel_type, data)?;
        Ok(match self.transform {
            Some(t) => volume.with_transform(t),
            None => volume,
        })
    }

    /// Writes every voxel, x fastest, little-endian in its type (what a volume file's body
    /// holds), made eight million at a time: never more than those in memory.
    pub fn write_le(&self, out: &mut dyn std::io::Write) -> std::io::Result<()> {
        self.write_le_in(out, WRITE_VOXELS)
    }

    /// [`write_le`](Self::write_le), `chunk` voxels at a time.
    fn write_le_in(&self, out: &mut dyn std::io::Write, chunk: usize) -> std::io::Result<()> {
        let n = self.dims.iter().product::<usize>();
        let mut values = vec![0.0f32; chunk.min(n)];
        let mut bytes = Vec::with_capacity(values.len() * self.voxel_type.size());
        for first in (0..n).step_by(chunk) {
            let values = &mut values[..chunk.min(n - first)];
            self.fill(first, values);
            bytes.clear();
            super::voxel::encode_le(values, self.voxel_type, &mut bytes);
            out.write_all(&bytes)?;
        }
        Ok(())
    }
}

/// Six materials in parallel layers of equal thickness along `normal` (physical space, spacing 1),
/// with mild Gaussian noise; voxel type u8. The layer of voxel `p` is
/// `floor(6 · (n·(p - c) + t) / 2t)` where `c` is the centre and `t` the half extent along `n`.
pub fn layers(dims: [usize; 3], normal: [f64; 3], seed: u64) -> Result<Volume> {
    Recipe::layers(dims, normal, seed)?.volume()
}

impl Recipe {
    /// The recipe of [`layers`].
    pub fn layers(dims: [usize; 3], normal: [f64; 3], seed: u64) -> Result<Self> {
        check_dims(dims)?;
        let len = normal.iter().map(|c| c * c).sum::<f64>().sqrt();
        if !(len.is_finite() && len > 0.0) {
            return Err(Error::invalid(
                "normal",
                format!("{normal:?}"),
                "a direction with a length",
            ));
        }
        let n = normal.map(|c| c / len);
        let half = |k: usize| (dims[k] as f64 - 1.0) / 2.0;
        let extent: f64 = (0..3).map(|k| n[k].abs() * half(k)).sum::<f64>().max(0.5);
        Ok(Self {
            dims,
            voxel_type: VoxelType::U8,
            transform: None,
            kind: Kind::Layers(n, extent, seed),
        })
    }

    /// The recipe of [`body`].
    pub fn body(dims: [usize; 3], seed: u64) -> Result<Self> {
        check_dims(dims)?;
        Ok(Self {
            dims,
            voxel_type: VoxelType::I16,
            transform: Some(body_transform(dims)),
            kind: Kind::Body(seed),
        })
    }

    /// The recipe of [`shepp_logan`].
    pub fn shepp_logan(dims: [usize; 3]) -> Result<Self> {
        check_dims(dims)?;
        Ok(Self {
            dims,
            voxel_type: VoxelType::F32,
            transform: None,
            kind: Kind::SheppLogan(shepp_logan_rotations()),
        })
    }
}

/// The layer (0 to 5) that [`layers`] puts voxel `(x, y, z)` in, without noise.
#[must_use]
pub fn layer_of(dims: [usize; 3], normal: [f64; 3], p: [usize; 3]) -> usize {
    let len = normal.iter().map(|c| c * c).sum::<f64>().sqrt();
    let n = normal.map(|c| c / len);
    let half = |k: usize| (dims[k] as f64 - 1.0) / 2.0;
    let extent: f64 = (0..3).map(|k| n[k].abs() * half(k)).sum::<f64>().max(0.5);
    let t: f64 = (0..3).map(|k| n[k] * (p[k] as f64 - half(k))).sum();
    (((t + extent) / (2.0 * extent) * 6.0).floor() as usize).min(5)
}

/// Hounsfield-like values of the `body` tissues.
mod hu {
    pub const AIR: f64 = -1000.0;
    pub const LUNG: f64 = -850.0;
    pub const FAT: f64 = -100.0;
    pub const WATER: f64 = 5.0;
    pub const SOFT: f64 = 40.0;
    pub const BRAIN: f64 = 35.0;
    pub const BLOOD: f64 = 50.0;
    pub const LIVER: f64 = 60.0;
    pub const KIDNEY: f64 = 30.0;
    pub const DISC: f64 = 80.0;
    pub const MARROW: f64 = 300.0;
    pub const BONE: f64 = 900.0;
}

/// Squared normalized distance from an axis-aligned ellipsoid's centre (≤ 1 inside).
fn ell(p: [f64; 3], c: [f64; 3], r: [f64; 3]) -> f64 {
    (0..3).map(|k| ((p[k] - c[k]) / r[k]).powi(2)).sum()
}

/// Squared normalized distance in the x-y plane from an ellipse's centre.
fn ell2(p: [f64; 3], c: [f64; 2], r: [f64; 2]) -> f64 {
    ((p[0] - c[0]) / r[0]).powi(2) + ((p[1] - c[1]) / r[1]).powi(2)
}

/// A vertebra with its canal, or the disc between two, at height z.
fn spine(p: [f64; 3], centre: [f64; 2], radius: f64) -> Option<f64> {
    let d = ell2(p, centre, [radius, radius]);
    if d > 1.0 {
        return None;
    }
    if d < 0.12 {
        return Some(hu::SOFT);
    }
    // Vertebrae 0.03 high with discs between them.
    Some(if (p[2] * 33.0).fract() < 0.2 {
        hu::DISC
    } else {
        hu::BONE
    })
}

/// A long bone: cortex around marrow.
fn long_bone(p: [f64; 3], centre: [f64; 2], radius: f64) -> Option<f64> {
    let d = ell2(p, centre, [radius, radius]);
    (d <= 1.0).then_some(if d < 0.45 { hu::MARROW } else { hu::BONE })
}

/// The tissue at normalized body coordinates: x and y in [-1, 1] across, z in [0, 1] feet to head.
fn body_hu(p: [f64; 3]) -> f64 {
    let [x, y, z] = p;
    if z > 0.86 {
        // Head: scalp, skull, brain, two ventricles.
        let d = ell(p, [0.0, 0.0, 0.93], [0.26, 0.32, 0.075]);
        return match d {
            d if d > 1.0 => hu::AIR,
            d if d > 0.9 => hu::SOFT,
            d if d > 0.75 => hu::BONE,
            _ if ell(p, [-0.06, -0.02, 0.935], [0.04, 0.12, 0.018]) <= 1.0
                || ell(p, [0.06, -0.02, 0.935], [0.04, 0.12, 0.018]) <= 1.0 =>
            {
                hu::WATER
            }
            _ => hu::BRAIN,
        };
    }
    if z > 0.82 {
        // Neck with spine and trachea.
        if ell2(p, [0.0, 0.02], [0.16, 0.2]) > 1.0 {
            return hu::AIR;
        }
        if let Some(v) = spine(p, [0.0, 0.1], 0.06) {
            return v;
        }
        return if ell2(p, [0.0, -0.09], [0.035, 0.035]) <= 1.0 {
            hu::AIR
        } else {
            hu::SOFT
        };
    }
    if z > 0.45 {
        return trunk_hu(p);
    }
    // Legs, with femur above the knee and tibia below.
    let leg_radius = 0.11 + 0.1 * (z / 0.45);
    for side in [-1.0, 1.0] {
        let c = [side * 0.22, 0.0];
        if ell2(p, c, [leg_radius, leg_radius]) <= 1.0 {
            if let Some(v) = long_bone(
                p,
                c,
                if (0.22..0.26).contains(&z) {
                    0.06
                } else {
                    0.04
                },
            ) {
                return v;
            }
            return if ell2(p, c, [leg_radius, leg_radius]) > 0.8 {
                hu::FAT
            } else {
                hu::SOFT
            };
        }
    }
    let _ = (x, y);
    hu::AIR
}

/// The trunk between the pelvis (z = 0.45) and the shoulders (z = 0.82), with the arms beside it.
fn trunk_hu(p: [f64; 3]) -> f64 {
    let z = p[2];
    if (0.48..0.80).contains(&z) {
        for side in [-1.0, 1.0] {
            let c = [side * 0.82, 0.0];
            if ell2(p, c, [0.1, 0.12]) <= 1.0 {
                return long_bone(p, c, 0.03).unwrap_or(hu::SOFT);
            }
        }
    }
    let shoulders = if z > 0.78 {
        1.0 - (z - 0.78) * 6.0
    } else {
        1.0
    };
    let outline = ell2(p, [0.0, 0.0], [0.62 * shoulders, 0.38]);
    if outline > 1.0 {
        return hu::AIR;
    }
    if outline > 0.85 {
        return hu::FAT;
    }
    if let Some(v) = spine(p, [0.0, 0.25], 0.07) {
        return v;
    }
    if z > 0.62 {
        // Thorax: ribs every 0.02 in z, heart, lungs.
        if outline > 0.68 && (z * 50.0).fract() < 0.3 && p[1] > -0.3 {
            return hu::BONE;
        }
        if ell(p, [0.08, -0.1, 0.69], [0.17, 0.17, 0.06]) <= 1.0 {
            return hu::BLOOD;
        }
        if ell(p, [-0.28, 0.02, 0.71], [0.22, 0.27, 0.09]) <= 1.0
            || ell(p, [0.28, 0.02, 0.71], [0.22, 0.27, 0.09]) <= 1.0
        {
            return hu::LUNG;
        }
        return hu::SOFT;
    }
    if z > 0.5 {
        // Abdomen: liver, stomach gas, kidneys.
        if ell(p, [-0.25, -0.05, 0.59], [0.3, 0.25, 0.05]) <= 1.0 {
            return hu::LIVER;
        }
        if ell(p, [0.25, -0.1, 0.585], [0.14, 0.11, 0.025]) <= 1.0 {
            return hu::AIR;
        }
        if ell(p, [-0.25, 0.2, 0.55], [0.07, 0.06, 0.03]) <= 1.0
            || ell(p, [0.25, 0.2, 0.55], [0.07, 0.06, 0.03]) <= 1.0
        {
            return hu::KIDNEY;
        }
        return hu::SOFT;
    }
    // Pelvis: a bony ring behind, the bladder in front.
    if (0.55..0.75).contains(&outline) && p[1] > -0.1 {
        return hu::BONE;
    }
    if ell(p, [0.0, -0.15, 0.47], [0.12, 0.1, 0.025]) <= 1.0 {
        return hu::WATER;
    }
    hu::SOFT
}

/// A CT-like figure in Hounsfield-like units (i16): head, neck, torso with lungs, heart, spine,
/// ribs and abdominal organs, arms, legs; long axis along z with the head at high z, the liver on
/// the low-x side and the spine at high y, so its axes are LPS, and its transform says so.
pub fn body(dims: [usize; 3], seed: u64) -> Result<Volume> {
    Recipe::body(dims, seed)?.volume()
}

/// The body's place in the world: it is laid out as a CT scan is (x to the patient's left, y to
/// the back, z to the head: LPS), centred on the origin, 1 mm voxels.
fn body_transform(dims: [usize; 3]) -> WorldTransform {
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let centre = dims.map(|n| -(n as f64 - 1.0) / 2.0);
    WorldTransform::lps(identity, centre)
}

/// The ten ellipsoids of the modified 3D Shepp-Logan phantom: intensity, semi-axes (a, b, c),
/// centre (x0, y0, z0) and Euler angles (phi, theta, psi) in degrees.
const SHEPP_LOGAN: [[f64; 10]; 10] = [
    [1.0, 0.69, 0.92, 0.81, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-0.8, 0.6624, 0.874, 0.78, 0.0, -0.0184, 0.0, 0.0, 0.0, 0.0],
    [-0.2, 0.11, 0.31, 0.22, 0.22, 0.0, 0.0, -18.0, 0.0, 10.0],
    [-0.2, 0.16, 0.41, 0.28, -0.22, 0.0, 0.0, 18.0, 0.0, 10.0],
    [0.1, 0.21, 0.25, 0.41, 0.0, 0.35, -0.15, 0.0, 0.0, 0.0],
    [0.1, 0.046, 0.046, 0.05, 0.0, 0.1, 0.25, 0.0, 0.0, 0.0],
    [0.1, 0.046, 0.046, 0.05, 0.0, -0.1, 0.25, 0.0, 0.0, 0.0],
    [0.1, 0.046, 0.023, 0.05, -0.08, -0.605, 0.0, 0.0, 0.0, 0.0],
    [0.1, 0.023, 0.023, 0.02, 0.0, -0.606, 0.0, 0.0, 0.0, 0.0],
    [0.1, 0.023, 0.046, 0.02, 0.06, -0.605, 0.0, 0.0, 0.0, 0.0],
];

/// The 3D modified Shepp-Logan phantom (f32, values 0 to 1) on [-1, 1]³, noise-free.
pub fn shepp_logan(dims: [usize; 3]) -> Result<Volume> {
    Recipe::shepp_logan(dims)?.volume()
}

/// The rotation of each of the [`SHEPP_LOGAN`] ellipsoids, from its Euler angles.
fn shepp_logan_rotations() -> Vec<[[f64; 3]; 3]> {
    SHEPP_LOGAN
        .iter()
        .map(|e| {
            let (phi, theta, psi) = (e[7].to_radians(), e[8].to_radians(), e[9].to_radians());
            let (sf, cf, st, ct, sp, cp) = (
                phi.sin(),
                phi.cos(),
                theta.sin(),
                theta.cos(),
                psi.sin(),
                psi.cos(),
            );
            [
                [cp * cf - ct * sf * sp, cp * sf + ct * cf * sp, sp * st],
                [-sp * cf - ct * sf * cp, -sp * sf + ct * cf * cp, cp * st],
                [st * sf, -st * cf, ct],
            ]
        })
        .collect()
}

/// The Shepp-Logan value of voxel `v` of a grid of `dims` on [-1, 1]³.
fn shepp_logan_at(v: [usize; 3], dims: [usize; 3], rotations: &[[[f64; 3]; 3]]) -> f32 {
    let coord = |i: usize, n: usize| {
        if n > 1 {
            -1.0 + 2.0 * i as f64 / (n - 1) as f64
        } else {
            0.0
        }
    };
    let p: [f64; 3] = std::array::from_fn(|k| coord(v[k], dims[k]));
    let mut value = 0.0;
    for (e, r) in SHEPP_LOGAN.iter().zip(rotations) {
        let q: [f64; 3] = std::array::from_fn(|k| r[k][0] * p[0] + r[k][1] * p[1] + r[k][2] * p[2]);
        if ell(q, [e[4], e[5], e[6]], [e[1], e[2], e[3]]) <= 1.0 {
            value += e[0];
        }
    }
    value as f32
}

#[cfg(test)]
mod tests;
