//! `slabscope.analyze` and `slabscope.Analysis`: the view search and the partition, as
//! `slabscope analyze` runs them, with the report `analyze --json` prints.

use std::sync::Arc;

use numpy::PyArray3;
use numpy::ndarray::{ArrayView3, ShapeBuilder};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slabscope::explain::StepsShown;
use slabscope::{AnalysisReport, Error, Plan};

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
/// and steps; `to_dict()` is the object `slabscope analyze --json` prints.
#[pyclass(module = "slabscope", frozen)]
pub struct Analysis {
    /// The library's analysis.
    pub inner: slabscope::Analysis,
    /// The volume analysed, as read.
    pub source: Arc<slabscope::Volume>,
    /// The pyramid level partitioned (the volume itself at full resolution).
    pub level: Arc<slabscope::Volume>,
    /// The report as JSON text.
    json: String,
    /// The report, parsed once for the properties.
    report: Py<PyDict>,
}

/// Finds the most structured view of `volume` and the slabs along it, with the CLI's analysis
/// keywords and defaults (`bins=32, block=3, level=1, phases=8, method="topdown", slabs=4,
/// background="auto"`, ...), `resolution="full"` (the paper's method), `views`, `max_memory`.
/// `progress(phase, fraction)` is called as it goes; Ctrl-C stops it.
#[pyfunction]
#[pyo3(signature = (volume, progress=None, **params))]
pub fn analyze(
    py: Python<'_>,
    volume: &Volume,
    progress: Option<&Bound<'_, PyAny>>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Analysis> {
    let kw = Kwargs::new(py, "analyze", params)?;
    // As the CLI words it: a slab count the user did not give (None is not given) is not blamed
    // on `slabs=`.
    let given = |key: &str| {
        params
            .and_then(|p| p.get_item(key).ok().flatten())
            .is_some_and(|v| !v.is_none())
    };
    let slabs_given = given("slabs") || given("threshold");
    let mut analysis_params = analysis_params(&kw)?;
    analysis_params.explain = explain(kw.get::<Bound<'_, PyAny>>("explain")?.as_ref())?;
    let resolution = resolution(&kw)?;
    let max_memory = crate::params::max_memory(&kw, volume.max_memory)?;
    kw.finish()?;
    let full = Arc::clone(&volume.inner);
    let wanted = resolution
        .level(full.dims(), full.coarser_levels())
        .or_py()?;
    let plan = run::quick(py, || {
        Plan::within(&full, wanted, max_memory, &analysis_params)
    })?;
    let result = run::long(py, progress, |monitor| {
        slabscope::analyze_planned(&plan, &analysis_params, monitor)
    });
    let analysis = result.map_err(|e| slabs_default(e, slabs_given))?;
    let report = AnalysisReport::new(&volume.name, &full, &analysis_params.view, &analysis)
        .or_py()?
        .computed_on(&plan.partition)
        .views_on(&plan.views);
    let json = slabscope::report::to_json(&report).or_py()?;
    let report = parse(py, &json)?.cast_into::<PyDict>()?.unbind();
    Ok(Analysis {
        inner: analysis,
        source: full,
        level: Arc::clone(&plan.partition),
        json,
        report,
    })
}

/// A slab count the user did not give is not blamed on `slabs=`, as the CLI words it.
fn slabs_default(e: PyErr, given: bool) -> PyErr {
    Python::attach(|py| {
        if given || !e.is_instance_of::<PyValueError>(py) {
            return e;
        }
        let text = e.value(py).to_string();
        match text.strip_prefix("slabs=4: expected ") {
            Some(expected) => PyValueError::new_err(format!(
                "the default of 4 slabs does not fit: {expected} (slabs=K asks for fewer)"
            )),
            None => e,
        }
    })
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

    /// That `volume` is the one analysed.
    pub fn check_volume(&self, volume: &Volume) -> PyResult<()> {
        if Arc::ptr_eq(&self.source, &volume.inner) {
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
    fn best_axis(&self) -> (f64, f64, f64) {
        let [x, y, z] = self.inner.axis();
        (x, y, z)
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
    fn slabs(&self) -> Vec<(usize, usize)> {
        self.inner.partition.slabs.clone()
    }

    /// The partition's steps, splits or merges in order (dicts as in the JSON).
    #[getter]
    fn steps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.partition_key(py, "steps")
    }

    /// The information the slabs keep about the values, bits.
    #[getter]
    fn information(&self) -> f64 {
        self.inner.partition.information
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

    /// The slab index of every voxel of the level partitioned, `[x, y, z]` (uint8, or uint16
    /// beyond 256 slabs), as `analyze --export-labels` writes it.
    fn labels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let labels = run::quick(py, || {
            slabscope::label_volume(&self.level, &self.inner.partition)
        })?;
        let dims = labels.dims();
        let shaped = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
        Ok(match labels.data() {
            slabscope::volume::Voxels::U8(s) => PyArray3::from_owned_array(
                py,
                ArrayView3::from_shape(dims.f(), s.as_slice())
                    .map_err(shaped)?
                    .to_owned(),
            )
            .into_any(),
            slabscope::volume::Voxels::U16(s) => PyArray3::from_owned_array(
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

    fn __repr__(&self) -> String {
        let [x, y, z] = self.inner.axis();
        format!(
            "<slabscope.Analysis axis ({x:.3}, {y:.3}, {z:.3}), {} slabs, {:.4} bits>",
            self.inner.partition.slabs.len(),
            self.inner.partition.information
        )
    }
}
