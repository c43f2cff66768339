//! World coordinates (docs/design.md §2): a volume's voxel-to-world transform, a 4×4 matrix from voxel
//! indices `(i, j, k)` to RAS+ millimetres (x to the Right, y to the Anterior, z to the Superior),
//! as NIfTI and nibabel use. Formats in LPS (NRRD's `space`, DICOM, MetaImage) are converted by
//! negating x and y. A transform the file did not state (raw, TIFF, `.dat`, NIfTI with both codes
//! 0) is spacing on the diagonal, and says nothing anatomical.

use serde::Serialize;

use super::{cross, dot, normalize};

/// A voxel-to-world transform.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WorldTransform {
    /// Rows of the 4×4 matrix, voxel index to RAS+ mm; the last row is `0 0 0 1`.
    pub matrix: [[f64; 4]; 4],
    /// Whether the file stated it: otherwise it is spacing on the diagonal, and no anatomical
    /// direction may be named.
    pub known: bool,
}

/// Volume axes within this many degrees of a world axis are named for it.
pub const NAMING_DEGREES: f64 = 10.0;

impl WorldTransform {
    /// Spacing on the diagonal: geometry without orientation.
    pub fn unknown(spacing: [f64; 3]) -> Self {
        let mut matrix = [[0.0; 4]; 4];
        for k in 0..3 {
            matrix[k][k] = spacing[k];
        }
        matrix[3][3] = 1.0;
        Self {
            matrix,
            known: false,
        }
    }

    /// A stated transform to RAS+ mm: `linear` takes voxel index steps to mm (its columns are
    /// the axes' world directions, scaled by their spacings), `origin` is voxel (0, 0, 0).
    pub fn ras(linear: [[f64; 3]; 3], origin: [f64; 3]) -> Self {
        let mut matrix = [[0.0; 4]; 4];
        for r in 0..3 {
            matrix[r][..3].copy_from_slice(&linear[r]);
            matrix[r][3] = origin[r];
        }
        matrix[3][3] = 1.0;
        Self {
            matrix,
            known: true,
        }
    }

    /// A stated transform to LPS mm (DICOM, ITK, NRRD's `left-posterior-superior`), converted.
    pub fn lps(linear: [[f64; 3]; 3], origin: [f64; 3]) -> Self {
        let flip = [-1.0, -1.0, 1.0];
        Self::ras(
            std::array::from_fn(|r| linear[r].map(|c| c * flip[r])),
            std::array::from_fn(|r| origin[r] * flip[r]),
        )
    }

    /// Whether every entry is finite and the 3×3 part invertible.
    pub fn is_usable(&self) -> bool {
        self.matrix.iter().flatten().all(|v| v.is_finite()) && invert(self.linear()).is_some()
    }

    /// The 3×3 part: voxel index steps to mm.
    pub fn linear(&self) -> [[f64; 3]; 3] {
        std::array::from_fn(|r| [self.matrix[r][0], self.matrix[r][1], self.matrix[r][2]])
    }

    /// World position of voxel index coordinates `ijk`.
    pub fn apply(&self, ijk: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|r| {
            (0..3).map(|c| self.matrix[r][c] * ijk[c]).sum::<f64>() + self.matrix[r][3]
        })
    }

    /// Each voxel axis's length in mm (the columns' norms).
    pub fn zooms(&self) -> [f64; 3] {
        let a = self.linear();
        std::array::from_fn(|c| (0..3).map(|r| a[r][c] * a[r][c]).sum::<f64>().sqrt())
    }

    /// The map from physical voxel space (indices times `spacing`, the space of the view search)
    /// to world mm, without the origin: `A·S⁻¹`.
    fn physical_to_world(&self, spacing: [f64; 3]) -> [[f64; 3]; 3] {
        let a = self.linear();
        std::array::from_fn(|r| std::array::from_fn(|c| a[r][c] / spacing[c]))
    }

    /// Whether the voxel axes are perpendicular in the world (no shear, within 1e-4).
    pub fn is_orthogonal(&self) -> bool {
        let a = self.linear();
        let col = |c: usize| [a[0][c], a[1][c], a[2][c]];
        let z = self.zooms();
        [(0, 1), (0, 2), (1, 2)]
            .iter()
            .all(|&(p, q)| dot(col(p), col(q)).abs() <= 1e-4 * z[p] * z[q])
    }

    /// The world normal of the planes perpendicular to physical direction `d` (the slab planes of
    /// an axis): `B⁻ᵀ·d` normalized, `B = A·S⁻¹`, which differs from `B·d` under shear.
    pub fn world_normal(&self, d: [f64; 3], spacing: [f64; 3]) -> Option<[f64; 3]> {
        let b = self.physical_to_world(spacing);
        let inv_t = transpose(invert(b)?);
        normalize(mul(inv_t, d))
    }

    /// The physical direction (spacing applied) whose slab planes have world normal `n`: the
    /// inverse of [`world_normal`](Self::world_normal), `Bᵀ·n` normalized.
    pub fn physical_axis(&self, n: [f64; 3], spacing: [f64; 3]) -> Option<[f64; 3]> {
        normalize(mul(transpose(self.physical_to_world(spacing)), n))
    }

    /// The world position, along the normal of physical direction `d`, of the plane at `s` mm
    /// along `d` (from voxel (0, 0, 0)) is `a·s + b`: this gives `(a, b)`, `(1, 0)` when the
    /// transform is singular.
    pub fn world_line(&self, d: [f64; 3], spacing: [f64; 3]) -> (f64, f64) {
        let b = self.physical_to_world(spacing);
        let (Some(n), Some(along)) = (self.world_normal(d, spacing), normalize(d)) else {
            return (1.0, 0.0);
        };
        let origin = [self.matrix[0][3], self.matrix[1][3], self.matrix[2][3]];
        (dot(n, mul(b, along)), dot(n, origin))
    }

    /// The world direction of physical direction `d` (spacing applied): `B·d`.
    pub fn world_direction(&self, d: [f64; 3], spacing: [f64; 3]) -> [f64; 3] {
        mul(self.physical_to_world(spacing), d)
    }

    /// The physical direction (spacing applied) of world direction `w`: `B⁻¹·w` normalized.
    pub fn physical_direction(&self, w: [f64; 3], spacing: [f64; 3]) -> Option<[f64; 3]> {
        normalize(mul(invert(self.physical_to_world(spacing))?, w))
    }

    /// Whether the voxel axes are left-handed in the world (a negative determinant, as LAS and
    /// LPS volumes have): a picture made in voxel space is then the mirror image of the anatomy.
    pub fn is_mirrored(&self) -> bool {
        let a = self.linear();
        let col = |c: usize| [a[0][c], a[1][c], a[2][c]];
        dot(col(0), cross(col(1), col(2))) < 0.0
    }

    /// How to show slabs along physical direction `d` so that no one asks which way is up (see
    /// [`DisplayFrame`]); `None` when the orientation is unknown.
    pub fn display_frame(&self, d: [f64; 3], spacing: [f64; 3]) -> Option<DisplayFrame> {
        if !self.known {
            return None;
        }
        let n = self.world_normal(d, spacing)?;
        let k = [2, 1, 0]
            .into_iter()
            .find(|&k| n[k].abs() > 0.1)
            .unwrap_or(0);
        let up = if n[k] < 0.0 { d.map(|c| -c) } else { d };
        let front = if n[1].abs() < 0.9 {
            [0.0, 1.0, 0.0]
        } else {
            [0.0, 0.0, -1.0]
        };
        Some(DisplayFrame {
            up,
            front: self.physical_direction(front, spacing)?,
            mirrored: self.is_mirrored(),
        })
    }

    /// The world point of physical point `p` (voxel indices times `spacing`).
    pub fn physical_point(&self, p: [f64; 3], spacing: [f64; 3]) -> [f64; 3] {
        self.apply(std::array::from_fn(|k| p[k] / spacing[k]))
    }

    /// The orientation codes, as nibabel's `aff2axcodes` gives them (`RAS`, `LPS`, `LSA`, ...),
    /// when the transform is known.
    pub fn axcodes(&self) -> Option<String> {
        if !self.known {
            return None;
        }
        let labels = [['L', 'R'], ['P', 'A'], ['I', 'S']];
        let z = self.zooms();
        let a = self.linear();
        let rs: [[f64; 3]; 3] = std::array::from_fn(|r| {
            std::array::from_fn(|c| if z[c] > 0.0 { a[r][c] / z[c] } else { 0.0 })
        });
        let mut r = nearest_rotation(rs)?;
        // Input axes in order of their largest component, each taking the world axis it points
        // along most, which no later axis may take (nibabel's io_orientation).
        let mut order = [0usize, 1, 2];
        let peak = |c: usize| (0..3).map(|k| r[k][c].abs()).fold(0.0, f64::max);
        order.sort_by(|&p, &q| peak(q).total_cmp(&peak(p)));
        let mut codes = [' '; 3];
        for c in order {
            let (out, v) = (0..3)
                .map(|k| (k, r[k][c]))
                .max_by(|x, y| x.1.abs().total_cmp(&y.1.abs()))?;
            if v.abs() < 1e-12 {
                return None;
            }
            codes[c] = labels[out][usize::from(v > 0.0)];
            r[out] = [0.0; 3];
        }
        Some(codes.iter().collect())
    }

    /// The NIfTI qform of an orthogonal transform: the quaternion `(b, c, d)` of its rotation
    /// (with `a ≥ 0`) and `qfac`, −1 when the axes are left-handed (the third then flipped);
    /// `None` under shear, which a quaternion cannot hold.
    pub fn quaternion(&self) -> Option<Quaternion> {
        if !self.is_orthogonal() {
            return None;
        }
        let z = self.zooms();
        let a = self.linear();
        let mut r: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|c| a[i][c] / z[c]));
        let det = dot(
            [r[0][0], r[1][0], r[2][0]],
            cross([r[0][1], r[1][1], r[2][1]], [r[0][2], r[1][2], r[2][2]]),
        );
        let qfac = if det < 0.0 { -1.0 } else { 1.0 };
        for row in &mut r {
            row[2] *= qfac;
        }
        // nifti_mat44_to_quatern: from the largest of the four diagonal combinations.
        let (xd, yd, zd) = (r[0][0], r[1][1], r[2][2]);
        let trace = xd + yd + zd + 1.0;
        let (qa, qb, qc, qd) = if trace > 0.5 {
            let a = 0.5 * trace.sqrt();
            (
                a,
                0.25 * (r[2][1] - r[1][2]) / a,
                0.25 * (r[0][2] - r[2][0]) / a,
                0.25 * (r[1][0] - r[0][1]) / a,
            )
        } else if 1.0 + xd - yd - zd > 0.5 {
            let b = 0.5 * (1.0 + xd - yd - zd).sqrt();
            (
                0.25 * (r[2][1] - r[1][2]) / b,
                b,
                0.25 * (r[1][0] + r[0][1]) / b,
                0.25 * (r[0][2] + r[2][0]) / b,
            )
        } else if 1.0 - xd + yd - zd > 0.5 {
            let c = 0.5 * (1.0 - xd + yd - zd).sqrt();
            (
                0.25 * (r[0][2] - r[2][0]) / c,
                0.25 * (r[1][0] + r[0][1]) / c,
                c,
                0.25 * (r[2][1] + r[1][2]) / c,
            )
        } else {
            let d = 0.5 * (1.0 - xd - yd + zd).sqrt();
            (
                0.25 * (r[1][0] - r[0][1]) / d,
                0.25 * (r[0][2] + r[2][0]) / d,
                0.25 * (r[2][1] + r[1][2]) / d,
                d,
            )
        };
        let sign = if qa < 0.0 { -1.0 } else { 1.0 };
        Some(Quaternion {
            b: sign * qb,
            c: sign * qc,
            d: sign * qd,
            qfac,
        })
    }

    /// The world box of a volume of `dims`: the smallest and largest corner coordinates of its
    /// voxel centres.
    pub fn world_bounds(&self, dims: [usize; 3]) -> [[f64; 3]; 2] {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for c in 0..8 {
            let ijk = std::array::from_fn(|k| {
                if c >> k & 1 == 1 {
                    dims[k].saturating_sub(1) as f64
                } else {
                    0.0
                }
            });
            let w = self.apply(ijk);
            for k in 0..3 {
                lo[k] = lo[k].min(w[k]);
                hi[k] = hi[k].max(w[k]);
            }
        }
        [lo, hi]
    }

    /// Physical direction `d` (spacing applied) in world terms: its slab planes' world normal
    /// and anatomical name.
    pub fn describe(&self, d: [f64; 3], spacing: [f64; 3]) -> WorldAxis {
        WorldAxis {
            world_axis: self
                .world_normal(d, spacing)
                .map_or(d, |n| n.map(|c| c + 0.0)),
            anatomy: self.anatomical_name(d, spacing),
            oriented: self.known,
        }
    }

    /// The volume axis (x, y or z: 0, 1 or 2) whose slab planes are nearest to `plane`, when the
    /// orientation is known.
    pub fn anatomical_axis(&self, plane: Anatomy, spacing: [f64; 3]) -> Option<usize> {
        if !self.known {
            return None;
        }
        let k = plane.world_index();
        (0..3)
            .filter_map(|m| {
                let mut d = [0.0; 3];
                d[m] = 1.0;
                Some((m, self.world_normal(d, spacing)?[k].abs()))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(m, _)| m)
    }

    /// The anatomical name of the slab planes perpendicular to physical direction `d`, when the
    /// orientation is known and their normal lies within [`NAMING_DEGREES`] of a world axis:
    /// `I→S, axial`, `P→A, coronal`, `L→R, sagittal` (the arrow follows `d`).
    pub fn anatomical_name(&self, d: [f64; 3], spacing: [f64; 3]) -> Option<String> {
        if !self.known {
            return None;
        }
        let n = self.world_normal(d, spacing)?;
        let k = (0..3).max_by(|&p, &q| n[p].abs().total_cmp(&n[q].abs()))?;
        if n[k].abs() < NAMING_DEGREES.to_radians().cos() {
            return None;
        }
        let (neg, pos, plane) = [
            ("L", "R", Anatomy::Sagittal.name()),
            ("P", "A", Anatomy::Coronal.name()),
            ("I", "S", Anatomy::Axial.name()),
        ][k];
        let (from, to) = if n[k] > 0.0 { (neg, pos) } else { (pos, neg) };
        Some(format!("{from}→{to}, {plane}"))
    }
}

/// The anatomical planes, named by their normals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anatomy {
    /// Planes normal to inferior→superior.
    Axial,
    /// Planes normal to posterior→anterior.
    Coronal,
    /// Planes normal to left→right.
    Sagittal,
}

impl Anatomy {
    /// `axial`, `coronal` or `sagittal`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Axial => "axial",
            Self::Coronal => "coronal",
            Self::Sagittal => "sagittal",
        }
    }

    /// The world (RAS+) axis the planes are normal to: 2, 1 or 0.
    pub fn world_index(self) -> usize {
        match self {
            Self::Axial => 2,
            Self::Coronal => 1,
            Self::Sagittal => 0,
        }
    }
}

/// An axis as the world sees it: the normal of its slab planes, and their anatomical name.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct WorldAxis {
    /// The unit normal of the slab planes in world space: RAS+ when the orientation is known,
    /// else the axis itself (the world is then physical voxel space).
    pub world_axis: [f64; 3],
    /// `I→S, axial`, `P→A, coronal`, `L→R, sagittal` when the orientation is known and the normal
    /// lies within [`NAMING_DEGREES`] of a world axis; null otherwise.
    pub anatomy: Option<String>,
    /// Whether the volume's orientation is known (an axis without an anatomical name is then
    /// oblique); the reports state it once, as `orientation`.
    #[serde(skip)]
    pub oriented: bool,
}

impl WorldAxis {
    /// `I→S, axial`; `oblique` for an axis no world axis names; empty when the orientation is
    /// unknown.
    pub fn anatomy_text(&self) -> &str {
        match &self.anatomy {
            Some(a) => a,
            None if self.oriented => "oblique",
            None => "",
        }
    }
}

/// How a picture of slabs along an axis is set up when the orientation is known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayFrame {
    /// The physical direction that points up in the picture: the axis's more superior end,
    /// else its more anterior end, else its more right end.
    pub up: [f64; 3],
    /// The physical direction the default camera looks from: the anterior, or the feet when the
    /// axis runs front to back (so that the patient's right is on the picture's left, as
    /// radiologists read).
    pub front: [f64; 3],
    /// Whether voxel space is the world's mirror image: the camera mirrors it back.
    pub mirrored: bool,
}

/// A NIfTI qform rotation: the quaternion's `b, c, d` (`a = √(1 − b² − c² − d²)`), and `qfac`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quaternion {
    /// Quaternion component b.
    pub b: f64,
    /// Quaternion component c.
    pub c: f64,
    /// Quaternion component d.
    pub d: f64,
    /// 1, or −1 when the third axis is flipped.
    pub qfac: f64,
}

fn mul(m: [[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| dot(m[r], v))
}

fn transpose(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|r| std::array::from_fn(|c| m[c][r]))
}

/// The inverse of a 3×3 matrix, `None` when it is singular.
pub fn invert(m: [[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let col = |c: usize| [m[0][c], m[1][c], m[2][c]];
    let (a, b, c) = (col(0), col(1), col(2));
    let det = dot(a, cross(b, c));
    if !det.is_finite() || det.abs() < 1e-300 {
        return None;
    }
    // Rows of the inverse: (b×c, c×a, a×b) / det.
    let rows = [cross(b, c), cross(c, a), cross(a, b)];
    Some(rows.map(|r| r.map(|x| x / det)))
}

/// The rotation nearest to `m` (its polar factor), by Newton's iteration `X ← (X + X⁻ᵀ)/2`.
fn nearest_rotation(m: [[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let mut x = m;
    for _ in 0..100 {
        let inv_t = transpose(invert(x)?);
        let next: [[f64; 3]; 3] =
            std::array::from_fn(|r| std::array::from_fn(|c| 0.5 * (x[r][c] + inv_t[r][c])));
        let change: f64 = (0..3)
            .flat_map(|r| (0..3).map(move |c| (r, c)))
            .map(|(r, c)| (next[r][c] - x[r][c]).abs())
            .sum();
        x = next;
        if change < 1e-14 {
            break;
        }
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_follow_nibabel() {
        let diag = |a: f64, b: f64, c: f64| [[a, 0.0, 0.0], [0.0, b, 0.0], [0.0, 0.0, c]];
        assert_eq!(
            WorldTransform::ras(diag(1.0, 1.0, 1.0), [0.0; 3])
                .axcodes()
                .unwrap(),
            "RAS"
        );
        assert_eq!(
            WorldTransform::ras(diag(-2.0, 1.0, 3.0), [0.0; 3])
                .axcodes()
                .unwrap(),
            "LAS"
        );
        // LSA: i to the left, j to the superior, k to the anterior.
        let lsa = [[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]];
        assert_eq!(WorldTransform::ras(lsa, [0.0; 3]).axcodes().unwrap(), "LSA");
        assert_eq!(
            WorldTransform::lps(diag(1.0, 1.0, 1.0), [0.0; 3])
                .axcodes()
                .unwrap(),
            "LPS"
        );
        assert_eq!(WorldTransform::unknown([1.0; 3]).axcodes(), None);
    }

    #[test]
    fn world_normals_and_names_follow_the_transform() {
        let lsa = WorldTransform::ras(
            [[-1.0, 0.0, 0.0], [0.0, 0.0, 2.0], [0.0, 1.0, 0.0]],
            [10.0, 20.0, 30.0],
        );
        let spacing = lsa.zooms();
        assert_eq!(spacing, [1.0, 1.0, 2.0]);
        // Volume z (k) runs to the anterior: its slab planes are coronal, P→A.
        assert_eq!(
            lsa.anatomical_name([0.0, 0.0, 1.0], spacing).unwrap(),
            "P→A, coronal"
        );
        assert_eq!(
            lsa.anatomical_name([0.0, 1.0, 0.0], spacing).unwrap(),
            "I→S, axial"
        );
        assert_eq!(
            lsa.anatomical_name([1.0, 0.0, 0.0], spacing).unwrap(),
            "R→L, sagittal"
        );
        let n = lsa.world_normal([0.0, 0.0, 1.0], spacing).unwrap();
        assert!((n[1] - 1.0).abs() < 1e-12);
        // Slice k = 3 lies 6 mm along volume z, at y = 20 + 6 mm.
        let (a, b) = lsa.world_line([0.0, 0.0, 1.0], spacing);
        let y = a * 6.0 + b;
        assert!((y - 26.0).abs() < 1e-12, "{y}");
        assert!(lsa.is_orthogonal());
        assert_eq!(lsa.anatomical_axis(Anatomy::Axial, spacing), Some(1));
        assert_eq!(lsa.anatomical_axis(Anatomy::Coronal, spacing), Some(2));
        assert_eq!(lsa.anatomical_axis(Anatomy::Sagittal, spacing), Some(0));
        assert_eq!(
            WorldTransform::unknown([1.0; 3]).anatomical_axis(Anatomy::Axial, [1.0; 3]),
            None
        );
        // The physical axis nearest the axial normal is volume y.
        let d = lsa.physical_axis([0.0, 0.0, 1.0], spacing).unwrap();
        assert!((d[1] - 1.0).abs() < 1e-12, "{d:?}");
    }

    #[test]
    fn shear_is_kept_and_the_normal_is_not_the_direction() {
        // A tilted gantry: k steps forward as it steps up.
        let t = WorldTransform::ras(
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.3], [0.0, 0.0, 1.0]],
            [0.0; 3],
        );
        assert!(!t.is_orthogonal());
        let spacing = t.zooms();
        let n = t.world_normal([0.0, 0.0, 1.0], spacing).unwrap();
        // The planes k = const are z = const: their normal is S, though k points up and forward.
        assert!(
            n[0].abs() < 1e-12 && n[1].abs() < 1e-12 && (n[2] - 1.0).abs() < 1e-12,
            "{n:?}"
        );
        assert_eq!(t.axcodes().unwrap(), "RAS");
    }
}
