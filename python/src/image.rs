//! `slabscope.render` and `slabscope.slice`: pictures as RGBA arrays in a small wrapper that a
//! notebook shows (`_repr_png_`) and that saves as `render -o` and `slice -o` write.

use numpy::PyArray3;
use numpy::ndarray::{Array3, ArrayView3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use slabscope::params::table;
use slabscope::render::{ImageOutput, encode, slice as slices};
use slabscope::request::{RenderRequest, SliceRequest};
use tiny_skia::Pixmap;

use crate::analysis::{Analysis, analyze};
use crate::errors::OrPy;
use crate::params::{Kwargs, analysis_params, given, look, render_params, size};
use crate::run;
use crate::volume::Volume;

/// A picture: `array` is its pixels, `(height, width, 4)` uint8 RGBA; a notebook shows it.
#[pyclass(module = "slabscope", frozen)]
pub struct Image {
    pixmap: Pixmap,
}

#[pymethods]
impl Image {
    /// The pixels, `(height, width, 4)` uint8 RGBA (a copy).
    #[getter]
    fn array<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let (w, h) = (self.pixmap.width() as usize, self.pixmap.height() as usize);
        let pixels = Array3::from_shape_vec((h, w, 4), self.pixmap.data().to_vec())
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(PyArray3::from_owned_array(py, pixels))
    }

    /// `(width, height)` in pixels.
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.pixmap.width(), self.pixmap.height())
    }

    /// The picture as PNG bytes.
    fn png<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = encode(&self.pixmap, ImageOutput::Png).or_py()?;
        Ok(PyBytes::new(py, &bytes))
    }

    fn _repr_png_<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        self.png(py)
    }

    /// Writes the picture to `path`: PNG, or JPEG for a `.jpg` or `.jpeg` name. An existing file
    /// is replaced only with `force=True`, never one that is not a regular file.
    #[pyo3(signature = (path, force=false))]
    fn save(&self, py: Python<'_>, path: &Bound<'_, PyAny>, force: bool) -> PyResult<()> {
        let out = crate::params::path(path)?;
        // Only picture names are taken, so no volume is ever written over.
        let format = ImageOutput::for_path(&out)
            .map_err(|e| PyValueError::new_err(crate::errors::message(&e)))?;
        slabscope::formats::check_output(&out, force).or_py()?;
        let bytes = encode(&self.pixmap, format).or_py()?;
        run::quick(py, || {
            slabscope::formats::write_atomic(&out, force, |mut file| {
                std::io::Write::write_all(&mut file, &bytes)
            })
        })
    }

    /// The pixels for NumPy (`np.asarray(image)`): `(height, width, 4)` uint8 RGBA, a read-only
    /// view of the picture's memory unless `dtype` or `copy=True` asks for a copy (`copy=False`
    /// with another `dtype` is a `ValueError`).
    #[pyo3(signature = (dtype=None, copy=None))]
    fn __array__<'py>(
        slf: &Bound<'py, Self>,
        dtype: Option<&Bound<'py, PyAny>>,
        copy: Option<bool>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let pixmap = &slf.get().pixmap;
        let (w, h) = (pixmap.width() as usize, pixmap.height() as usize);
        let shaped = ArrayView3::from_shape((h, w, 4), pixmap.data())
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        // SAFETY: the view borrows the pixels of the frozen `Image` `slf`, which never change;
        // the array keeps `slf` alive and is made read-only.
        let view = unsafe { PyArray3::borrow_from_array(&shaped, slf.clone().into_any()) };
        view.getattr("flags")?.setattr("writeable", false)?;
        crate::pickle::numpy_array("Image", view.into_any(), dtype, copy)
    }

    /// Pickled as its size and pixels.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pixels = PyBytes::new(py, self.pixmap.data());
        let args = (self.pixmap.width(), self.pixmap.height(), pixels);
        crate::pickle::reduced(py, "_image_of", args)
    }

    fn __copy__<'py>(slf: &Bound<'py, Self>) -> Bound<'py, Self> {
        slf.clone()
    }

    /// The picture itself: it never changes.
    fn __deepcopy__<'py>(slf: &Bound<'py, Self>, _memo: &Bound<'py, PyAny>) -> Bound<'py, Self> {
        slf.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "<slabscope.Image {}x{}>",
            self.pixmap.width(),
            self.pixmap.height()
        )
    }
}

/// Unpickles a picture: `width` x `height` pixels, RGBA bytes as the pixmap holds them.
#[pyfunction]
pub fn _image_of(width: u32, height: u32, pixels: Vec<u8>) -> PyResult<Image> {
    tiny_skia::IntSize::from_wh(width, height)
        .and_then(|size| Pixmap::from_vec(pixels, size))
        .map(|pixmap| Image { pixmap })
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "a pickled Image of {width}x{height} pixels: its bytes are not that many RGBA pixels"
            ))
        })
}

/// The exploded view of `volume`'s slabs in `analysis` (analysed with the defaults when None),
/// drawn from the level the analysis partitioned, with `render`'s keywords: `size=(640, 480)`,
/// `mode="cut"`, `tf`, `colormap`, `window`, `azimuth=30`, `elevation=20`, `zoom=1`,
/// `perspective`, `gap="similarity"`, `spread`, `highlight`, `solo`, `step=1`, `no_shading`,
/// `no_outlines`, `no_labels`. With `faces=True` (`render --faces`), instead the faces of every
/// slab, its last slice above its first, a column a slab, fit into the size: of the keywords
/// only `size` and the look (`tf`, `colormap`, `window`) apply, as on the CLI.
#[pyfunction]
#[pyo3(signature = (volume, analysis=None, progress=None, **options))]
pub fn render(
    py: Python<'_>,
    volume: &Bound<'_, Volume>,
    analysis: Option<&Analysis>,
    progress: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Image> {
    let reporter = run::Reporter::new("render", progress)?;
    let kw = Kwargs::new(py, "render", options)?;
    let size = size(&kw, &table::RENDER_SIZE)?;
    let slabscope::params::Scene {
        params,
        gap,
        spread,
    } = render_params(&kw, size)?;
    let faces = given(&kw, &[&table::FACES])?
        .switch(&table::FACES)
        .or_py()?;
    let _threads = run::Threads::bound(crate::params::threads(&kw)?);
    kw.finish()?;
    let made;
    let analysis = if let Some(a) = analysis {
        a.check_volume(py, volume.get())?;
        a
    } else {
        made = analyze(py, volume, progress, None)?;
        &made
    };
    let analysed = analysis.computed(py)?;
    let request = RenderRequest {
        scene: slabscope::params::Scene {
            params,
            gap,
            spread,
        },
        faces,
    };
    let pixmap = run::long(py, reporter.callback(), |monitor| {
        request.render(analysed, monitor)
    })?;
    crate::errors::intact(volume.get().inner(py)?)?;
    Ok(Image { pixmap })
}

/// One slice across the slab axis, oriented as radiologists read it, as `slabscope slice`
/// writes it: the axis of `analysis` when given, else the one the analysis keywords name
/// (`axis="best"`: the view search's); `index` (the middle slice when None; negative counts
/// from the end, `-1` the last slice), `size=(512,
/// 512)`, `no_letters`, `tf`, `colormap`, `window`.
#[pyfunction]
#[pyo3(signature = (volume, analysis=None, index=None, progress=None, **options))]
pub fn slice(
    py: Python<'_>,
    volume: &Volume,
    analysis: Option<&Analysis>,
    index: Option<&Bound<'_, PyAny>>,
    progress: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Image> {
    let reporter = run::Reporter::new("slice", progress)?;
    let kw = Kwargs::new(py, "slice", options)?;
    let fit = size(&kw, &table::SLICE_SIZE)?;
    let letters = !given(&kw, &[&table::NO_LETTERS])?
        .switch(&table::NO_LETTERS)
        .or_py()?;
    let look = look(&kw)?;
    let (params, _) = analysis_params(&kw)?;
    let _threads = run::Threads::bound(crate::params::threads(&kw)?);
    kw.finish()?;
    let full = volume.inner(py)?;
    let mut request = SliceRequest {
        params,
        axis: None,
        index: None,
        look,
        picture: slices::SliceParams {
            fit,
            letters,
            ..slices::SliceParams::default()
        },
    };
    match analysis {
        Some(a) => {
            a.check_volume(py, volume)?;
            request.axis = Some(a.axis(py)?);
        }
        None => {
            run::long(py, reporter.callback(), |monitor| {
                request.find_axis(full, monitor)
            })?;
        }
    }
    request.index = match index.filter(|i| !i.is_none()) {
        None => None,
        Some(given) => match given.extract::<i64>() {
            Ok(i) if i < 0 => Some(from_end(py, full, &request, i)?),
            Ok(i) => Some(usize::try_from(i).unwrap_or(usize::MAX)),
            // An int beyond 64 bits names no slice.
            Err(e) if e.is_instance_of::<pyo3::exceptions::PyOverflowError>(py) => {
                let n = slices_along(py, full, &request)?;
                return Err(no_such_slice(crate::errors::repr(given), n));
            }
            Err(_) => {
                return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                    "index={}: expected an int",
                    crate::errors::repr(given)
                )));
            }
        },
    };
    let pixmap = run::quick(py, || request.run(full, &slabscope::Monitor::none()))?;
    crate::errors::intact(full)?;
    Ok(Image { pixmap })
}

/// The slice a negative `index` names along `request`'s axis, counting from the end as
/// Python's sequences do (`-1` is the last slice).
fn from_end(
    py: Python<'_>,
    volume: &slabscope::Volume,
    request: &SliceRequest,
    index: i64,
) -> PyResult<usize> {
    let n = slices_along(py, volume, request)?;
    if index < -n {
        return Err(no_such_slice(index, n));
    }
    Ok(usize::try_from(n + index).unwrap_or(0))
}

/// How many slices `volume` has along `request`'s axis (found before: no search runs).
fn slices_along(
    py: Python<'_>,
    volume: &slabscope::Volume,
    request: &SliceRequest,
) -> PyResult<i64> {
    let slices = run::quick(py, || request.slices(volume, &slabscope::Monitor::none()))?;
    Ok(i64::try_from(slices).unwrap_or(i64::MAX))
}

/// `index=shown` names no slice of the `n` along the axis.
fn no_such_slice(shown: impl std::fmt::Display, n: i64) -> PyErr {
    crate::errors::invalid(
        "index",
        shown,
        &format!(
            "a slice from 0 to {}, or from -{n} to -1 counting from the end (there are {n} slices \
             along this axis)",
            n - 1
        ),
    )
}
