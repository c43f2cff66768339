//! Geometry in one place: vectors in physical voxel space (millimetres, voxel (0,0,0) at the
//! origin), the [`Axis`] type that every front end parses and prints, the orthonormal frame of
//! an axis that the camera builds on, and the ray lattice on that frame (docs/design.md §2). It
//! imports nothing of the crate: what it rejects it says with its own [`InvalidParameter`].

pub mod lattice;
pub mod world;

use std::fmt;
use std::str::FromStr;

use serde::{Serialize, Serializer};

pub use world::{Anatomy, DisplayFrame, WorldAxis, WorldTransform};

/// A value geometry cannot take: a direction without length, an axis that does not parse, a
/// spacing out of range. It carries what the crate's `InvalidParameter` error carries, and
/// converts into it, so that a front end words it as any other parameter.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{parameter} {value}: expected {expected}")]
pub struct InvalidParameter {
    /// The parameter's name, as the library's parameter types spell it (`axis`, `ray_spacing`).
    pub parameter: &'static str,
    /// The value given, as text.
    pub value: String,
    /// What it must be.
    pub expected: String,
}

impl InvalidParameter {
    /// `parameter` was `value`, and should be `expected`.
    pub fn new(
        parameter: &'static str,
        value: impl fmt::Display,
        expected: impl Into<String>,
    ) -> Self {
        Self {
            parameter,
            value: value.to_string(),
            expected: expected.into(),
        }
    }
}

/// Geometry's result type: a value, or the parameter it could not take.
pub type Result<T, E = InvalidParameter> = std::result::Result<T, E>;

/// The largest ratio between two voxel spacings (and between a lattice spacing and the smallest
/// voxel spacing): real data reach about 200 (histology), and the work of the view search grows
/// with the square of the ratio.
pub const MAX_SPACING_RATIO: f64 = 1e4;

/// Dot product.
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a` scaled to unit length, or `None` for a zero or non-finite vector.
pub fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n.is_finite() && n > 1e-12).then(|| a.map(|c| c / n))
}

/// The coordinate axis (0 for x, 1 for y, 2 for z) that the unit vector `d` lies along, if any.
pub fn coordinate_axis(d: [f64; 3]) -> Option<usize> {
    (0..3).find(|&m| d[m].abs() > 1.0 - 1e-12)
}

/// The canonical one of `d` and `-d`: the one whose first non-zero component (|c| > 1e-9, in
/// x, y, z order) is positive.
pub fn canonical(d: [f64; 3]) -> [f64; 3] {
    match d.iter().find(|c| c.abs() > 1e-9) {
        Some(c) if *c < 0.0 => d.map(|c| -c),
        _ => d,
    }
}

/// The orthonormal frame `(d, u, v)` of docs/design.md §2: `e` is the coordinate axis where `|d|` has
/// its smallest component (the first on ties), `u = normalize(e - (e·d) d)`, `v = d × u`.
pub fn frame(d: [f64; 3]) -> Result<([f64; 3], [f64; 3], [f64; 3])> {
    let d = normalize(d).ok_or_else(|| {
        InvalidParameter::new("axis", format!("{d:?}"), "a direction with a length")
    })?;
    let mut smallest = 0;
    for k in 1..3 {
        if d[k].abs() < d[smallest].abs() {
            smallest = k;
        }
    }
    let mut e = [0.0; 3];
    e[smallest] = 1.0;
    let ed = dot(e, d);
    let u = normalize([e[0] - ed * d[0], e[1] - ed * d[1], e[2] - ed * d[2]])
        .expect("e is not parallel to d, since it is d's smallest component");
    Ok((d, u, cross(d, u)))
}

/// A unit direction's azimuth (the angle of its projection on the x-y plane from +x) and
/// elevation (its angle above the x-y plane), degrees; never -0, for display.
pub fn azimuth_elevation(d: [f64; 3]) -> (f64, f64) {
    (
        d[1].atan2(d[0]).to_degrees() + 0.0,
        d[2].clamp(-1.0, 1.0).asin().to_degrees() + 0.0,
    )
}

/// The unit lengths of about `mm` read best in for people, with its size per millimetre: mm
/// down to a tenth of a millimetre, µm down to a tenth of a micrometre (light microscopy),
/// ångström below (electron microscopy's maps). Reports in JSON stay in mm.
#[must_use]
pub fn length_unit(mm: f64) -> (&'static str, f64) {
    if mm >= 0.1 || mm <= 0.0 || !mm.is_finite() {
        ("mm", 1.0)
    } else if mm >= 1e-4 {
        ("µm", 1e3)
    } else {
        ("Å", 1e7)
    }
}

/// The smallest of three spacings.
pub fn min_spacing(spacing: [f64; 3]) -> f64 {
    spacing.iter().copied().fold(f64::INFINITY, f64::min)
}

/// A direction in physical voxel space: unit length and canonical (of `d` and `-d`, the one whose
/// first non-zero component is positive), as docs/design.md §2 reports axes.
///
/// Parsed from `x`, `y`, `z` or `DX,DY,DZ`; printed as `[ 0.526,-0.851, 0.000]` (the precision
/// sets the decimals, three by default), with [`name`](Self::name) giving `x`, `y` or `z` for
/// the coordinate axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis([f64; 3]);

impl Axis {
    /// The x axis.
    pub const X: Self = Self([1.0, 0.0, 0.0]);
    /// The y axis.
    pub const Y: Self = Self([0.0, 1.0, 0.0]);
    /// The z axis.
    pub const Z: Self = Self([0.0, 0.0, 1.0]);

    /// The canonical unit axis along `d`; an error for a zero or non-finite vector.
    pub fn new(d: [f64; 3]) -> Result<Self> {
        normalize(d).map(|u| Self(canonical(u))).ok_or_else(|| {
            InvalidParameter::new("axis", format!("{d:?}"), "a direction with a length")
        })
    }

    /// The unit direction.
    pub fn direction(self) -> [f64; 3] {
        self.0
    }

    /// The coordinate axis it lies along (0 for x, 1 for y, 2 for z), if any.
    pub fn coordinate(self) -> Option<usize> {
        coordinate_axis(self.0)
    }

    /// `x`, `y` or `z` for a coordinate axis.
    pub fn name(self) -> Option<&'static str> {
        self.coordinate().map(|m| ["x", "y", "z"][m])
    }

    /// `[ 0.000, 0.000, 1.000] (z)`: the axis with its coordinate name, or without one for an
    /// oblique axis.
    pub fn labelled(self) -> String {
        match self.name() {
            Some(n) => format!("{self} ({n})"),
            None => self.to_string(),
        }
    }

    /// The angle between two axes in degrees, ignoring their sign.
    pub fn angle(self, other: Self) -> f64 {
        dot(self.0, other.0)
            .abs()
            .clamp(0.0, 1.0)
            .acos()
            .to_degrees()
    }
}

impl From<Axis> for [f64; 3] {
    fn from(a: Axis) -> Self {
        a.0
    }
}

impl Serialize for Axis {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

impl FromStr for Axis {
    type Err = InvalidParameter;

    /// `x`, `y`, `z`, or three comma-separated numbers `DX,DY,DZ` (not all zero).
    fn from_str(text: &str) -> Result<Self> {
        let bad = || InvalidParameter::new("axis", text, "x, y, z or a direction DX,DY,DZ");
        match text.trim() {
            "x" => Ok(Self::X),
            "y" => Ok(Self::Y),
            "z" => Ok(Self::Z),
            t => parse_triple(t)
                .filter(|d| d.iter().all(|c| c.is_finite()))
                .ok_or_else(bad)
                .and_then(|d| Self::new(d).map_err(|_| bad())),
        }
    }
}

impl fmt::Display for Axis {
    /// `[ 0.526,-0.851, 0.000]`: each component in `precision + 3` characters (three decimals by
    /// default), and never `-0.000`.
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let decimals = f.precision().unwrap_or(3);
        let width = decimals + 3;
        let half = 0.5 * 10f64.powi(-(decimals as i32));
        let c = self.0.map(|c| if c.abs() < half { 0.0 } else { c });
        write!(
            f,
            "[{:width$.decimals$},{:width$.decimals$},{:width$.decimals$}]",
            c[0], c[1], c[2]
        )
    }
}

/// Which axis to cut slabs along: the view search's best, a direction in the volume, or the
/// volume axis nearest an anatomical plane's normal (which needs a known orientation).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AxisChoice {
    /// The view search's best.
    #[default]
    Best,
    /// This direction in physical voxel space.
    Along(Axis),
    /// The volume axis (x, y or z) nearest the normal of these planes.
    Anatomical(Anatomy),
}

impl AxisChoice {
    /// The direction chosen in a volume of voxel-to-world `transform` and voxel `spacing`, `None`
    /// for the view search's best; an error for an anatomical plane when the orientation is
    /// unknown.
    pub fn resolve(self, transform: &WorldTransform, spacing: [f64; 3]) -> Result<Option<Axis>> {
        match self {
            Self::Best => Ok(None),
            Self::Along(a) => Ok(Some(a)),
            Self::Anatomical(plane) => transform
                .anatomical_axis(plane, spacing)
                .map(|m| Some([Axis::X, Axis::Y, Axis::Z][m]))
                .ok_or_else(|| {
                    InvalidParameter::new(
                        "axis",
                        plane.name(),
                        "x, y, z or a direction, since the file states no orientation (so no \
                         axis can be named axial, coronal or sagittal)",
                    )
                }),
        }
    }
}

impl FromStr for AxisChoice {
    type Err = InvalidParameter;

    /// `best`, `axial`, `coronal`, `sagittal`, or an [`Axis`].
    fn from_str(text: &str) -> Result<Self> {
        Ok(match text.trim() {
            "best" => Self::Best,
            "axial" => Self::Anatomical(Anatomy::Axial),
            "coronal" => Self::Anatomical(Anatomy::Coronal),
            "sagittal" => Self::Anatomical(Anatomy::Sagittal),
            t => Self::Along(t.parse().map_err(|_| {
                InvalidParameter::new(
                    "axis",
                    text,
                    "best, x, y, z, axial, coronal, sagittal or a direction DX,DY,DZ",
                )
            })?),
        })
    }
}

/// Three comma-separated numbers, such as `1,0.5,2`.
pub fn parse_triple(text: &str) -> Option<[f64; 3]> {
    let v: Vec<f64> = text
        .split(',')
        .map(|p| p.trim().parse().ok())
        .collect::<Option<_>>()?;
    <[f64; 3]>::try_from(v).ok()
}

#[cfg(test)]
mod tests {
    #[test]
    fn small_lengths_read_in_their_own_unit() {
        use super::length_unit;
        assert_eq!(length_unit(1.0), ("mm", 1.0));
        assert_eq!(length_unit(0.1), ("mm", 1.0));
        assert_eq!(length_unit(0.0005), ("µm", 1e3));
        assert_eq!(length_unit(1.5e-7), ("Å", 1e7));
    }

    use super::*;

    #[test]
    fn frame_is_orthonormal_and_follows_the_design() {
        let (d, u, v) = frame([0.0, 0.0, 2.0]).unwrap();
        assert_eq!(
            (d, u, v),
            ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        );
        let (_, u, v) = frame([1.0, 0.0, 0.0]).unwrap();
        assert_eq!((u, v), ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]));
        for axis in [[1.0, 2.0, 3.0], [-0.3, 0.1, 0.9], [1.0, 1.0, 1.0]] {
            let (d, u, v) = frame(axis).unwrap();
            for (a, b) in [(d, u), (d, v), (u, v)] {
                assert!(dot(a, b).abs() < 1e-12);
            }
            for a in [d, u, v] {
                assert!((dot(a, a) - 1.0).abs() < 1e-12);
            }
        }
        assert!(frame([0.0; 3]).is_err());
    }

    #[test]
    fn canonical_picks_the_positive_first_component() {
        assert_eq!(canonical([-1.0, 2.0, 0.0]), [1.0, -2.0, -0.0]);
        assert_eq!(canonical([0.0, -0.5, 1.0]), [-0.0, 0.5, -1.0]);
        assert_eq!(canonical([1e-12, 0.0, -1.0]), [-1e-12, -0.0, 1.0]);
    }

    #[test]
    fn axes_parse_print_and_are_canonical() {
        assert_eq!("z".parse::<Axis>().unwrap(), Axis::Z);
        assert_eq!(" y ".parse::<Axis>().unwrap().name(), Some("y"));
        let a: Axis = "0,-3,4".parse().unwrap();
        assert_eq!(a.direction(), [0.0, 0.6, -0.8]);
        assert_eq!(a.to_string(), "[ 0.000, 0.600,-0.800]");
        assert_eq!(format!("{a:.2}"), "[ 0.00, 0.60,-0.80]");
        assert_eq!(a.name(), None);
        assert_eq!(a.labelled(), a.to_string());
        assert_eq!(
            Axis::new([0.0, 0.0, 2.0]).unwrap().labelled(),
            "[ 0.000, 0.000, 1.000] (z)"
        );
        assert_eq!(
            Axis::new([-1e-5, 0.0, -1.0]).unwrap().to_string(),
            "[ 0.000, 0.000, 1.000]"
        );
        for bad in ["w", "0,0,0", "1,2", "1,nan,0", "1,2,3,4", ""] {
            let e = bad.parse::<Axis>().unwrap_err().to_string();
            assert!(e.contains("x, y, z or a direction"), "{bad}: {e}");
        }
        assert!((Axis::X.angle(Axis::new([1.0, 1.0, 0.0]).unwrap()) - 45.0).abs() < 1e-9);
        assert_eq!(serde_json::to_string(&Axis::Y).unwrap(), "[0.0,1.0,0.0]");
    }
}
