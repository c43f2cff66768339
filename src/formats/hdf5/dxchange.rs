//! The voxel size `DXchange` gives a reconstruction (`/exchange/data`): the effective pixel size
//! of its detector, in `/measurement/instrument/detection_system/objective/resolution`, else the
//! detector's `/measurement/instrument/detector/pixel_size_x` over the objective's
//! `magnification` (1 when none is given), as tomopy-cli reads them; each value in the unit its
//! `units` attribute names, µm when it names none. A reconstruction's voxels are cubes of that
//! size.

use rust_hdf5::H5File;

/// The effective pixel size.
const RESOLUTION: &str = "measurement/instrument/detection_system/objective/resolution";
/// The detector's pixel size, before magnification.
const PIXEL_SIZE: &str = "measurement/instrument/detector/pixel_size_x";
/// The objective's magnification.
const MAGNIFICATION: &str = "measurement/instrument/detection_system/objective/magnification";

/// The voxel size (x, y, z) in mm `DXchange` gives the dataset `read` (a path under
/// `exchange/`), and the note saying where it came from; `None` when it gives none usable.
pub(super) fn spacing(file: &H5File, read: &str) -> Option<([f64; 3], String)> {
    if !read.trim_start_matches('/').starts_with("exchange/") {
        return None;
    }
    let (mm, note) = if let Some((mm, shown)) = length(file, RESOLUTION) {
        (
            mm,
            format!("voxel size from DXchange's /{RESOLUTION} ({shown})"),
        )
    } else {
        let (pixel, shown) = length(file, PIXEL_SIZE)?;
        let magnification = match file.dataset(MAGNIFICATION) {
            Ok(_) => number(file, MAGNIFICATION).filter(|&m| m > 0.0)?,
            Err(_) => 1.0,
        };
        (
            pixel / magnification,
            format!(
                "voxel size from DXchange's /{PIXEL_SIZE} ({shown}) over \
                 /{MAGNIFICATION} ({magnification})"
            ),
        )
    };
    (mm.is_finite() && mm > 0.0).then_some(([mm; 3], note))
}

/// The first value of the dataset `path`, when it is a finite number.
fn number(file: &H5File, path: &str) -> Option<f64> {
    let ds = file.dataset(path).ok()?;
    let values = ds.read_numeric_as::<f64>().ok()?;
    values.first().copied().filter(|v| v.is_finite())
}

/// The millimetres in one `unit` (a `units` attribute's value), µm when none is given; `None`
/// for a unit that is no length read here.
pub(super) fn mm_per(unit: Option<&str>) -> Option<f64> {
    Some(match unit.map(str::trim) {
        None | Some("um" | "µm" | "micron" | "microns" | "micrometer" | "micrometers") => 1e-3,
        Some("nm" | "nanometer" | "nanometers") => 1e-6,
        Some("angstrom" | "angstroms" | "Å" | "A") => 1e-7,
        Some("mm" | "millimeter" | "millimeters") => 1.0,
        Some("m" | "meter" | "meters") => 1e3,
        Some(_) => return None,
    })
}

/// The length the dataset `path` holds, in mm (its value in the unit its `units` attribute
/// names, µm when none), and as the file gives it.
fn length(file: &H5File, path: &str) -> Option<(f64, String)> {
    let value = number(file, path)?;
    let unit = file
        .dataset(path)
        .ok()?
        .attr("units")
        .ok()
        .and_then(|a| a.read_string().ok());
    let to_mm = mm_per(unit.as_deref())?;
    let shown = format!("{value} {}", unit.as_deref().unwrap_or("µm").trim());
    Some((value * to_mm, crate::error::names::text(&shown)))
}
