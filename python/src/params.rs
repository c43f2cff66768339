//! Keyword arguments in the CLI's words and with its defaults: `bins=32` for `--bins 32`,
//! `no_shading=True` for `--no-shading`, `dtype` for `--type`. Each call takes its keywords from
//! one dictionary, so a misspelt keyword is an error naming it, not a silent default.

use std::path::PathBuf;

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slabscope::params::{Given, Param, Scene, Takes, table, text};
use slabscope::render::TransferChoice;
use slabscope::volume::{Resolution, VoxelType};
use slabscope::{AnalysisParams, LoadOptions};

use crate::errors::{OrPy, repr};

/// The keyword arguments of one call, taken one by one.
pub struct Kwargs<'py> {
    dict: Bound<'py, PyDict>,
    call: &'static str,
}

impl<'py> Kwargs<'py> {
    /// The keywords `given` to `call` (a copy: the caller's dictionary is left alone).
    pub fn new(
        py: Python<'py>,
        call: &'static str,
        given: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Self> {
        let dict = match given {
            Some(d) => d.copy()?,
            None => PyDict::new(py),
        };
        Ok(Self { dict, call })
    }

    /// Takes keyword `name`: `None` when it is missing or `None`.
    pub fn get<T: for<'a> FromPyObject<'a, 'py>>(&self, name: &str) -> PyResult<Option<T>> {
        let Some(value) = self.dict.get_item(name)? else {
            return Ok(None);
        };
        self.dict.del_item(name)?;
        if value.is_none() {
            return Ok(None);
        }
        value.extract::<T>().map(Some).map_err(|e| {
            let e: PyErr = e.into();
            PyTypeError::new_err(format!(
                "{}(): {name}={}: {}",
                self.call,
                repr(&value),
                e.value(value.py())
            ))
        })
    }

    /// Fails on any keyword not taken, as Python does for a function's unknown keyword.
    pub fn finish(self) -> PyResult<()> {
        match self.dict.keys().iter().next() {
            None => Ok(()),
            Some(key) => Err(PyTypeError::new_err(format!(
                "{}() got an unexpected keyword argument {}",
                self.call,
                key.repr()?
            ))),
        }
    }
}

/// The values of `params`' keywords given to this call, as the library's text: each kind taken
/// as Python gives it (`True`, `32`, `0.5`, `"topdown"`, `(1, 0, 0)`, a NumPy dtype), so that a
/// value of the wrong type is a `TypeError` naming its keyword, and a value out of range the
/// library's `ValueError`, worded in keywords.
pub fn given(kw: &Kwargs<'_>, params: &[&'static Param]) -> PyResult<Given> {
    let mut given = Given::new();
    for &p in params {
        let text = match p.takes {
            Takes::Switch => kw.get::<bool>(p.keyword)?.map(|b| b.to_string()),
            Takes::Count { .. } => kw.get::<i64>(p.keyword)?.map(|n| n.to_string()),
            Takes::Number { .. } | Takes::Positive => {
                kw.get::<f64>(p.keyword)?.map(|v| v.to_string())
            }
            Takes::Words { .. } => kw.get::<String>(p.keyword)?,
            Takes::Text { .. } => match kw.get::<Bound<'_, PyAny>>(p.keyword)? {
                None => None,
                Some(v) => Some(checked_text(p, &v)?),
            },
        };
        if let Some(text) = text {
            given.set(p, text);
        }
    }
    Ok(given)
}

/// `value` as the library's text for `p`; a value the entry refuses that Python gave as
/// something else than text (a tuple, a number) is a `ValueError` showing it as Python does
/// (`spacing=(1, 1)`, not the library's `spacing=1,1`).
fn checked_text(p: &Param, value: &Bound<'_, PyAny>) -> PyResult<String> {
    let text = as_text(p, value)?;
    if !value.is_instance_of::<pyo3::types::PyString>() && p.check(&text).is_err() {
        return Err(crate::errors::to_py(p.invalid(repr(value))));
    }
    Ok(text)
}

/// A value of a parameter written in a syntax of its own, as the library's text: text as it is,
/// a number as its digits, a sequence of numbers joined by commas (`(1, 0, 0)` is `"1,0,0"`),
/// anything else NumPy takes as a dtype by its name.
pub fn as_text(p: &Param, value: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(t) = value.extract::<String>() {
        return Ok(t);
    }
    if !value.is_instance_of::<pyo3::types::PyBool>() {
        if let Ok(n) = value.extract::<i64>() {
            return axis_number(p, n, value);
        }
        if let Ok(v) = value.extract::<f64>() {
            return Ok(v.to_string());
        }
        if let Ok(values) = value.extract::<Vec<f64>>() {
            let texts: Vec<String> = values.iter().map(f64::to_string).collect();
            return Ok(texts.join(","));
        }
        if let Ok(numpy) = value.py().import("numpy")
            && let Ok(name) = numpy
                .getattr("dtype")
                .and_then(|d| d.call1((value,)))
                .and_then(|d| d.getattr("name"))
                .and_then(|n| n.extract::<String>())
        {
            return Ok(name);
        }
    }
    Err(PyTypeError::new_err(crate::errors::message(
        &p.invalid(repr(value)),
    )))
}

/// A whole number given for `p`: its digits, except for `axis`, where NumPy's axis numbers 0, 1
/// and 2 stand for x, y and z.
fn axis_number(p: &Param, n: i64, value: &Bound<'_, PyAny>) -> PyResult<String> {
    if p.name != table::AXIS.name {
        return Ok(n.to_string());
    }
    match n {
        0 => Ok("x".into()),
        1 => Ok("y".into()),
        2 => Ok("z".into()),
        _ => Err(crate::errors::invalid(
            p.name,
            repr(value),
            &format!("0, 1 or 2 (x, y, z), {}", p.expected()),
        )),
    }
}

/// The load options: `dims`, `dtype`, `spacing`, `endian`, `offset` for raw files,
/// `max_memory`, `scratch`, `threads`, `volume`, `channel`, `array`, `series`,
/// `include_localizers`, `resample`, `show_phi`, `label_image`, `endpoint`, `missing_as_fill`,
/// `cache`; and the pool of `threads` threads.
pub fn load_options(kw: &Kwargs<'_>) -> PyResult<(LoadOptions, Option<rayon::ThreadPool>)> {
    let given = given(kw, table::LOAD)?;
    Ok((given.load().or_py()?, given.thread_pool().or_py()?))
}

/// `threads`: a pool of that many threads for the call's work (`None`: all of them).
pub fn threads(kw: &Kwargs<'_>) -> PyResult<Option<rayon::ThreadPool>> {
    given(kw, &[&table::THREADS])?.thread_pool().or_py()
}

/// `threads`: how many threads (`None`: all of them), read and checked, no pool made.
pub fn thread_count(kw: &Kwargs<'_>) -> PyResult<Option<usize>> {
    given(kw, &[&table::THREADS])?.threads().or_py()
}

/// `threads`: a pool of that many threads kept for the process's later calls (a task of
/// `slabscope.dask.analyze_array` a call, hundreds of them: one pool each would start and stop
/// its threads every time), `None` for all of them.
pub fn shared_threads(kw: &Kwargs<'_>) -> PyResult<Option<std::sync::Arc<rayon::ThreadPool>>> {
    use std::sync::{Arc, Mutex, PoisonError};
    static POOLS: Mutex<Vec<(usize, Arc<rayon::ThreadPool>)>> = Mutex::new(Vec::new());
    let Some(n) = thread_count(kw)? else {
        return Ok(None);
    };
    let mut pools = POOLS.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some((_, pool)) = pools.iter().find(|(m, _)| *m == n) {
        return Ok(Some(Arc::clone(pool)));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| {
            pyo3::exceptions::PyRuntimeError::new_err(format!("a pool of {n} threads: {e}"))
        })?;
    let pool = Arc::new(pool);
    pools.push((n, Arc::clone(&pool)));
    Ok(Some(pool))
}

/// `max_memory`: bytes as a number or as text (`"8G"`), or `default`.
pub fn max_memory(kw: &Kwargs<'_>, default: u64) -> PyResult<u64> {
    let given = given(kw, &[&table::MAX_MEMORY])?;
    Ok(given
        .parsed(&table::MAX_MEMORY, text::bytes)
        .or_py()?
        .unwrap_or(default))
}

/// An error worded by `refusal` (given the budget) unless `bytes` fit the budget `max_memory=`
/// among `params` gives a task of `analyze_array` (none given: no bound): what each task
/// weighs before it spends it.
pub(crate) fn within_task_budget(
    py: Python<'_>,
    params: Option<&Bound<'_, PyDict>>,
    bytes: u64,
    refusal: impl FnOnce(u64) -> String,
) -> PyResult<()> {
    let budget = max_memory(&Kwargs::new(py, "analyze_array", params)?, u64::MAX)?;
    if bytes > budget {
        return Err(PyValueError::new_err(refusal(budget)));
    }
    Ok(())
}

/// The NumPy dtype name of a voxel type.
pub fn numpy_name(t: VoxelType) -> &'static str {
    match t {
        VoxelType::U8 => "uint8",
        VoxelType::I8 => "int8",
        VoxelType::U16 => "uint16",
        VoxelType::I16 => "int16",
        VoxelType::U32 => "uint32",
        VoxelType::I32 => "int32",
        VoxelType::F32 => "float32",
        VoxelType::F64 => "float64",
    }
}

/// The analysis keywords of `analyze`, with the CLI's defaults: `bins`, `block`, `level`,
/// `ray_spacing`, `sample_spacing`, `phases`, `phase_subset`, `refine`, `axis`, `axis_by`,
/// `gain`, `method`, `slabs`, `threshold`, `background`; `views` runs the view search for a
/// named axis too. The values given come back too, to blame an error on a default.
pub fn analysis_params(kw: &Kwargs<'_>) -> PyResult<(AnalysisParams, Given)> {
    let given = given(kw, &[table::ANALYSIS, &[&table::VIEWS]].concat())?;
    Ok((given.analysis().or_py()?, given))
}

/// `resolution`: `"full"` (the default, the paper's method), `"auto"` or a pyramid level; and
/// whether it was given.
pub fn resolution(kw: &Kwargs<'_>) -> PyResult<(Resolution, bool)> {
    given(kw, &[&table::RESOLUTION])?.resolution_named().or_py()
}

/// The look keywords: `tf` (auto, ct-bone, ct-soft, mri), `colormap`, `window`.
pub fn look(kw: &Kwargs<'_>) -> PyResult<TransferChoice> {
    given(kw, table::LOOK)?.look().or_py()
}

/// A picture size `(width, height)`, as `--size WxH` takes it: `size` is the entry with the
/// call's default.
pub fn size(kw: &Kwargs<'_>, size: &'static Param) -> PyResult<(u32, u32)> {
    given(kw, &[size])?.size(size).or_py()
}

/// The render keywords, as `render`'s flags: `mode`, the look, `azimuth`, `elevation`, `zoom`,
/// `perspective`, `highlight`, `solo`, `step`, `no_shading`, `no_outlines`, `no_labels`; and the
/// layout's `gap` and `spread`.
pub fn render_params(kw: &Kwargs<'_>, (width, height): (u32, u32)) -> PyResult<Scene> {
    let params = [table::SCENE_FIRST, table::LOOK, table::SCENE].concat();
    given(kw, &params)?.scene(width, height).or_py()
}

/// A path given as `str` or `os.PathLike`.
pub fn path(given: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    given.extract::<PathBuf>().map_err(|_| {
        PyTypeError::new_err(format!(
            "expected a path (str or os.PathLike), got {}",
            given
                .get_type()
                .name()
                .map_or_else(|_| "?".into(), |n| n.to_string())
        ))
    })
}

/// The table's entries a call takes, in the order its signature lists them.
fn call_params(call: &str) -> Option<Vec<&'static Param>> {
    let analysis_and = |first: &[&'static Param]| [first, table::ANALYSIS].concat();
    Some(match call {
        "load" => table::LOAD.to_vec(),
        "list_volumes" => [table::LOAD, &[&table::SHARD]].concat(),
        "analyze" => [
            table::ANALYSIS,
            &[
                &table::VIEWS,
                &table::RESOLUTION,
                &table::MAX_MEMORY,
                &table::THREADS,
            ],
        ]
        .concat(),
        "render" => [
            &[&table::RENDER_SIZE, &table::THREADS],
            table::SCENE_FIRST,
            table::LOOK,
            table::SCENE,
            &[&table::FACES],
        ]
        .concat(),
        "slice" => analysis_and(
            &[
                &[&table::SLICE_SIZE, &table::THREADS, &table::NO_LETTERS][..],
                table::LOOK,
            ]
            .concat(),
        ),
        "triage" => [
            table::ANALYSIS,
            table::LOAD,
            &[&table::SHARD, &table::FULL, &table::TRIAGE_TIMEOUT],
        ]
        .concat(),
        _ => return None,
    })
}

/// The default of `p` as Python writes it: `False`, `32`, `0.5`, `"topdown"`, `(640, 480)`, or
/// `None` when the library works it out.
fn python_default<'py>(py: Python<'py>, p: &Param) -> PyResult<Bound<'py, PyAny>> {
    let default = match p.takes {
        Takes::Switch => false.into_pyobject(py)?.to_owned().into_any(),
        Takes::Count {
            default: Some(d), ..
        } => d.into_pyobject(py)?.into_any(),
        Takes::Number {
            default: Some(d), ..
        } => d.into_pyobject(py)?.into_any(),
        Takes::Words { default, .. } => default.into_pyobject(py)?.into_any(),
        Takes::Text {
            default: Some(d), ..
        } => match text::size(d) {
            Some(size) if p.value_name == Some("WxH") => size.into_pyobject(py)?.into_any(),
            _ => d.into_pyobject(py)?.into_any(),
        },
        _ => py.None().into_bound(py),
    };
    Ok(default)
}

/// The keywords `call` takes from the library's table, each a dictionary: `keyword`, `flag`,
/// `default` (as Python writes it), `kind` (`switch`, `count`, `number`, `positive`, `words`,
/// `text`), `min` and `max` for numbers, `words`, `expected` and `help`. The package makes its
/// functions' signatures from them, and a test holds them against the CLI's help.
#[pyfunction]
pub fn parameters<'py>(py: Python<'py>, call: &str) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let params = call_params(call).ok_or_else(|| {
        pyo3::exceptions::PyValueError::new_err(format!(
            "call={call:?}: expected load, list_volumes, analyze, render, slice or triage"
        ))
    })?;
    params
        .into_iter()
        .map(|p| {
            let d = PyDict::new(py);
            d.set_item("keyword", p.keyword)?;
            d.set_item("flag", format!("--{}", p.flag))?;
            d.set_item("default", python_default(py, p)?)?;
            d.set_item("expected", p.expected())?;
            d.set_item("help", p.help)?;
            d.set_item("conflicts", p.conflicts.to_vec())?;
            let kind = match p.takes {
                Takes::Switch => "switch",
                Takes::Count { min, max, .. } => {
                    d.set_item("min", min)?;
                    d.set_item("max", (max != u64::MAX).then_some(max))?;
                    "count"
                }
                Takes::Number { min, max, .. } => {
                    d.set_item("min", min)?;
                    d.set_item("max", max)?;
                    "number"
                }
                Takes::Positive => "positive",
                Takes::Words { words, .. } => {
                    let all: Vec<&str> = words().iter().map(|w| w.word).collect();
                    d.set_item("words", all)?;
                    "words"
                }
                Takes::Text { .. } => "text",
            };
            d.set_item("kind", kind)?;
            Ok(d)
        })
        .collect()
}
