//! `slabscope.load` and `slabscope.Volume`: a volume read by slabscope's own readers, or made
//! from a NumPy array indexed `[x, y, z]` as nibabel gives it (read in place when its memory is
//! already as slabscope holds voxels: Fortran order, a type held as stored, native byte order).

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use numpy::ndarray::{ArrayView3, ShapeBuilder};
use numpy::{Element, PyArray2, PyArray3, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slabscope::geometry::world::WorldTransform;
use slabscope::volume::pyramid::Finest;
use slabscope::volume::{VoxelType, Voxels};

use crate::errors::repr;
use crate::foreign::{self, Affine, Library, geometry};
use crate::lent::lend_any;
use crate::params::{Kwargs, load_options, numpy_name};
use crate::run;

/// A volume: its voxels (`array`, `[x, y, z]`), spacing in mm, voxel-to-world `affine` and
/// `orientation`. Made by `slabscope.load(path)` or `Volume.from_array(array)`.
#[pyclass(module = "slabscope", frozen)]
pub struct Volume {
    /// The volume (level 0): held, or for a store at a URL read when first needed
    /// ([`inner`](Self::inner)).
    pub(crate) level0: OnceLock<Arc<slabscope::Volume>>,
    /// Of a store at a URL with coarser datasets, what is known before level 0 is read.
    pub(crate) unread: Option<Arc<crate::lazy::Unread>>,
    /// How reports name it: the path as given, or `array`.
    pub name: String,
    /// The memory budget its analyses run within, bytes.
    pub max_memory: u64,
    /// The NumPy array whose memory holds the voxels, for a volume made from one.
    array: Option<Py<PyAny>>,
    /// Whether making it copied the array's voxels.
    #[pyo3(get)]
    copied: bool,
    /// The format it was read as (`nifti`, `nrrd`, `dicom`, ...), `array` for an array.
    #[pyo3(get)]
    format: String,
    /// What a user should know about the file (a 4D file's volume taken, a series' gaps...):
    /// the `notes` property, with level 0's once read lazily.
    notes: Vec<String>,
    /// The file it was read from (absolute, or its URL) and the keywords it was read with: what
    /// it pickles as, unless `carry` (None for a volume made from an array).
    pub(crate) file: Option<(PathBuf, Py<PyDict>)>,
    /// Whether it pickles as its voxels even when read from a file (`carrying_voxels()`).
    carry: bool,
}

/// Reads the volume at `path` (a file, a folder of TIFF slices or of DICOM files, an OME-Zarr
/// store, a store at a URL: of one with coarser datasets, level 0 read when first needed) with the CLI's loader options as keywords: `dims`, `dtype`, `spacing`, `endian`,
/// `offset` (raw files), `max_memory`, `scratch`, `threads`, `volume`, `channel`, `array`,
/// `series`, `include_localizers`, `resample`, `show_phi`, `label_image`, `endpoint`,
/// `missing_as_fill`, `cache`.
#[pyfunction]
#[pyo3(signature = (path, **options))]
pub fn load(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Volume> {
    let file = crate::params::path(path)?;
    load_file(py, file, options)
}

/// The volume at `file` read with the keywords `options` (`load`'s), named as the path given.
pub fn load_file(
    py: Python<'_>,
    file: PathBuf,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Volume> {
    let kw = Kwargs::new(py, "load", options)?;
    let (opts, pool) = load_options(&kw)?;
    kw.finish()?;
    let _threads = run::Threads::bound(pool);
    let (level0, unread, format, notes) = match crate::lazy::read(py, &file, &opts)? {
        crate::lazy::Read::Level0(loaded) => (
            OnceLock::from(Arc::new(loaded.volume)),
            None,
            loaded.format.name(),
            loaded.notes,
        ),
        crate::lazy::Read::Unread(unread) => {
            let format = unread.format.map_or("array", |f| f.name());
            (OnceLock::new(), Some(Arc::new(unread)), format, Vec::new())
        }
    };
    let kept = match options {
        Some(d) => d.copy()?,
        None => PyDict::new(py),
    };
    let file = if slabscope::formats::remote::is_url(&file) {
        file
    } else {
        std::path::absolute(&file).unwrap_or(file)
    };
    Ok(Volume {
        level0,
        unread,
        name: slabscope::error::shown(&file),
        max_memory: opts.max_memory,
        array: None,
        copied: false,
        format: format.to_string(),
        notes,
        file: Some((file, kept.unbind())),
        carry: false,
    })
}

/// The voxel type a NumPy array of `dtype` stands for (a file of it would have): its own, or
/// for the types no file holds, f32 (float16) or f64 (the 64-bit integers, long doubles).
fn array_type(dtype: &Bound<'_, PyAny>) -> PyResult<VoxelType> {
    let kind: String = dtype.getattr("kind")?.extract()?;
    let name: String = dtype.getattr("name")?.extract()?;
    let stored = match kind.as_str() {
        "u" | "i" | "f" => VoxelType::parse(&name).unwrap_or(if kind == "f" && name == "float16" {
            VoxelType::F32
        } else {
            VoxelType::F64
        }),
        "b" => {
            return Err(PyTypeError::new_err(
                "a bool array is not a volume: give numbers (e.g. array.astype(numpy.uint8))",
            ));
        }
        "c" => {
            return Err(PyTypeError::new_err(format!(
                "a {name} array is not a volume: slabscope reads real numbers (take .real or abs())"
            )));
        }
        _ => {
            return Err(PyTypeError::new_err(format!(
                "a {name} array is not a volume: slabscope reads real numbers"
            )));
        }
    };
    Ok(stored)
}

/// `spacing=` as `load` takes it (three positive numbers, a sequence or `"SX,SY,SZ"`), else a
/// `ValueError` naming the keyword and showing the value as given.
fn given_spacing(value: &Bound<'_, PyAny>) -> PyResult<[f64; 3]> {
    let entry = &slabscope::params::table::SPACING;
    let invalid = || crate::errors::to_py(entry.invalid(repr(value)));
    let text = crate::params::as_text(entry, value).map_err(|_| invalid())?;
    slabscope::params::text::spacing(&text).ok_or_else(invalid)
}

/// One copy of `array` in Fortran order as `held` (infinities made missing, as every reader
/// holds them), and its voxels read in place.
pub fn copy_of<'py>(
    array: &Bound<'py, PyAny>,
    held: VoxelType,
) -> PyResult<(Voxels, Bound<'py, PyAny>)> {
    let py = array.py();
    let numpy = py.import("numpy")?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", numpy_name(held))?;
    kwargs.set_item("order", "F")?;
    let copy = numpy.call_method("array", (array,), Some(&kwargs))?;
    if held == VoxelType::F32 {
        let at = PyDict::new(py);
        at.set_item("where", numpy.call_method1("isinf", (&copy,))?)?;
        numpy.call_method("copyto", (&copy, numpy.getattr("nan")?), Some(&at))?;
    }
    let voxels = lend_any(&copy, held)
        .ok_or_else(|| PyValueError::new_err("the copied array could not be read in place"))?;
    Ok((voxels, copy))
}

/// Runs `$body` with `$data` bound to the voxels as a slice of their own type.
macro_rules! with_voxels {
    ($voxels:expr, |$data:ident| $body:expr) => {
        match $voxels {
            Voxels::U8(s) => {
                let $data = s.as_slice();
                $body
            }
            Voxels::I8(s) => {
                let $data = s.as_slice();
                $body
            }
            Voxels::U16(s) => {
                let $data = s.as_slice();
                $body
            }
            Voxels::I16(s) => {
                let $data = s.as_slice();
                $body
            }
            Voxels::F32(s) => {
                let $data = s.as_slice();
                $body
            }
        }
    };
}
pub(crate) use with_voxels;

/// A read-only NumPy view of `data` (a volume's voxels, `[x, y, z]` in Fortran order) that
/// keeps `owner` alive.
fn view<'py, T: Element>(
    data: &[T],
    dims: [usize; 3],
    owner: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let shaped =
        ArrayView3::from_shape(dims.f(), data).map_err(|e| PyValueError::new_err(e.to_string()))?;
    // SAFETY: the view borrows voxels the frozen `Volume` object `owner` holds and never
    // changes; the array keeps `owner` alive and is made read-only.
    let array = unsafe { PyArray3::borrow_from_array(&shaped, owner.clone()) };
    array.getattr("flags")?.setattr("writeable", false)?;
    Ok(array.into_any())
}

/// What a volume restored from its voxels is called and was: the rest of a pickled volume.
pub struct About {
    pub name: String,
    pub format: String,
    pub notes: Vec<String>,
    pub max_memory: u64,
    pub copied: bool,
}

impl Volume {
    /// The volume of `array`, the voxels a pickled volume carried (in the type they were held
    /// in, Fortran order: read in place), stored in files as `stored`, with its geometry.
    pub fn restore(
        array: &Bound<'_, PyAny>,
        stored: VoxelType,
        spacing: [f64; 3],
        transform: WorldTransform,
        about: About,
    ) -> PyResult<Self> {
        let untyped = array.cast::<PyUntypedArray>()?;
        let shape = untyped.shape().to_vec();
        let [nx, ny, nz] = shape[..] else {
            return Err(PyValueError::new_err(format!(
                "a pickled Volume of shape {shape:?}: expected 3 dimensions"
            )));
        };
        let name: String = untyped.dtype().getattr("name")?.extract()?;
        let held = VoxelType::parse(&name)
            .unwrap_or_else(|| slabscope::volume::voxels::held_type(stored, false));
        let (voxels, kept) = match lend_any(array, held) {
            Some(v) => (v, array.clone()),
            None => copy_of(array, held)?,
        };
        let volume = run::quick(array.py(), || {
            slabscope::Volume::from_voxels([nx, ny, nz], spacing, stored, voxels)
        })?
        .with_transform(transform);
        Ok(Self {
            level0: OnceLock::from(Arc::new(volume)),
            unread: None,
            name: about.name,
            max_memory: about.max_memory,
            array: Some(kept.unbind()),
            copied: about.copied,
            format: about.format,
            notes: about.notes,
            file: None,
            carry: true,
        })
    }

    /// What pickling needs of this volume: its file and load keywords unless it carries its
    /// voxels, and what `restore` takes.
    pub fn file(&self) -> Option<&(PathBuf, Py<PyDict>)> {
        self.file.as_ref().filter(|_| !self.carry)
    }

    /// The rest of the volume for `restore`.
    pub fn about(&self) -> About {
        About {
            name: self.name.clone(),
            format: self.format.clone(),
            notes: [self.notes.clone(), self.level0_notes()].concat(),
            max_memory: self.max_memory,
            copied: self.copied,
        }
    }

    /// Whether its voxels are a user's array, read in place (a deep copy copies them).
    pub fn lends(&self) -> bool {
        self.array.is_some() && !self.copied
    }

    fn clone_ref(&self, py: Python<'_>) -> Self {
        Self {
            level0: self.level0.clone(),
            unread: self.unread.clone(),
            name: self.name.clone(),
            max_memory: self.max_memory,
            array: self.array.as_ref().map(|a| a.clone_ref(py)),
            copied: self.copied,
            format: self.format.clone(),
            notes: self.notes.clone(),
            file: self
                .file
                .as_ref()
                .map(|(p, d)| (p.clone(), d.clone_ref(py))),
            carry: self.carry,
        }
    }
}

#[pymethods]
impl Volume {
    /// This volume, pickled with its voxels: a volume read from a file otherwise pickles as its
    /// path and `load` keywords (small, and read again where it is unpickled, which needs the
    /// file there); a volume made from an array always carries its voxels.
    fn carrying_voxels(&self, py: Python<'_>) -> Self {
        Self {
            carry: true,
            ..self.clone_ref(py)
        }
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::pickle::reduce_volume(slf)
    }

    /// The voxels for NumPy (`np.asarray(volume)`): `array`, the read-only view, unless `dtype`
    /// or `copy=True` asks for a copy (`copy=False` with another `dtype` is a `ValueError`).
    #[pyo3(signature = (dtype=None, copy=None))]
    fn __array__<'py>(
        slf: &Bound<'py, Self>,
        dtype: Option<&Bound<'py, PyAny>>,
        copy: Option<bool>,
    ) -> PyResult<Bound<'py, PyAny>> {
        crate::pickle::numpy_array("Volume", slf.getattr("array")?, dtype, copy)
    }

    fn __copy__<'py>(slf: &Bound<'py, Self>) -> Bound<'py, Self> {
        slf.clone()
    }

    /// The volume itself (it never changes), or, when its voxels are a user's array read in
    /// place, a volume of a copy of them.
    fn __deepcopy__<'py>(
        slf: &Bound<'py, Self>,
        _memo: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        crate::pickle::deepcopy_volume(slf)
    }

    /// A volume of `array`'s voxels, indexed `[x, y, z]` (nibabel's order: x fastest in a
    /// Fortran-ordered array). An array of uint8, int8, uint16, int16 or float32 in Fortran
    /// order is read in place (`copied` is False: do not write to it while the volume is in
    /// use); any other real array is copied once. `affine` (4x4, voxel index to RAS+ mm) gives
    /// the orientation; `spacing` (mm) must then agree with it.
    /// A nibabel or `SimpleITK` image is taken as `from_nibabel` and `from_sitk` take it, and
    /// nibabel's own argument order, `from_array(array, image.affine)`, is understood.
    #[staticmethod]
    #[pyo3(signature = (array, spacing=None, affine=None))]
    fn from_array(
        py: Python<'_>,
        array: &Bound<'_, PyAny>,
        spacing: Option<&Bound<'_, PyAny>>,
        affine: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        if let Some(library) = Library::of(array)? {
            if spacing.is_some() || affine.is_some() {
                return Err(PyValueError::new_err(
                    "from_array of a nibabel or SimpleITK image: the image carries its own \
                     spacing and affine (give neither)",
                ));
            }
            return Self::of_image(array, library);
        }
        let (spacing, affine) = match (spacing, affine) {
            (Some(s), None) if foreign::is_affine(s) => (None, Some(s)),
            other => other,
        };
        let affine = affine
            .map(|a| {
                a.extract::<Affine>().map_err(|_| {
                    crate::errors::invalid(
                        "affine",
                        repr(a),
                        "a 4x4 matrix (voxel index to RAS+ mm)",
                    )
                })
            })
            .transpose()?;
        let spacing = spacing.map(given_spacing).transpose()?;
        Self::of_array(py, array, spacing, affine)
    }

    /// A volume of a nibabel image (`nibabel.load(path)`): its voxels as nibabel gives them
    /// (`image.dataobj`, scaled by the header; an unscaled integer image is read in place) and
    /// its affine; named by its file.
    #[staticmethod]
    fn from_nibabel(image: &Bound<'_, PyAny>) -> PyResult<Self> {
        Self::of_image(image, Library::Nibabel)
    }

    /// A volume of a `SimpleITK` image: its voxels (indexed `[z, y, x]` by `SimpleITK`, `[x, y, z]`
    /// here) and its spacing, origin and direction, turned from LPS to RAS+.
    #[staticmethod]
    fn from_sitk(image: &Bound<'_, PyAny>) -> PyResult<Self> {
        Self::of_image(image, Library::SimpleItk)
    }

    /// The voxels as a read-only NumPy array indexed `[x, y, z]`, sharing the volume's memory
    /// (for a volume made from an array, a view of that array or of its one copy).
    #[getter]
    fn array<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let this = slf.get();
        if let Some(a) = &this.array {
            // A read-only view of the array lent (or of its copy): the volume's voxels do not
            // change through it.
            let view = a.bind(slf.py()).call_method0("view")?;
            view.getattr("flags")?.setattr("writeable", false)?;
            return Ok(view);
        }
        let inner = this.inner(slf.py())?;
        crate::errors::intact(inner)?;
        let dims = inner.dims();
        with_voxels!(inner.data(), |data| view(data, dims, slf.as_any()))
    }

    /// Dimensions `(nx, ny, nz)` (of a store at a URL, known before level 0 is read).
    #[getter]
    fn shape(&self, py: Python<'_>) -> PyResult<(usize, usize, usize)> {
        let [x, y, z] = self.grid(py)?.0;
        Ok((x, y, z))
    }

    /// Voxel spacing `(sx, sy, sz)` in mm.
    #[getter]
    fn spacing(&self, py: Python<'_>) -> PyResult<(f64, f64, f64)> {
        let [x, y, z] = self.grid(py)?.1;
        Ok((x, y, z))
    }

    /// The 4x4 voxel-to-world matrix (voxel index to RAS+ mm); spacing on the diagonal when the
    /// file states no orientation.
    #[getter]
    fn affine<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows: Vec<Vec<f64>> = self.grid(py)?.2.matrix.iter().map(|r| r.to_vec()).collect();
        PyArray2::from_vec2(py, &rows).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The orientation codes as nibabel's `aff2axcodes` gives them (`"LPS"`, `"RAS"`, ...), or
    /// None when the file states no orientation.
    #[getter]
    fn orientation(&self, py: Python<'_>) -> PyResult<Option<String>> {
        Ok(self.grid(py)?.2.axcodes())
    }

    /// The voxel type of the file (or array), as a NumPy dtype name: the CLI's `--type`.
    #[getter]
    pub fn dtype(&self, py: Python<'_>) -> PyResult<&'static str> {
        Ok(numpy_name(self.voxel_type(py)?))
    }

    /// `(min, max)` of the finite voxels.
    #[getter]
    fn range(&self, py: Python<'_>) -> PyResult<(f32, f32)> {
        let s = self.inner(py)?.stats();
        Ok((s.min, s.max))
    }

    /// How many voxels are missing (NaN).
    #[getter]
    fn missing(&self, py: Python<'_>) -> PyResult<u64> {
        Ok(self.inner(py)?.stats().missing as u64)
    }

    /// What a user should know about the file (a 4D file's volume taken, a series' gaps...), and
    /// of a store at a URL the notes of its datasets read so far (the coarser one an analysis
    /// read, as the CLI says them of `analyze URL --resolution auto`).
    #[getter]
    fn notes(&self) -> Vec<String> {
        [self.notes.clone(), self.level0_notes(), self.served_notes()].concat()
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let ([x, y, z], spacing, transform) = self.grid(py)?;
        // In µm or Å where the voxels are that small, as `info` says them.
        let (unit, per_mm) =
            slabscope::geometry::length_unit(spacing.into_iter().fold(0.0, f64::max));
        let [sx, sy, sz] = spacing.map(|s| {
            format!("{:.6}", s * per_mm)
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string()
        });
        Ok(format!(
            "<slabscope.Volume {:?} {x}x{y}x{z} {} spacing ({sx}, {sy}, {sz}) {unit}{}>",
            self.name,
            self.dtype(py)?,
            (transform.axcodes()).map_or_else(String::new, |o| format!(" {o}"))
        ))
    }
}

impl Volume {
    /// The file it was read from (absolute), for a volume read from one.
    pub fn source_file(&self) -> Option<&std::path::Path> {
        self.file.as_ref().map(|(path, _)| path.as_path())
    }

    /// A volume of `finest`'s grid and `voxel_type` whose voxels are held nowhere here: what an
    /// analysis counted in parts across a cluster is of (`slabscope.dask.analyze_array`). Its
    /// shape, spacing, affine and type are known; reading its voxels is an error saying why.
    pub(crate) fn of_grid(finest: Finest, voxel_type: VoxelType, name: String) -> Self {
        Self {
            level0: OnceLock::new(),
            unread: Some(Arc::new(crate::lazy::Unread::nowhere(finest, voxel_type))),
            name,
            max_memory: slabscope::formats::default_max_memory(),
            array: None,
            copied: false,
            format: "array".into(),
            notes: Vec::new(),
            file: None,
            carry: false,
        }
    }

    /// A volume of `array`'s voxels, `[x, y, z]`, with `spacing` or `affine` (see `from_array`).
    pub(crate) fn of_array(
        py: Python<'_>,
        array: &Bound<'_, PyAny>,
        spacing: Option<[f64; 3]>,
        affine: Option<Affine>,
    ) -> PyResult<Self> {
        let numpy = py.import("numpy")?;
        let original = if array.cast::<PyUntypedArray>().is_ok() {
            array.clone()
        } else {
            numpy.call_method1("asarray", (array,))?
        };
        let untyped = original.cast::<PyUntypedArray>()?;
        let stored = array_type(untyped.dtype().as_any())?;
        let shape = untyped.shape().to_vec();
        let [nx, ny, nz] = shape[..] else {
            return Err(PyValueError::new_err(format!(
                "an array of shape {shape:?}: a volume has 3 dimensions, [x, y, z] (take one volume of a 4D image with array[..., t])"
            )));
        };
        let dims = [nx, ny, nz];
        if dims.contains(&0) {
            return Err(PyValueError::new_err(format!(
                "an array of shape {shape:?}: a volume has at least one voxel"
            )));
        }
        let (spacing, transform) = geometry(affine, spacing)?;
        let held = slabscope::volume::voxels::held_type(stored, false);
        let (voxels, kept, copied) = if let Some(v) = lend_any(&original, held) {
            (v, original.clone(), false)
        } else {
            let (v, copy) = copy_of(&original, held)?;
            (v, copy, true)
        };
        let volume = run::quick(py, || {
            slabscope::Volume::from_voxels(dims, spacing, stored, voxels)
        })?
        .with_transform(transform);
        Ok(Self {
            level0: OnceLock::from(Arc::new(volume)),
            unread: None,
            name: "array".into(),
            max_memory: slabscope::formats::default_max_memory(),
            array: Some(kept.unbind()),
            copied,
            format: "array".into(),
            notes: Vec::new(),
            file: None,
            carry: true,
        })
    }
}
