//! `slabscope.analyze` and `slabscope.Analysis`: the view search and the partition, as
//! `slabscope analyze` runs them, with the report `analyze --json` prints.

use std::sync::{Arc, OnceLock};

use numpy::PyArray3;
use numpy::ndarray::{ArrayView3, ShapeBuilder};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slabscope::Error;
use slabscope::explain::StepsShown;
use slabscope::request::{Analysed, AnalysisRequest, Level};
use slabscope::volume::Voxels;

use crate::errors::{OrPy, to_py};
use crate::params::{Kwargs, analysis_params, resolution};
use crate::run;
use crate::volume::Volume;

/// `explain=`: `None` or `False` (nothing), `True` (the last 32 steps), `"all"`, or a number of
/// steps, as `analyze --explain [all|N]`.
fn explain(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<StepsShown>> {
    let Some(v) = value.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    if let Ok(b) = v.extract::<bool>() {
        return Ok(b.then(StepsShown::default));
    }
    if let Ok(word) = v.extract::<String>()
        && word == "all"
    {
        return Ok(Some(StepsShown::All));
    }
    match v.extract::<usize>() {
        Ok(n) if n >= 1 => Ok(Some(StepsShown::Last(n))),
        _ => Err(crate::errors::invalid(
            "explain",
            v.repr().map_or_else(|_| "?".to_string(), |r| r.to_string()),
            "True, \"all\" or a number of steps",
        )),
    }
}

/// The result of `analyze`: the views with their scores, the best axis, the partition's slabs
/// and steps; `to_dict()` is the object `slabscope analyze --json` prints. It pickles as its
/// volume, keywords and report: unpickled, what needs the partition analyses again when first
/// asked (and fails if that no longer gives the report, its file having changed).
#[pyclass(module = "slabscope", frozen)]
pub struct Analysis {
    /// The volume analysed.
    volume: Py<Volume>,
    /// The keywords it was analysed with.
    params: Py<PyDict>,
    /// The library's analysis, where it ran (its `level()` is the pyramid level partitioned)
    /// and how it was asked; empty when unpickled, until needed.
    computed: OnceLock<Analysed>,
    /// The report as JSON text.
    json: String,
    /// The report, parsed once for the properties.
    report: Py<PyDict>,
}

/// Finds the most structured view of `volume` and the slabs along it, with the CLI's analysis
/// keywords and defaults (`bins=32, block=3, level=1, phases=8, method="topdown", slabs=4,
/// background="auto"`, ...), `resolution="full"` (the paper's method), `views`, `max_memory`.
/// `progress(phase, fraction)` is called as it goes; Ctrl-C stops it. `volume` may also be a
/// NumPy array or a nibabel or `SimpleITK` image, taken as `Volume.from_array` takes it.
#[pyfunction]
#[pyo3(signature = (volume, progress=None, **params))]
pub fn analyze(
    py: Python<'_>,
    volume: &Bound<'_, PyAny>,
    progress: Option<&Bound<'_, PyAny>>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Analysis> {
    let volume = &crate::foreign::volume_of(volume)?;
    let reporter = run::Reporter::new("analyze", progress)?;
    let (computed, json) = compute(py, volume.get(), reporter.callback(), params, None)?;
    drop(reporter);
    of_computed(py, volume, params, computed, json)
}

/// The analysis of `volume` with the keywords `params` whose view search's result `views`
/// was counted in parts (`slabscope.dask.analyze_array`): `analyze`'s, report and all.
pub fn analyze_with(
    py: Python<'_>,
    volume: &Bound<'_, Volume>,
    views: Option<slabscope::view::ViewSearch>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Analysis> {
    let (computed, json) = compute(py, volume.get(), None, params, views)?;
    of_computed(py, volume, params, computed, json)
}

/// The `Analysis` of `volume` with `params` that gave `computed` and its report `json`.
fn of_computed(
    py: Python<'_>,
    volume: &Bound<'_, Volume>,
    params: Option<&Bound<'_, PyDict>>,
    computed: Analysed,
    json: String,
) -> PyResult<Analysis> {
    let report = parse(py, &json)?.cast_into::<PyDict>()?.unbind();
    let params = match params {
        Some(d) => d.copy()?,
        None => PyDict::new(py),
    };
    Ok(Analysis {
        volume: volume.clone().unbind(),
        params: params.unbind(),
        computed: OnceLock::from(computed),
        json,
        report,
    })
}

/// The analysis of `volume` with the keywords `params`, and its report as JSON text.
fn compute(
    py: Python<'_>,
    volume: &Volume,
    progress: Option<&Bound<'_, PyAny>>,
    params: Option<&Bound<'_, PyDict>>,
    views: Option<slabscope::view::ViewSearch>,
) -> PyResult<(Analysed, String)> {
    let kw = Kwargs::new(py, "analyze", params)?;
    let (mut analysis_params, given) = analysis_params(&kw)?;
    analysis_params.explain = explain(kw.get::<Bound<'_, PyAny>>("explain")?.as_ref())?;
    let (resolution, named) = resolution(&kw)?;
    let max_memory = crate::params::max_memory(&kw, volume.max_memory)?;
    let _threads = run::Threads::bound(crate::params::threads(&kw)?);
    kw.finish()?;
    let full = volume.analysed(py, resolution)?;
    let request = AnalysisRequest {
        level: Level::Asked(resolution, named),
        given: Some(given),
        ..AnalysisRequest::new(analysis_params, max_memory)
    };
    let planned = run::quick(py, || request.plan(&full))?;
    // A slab count the user did not give is not blamed on `slabs=`.
    let analysed = run::long(py, progress, |monitor| planned.run_with(views, monitor))?;
    crate::errors::intact(&full)?;
    let report = analysed.report(&volume.name, &full).or_py()?;
    let json = slabscope::report::to_json(&report).or_py()?;
    Ok((analysed, json))
}

/// Whether two volumes hold the same voxels (NaN equal to NaN).
fn same_voxels(a: &Voxels, b: &Voxels) -> bool {
    match (a, b) {
        (Voxels::U8(x), Voxels::U8(y)) => x.as_slice() == y.as_slice(),
        (Voxels::I8(x), Voxels::I8(y)) => x.as_slice() == y.as_slice(),
        (Voxels::U16(x), Voxels::U16(y)) => x.as_slice() == y.as_slice(),
        (Voxels::I16(x), Voxels::I16(y)) => x.as_slice() == y.as_slice(),
        (Voxels::F32(x), Voxels::F32(y)) => {
            let (x, y) = (x.as_slice(), y.as_slice());
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits())
        }
        _ => false,
    }
}

/// JSON text as Python objects.
pub fn parse<'py>(py: Python<'py>, json: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (json,))
}

impl Analysis {
    fn key<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        self.report.bind(py).as_any().get_item(key)
    }

    fn partition_key<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        self.key(py, "partition")?.get_item(key)
    }

    /// The axis the slabs are cut across, as the report gives it (the partition's).
    pub fn axis(&self, py: Python<'_>) -> PyResult<[f64; 3]> {
        self.partition_key(py, "axis")?.extract()
    }

    /// An unpickled analysis: of `volume` with `params`, whose report is `json`.
    pub fn pending(
        py: Python<'_>,
        volume: Py<Volume>,
        params: Py<PyDict>,
        json: String,
    ) -> PyResult<Self> {
        let report = parse(py, &json)?.cast_into::<PyDict>()?.unbind();
        Ok(Self {
            volume,
            params,
            computed: OnceLock::new(),
            json,
            report,
        })
    }

    /// The memory budget the analysis ran within: its `max_memory=`, else its volume's.
    fn max_memory(&self, py: Python<'_>) -> PyResult<u64> {
        let kw = Kwargs::new(py, "analyze", Some(self.params.bind(py)))?;
        crate::params::max_memory(&kw, self.volume.get().max_memory)
    }

    /// The library's analysis and the level it partitioned: analysed again, once, for an
    /// unpickled analysis, which must then give the same report.
    pub fn computed(&self, py: Python<'_>) -> PyResult<&Analysed> {
        if let Some(done) = self.computed.get() {
            return Ok(done);
        }
        let params = self.params.bind(py);
        let (computed, json) = compute(py, self.volume.get(), None, Some(params), None)?;
        if json != self.json {
            return Err(PyValueError::new_err(format!(
                "analysis of {:?}: analysing its volume again gives another report (its file changed since it was pickled?): analyze it again",
                self.volume.get().name
            )));
        }
        let _ = self.computed.set(computed);
        self.computed
            .get()
            .ok_or_else(|| PyValueError::new_err("analysis: its partition could not be kept"))
    }

    /// That `volume` is the one analysed: the same object, or (read again, or pickled apart
    /// from it) a volume of the same shape, spacing, type, geometry and voxels.
    pub fn check_volume(&self, py: Python<'_>, volume: &Volume) -> PyResult<()> {
        if std::ptr::eq(self.volume.get(), volume) {
            return Ok(());
        }
        let (a, b) = (self.volume.get().inner(py)?, volume.inner(py)?);
        let same = Arc::ptr_eq(a, b)
            || (a.dims() == b.dims()
                && a.spacing() == b.spacing()
                && a.voxel_type() == b.voxel_type()
                && a.transform() == b.transform()
                && a.stats() == b.stats()
                && py.detach(|| same_voxels(a.data(), b.data())));
        if same {
            Ok(())
        } else {
            Err(PyValueError::new_err(
                "the analysis is of another volume: analyze this one first",
            ))
        }
    }
}

#[pymethods]
impl Analysis {
    /// The object `slabscope analyze --json` prints for the same volume and keywords (a new
    /// dictionary each call).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        parse(py, &self.json)
    }

    /// The report as JSON text, exactly as `analyze --json` prints it.
    fn to_json(&self) -> String {
        self.json.clone()
    }

    /// The views searched, best first by the ranking that picked the axis (dicts as in the
    /// JSON's `views`); empty when an axis was named without `views=True`.
    #[getter]
    fn views<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.key(py, "views")
    }

    /// The axis the slabs are cut across, a unit vector `(x, y, z)` in voxel space.
    #[getter]
    fn best_axis(&self, py: Python<'_>) -> PyResult<(f64, f64, f64)> {
        let [x, y, z] = self.axis(py)?;
        Ok((x, y, z))
    }

    /// Whether other axes rank within two standard errors of the best (see `contenders`).
    #[getter]
    fn uncertain<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.key(py, "uncertain")
    }

    /// The axes within two standard errors of the best, with their means and errors.
    #[getter]
    fn contenders<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.key(py, "contenders")
    }

    /// The slabs as `(first, end)` slice ranges along the axis, end exclusive.
    #[getter]
    fn slabs(&self, py: Python<'_>) -> PyResult<Vec<(usize, usize)>> {
        let slabs: Vec<[usize; 2]> = self.partition_key(py, "slabs")?.extract()?;
        Ok(slabs.into_iter().map(|[first, end]| (first, end)).collect())
    }

    /// The partition's steps, splits or merges in order (dicts as in the JSON).
    #[getter]
    fn steps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.partition_key(py, "steps")
    }

    /// The information the slabs keep about the values, bits.
    #[getter]
    fn information(&self, py: Python<'_>) -> PyResult<f64> {
        self.partition_key(py, "information")?.extract()
    }

    /// The whole partition object of the JSON (slabs, steps, curves, per-slab information).
    #[getter]
    fn partition<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.key(py, "partition")
    }

    /// What a user should know about the analysis (its pyramid level, an axis named...).
    #[getter]
    fn notes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.key(py, "notes")
    }

    /// Every voxel's slab, `[x, y, z]` at the volume's shape whatever level the analysis ran
    /// on: the slab's index + 1, and 0 for background and missing voxels (uint8, or uint16
    /// beyond 255 slabs), as `analyze --export-labels` writes it. An array held whole: beyond
    /// the memory budget (`max_memory=`) it is refused, and `write_labels(path)` streams them
    /// to a file instead.
    fn labels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let computed = self.computed(py)?;
        let (inner, level) = (&computed.analysis, computed.level());
        let full = Arc::clone(self.volume.get().inner(py)?);
        let name = std::path::Path::new(&self.volume.get().name);
        let slabs = inner.partition.slabs.len();
        let budget = slabscope::budget::Budget::new(self.max_memory(py)?);
        if let Err(e) = budget.labels_held(name, &full, &computed.plan, slabs) {
            return Err(crate::errors::VolumeError::new_err(format!(
                "{e} (raise it with max_memory=, or write them to a file a few planes at a time \
                 with write_labels(path))"
            )));
        }
        let labels = run::quick(py, || {
            slabscope::label_volume(&full, level, &inner.partition, &slabscope::Monitor::none())
        })?;
        crate::errors::intact(&full)?;
        let dims = labels.dims();
        let shaped = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
        Ok(match labels.data() {
            Voxels::U8(s) => PyArray3::from_owned_array(
                py,
                ArrayView3::from_shape(dims.f(), s.as_slice())
                    .map_err(shaped)?
                    .to_owned(),
            )
            .into_any(),
            Voxels::U16(s) => PyArray3::from_owned_array(
                py,
                ArrayView3::from_shape(dims.f(), s.as_slice())
                    .map_err(shaped)?
                    .to_owned(),
            )
            .into_any(),
            _ => {
                return Err(to_py(Error::Degenerate(
                    "labels held in an unexpected type".into(),
                )));
            }
        })
    }

    /// Writes every voxel's label (as `labels()`: the slab's index + 1, 0 for background) to
    /// `path` as `analyze --export-labels` does: NRRD (`.nrrd`) or `NIfTI` (`.nii`, `.nii.gz`) by
    /// the extension, at the volume's shape and world geometry, computed and written a few
    /// planes at a time, so that labels beyond the memory budget are never held whole. An
    /// existing file is replaced only with `force=True`, never the volume's own file nor one
    /// that is not a regular file.
    #[pyo3(signature = (path, force=false, progress=None))]
    fn write_labels(
        &self,
        py: Python<'_>,
        path: &Bound<'_, PyAny>,
        force: bool,
        progress: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let out = crate::params::path(path)?;
        slabscope::formats::VolumeOutput::for_path(&out)
            .map_err(|e| PyValueError::new_err(crate::errors::message(&e)))?;
        let volume = self.volume.get();
        if volume
            .source_file()
            .is_some_and(|input| slabscope::formats::same_file(&out, input))
        {
            return Err(PyValueError::new_err(format!(
                "{}: is the file the volume was read from; slabscope never writes over its input",
                slabscope::error::shown(&out)
            )));
        }
        slabscope::formats::check_output(&out, force).or_py()?;
        let computed = self.computed(py)?;
        let full = Arc::clone(volume.inner(py)?);
        let part = &computed.analysis.partition;
        let room = slabscope::budget::Budget::new(self.max_memory(py)?)
            .labels(
                std::path::Path::new(&volume.name),
                &full,
                &computed.plan,
                part.slabs.len(),
            )
            .or_py()?;
        let labelled = (full.as_ref(), computed.level().as_ref(), part);
        run::long(py, progress, |monitor| {
            slabscope::report::write_labels(&out, labelled, room, force, monitor)
        })?;
        crate::errors::intact(&full)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let (x, y, z) = self.best_axis(py)?;
        Ok(format!(
            "<slabscope.Analysis axis ({x:.3}, {y:.3}, {z:.3}), {} slabs, {:.4} bits>",
            self.slabs(py)?.len(),
            self.information(py)?
        ))
    }

    /// The volume analysed.
    #[getter]
    fn volume(&self, py: Python<'_>) -> Py<Volume> {
        self.volume.clone_ref(py)
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let args = (
            self.volume.clone_ref(py),
            self.params.bind(py).copy()?,
            self.json.clone(),
        );
        crate::pickle::reduced(py, "_analysis_of", args)
    }

    fn __copy__<'py>(slf: &Bound<'py, Self>) -> Bound<'py, Self> {
        slf.clone()
    }

    /// The analysis itself (it never changes) when a deep copy of its volume is the volume
    /// itself; else an analysis of that copy, analysed again when its partition is needed.
    fn __deepcopy__<'py>(
        slf: &Bound<'py, Self>,
        memo: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let this = slf.get();
        let volume = this.volume.bind(py);
        let copy = py
            .import("copy")?
            .call_method1("deepcopy", (volume, memo))?;
        if copy.is(volume) {
            return Ok(slf.clone().into_any());
        }
        let params = this.params.bind(py).copy()?.unbind();
        let again = Self::pending(
            py,
            copy.cast_into::<Volume>()?.unbind(),
            params,
            this.json.clone(),
        )?;
        Ok(Bound::new(py, again)?.into_any())
    }
}
