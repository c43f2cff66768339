//! Where a volume read from a file lies: its voxel spacing and the origin of its voxel-to-world
//! transform, held to bounds once for every reader (#47). Every reader's volume passes
//! [`check_spacing`] in `load`'s last step, and every transform a reader states passes
//! [`place`].
//!
//! - A spacing outside [`MIN_SPACING_MM`] to [`MAX_SPACING_MM`] along any axis is refused: no
//!   scanner or microscope makes it (electron microscopy's ångström voxels, 1e-7 mm, are a
//!   hundred times inside the bound; a light year is 1e19 mm), every size and length an analysis
//!   reports would be nonsense, and no other spacing could stand in for it without changing
//!   what is measured.
//! - An origin that is not finite or lies beyond ±[`MAX_ORIGIN_MM`] (a million kilometres) is
//!   replaced with 0 and a note: the origin only places the volume in the world, no measure
//!   depends on it, and the orientation beside it is still the file's. A voxel-to-world scale
//!   outside the spacing bounds drops the orientation too, with a note, as a singular one is.

use std::path::Path;

use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::Volume;

/// The finest voxel spacing read, in mm: 1e-9 mm, a hundredth of an ångström.
pub const MIN_SPACING_MM: f64 = 1e-9;

/// The coarsest voxel spacing read, in mm: 1e9 mm, a thousand kilometres.
pub const MAX_SPACING_MM: f64 = 1e9;

/// The farthest origin kept, in mm from 0 along each world axis: 1e12 mm.
pub const MAX_ORIGIN_MM: f64 = 1e12;

/// The axes' names, x first.
const AXES: [&str; 3] = ["x", "y", "z"];

/// Fails, naming `path`, unless every spacing of `volume` is within [`MIN_SPACING_MM`] to
/// [`MAX_SPACING_MM`].
pub(crate) fn check_spacing(path: &Path, volume: &Volume) -> Result<()> {
    for (k, &s) in volume.spacing().iter().enumerate() {
        if !spacing_ok(s) {
            return Err(Error::format(
                path,
                format!(
                    "voxel spacing {s:.3e} mm along {}: expected {MIN_SPACING_MM:e} mm to \
                     {MAX_SPACING_MM:e} mm",
                    AXES[k]
                ),
            ));
        }
    }
    Ok(())
}

/// Whether `s` mm is a spacing read.
fn spacing_ok(s: f64) -> bool {
    (MIN_SPACING_MM..=MAX_SPACING_MM).contains(&s)
}

/// `volume` placed by the transform a file states, when it states one: an origin out of bounds
/// replaced with 0, and an orientation that is singular, not finite or scaled out of the
/// spacing bounds left out, each with a note in `notes`.
pub(crate) fn place(volume: Volume, t: Option<WorldTransform>, notes: &mut Vec<String>) -> Volume {
    let Some(mut t) = t else {
        return volume;
    };
    let origin = [t.matrix[0][3], t.matrix[1][3], t.matrix[2][3]];
    if origin
        .iter()
        .any(|o| !(o.is_finite() && o.abs() <= MAX_ORIGIN_MM))
    {
        notes.push(format!(
            "the origin in the header, [{:.3e}, {:.3e}, {:.3e}] mm, is not finite or beyond \
             ±{MAX_ORIGIN_MM:e} mm: the volume is placed at 0",
            origin[0], origin[1], origin[2]
        ));
        for row in &mut t.matrix[..3] {
            row[3] = 0.0;
        }
    }
    let linear_finite = t.linear().iter().flatten().all(|v| v.is_finite());
    if linear_finite && !t.zooms().into_iter().all(spacing_ok) {
        notes.push(format!(
            "the orientation in the header scales a voxel to {:.3e} mm, outside {MIN_SPACING_MM:e} \
             mm to {MAX_SPACING_MM:e} mm: ignored",
            t.zooms()
                .into_iter()
                .find(|&z| !spacing_ok(z))
                .unwrap_or_default()
        ));
        return volume;
    }
    if !t.is_usable() {
        notes.push("the orientation in the header is singular or not finite: ignored".into());
        return volume;
    }
    volume.with_transform(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    fn volume(spacing: [f64; 3]) -> Result<Volume> {
        Volume::new(
            [2, 2, 2],
            spacing,
            VoxelType::U8,
            (0..8).map(|i| i as f32).collect(),
        )
    }

    #[test]
    fn spacings_outside_the_bounds_are_refused_naming_the_file_and_axis() {
        let path = Path::new("scan.nii");
        for ok in [[1e-7; 3], [1e-9; 3], [1e9; 3], [0.5, 0.7, 1.2]] {
            assert!(check_spacing(path, &volume(ok).unwrap()).is_ok(), "{ok:?}");
        }
        for (bad, axis) in [
            ([1e-300; 3], "x"),
            ([1e9, 1e9, 2e9], "z"),
            ([1e-10, 1e-10, 1e-10], "x"),
        ] {
            let e = check_spacing(path, &volume(bad).unwrap())
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("scan.nii: voxel spacing"), "{e}");
            assert!(
                e.contains(&format!("along {axis}")) && !e.contains('\n'),
                "{e}"
            );
            assert!(e.len() < 120, "{e}");
        }
    }

    #[test]
    fn an_origin_out_of_bounds_is_replaced_with_a_note() {
        let linear = [[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 2.0]];
        for origin in [
            [f64::INFINITY, 0.0, 0.0],
            [0.0, f64::NAN, 0.0],
            [0.0, 0.0, -2e12],
        ] {
            let mut notes = Vec::new();
            let v = place(
                volume([0.5, 0.5, 2.0]).unwrap(),
                Some(WorldTransform::ras(linear, origin)),
                &mut notes,
            );
            assert_eq!(notes.len(), 1, "{notes:?}");
            assert!(notes[0].contains("placed at 0"), "{notes:?}");
            assert_eq!(v.transform().linear(), linear, "the orientation is kept");
            assert_eq!(v.transform().apply([0.0; 3]), [0.0; 3]);
        }
        let mut notes = Vec::new();
        let origin = [-1e11, 3.5, 7.0];
        let v = place(
            volume([1.0; 3]).unwrap(),
            Some(WorldTransform::ras(linear, origin)),
            &mut notes,
        );
        assert!(notes.is_empty(), "{notes:?}");
        assert_eq!(v.transform().apply([0.0; 3]), origin);
        let tiny = [[1e-300, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let v = place(
            volume([1.0; 3]).unwrap(),
            Some(WorldTransform::ras(tiny, [0.0; 3])),
            &mut notes,
        );
        assert!(notes[0].contains("ignored"), "{notes:?}");
        assert_eq!(v.transform().zooms(), [1.0; 3]);
    }
}
