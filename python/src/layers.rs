//! A layer of an array's planes along z as a chunk of the grid, and the found background's
//! rounds over the layers (issue #44), for `slabscope.dask.analyze_array`: a layer's border
//! values, the threshold from all of them, a layer's summary of its components, the join of
//! the summaries into each layer's answer, a layer's mask; and a threshold's round (a layer's
//! voxels at or below it).

use numpy::PyUntypedArrayMethods;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use slabscope::volume::Voxel;
use slabscope::volume::background::parts::{
    BackgroundJoin, Chunk, ChunkAnswer, ChunkLabels, ChunkSummary, border_values_in,
};
use slabscope::volume::background::{BackgroundRule, threshold_of_border};
use slabscope::volume::{VoxelType, Voxels};

use crate::errors::OrPy;
use crate::split::analysis_of;

/// The voxels of `array` (indexed `[x, y, z]`, x fastest) in the held type `t`: read in place
/// where they are of that type in Fortran order, else copied once.
pub(crate) fn voxels_of<'py>(
    array: &Bound<'py, PyAny>,
    t: VoxelType,
) -> PyResult<(Voxels, Bound<'py, PyAny>)> {
    match crate::lent::lend_any(array, t) {
        Some(lent) => Ok((lent, array.clone())),
        None => crate::volume::copy_of(array, t),
    }
}

/// The shape of an array as `[x, y, z]`, an error unless it has three dimensions.
fn shape_of(array: &Bound<'_, PyAny>) -> PyResult<[usize; 3]> {
    let shape = array.cast::<numpy::PyUntypedArray>()?.shape().to_vec();
    match shape[..] {
        [x, y, z] => Ok([x, y, z]),
        _ => Err(PyValueError::new_err(format!(
            "an array of shape {shape:?}: voxels indexed [x, y, z]"
        ))),
    }
}

/// A layer's chunk of the grid: whole planes from `z0`, as many as `layer` holds.
fn layer_chunk(layer: &Bound<'_, PyAny>, z0: usize, dims: [usize; 3]) -> PyResult<Chunk> {
    let [x, y, z] = shape_of(layer)?;
    if [x, y] != [dims[0], dims[1]] {
        return Err(PyValueError::new_err(format!(
            "a layer of {x}×{y} voxels a plane: whole planes of {}×{}",
            dims[0], dims[1]
        )));
    }
    Chunk::new(dims, [0, 0, z0], [x, y, z]).or_py()
}

/// Runs `$body` with `$v` bound to the voxels of `$layer` in the held type `$dtype`, as a
/// slice of their own type.
macro_rules! with_layer {
    ($layer:expr, $dtype:expr, |$v:ident| $body:expr) => {{
        let (voxels, _kept) = crate::layers::voxels_of($layer, crate::parts::voxel_type($dtype))?;
        crate::volume::with_voxels!(&voxels, |$v| $body)
    }};
}
pub(crate) use with_layer;

/// A layer's finite values on the volume's faces, as little-endian f32 bytes: the first round
/// of the found background.
#[pyfunction]
pub fn _layer_border<'py>(
    py: Python<'py>,
    layer: &Bound<'py, PyAny>,
    z0: usize,
    dims: [usize; 3],
    dtype: &str,
) -> PyResult<Bound<'py, PyBytes>> {
    let chunk = layer_chunk(layer, z0, dims)?;
    let values = with_layer!(layer, dtype, |v| border_values_in(v, &chunk).or_py()?);
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    Ok(PyBytes::new(py, &bytes))
}

/// The found background's threshold from every layer's border values (`borders`, in any
/// order), the volume's finite range `(min, max)` and dims: what one process finds, or None.
#[pyfunction]
pub fn _background_threshold(
    borders: Vec<Vec<u8>>,
    dims: [usize; 3],
    range: (f32, f32),
) -> PyResult<Option<f32>> {
    let mut values = Vec::new();
    for b in &borders {
        if b.len() % 4 != 0 {
            return Err(PyValueError::new_err(format!(
                "border values of {} bytes: 4 a value",
                b.len()
            )));
        }
        values.extend(
            b.chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
        );
    }
    Ok(threshold_of_border(values, range, dims))
}

/// A layer's labels of its voxels at or below `threshold`, after checking what labelling holds
/// against `max_memory` (`max_memory=` as `analyze` takes it; None: no check).
fn labels_of(
    layer: &Bound<'_, PyAny>,
    z0: usize,
    dims: [usize; 3],
    dtype: &str,
    threshold: f32,
    max_memory: Option<&Bound<'_, PyAny>>,
) -> PyResult<ChunkLabels> {
    let py = layer.py();
    let chunk = layer_chunk(layer, z0, dims)?;
    let most = ChunkLabels::most_bytes(&chunk);
    let given = PyDict::new(py);
    given.set_item("max_memory", max_memory)?;
    crate::params::within_task_budget(py, Some(&given), most, |budget| {
        format!(
            "labelling the background of planes {z0}..{} takes up to {most} bytes, beyond the \
             task's budget of {budget} (chunks of fewer planes along z, or raise max_memory=)",
            z0 + chunk.size()[2]
        )
    })?;
    with_layer!(layer, dtype, |v| py
        .detach(|| ChunkLabels::find(v, &chunk, threshold))
        .or_py())
}

/// A layer's summary of its components at or below `threshold` (the found background's second
/// round), as bytes.
#[pyfunction]
#[pyo3(signature = (layer, z0, dims, dtype, threshold, max_memory=None))]
pub fn _layer_summary<'py>(
    layer: &Bound<'py, PyAny>,
    z0: usize,
    dims: [usize; 3],
    dtype: &str,
    threshold: f32,
    max_memory: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyBytes>> {
    let labels = labels_of(layer, z0, dims, dtype, threshold, max_memory)?;
    Ok(PyBytes::new(layer.py(), &labels.summary().to_bytes()))
}

/// Every layer's answer (which of its face labels are background) from all their summaries, in
/// any order: `(z0, answer)` in order of z0.
#[pyfunction]
pub fn _background_answers(
    py: Python<'_>,
    summaries: Vec<Vec<u8>>,
    dims: [usize; 3],
) -> PyResult<Vec<(usize, Py<PyBytes>)>> {
    let mut join = BackgroundJoin::new(dims);
    for bytes in &summaries {
        join.add(ChunkSummary::from_bytes(bytes).or_py()?).or_py()?;
    }
    let mut answers = join.finish().or_py()?;
    answers.sort_by_key(|a| a.chunk().origin()[2]);
    Ok(answers
        .iter()
        .map(|a| {
            (
                a.chunk().origin()[2],
                PyBytes::new(py, &a.to_bytes()).unbind(),
            )
        })
        .collect())
}

/// A layer's mask of background voxels (the found background's third round), as bytes, from
/// its `answer`, and how many voxels it holds.
#[pyfunction]
#[pyo3(signature = (layer, z0, dims, dtype, threshold, answer, max_memory=None))]
pub fn _layer_mask<'py>(
    layer: &Bound<'py, PyAny>,
    z0: usize,
    dims: [usize; 3],
    dtype: &str,
    threshold: f32,
    answer: &[u8],
    max_memory: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyBytes>, usize)> {
    let labels = labels_of(layer, z0, dims, dtype, threshold, max_memory)?;
    let answer = ChunkAnswer::from_bytes(answer).or_py()?;
    let mask = labels.mask(&answer).or_py()?;
    Ok((PyBytes::new(layer.py(), &mask.to_bytes()), mask.count()))
}

/// How many of a layer's voxels are at or below the threshold the analysis keywords `params`
/// give as their background (`background=` a value): that rule's round, for its fraction.
#[pyfunction]
#[pyo3(signature = (layer, dtype, **params))]
pub fn _layer_below(
    py: Python<'_>,
    layer: &Bound<'_, PyAny>,
    dtype: &str,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<usize> {
    let BackgroundRule::Below(t) = analysis_of(py, params)?.background else {
        return Err(PyValueError::new_err(
            "_layer_below: background= a value, the voxels at or below it",
        ));
    };
    with_layer!(layer, dtype, |v| Ok(
        py.detach(|| v.iter().filter(|x| x.to_f32() <= t).count())
    ))
}
