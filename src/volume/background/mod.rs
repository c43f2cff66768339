//! The background of a volume (beyond the paper, docs/design.md §2): what lies around the object, left out
//! of slab histograms so that slabs are not spent on air. By default it is found: the region
//! connected to the volume's border at or below a threshold estimated from the border voxels, so
//! that dark cavities inside the object (lungs, airways, ventricles) stay in.

use std::sync::Arc;

use rayon::prelude::*;
use serde::Serialize;

use crate::error::Result;
use crate::progress::Monitor;
use crate::volume::{Volume, Voxel};

mod fill;
pub mod parts;

/// How the background is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
#[serde(rename_all = "lowercase", tag = "mode", content = "value")]
pub enum BackgroundRule {
    /// None: every voxel counts, as in the paper.
    None,
    /// Found: the region connected to the border at or below a threshold from the border.
    #[default]
    Auto,
    /// Every voxel at or below this value.
    Below(f32),
}

/// The background a rule found in a volume.
#[derive(Clone, Debug, PartialEq)]
pub struct Background {
    /// The rule.
    pub rule: BackgroundRule,
    /// The threshold: voxels at or below it can be background (`None` when there is none).
    pub value: Option<f32>,
    /// The share of the volume's voxels that are background.
    pub fraction: f64,
    /// For a found background: one bit per voxel.
    mask: Option<Mask>,
}

/// [`Background::contains`] resolved for a loop: a found background's mask, a threshold, or
/// nothing.
#[derive(Clone, Copy, Debug)]
pub enum BackgroundTest<'a> {
    /// One bit per voxel.
    Mask(&'a [u64]),
    /// Every voxel at or below the value.
    Below(f32),
    /// No background.
    Nothing,
}

impl BackgroundTest<'_> {
    /// Whether the voxel at linear `index`, of value `v`, is background.
    #[inline]
    pub fn contains(self, index: usize, v: f32) -> bool {
        match self {
            Self::Mask(words) => words[index / 64] >> (index % 64) & 1 == 1,
            Self::Below(t) => v <= t,
            Self::Nothing => false,
        }
    }
}

/// Room for a found background's mask, a word per 64 voxels, handed to
/// [`Background::find_in`]: memory, or the writable map of a scratch file (its pages the
/// kernel's page cache, which it can write out and drop, not the process's own memory).
pub enum MaskWords {
    /// Words in memory.
    Memory(Vec<u64>),
    /// The map of a scratch file of 8 bytes a word, its room on disk reserved.
    Mapped(memmap2::MmapMut),
}

impl MaskWords {
    /// `words` words in memory.
    #[must_use]
    pub fn memory(words: usize) -> Self {
        Self::Memory(vec![0; words])
    }

    /// The words, to write.
    pub fn words_mut(&mut self) -> &mut [u64] {
        match self {
            Self::Memory(v) => v,
            // A map starts on a page, so its bytes are aligned as words.
            Self::Mapped(m) => bytemuck::cast_slice_mut(&mut m[..]),
        }
    }
}

/// A found background's mask, as [`MaskWords`] held once made (a map made read-only).
#[derive(Clone, Debug)]
enum Mask {
    Memory(Vec<u64>),
    Mapped(Arc<memmap2::Mmap>),
}

impl Mask {
    fn of(words: MaskWords) -> Result<Self> {
        Ok(match words {
            MaskWords::Memory(v) => Self::Memory(v),
            MaskWords::Mapped(m) => Self::Mapped(Arc::new(m.make_read_only().map_err(|e| {
                crate::error::Error::Degenerate(format!(
                    "the background's mask in its scratch file could not be made read-only ({e})"
                ))
            })?)),
        })
    }

    #[inline]
    fn words(&self) -> &[u64] {
        match self {
            Self::Memory(v) => v,
            Self::Mapped(m) => bytemuck::cast_slice(&m[..]),
        }
    }
}

impl PartialEq for Mask {
    fn eq(&self, other: &Self) -> bool {
        self.words() == other.words()
    }
}

/// Border voxels a threshold is estimated from must mostly be dark: their median must lie in
/// the lowest this share of the volume's range.
const DARK_BORDER: f64 = 0.25;

/// The threshold lies this many robust standard deviations above the border's median.
const NOISE_WIDTH: f64 = 5.0;

impl Background {
    /// No background.
    pub fn none() -> Self {
        Self {
            rule: BackgroundRule::None,
            value: None,
            fraction: 0.0,
            mask: None,
        }
    }

    /// The background `rule` finds in `volume`, a found one's mask in memory; stops when
    /// `monitor` is cancelled.
    pub fn find(volume: &Volume, rule: BackgroundRule, monitor: &Monitor) -> Result<Self> {
        Self::find_in(volume, rule, monitor, |words| Ok(MaskWords::memory(words)))
    }

    /// [`find`](Self::find), a found background's mask made in the words `room` gives for the
    /// number of words asked (called only when there is a mask to make).
    pub fn find_in(
        volume: &Volume,
        rule: BackgroundRule,
        monitor: &Monitor,
        room: impl FnOnce(usize) -> Result<MaskWords>,
    ) -> Result<Self> {
        let value = match rule {
            BackgroundRule::None => None,
            BackgroundRule::Below(t) => Some(t),
            BackgroundRule::Auto => border_threshold(volume),
        };
        Self::at(volume, (rule, value), monitor, room)
    }

    /// The background of `volume` by `rule` at the threshold `value` (none without one): what
    /// [`find_in`](Self::find_in) gives when it finds `value`.
    fn at(
        volume: &Volume,
        (rule, value): (BackgroundRule, Option<f32>),
        monitor: &Monitor,
        room: impl FnOnce(usize) -> Result<MaskWords>,
    ) -> Result<Self> {
        Ok(match (rule, value) {
            (BackgroundRule::None, _) | (_, None) => Self {
                rule,
                ..Self::none()
            },
            (BackgroundRule::Below(_), Some(t)) => {
                let n = crate::volume::with_voxels!(volume.data(), |v| {
                    v.par_iter().filter(|&&v| v.to_f32() <= t).count()
                });
                Self {
                    rule: BackgroundRule::Below(t),
                    value: Some(t),
                    fraction: n as f64 / volume.len() as f64,
                    mask: None,
                }
            }
            (BackgroundRule::Auto, Some(t)) => {
                let words = room(volume.len().div_ceil(64))?;
                let (mask, count) = connected_below(volume, t, monitor, words)?;
                Self {
                    rule,
                    value: Some(t),
                    fraction: count as f64 / volume.len() as f64,
                    mask: Some(Mask::of(mask)?),
                }
            }
        })
    }

    /// The found background ([`BackgroundRule::Auto`]) of a volume of dimensions `dims` at the
    /// threshold `value`, assembled from its parts ([`parts`]): `words` the mask, every
    /// chunk's bits written at their own linear indices ([`parts::ChunkMask::write_into`]),
    /// `count` the background's voxels (the chunks' counts added). Equal to what
    /// [`find`](Self::find) gives when it finds `value` (without one, no background: `words`
    /// and `count` are not read). An error when `words` is not a word per 64 voxels or does
    /// not hold `count` bits.
    pub fn of_parts(
        dims: [usize; 3],
        value: Option<f32>,
        mut words: MaskWords,
        count: usize,
    ) -> Result<Self> {
        let Some(t) = value else {
            return Ok(Self {
                rule: BackgroundRule::Auto,
                ..Self::none()
            });
        };
        let len = parts::Chunk::new(dims, [0; 3], dims)?.len();
        let mask = words.words_mut();
        if mask.len() != len.div_ceil(64) {
            return Err(crate::error::Error::invalid(
                "background mask",
                format!("{} words", mask.len()),
                format!("{} words, one per 64 of the {len} voxels", len.div_ceil(64)),
            ));
        }
        let set: usize = mask.par_iter().map(|w| w.count_ones() as usize).sum();
        if set != count {
            return Err(crate::error::Error::invalid(
                "background count",
                count,
                format!("the {set} voxels its mask holds"),
            ));
        }
        Ok(Self {
            rule: BackgroundRule::Auto,
            value: Some(t),
            fraction: count as f64 / len as f64,
            mask: Some(Mask::of(words)?),
        })
    }

    /// The background a task holding part of a volume tests the voxels it reads against, by
    /// `rule` at the threshold `value` the whole volume's gives (a found one's from its border,
    /// [`threshold_of_border`]; `Below` its own, `value` unread): for [`BackgroundRule::Auto`] the bits of
    /// `masks`, the chunks around the voxels the task reads, at their own linear indices of a
    /// mask of the whole grid whose other bits are clear (its pages never written, so never
    /// held). Its `fraction` is of the chunks given (of none for `Below`): a part's counts never
    /// read it. An error when a mask is of another grid.
    pub fn in_part(
        dims: [usize; 3],
        rule: BackgroundRule,
        value: Option<f32>,
        masks: &[parts::ChunkMask],
    ) -> Result<Self> {
        let t = match (rule, value) {
            (BackgroundRule::Below(t), _) => {
                return Ok(Self {
                    rule,
                    value: Some(t),
                    fraction: 0.0,
                    mask: None,
                });
            }
            (BackgroundRule::None, _) | (_, None) => {
                return Ok(Self {
                    rule,
                    ..Self::none()
                });
            }
            (BackgroundRule::Auto, Some(t)) => t,
        };
        let len = parts::Chunk::new(dims, [0; 3], dims)?.len();
        let mut words = MaskWords::memory(len.div_ceil(64));
        let (mut count, mut held) = (0, 0);
        for mask in masks {
            if mask.chunk().dims() != dims {
                return Err(crate::error::Error::invalid(
                    "background mask",
                    format!("a chunk of a {:?} grid", mask.chunk().dims()),
                    format!("a chunk of the {dims:?} grid"),
                ));
            }
            mask.write_into(words.words_mut())?;
            count += mask.count();
            held += mask.chunk().len();
        }
        Ok(Self {
            rule: BackgroundRule::Auto,
            value: Some(t),
            fraction: count as f64 / held.max(1) as f64,
            mask: Some(Mask::of(words)?),
        })
    }

    /// The background as the client of an analysis in parts knows it: by `rule` at the
    /// threshold `value` the whole volume's gives (`Below` its own, `value` unread), `count` of
    /// the volume's `len` voxels (the parts' counts added), and no mask: it tests no voxel (a
    /// task's does, [`in_part`](Self::in_part)). What reports it reads is `find`'s: the rule,
    /// the threshold and the fraction.
    #[must_use]
    pub fn summarized(rule: BackgroundRule, value: Option<f32>, count: usize, len: usize) -> Self {
        let value = match rule {
            BackgroundRule::None => return Self::none(),
            BackgroundRule::Below(t) => Some(t),
            BackgroundRule::Auto => value,
        };
        Self {
            rule,
            value,
            fraction: if value.is_some() {
                count as f64 / len as f64
            } else {
                0.0
            },
            mask: None,
        }
    }

    /// Whether the voxel at linear `index`, of value `v`, is background.
    #[inline]
    pub fn contains(&self, index: usize, v: f32) -> bool {
        self.test().contains(index, v)
    }

    /// The test of [`contains`](Self::contains) with its mask found once, for a loop over
    /// voxels (`contains` finds where the mask lies at every voxel).
    #[inline]
    pub fn test(&self) -> BackgroundTest<'_> {
        match (&self.mask, self.rule) {
            (Some(mask), _) => BackgroundTest::Mask(mask.words()),
            (None, BackgroundRule::Below(t)) => BackgroundTest::Below(t),
            (None, _) => BackgroundTest::Nothing,
        }
    }

    /// The bytes it holds in memory: its mask, for a found background made in memory (a mask
    /// in a mapped scratch file is the page cache's).
    pub fn memory_bytes(&self) -> u64 {
        match &self.mask {
            Some(Mask::Memory(m)) => 8 * m.len() as u64,
            _ => 0,
        }
    }

    /// Whether any voxel is background.
    pub fn is_empty(&self) -> bool {
        self.fraction == 0.0
    }
}

/// The voxels on the volume's six faces (those that are not finite too).
fn border_values(volume: &Volume) -> Vec<f32> {
    crate::volume::with_voxels!(volume.data(), |v| border_values_of(v, volume.dims()))
}

/// [`border_values`] of voxels `v` of dimensions `dims`.
fn border_values_of<T: Voxel>(v: &[T], [nx, ny, nz]: [usize; 3]) -> Vec<f32> {
    let mut out = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            let edge_zy = z == 0 || z + 1 == nz || y == 0 || y + 1 == ny;
            let row = (z * ny + y) * nx;
            if edge_zy {
                out.extend(v[row..row + nx].iter().map(|x| x.to_f32()));
            } else {
                out.push(v[row].to_f32());
                out.push(v[row + nx - 1].to_f32());
            }
        }
    }
    out
}

/// The background threshold from the border: the border's median plus five robust standard
/// deviations (1.4826 × the median absolute deviation), when the border is mostly dark; `None`
/// when the volume has no background to speak of (its border is bright, or it is all border).
pub fn border_threshold(volume: &Volume) -> Option<f32> {
    let s = volume.stats();
    threshold_of_border(border_values(volume), (s.min, s.max), volume.dims())
}

/// [`border_threshold`] of a volume of dimensions `dims` whose finite voxels range over
/// `(min, max)` and whose six faces hold the finite values `border` (in any order; any value
/// that is not finite is left out): what tasks each holding a part of the volume give together
/// ([`parts::border_values_in`]).
#[must_use]
pub fn threshold_of_border(
    mut border: Vec<f32>,
    (min, max): (f32, f32),
    dims: [usize; 3],
) -> Option<f32> {
    border.retain(|x| x.is_finite());
    let range = f64::from(max) - f64::from(min);
    if border.is_empty() || range <= 0.0 || dims.iter().any(|&d| d < 3) {
        return None;
    }
    let median = median_of(&mut border);
    if (f64::from(median) - f64::from(min)) / range > DARK_BORDER {
        return None;
    }
    let mut deviations: Vec<f32> = border.iter().map(|v| (v - median).abs()).collect();
    let sigma = 1.4826 * f64::from(median_of(&mut deviations));
    Some((f64::from(median) + NOISE_WIDTH * sigma) as f32)
}

fn median_of(values: &mut [f32]) -> f32 {
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// The voxels at or below `t` connected (6-neighbours) to a border voxel at or below `t`, as a
/// bit mask made in `words`, with their count ([`fill`]).
fn connected_below(
    volume: &Volume,
    t: f32,
    monitor: &Monitor,
    words: MaskWords,
) -> Result<(MaskWords, usize)> {
    crate::volume::with_voxels!(volume.data(), |v| {
        fill::connected_below_of(v, volume.dims(), t, monitor, words)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    /// A 20³ volume: noisy air (0 to 4) around a ball of 100 that holds a dark cavity.
    fn ball_with_cavity() -> Volume {
        let n = 20;
        let data = (0..n * n * n)
            .map(|i| {
                let (x, y, z) = (i % n, (i / n) % n, i / (n * n));
                let r2 = |c: usize| {
                    let d = |a: usize| a as f64 - c as f64;
                    d(x) * d(x) + d(y) * d(y) + d(z) * d(z)
                };
                let noise = (i * 7919 % 5) as f32;
                if r2(10) <= 9.0 {
                    noise
                } else if r2(10) <= 64.0 {
                    100.0 + noise
                } else {
                    noise
                }
            })
            .collect();
        Volume::new([n, n, n], [1.0; 3], VoxelType::F32, data).unwrap()
    }

    #[test]
    fn the_fill_stops_when_cancelled() {
        // Dark all round a bright core: the fill walks 96 × 96 rows of air at least.
        let n = 96;
        let data = (0..n * n * n)
            .map(|i| {
                let c = [i % n, (i / n) % n, i / (n * n)];
                if c.iter().all(|&x| (40..56).contains(&x)) {
                    500.0
                } else {
                    (i % 3) as f32
                }
            })
            .collect();
        let v = Volume::new([n, n, n], [1.0; 3], VoxelType::F32, data).unwrap();
        let cancel = std::sync::atomic::AtomicBool::new(true);
        let stopped =
            Background::find(&v, BackgroundRule::Auto, &Monitor::new(Some(&cancel), None));
        assert!(matches!(stopped, Err(crate::error::Error::Cancelled)));
        let found = Background::find(&v, BackgroundRule::Auto, &Monitor::none()).unwrap();
        assert!(found.fraction > 0.99, "{}", found.fraction);
    }

    #[test]
    fn the_air_around_is_background_and_the_cavity_inside_is_not() {
        let v = ball_with_cavity();
        let b = Background::find(&v, BackgroundRule::Auto, &Monitor::none()).unwrap();
        let t = b.value.unwrap();
        assert!((4.0..100.0).contains(&t), "{t}");
        let idx = |x: usize, y: usize, z: usize| x + 20 * (y + 20 * z);
        assert!(b.contains(idx(0, 0, 0), 0.0));
        assert!(b.contains(idx(1, 10, 10), 0.0), "air beside the ball");
        assert!(!b.contains(idx(10, 10, 10), 0.0), "the cavity is inside");
        assert!(!b.contains(idx(10, 10, 15), 100.0), "the ball");
        let outside = (0..8000)
            .filter(|&i| {
                let (x, y, z) = (i % 20, (i / 20) % 20, i / 400);
                let d = |a: usize| a as f64 - 10.0;
                d(x) * d(x) + d(y) * d(y) + d(z) * d(z) > 64.0
            })
            .count();
        assert_eq!((b.fraction * 8000.0).round() as usize, outside);
    }

    #[test]
    fn a_bright_border_has_no_background_and_rules_do_what_they_say() {
        let v = Volume::new(
            [4, 4, 4],
            [1.0; 3],
            VoxelType::F32,
            (0..64)
                .map(|i| if i == 21 { 0.0 } else { 50.0 + (i % 3) as f32 })
                .collect(),
        )
        .unwrap();
        let auto = Background::find(&v, BackgroundRule::Auto, &Monitor::none()).unwrap();
        assert_eq!((auto.value, auto.fraction), (None, 0.0));
        let none = Background::find(&v, BackgroundRule::None, &Monitor::none()).unwrap();
        assert!(!none.contains(21, 0.0));
        let below = Background::find(&v, BackgroundRule::Below(50.0), &Monitor::none()).unwrap();
        assert!(below.contains(21, 0.0) && !below.contains(0, 51.0));
        assert!((below.fraction - 22.0 / 64.0).abs() < 1e-12);
    }
}
