//! Pickling and copies of `Volume` (its file and `load` keywords, or its voxels), `Analysis`
//! (its volume, keywords and report; the partition rebuilt when first needed) and the functions
//! that unpickle them. `Image` and `Triage` keep theirs beside them (image.rs, triage.rs). And
//! NumPy's `__array__` of `Volume` and `Image`.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slabscope::geometry::world::WorldTransform;
use slabscope::volume::VoxelType;

use crate::analysis::Analysis;
use crate::params::numpy_name;
use crate::volume::{About, Volume, load_file};

/// What `__reduce__` returns: the extension module's function `name`, which unpickles the
/// object, and the arguments it is called with.
pub fn reduced<'py>(
    py: Python<'py>,
    name: &str,
    args: impl IntoPyObject<'py, Error: Into<PyErr>>,
) -> PyResult<Bound<'py, PyAny>> {
    let restorer = py.import("slabscope._slabscope")?.getattr(name)?;
    Ok((restorer, args).into_pyobject(py)?.into_any())
}

/// `Volume.__reduce__`: a volume read from a file as its path (absolute), `load` keywords and
/// name; any other (made from an array, or `carrying_voxels()`) as its voxels and geometry.
pub fn reduce_volume<'py>(slf: &Bound<'py, Volume>) -> PyResult<Bound<'py, PyAny>> {
    let py = slf.py();
    let this = slf.get();
    if let Some((path, options)) = this.file() {
        let options = options.bind(py).copy()?;
        // A URL as text: a Python path would fold its `//`.
        if slabscope::formats::remote::is_url(path) {
            let url = path.to_string_lossy().into_owned();
            return reduced(py, "_volume_from_file", (url, options, this.name.clone()));
        }
        let args = (path.clone(), options, this.name.clone());
        return reduced(py, "_volume_from_file", args);
    }
    if let (None, Some(unread)) = (this.level0.get(), &this.unread)
        && !unread.readable()
    {
        let f = &unread.finest;
        let grid = (f.dims, f.spacing, f.transform.matrix, f.transform.known);
        let args = (grid, numpy_name(unread.voxel_type), this.name.clone());
        return reduced(py, "_volume_of_grid", args);
    }
    let voxels = slf.getattr("array")?;
    let args = (voxels, state(py, this)?);
    reduced(py, "_volume_from_voxels", args)
}

/// A pickled volume's grid: dims, spacing, affine and whether the file stated it.
type Grid = ([usize; 3], [f64; 3], [[f64; 4]; 4], bool);

/// Unpickles a volume counted in parts across a cluster, whose voxels are held nowhere: its
/// `grid`, stored type and name.
#[pyfunction]
pub fn _volume_of_grid(grid: Grid, dtype: &str, name: String) -> PyResult<Volume> {
    let voxel_type = VoxelType::parse(dtype).ok_or_else(|| {
        PyValueError::new_err(format!(
            "a pickled Volume's dtype {dtype:?}: not a voxel type"
        ))
    })?;
    let (dims, spacing, matrix, known) = grid;
    let finest = slabscope::volume::pyramid::Finest {
        dims,
        spacing,
        transform: WorldTransform { matrix, known },
    };
    Ok(Volume::of_grid(finest, voxel_type, name))
}

/// What a volume carrying its voxels pickles besides them.
fn state<'py>(py: Python<'py>, volume: &Volume) -> PyResult<Bound<'py, PyDict>> {
    let inner = volume.inner(py)?;
    let about = volume.about();
    let state = PyDict::new(py);
    state.set_item("dtype", numpy_name(inner.voxel_type()))?;
    state.set_item("spacing", inner.spacing())?;
    state.set_item("affine", inner.transform().matrix)?;
    state.set_item("known", inner.transform().known)?;
    state.set_item("name", about.name)?;
    state.set_item("format", about.format)?;
    state.set_item("notes", about.notes)?;
    state.set_item("max_memory", about.max_memory)?;
    state.set_item("copied", about.copied)?;
    Ok(state)
}

/// `Volume.__deepcopy__`: the volume itself, which never changes, unless its voxels are a
/// user's array read in place: then a volume of a copy of them.
pub fn deepcopy_volume<'py>(slf: &Bound<'py, Volume>) -> PyResult<Bound<'py, PyAny>> {
    let this = slf.get();
    if !this.lends() {
        return Ok(slf.clone().into_any());
    }
    let py = slf.py();
    let kwargs = PyDict::new(py);
    kwargs.set_item("order", "F")?;
    let copy = py
        .import("numpy")?
        .call_method("array", (slf.getattr("array")?,), Some(&kwargs))?;
    let about = About {
        copied: true,
        ..this.about()
    };
    let inner = this.inner(py)?;
    let volume = Volume::restore(
        &copy,
        inner.voxel_type(),
        inner.spacing(),
        *inner.transform(),
        about,
    )?;
    Ok(Bound::new(py, volume)?.into_any())
}

/// Unpickles a volume read from a file: reads `path` again with the `load` keywords `options`.
#[pyfunction]
pub fn _volume_from_file(
    py: Python<'_>,
    path: std::path::PathBuf,
    options: &Bound<'_, PyDict>,
    name: String,
) -> PyResult<Volume> {
    let mut volume = load_file(py, path, Some(options))?;
    volume.name = name;
    Ok(volume)
}

/// An item of a pickled volume's state.
fn item<'py, T: for<'a> FromPyObject<'a, 'py>>(
    state: &Bound<'py, PyDict>,
    key: &str,
) -> PyResult<T> {
    let value = state
        .get_item(key)?
        .ok_or_else(|| PyValueError::new_err(format!("a pickled Volume without its {key}")))?;
    value.extract::<T>().map_err(|e| {
        let e: PyErr = e.into();
        PyValueError::new_err(format!("a pickled Volume's {key}: {}", e.value(state.py())))
    })
}

/// Unpickles a volume that carried its voxels (`array`, read in place).
#[pyfunction]
pub fn _volume_from_voxels(
    array: &Bound<'_, PyAny>,
    state: &Bound<'_, PyDict>,
) -> PyResult<Volume> {
    let dtype: String = item(state, "dtype")?;
    let stored = VoxelType::parse(&dtype).ok_or_else(|| {
        PyValueError::new_err(format!(
            "a pickled Volume's dtype {dtype:?}: not a voxel type"
        ))
    })?;
    let transform = WorldTransform {
        matrix: item(state, "affine")?,
        known: item(state, "known")?,
    };
    let about = About {
        name: item(state, "name")?,
        format: item(state, "format")?,
        notes: item(state, "notes")?,
        max_memory: item(state, "max_memory")?,
        copied: item(state, "copied")?,
    };
    Volume::restore(array, stored, item(state, "spacing")?, transform, about)
}

/// Unpickles an analysis: of `volume`, with the keywords `params`, whose report is `json`; what
/// needs the partition (`labels()`, `render`, `slice`) analyses again when first asked.
#[pyfunction]
pub fn _analysis_of(
    py: Python<'_>,
    volume: Bound<'_, Volume>,
    params: &Bound<'_, PyDict>,
    json: String,
) -> PyResult<Analysis> {
    Analysis::pending(py, volume.unbind(), params.copy()?.unbind(), json)
}

/// `__array__(dtype=None, copy=None)` of `what` (`Volume` or `Image`), whose read-only view of
/// its memory is `view`, as NumPy 2 asks: `copy=False` never copies (a `ValueError` when `dtype`
/// needs it), `copy=True` always does, `None` only for another `dtype`.
pub fn numpy_array<'py>(
    what: &str,
    view: Bound<'py, PyAny>,
    dtype: Option<&Bound<'py, PyAny>>,
    copy: Option<bool>,
) -> PyResult<Bound<'py, PyAny>> {
    let py = view.py();
    let held = view.getattr("dtype")?;
    let wanted = match dtype.filter(|d| !d.is_none()) {
        Some(d) => Some(py.import("numpy")?.call_method1("dtype", (d,))?),
        None => None,
    };
    let converts = match &wanted {
        Some(w) => !w.eq(&held)?,
        None => false,
    };
    match (wanted, copy) {
        (Some(w), Some(false)) if converts => Err(PyValueError::new_err(format!(
            "{what}.__array__: dtype={} with copy=False: its {} values can only be had as a copy",
            crate::errors::repr(&w),
            crate::errors::repr(&held)
        ))),
        (Some(w), _) if converts => view.call_method1("astype", (w,)),
        (_, Some(true)) => view.call_method1("copy", ("K",)),
        _ => Ok(view),
    }
}
