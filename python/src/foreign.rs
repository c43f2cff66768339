//! Images of other Python libraries as volumes, as they come: nibabel's (an array indexed
//! `[x, y, z]` and a RAS+ affine) and `SimpleITK`'s (an array indexed `[z, y, x]`, with spacing,
//! origin and direction in LPS).

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use slabscope::geometry::world::WorldTransform;

use crate::errors::repr;
use crate::volume::Volume;

/// A voxel-to-world matrix, rows, voxel index to RAS+ mm (nibabel's `affine`).
pub type Affine = [[f64; 4]; 4];

/// The library an image object comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Library {
    Nibabel,
    SimpleItk,
}

impl Library {
    /// The library `obj` is an image of, told by what it has: nibabel's `dataobj` and `affine`,
    /// `SimpleITK`'s `GetSpacing`, `GetOrigin` and `GetDirection`.
    pub fn of(obj: &Bound<'_, PyAny>) -> PyResult<Option<Self>> {
        let has = |name: &str| obj.hasattr(name);
        Ok(if has("dataobj")? && has("affine")? {
            Some(Self::Nibabel)
        } else if has("GetSpacing")? && has("GetOrigin")? && has("GetDirection")? {
            Some(Self::SimpleItk)
        } else {
            None
        })
    }

    /// The image's voxels indexed `[x, y, z]` and its affine.
    pub fn parts<'py>(self, image: &Bound<'py, PyAny>) -> PyResult<(Bound<'py, PyAny>, Affine)> {
        match self {
            Self::Nibabel => nibabel(image),
            Self::SimpleItk => simple_itk(image),
        }
    }
}

/// A nibabel image's voxels (scaled by its header's slope and intercept, as nibabel gives
/// them: an unscaled integer image stays in its type and is read in place) and affine. A 4D
/// image of one volume is that volume; of more, an error saying how to take one.
fn nibabel<'py>(image: &Bound<'py, PyAny>) -> PyResult<(Bound<'py, PyAny>, Affine)> {
    let py = image.py();
    let shape: Vec<usize> = image.getattr("shape")?.extract()?;
    let numpy = py.import("numpy")?;
    let array = numpy.call_method1("asanyarray", (image.getattr("dataobj")?,))?;
    let array = match shape[..] {
        [_, _, _] => array,
        [_, _, _, 1] => array.get_item((py.Ellipsis(), 0))?,
        _ => {
            return Err(PyValueError::new_err(format!(
                "a nibabel image of shape {shape:?}: a volume has 3 dimensions, [x, y, z] (take one \
                 volume of a 4D image with Volume.from_array(image.dataobj[..., t], affine=image.affine))"
            )));
        }
    };
    let affine = image.getattr("affine")?.call_method0("tolist")?;
    let affine = affine
        .extract()
        .map_err(|_| PyValueError::new_err("a nibabel image whose affine is not 4x4"))?;
    Ok((array, affine))
}

/// A `SimpleITK` image's voxels, `[z, y, x]` transposed to `[x, y, z]` (a copy of its buffer,
/// which the image may free), and its spacing, origin and direction (LPS) as a RAS+ affine.
fn simple_itk<'py>(image: &Bound<'py, PyAny>) -> PyResult<(Bound<'py, PyAny>, Affine)> {
    let py = image.py();
    let dimension: usize = image.call_method0("GetDimension")?.extract()?;
    let components: usize = image
        .call_method0("GetNumberOfComponentsPerPixel")?
        .extract()?;
    if dimension != 3 || components != 1 {
        return Err(PyValueError::new_err(format!(
            "a SimpleITK image of {dimension} dimensions and {components} components a pixel: a \
             volume has 3 dimensions and one value a voxel (take one with sitk.VectorIndexSelectionCast)"
        )));
    }
    let sitk = py
        .import("SimpleITK")
        .map_err(|_| PyTypeError::new_err("a SimpleITK image, but SimpleITK cannot be imported"))?;
    let zyx = sitk.call_method1("GetArrayFromImage", (image,))?;
    let array = zyx.getattr("T")?;
    let spacing: [f64; 3] = image.call_method0("GetSpacing")?.extract()?;
    let origin: [f64; 3] = image.call_method0("GetOrigin")?.extract()?;
    let direction: [f64; 9] = image.call_method0("GetDirection")?.extract()?;
    Ok((array, ras_affine(spacing, origin, direction)))
}

/// The RAS+ affine of an LPS geometry (ITK's): `direction` (row-major 3x3, columns the index
/// axes) scaled by `spacing`, then x and y negated.
fn ras_affine(spacing: [f64; 3], origin: [f64; 3], direction: [f64; 9]) -> Affine {
    let sign = [-1.0, -1.0, 1.0];
    let mut m = [
        [0.0, 0.0, 0.0, 0.0],
        [0.0; 4],
        [0.0; 4],
        [0.0, 0.0, 0.0, 1.0],
    ];
    for r in 0..3 {
        for c in 0..3 {
            m[r][c] = sign[r] * direction[3 * r + c] * spacing[c];
        }
        m[r][3] = sign[r] * origin[r];
    }
    m
}

/// Whether `value` is a 4x4 matrix (nibabel's argument order, `from_array(array, affine)`,
/// gives the affine where the spacing goes).
pub fn is_affine(value: &Bound<'_, PyAny>) -> bool {
    value.extract::<Affine>().is_ok()
}

/// The voxel-to-world transform of `affine` (rows, voxel index to RAS+ mm, as nibabel's) and
/// `spacing`, which must agree with each other.
pub(crate) fn geometry(
    affine: Option<[[f64; 4]; 4]>,
    spacing: Option<[f64; 3]>,
) -> PyResult<([f64; 3], WorldTransform)> {
    let Some(m) = affine else {
        let spacing = spacing.unwrap_or([1.0; 3]);
        return Ok((spacing, WorldTransform::unknown(spacing)));
    };
    if m.iter().flatten().any(|v| !v.is_finite()) || m[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(PyValueError::new_err(
            "affine: expected a finite 4x4 matrix whose last row is 0, 0, 0, 1",
        ));
    }
    let linear = [
        [m[0][0], m[0][1], m[0][2]],
        [m[1][0], m[1][1], m[1][2]],
        [m[2][0], m[2][1], m[2][2]],
    ];
    let t = WorldTransform::ras(linear, [m[0][3], m[1][3], m[2][3]]);
    if !t.is_usable() {
        return Err(PyValueError::new_err(
            "affine: the matrix is singular (its 3x3 part has no inverse)",
        ));
    }
    let zooms = t.zooms();
    if let Some(s) = spacing
        && s.iter()
            .zip(zooms)
            .any(|(a, b)| (a - b).abs() > 1e-6 * b.abs().max(1.0))
    {
        return Err(PyValueError::new_err(format!(
            "spacing=({}, {}, {}) disagrees with the affine's voxel sizes ({:.6}, {:.6}, {:.6}): give one of them",
            s[0], s[1], s[2], zooms[0], zooms[1], zooms[2]
        )));
    }
    Ok((zooms, t))
}

impl Volume {
    /// A volume of `image`, an image of `library`, named by its file when it has one.
    pub(crate) fn of_image(image: &Bound<'_, PyAny>, library: Library) -> PyResult<Self> {
        if Library::of(image)? != Some(library) {
            let wanted = match library {
                Library::Nibabel => "a nibabel image (nibabel.load(path))",
                Library::SimpleItk => "a SimpleITK image (sitk.ReadImage(path))",
            };
            return Err(PyTypeError::new_err(format!(
                "expected {wanted}, not {}",
                repr(image)
            )));
        }
        let (array, affine) = library.parts(image)?;
        let mut volume = Self::of_array(image.py(), &array, None, Some(affine))?;
        let file = match library {
            Library::Nibabel => image.call_method0("get_filename")?,
            Library::SimpleItk => image.py().None().into_bound(image.py()),
        };
        if let Ok(name) = file.extract::<String>() {
            volume.name = name;
        }
        Ok(volume)
    }
}

/// `obj` as a volume: a `Volume` itself, or one made of a NumPy array (`[x, y, z]`) or a nibabel
/// or `SimpleITK` image, as `Volume.from_array` makes it.
pub fn volume_of<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, Volume>> {
    if let Ok(volume) = obj.cast::<Volume>() {
        return Ok(volume.clone());
    }
    let py = obj.py();
    let made = match Library::of(obj)? {
        Some(library) => Volume::of_image(obj, library)?,
        None if obj.is_instance_of::<pyo3::types::PyString>()
            || obj.is_instance(&py.import("os")?.getattr("PathLike")?)? =>
        {
            return Err(PyTypeError::new_err(format!(
                "volume={}: expected a Volume, a NumPy array or a nibabel or SimpleITK image \
                 (read a file with slabscope.load(path))",
                repr(obj)
            )));
        }
        None => Volume::of_array(py, obj, None, None)?,
    };
    Bound::new(py, made)
}
