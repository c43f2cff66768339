//! The view search counted in parts (issue #44), for `slabscope.dask.analyze_array`:
//! `ViewPart` (the counts of one or more slabs of one round: it adds with `+` and pickles as
//! bytes), and the functions a task and the client call: the voxel planes a slab's task holds,
//! a slab's part counted from those planes alone, the paper lattices' sample counts, the
//! refinement's rounds asked of the client, and the analysis finished from the parts' sums.

use numpy::PyUntypedArrayMethods;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use slabscope::measure::PartialCounts;
use slabscope::view::{ViewRound, ViewRounds};
use slabscope::volume::{SlabGrid, Stats, VoxelType, Voxels};

use crate::errors::OrPy;
use crate::params::{Kwargs, analysis_params};
use crate::volume::Volume;

/// The counts of one round of the view search over some slabs: one entry a lattice.
#[pyclass(module = "slabscope")]
pub struct ViewPart {
    /// 0 for the paper's lattices, 1 for the shifted ones, 2 and 3 the same of a refinement
    /// step (`ViewRound::kind`).
    round: u8,
    counts: Vec<PartialCounts>,
}

impl ViewPart {
    /// An error unless `other` counts the same round of the same search.
    fn check(&self, other: &Self) -> PyResult<()> {
        if self.round != other.round
            || self.counts.len() != other.counts.len()
            || !(self.counts.iter().zip(&other.counts)).all(|(a, b)| a.counts.agrees(&b.counts))
        {
            return Err(PyValueError::new_err(
                "ViewPart + ViewPart: parts of two different rounds or searches",
            ));
        }
        Ok(())
    }
}

#[pymethods]
impl ViewPart {
    /// The round: 0 for the paper's lattices, 1 for the shifted ones, 2 and 3 the same of a
    /// refinement step.
    #[getter]
    fn round(&self) -> u8 {
        self.round
    }

    /// Whether every ray's pieces are joined: the whole volume's slabs are in it.
    #[getter]
    fn complete(&self) -> bool {
        self.counts.iter().all(PartialCounts::is_complete)
    }

    fn __add__(&self, other: &Self) -> PyResult<Self> {
        self.check(other)?;
        let mut counts = self.counts.clone();
        for (a, b) in counts.iter_mut().zip(&other.counts) {
            a.add_ref(b);
        }
        Ok(Self {
            round: self.round,
            counts,
        })
    }

    /// `total += part`: `part` added in place, the total not copied (a client adding the parts
    /// of a round as they come). `part += part` adds by `+` (the part is borrowed twice).
    fn __iadd__(&mut self, other: PyRef<'_, Self>) -> PyResult<()> {
        self.check(&other)?;
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            a.add_ref(b);
        }
        Ok(())
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let bytes: Vec<Bound<'py, PyBytes>> = self
            .counts
            .iter()
            .map(|c| PyBytes::new(py, &c.to_bytes()))
            .collect();
        crate::pickle::reduced(py, "_view_part_of", (self.round, bytes))
    }
}

/// Unpickles a `ViewPart`.
#[pyfunction]
pub fn _view_part_of(round: u8, counts: Vec<Vec<u8>>) -> PyResult<ViewPart> {
    if round > 3 {
        return Err(PyValueError::new_err(format!(
            "a ViewPart of round {round}: expected 0 (the paper's lattices), 1 (the shifted ones), 2 or 3 (the same of a refinement step)"
        )));
    }
    let counts = counts
        .iter()
        .map(|b| PartialCounts::from_bytes(b))
        .collect::<Result<Vec<_>, String>>()
        .map_err(PyValueError::new_err)?;
    Ok(ViewPart { round, counts })
}

/// The held type of its NumPy name (float32 for any other).
pub(crate) fn voxel_type(dtype: &str) -> VoxelType {
    match dtype {
        "uint8" => VoxelType::U8,
        "int8" => VoxelType::I8,
        "uint16" => VoxelType::U16,
        "int16" => VoxelType::I16,
        _ => VoxelType::F32,
    }
}

/// The grid every task is told: dims `[x, y, z]`, spacing, the held type's name and the range.
pub(crate) fn grid(
    dims: [usize; 3],
    spacing: [f64; 3],
    dtype: &str,
    range: (f32, f32, u64),
) -> SlabGrid {
    let voxel_type = voxel_type(dtype);
    let n = dims.iter().product::<usize>();
    SlabGrid {
        dims,
        spacing,
        transform: slabscope::geometry::WorldTransform::unknown(spacing),
        voxel_type,
        // The counts read the range and whether any voxel is finite: the mean is not counted.
        stats: Stats {
            min: range.0,
            max: range.1,
            mean: f64::from(range.0),
            finite: range.2 as usize,
            missing: n.saturating_sub(range.2 as usize),
        },
    }
}

/// The rounds of the analysis keywords `params` on a grid (any volume of it).
pub(crate) fn rounds(
    py: Python<'_>,
    volume: &slabscope::Volume,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<ViewRounds> {
    let kw = Kwargs::new(py, "analyze_array", params)?;
    let (analysis, _) = analysis_params(&kw)?;
    ViewRounds::new(volume, &analysis.view).or_py()
}

/// The round of the sphere's axes (`axes` None) or a refinement step's, of their paper
/// lattices (`samples` None) or their shifted ones.
fn round_of(axes: Option<Vec<[f64; 3]>>, samples: Option<Vec<u64>>) -> ViewRound {
    match (axes, samples) {
        (None, None) => ViewRound::Paper,
        (None, Some(samples)) => ViewRound::Shifted(samples),
        (Some(axes), None) => ViewRound::RefinePaper(axes),
        (Some(axes), Some(samples)) => ViewRound::RefineShifted(axes, samples),
    }
}

/// The cell planes `planes` of a slab of the grid counted in a round (`samples`: `None` for
/// the paper's lattices, the paper's sample counts for the shifted ones; `axes`: `None` for
/// the sphere's, those of a refinement step as `_refine_in_parts` asks) from `voxels`, its
/// voxel planes from `first` on (indexed `[x, y, z]`, x fastest), as `_slab_planes` gives them.
#[pyfunction]
#[pyo3(signature = (voxels, first, planes, dims, spacing, dtype, range, samples=None, axes=None, **params))]
#[allow(clippy::too_many_arguments)]
pub fn _count_view_slab(
    py: Python<'_>,
    voxels: &Bound<'_, PyAny>,
    first: usize,
    planes: (usize, usize),
    dims: [usize; 3],
    spacing: [f64; 3],
    dtype: &str,
    range: (f32, f32, u64),
    samples: Option<Vec<u64>>,
    axes: Option<Vec<[f64; 3]>>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<ViewPart> {
    let grid = grid(dims, spacing, dtype, range);
    let shape = voxels.cast::<numpy::PyUntypedArray>()?.shape().to_vec();
    if shape.len() != 3 || shape[0] != dims[0] || shape[1] != dims[1] {
        return Err(PyValueError::new_err(format!(
            "a slab of shape {shape:?}: whole planes of {}×{} voxels, indexed [x, y, z]",
            dims[0], dims[1]
        )));
    }
    // The planes the slab's samples read, every one of them: a plane missing would read as
    // zeros, the counts wrong with no error.
    let whole = empty(&grid)?;
    let rounds = rounds(py, &whole, params)?;
    let needed = rounds.voxel_planes(&(planes.0..planes.1), dims[2]);
    if first != needed.start || shape[2] != needed.len() {
        return Err(PyValueError::new_err(format!(
            "cell planes {}..{} read voxel planes {}..{}, not the {} from plane {first} given",
            planes.0, planes.1, needed.start, needed.end, shape[2]
        )));
    }
    // Read in place where the array is of the held type in Fortran order (a C-ordered
    // [z, y, x] block's transpose is); else copied once. Either way `of_slab` copies the
    // planes into their place in the grid.
    let lent = crate::lent::lend_any(voxels, grid.voxel_type);
    let round = round_of(axes, samples);
    let pool = task_threads(py, params)?;
    let threads = pool
        .as_ref()
        .map_or_else(rayon::current_num_threads, |p| p.current_num_threads());
    // Weighed before any voxel is copied.
    let bytes = task_bytes(
        (&rounds, &whole, &round),
        (&(planes.0..planes.1), needed.len(), grid.voxel_type),
        lent.is_some(),
        threads,
    )?;
    check_slab_room(py, params, planes, bytes)?;
    let (data, _copy) = match lent {
        Some(lent) => (lent, voxels.clone()),
        None => crate::volume::copy_of(voxels, grid.voxel_type)?,
    };
    let slab = crate::volume::with_voxels!(&data, |s| slabscope::Volume::of_slab(&grid, first, s))
        .or_py()?;
    let counts = py
        .detach(|| {
            crate::run::in_pool(pool.as_deref(), || {
                rounds.count_slab(&slab, &round, planes.0..planes.1)
            })
        })
        .or_py()?;
    Ok(ViewPart {
        round: round.kind(),
        counts,
    })
}

/// What a view task counting the cell planes `planes` of `round` holds, bytes: its
/// `voxel_planes` held as `voxel_type` as given, copied into the slab (and once more first
/// where they cannot be lent as they are), and the round's counts (`ViewRounds::slab_bytes`) on
/// `threads` threads; `whole` the grid's volume holding no voxel.
fn task_bytes(
    (rounds, whole, round): (&ViewRounds, &slabscope::Volume, &ViewRound),
    (planes, voxel_planes, voxel_type): (&std::ops::Range<usize>, usize, VoxelType),
    lent: bool,
    threads: usize,
) -> PyResult<u64> {
    let [nx, ny, _] = whole.dims();
    let given = (nx * ny * voxel_planes * voxel_type.size()) as u64;
    let copies = if lent { 2 } else { 3 };
    let counts = rounds
        .slab_bytes(whole, round, (planes, threads), voxel_type)
        .or_py()?;
    Ok((copies * given).saturating_add(counts))
}

/// An error unless what a view task counting the cell planes `planes` holds (`bytes`: its voxel
/// planes as given and copied, the cell map over them and its round's counts) fits its
/// `max_memory=` (if given).
fn check_slab_room(
    py: Python<'_>,
    params: Option<&Bound<'_, PyDict>>,
    planes: (usize, usize),
    bytes: u64,
) -> PyResult<()> {
    crate::params::within_task_budget(py, params, bytes, |budget| {
        format!(
            "the slab of cell planes {}..{} holds {bytes} bytes (its voxel planes as given and \
             copied, the cell map over them and its round's counts), beyond the task's budget of \
             {budget} (chunks of fewer planes along z, so more and thinner slabs, or raise \
             max_memory=)",
            planes.0, planes.1
        )
    })
}

/// The pool of the `threads=` the analysis keywords `params` give a task (kept for the
/// process's later tasks), `None` for all the machine's threads.
pub(crate) fn task_threads(
    py: Python<'_>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Option<std::sync::Arc<rayon::ThreadPool>>> {
    crate::params::shared_threads(&Kwargs::new(py, "analyze_array", params)?)
}

/// A volume of the grid holding no voxel: what the rounds are made from on the client.
pub(crate) fn empty(grid: &SlabGrid) -> PyResult<slabscope::Volume> {
    slabscope::Volume::of_slab::<u8>(grid, 0, &[]).or_py()
}

/// The voxel planes `(first, end)` the task counting each slab of cell planes of `planes`
/// holds (found once for every round), and whether a second round is foreseen
/// (`ViewRounds::foresees_shifted`).
#[pyfunction]
#[pyo3(signature = (planes, dims, spacing, dtype, range, **params))]
pub fn _slab_planes(
    py: Python<'_>,
    planes: Vec<(usize, usize)>,
    dims: [usize; 3],
    spacing: [f64; 3],
    dtype: &str,
    range: (f32, f32, u64),
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<(Vec<(usize, usize)>, bool)> {
    let grid = grid(dims, spacing, dtype, range);
    let whole = empty(&grid)?;
    let rounds = rounds(py, &whole, params)?;
    let held = planes
        .iter()
        .map(|&(a, b)| {
            let held = rounds.voxel_planes(&(a..b), dims[2]);
            (held.start, held.end)
        })
        .collect();
    let foreseen = rounds.foresees_shifted(&whole).or_py()?;
    Ok((held, foreseen))
}

/// The slabs of cell planes a round's tasks count: the chunk layers' slabs `layers` (in order
/// along z) joined into as few slabs as keep `tasks` tasks at work, each within the task budget
/// `max_memory=` (if given) as `_count_view_slab` weighs it on `counting_threads` (its voxel
/// planes as given and copied twice, the cell map over them, the round's counts): more and
/// thinner ones where fewer do not fit, the layers' own at most. Each seam between slabs costs
/// every ray crossing it a piece sent to the client and stitched there, and a set-up in each
/// slab: on the 512³ body in 8 layers on 2 workers, slabs of 2 and 4 layers took 0.76× the
/// CPU of a slab a layer (docs/performance.md).
#[pyfunction]
#[pyo3(signature = (layers, tasks, counting_threads, dims, spacing, dtype, range, samples=None, axes=None, **params))]
#[allow(clippy::too_many_arguments)]
pub fn _view_slabs(
    py: Python<'_>,
    layers: Vec<(usize, usize)>,
    tasks: usize,
    counting_threads: usize,
    dims: [usize; 3],
    spacing: [f64; 3],
    dtype: &str,
    range: (f32, f32, u64),
    samples: Option<Vec<u64>>,
    axes: Option<Vec<[f64; 3]>>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<(usize, usize)>> {
    let grid = grid(dims, spacing, dtype, range);
    let whole = empty(&grid)?;
    let rounds = rounds(py, &whole, params)?;
    let round = round_of(axes, samples);
    let budget = crate::params::max_memory(&Kwargs::new(py, "analyze_array", params)?, u64::MAX)?;
    let n = layers.len();
    for k in tasks.clamp(1, n.max(1))..n {
        let slabs = joined(&layers, k);
        // A slab's counts grow with its cell planes alone, its voxel planes with where it lies
        // too (the margins around it, cut at the volume's ends): the most of each weighs for all.
        let Some(&(a, b)) = slabs.iter().max_by_key(|(a, b)| b - a) else {
            break;
        };
        let held = (slabs.iter())
            .map(|&(a, b)| rounds.voxel_planes(&(a..b), dims[2]).len())
            .max()
            .unwrap_or(0);
        // Weighed as a task whose planes are copied before they are lent, the most it holds.
        let bytes = task_bytes(
            (&rounds, &whole, &round),
            (&(a..b), held, grid.voxel_type),
            false,
            counting_threads,
        )?;
        if bytes <= budget {
            return Ok(slabs);
        }
    }
    Ok(layers)
}

/// `layers` (consecutive slabs) joined into `k` slabs of as even a count of layers as can be.
fn joined(layers: &[(usize, usize)], k: usize) -> Vec<(usize, usize)> {
    let n = layers.len();
    (0..k)
        .map(|i| (layers[i * n / k].0, layers[(i + 1) * n / k - 1].1))
        .collect()
}

/// The samples each axis's paper lattice counted, from the first round's sum, if a second
/// round (the shifted lattices the first did not count right) is to be counted with them; else
/// `None` (`ViewRounds::shifted_after`).
#[pyfunction]
#[pyo3(signature = (paper, dims, spacing, dtype, range, **params))]
pub fn _shifted_samples(
    py: Python<'_>,
    paper: &ViewPart,
    dims: [usize; 3],
    spacing: [f64; 3],
    dtype: &str,
    range: (f32, f32, u64),
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Option<Vec<u64>>> {
    let grid = grid(dims, spacing, dtype, range);
    let volume = empty(&grid)?;
    let rounds = rounds(py, &volume, params)?;
    match rounds
        .shifted_after(&volume, &ViewRound::Paper, &paper.counts)
        .or_py()?
    {
        Some(ViewRound::Shifted(samples)) => Ok(Some(samples)),
        _ => Ok(None),
    }
}

/// A refinement step's round as `_refine_in_parts` asks for it and `_analyze_with_parts`
/// is given it: its axes and (for its shifted lattices) its paper lattices' samples.
type Asked = (Vec<[f64; 3]>, Option<Vec<u64>>);

/// A refinement round as `_analyze_with_parts` is given it: its axes, samples and sum.
pub(crate) type Refined<'py> = (Vec<[f64; 3]>, Option<Vec<u64>>, PyRef<'py, ViewPart>);

fn asked(round: &ViewRound) -> Asked {
    match round {
        ViewRound::RefinePaper(axes) => (axes.clone(), None),
        ViewRound::RefineShifted(axes, samples) => (axes.clone(), Some(samples.clone())),
        _ => (Vec::new(), None),
    }
}

/// The refinement's rounds on the client, after the sphere's (`paper` and `shifted` their
/// sums): `count(axes, samples)` is called for each round in turn (a step's paper lattices,
/// `samples` None, then with phases its shifted ones) and returns the sum of its parts, which
/// the next round's axes depend on. Nothing without `refine=True`.
#[pyfunction]
#[pyo3(signature = (paper, dims, spacing, dtype, range, count, shifted=None, **params))]
#[allow(clippy::too_many_arguments)]
pub fn _refine_in_parts(
    py: Python<'_>,
    paper: &ViewPart,
    dims: [usize; 3],
    spacing: [f64; 3],
    dtype: &str,
    range: (f32, f32, u64),
    count: &Bound<'_, PyAny>,
    shifted: Option<&ViewPart>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<()> {
    let grid = grid(dims, spacing, dtype, range);
    let volume = empty(&grid)?;
    let rounds = rounds(py, &volume, params)?;
    let shifted = shifted.map_or(&[][..], |s| &s.counts[..]);
    let sphere = rounds.finish(&volume, &paper.counts, shifted).or_py()?;
    let mut failed = None;
    let done = rounds.refine(&volume, sphere, |round| {
        let part = count
            .call1(asked(round))
            .and_then(|p| Ok(p.cast_into::<ViewPart>()?));
        match part {
            Ok(part) if part.borrow().round == round.kind() => Ok(part.borrow().counts.clone()),
            Ok(part) => {
                let e = format!(
                    "count gave a part of round {}, not {}",
                    part.borrow().round,
                    round.kind()
                );
                failed = Some(PyValueError::new_err(e));
                Err(slabscope::Error::Cancelled)
            }
            Err(e) => {
                failed = Some(e);
                Err(slabscope::Error::Cancelled)
            }
        }
    });
    match (done, failed) {
        (_, Some(e)) => Err(e),
        (done, None) => done.map(drop).or_py(),
    }
}

/// The analysis of `volume` (the whole one) by the analysis keywords `params`, its view search
/// finished from the rounds' sums `paper` and `shifted`, and with `refine=True` refined from
/// `refined`, the refinement's rounds as `_refine_in_parts` asked for them, in order, each
/// `(axes, samples, sum)`: `analyze`'s, to the byte.
#[pyfunction]
#[pyo3(signature = (volume, paper, shifted=None, refined=None, **params))]
pub fn _analyze_with_parts(
    py: Python<'_>,
    volume: &Bound<'_, Volume>,
    paper: &ViewPart,
    shifted: Option<&ViewPart>,
    refined: Option<Vec<Refined<'_>>>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<crate::analysis::Analysis> {
    let inner = volume.get().inner(py)?;
    let rounds = rounds(py, inner, params)?;
    let views = views_of(py, &rounds, inner, paper, shifted, refined)?;
    crate::analysis::analyze_with(py, volume, Some(views), params)
}

/// The view search of `volume` by `rounds` finished from the rounds' sums `paper` and
/// `shifted`, and with the refinement from `refined` (its rounds as `_refine_in_parts` asked for
/// them, in order, each `(axes, samples, sum)`).
pub(crate) fn views_of(
    py: Python<'_>,
    rounds: &ViewRounds,
    inner: &slabscope::Volume,
    paper: &ViewPart,
    shifted: Option<&ViewPart>,
    refined: Option<Vec<Refined<'_>>>,
) -> PyResult<slabscope::ViewSearch> {
    let shifted = shifted.map_or(&[][..], |s| &s.counts[..]);
    let given: Vec<(Asked, u8, Vec<PartialCounts>)> = refined
        .unwrap_or_default()
        .into_iter()
        .map(|(axes, samples, part)| ((axes, samples), part.round, part.counts.clone()))
        .collect();
    let refine = rounds.params().refine;
    if !refine && !given.is_empty() {
        return Err(PyValueError::new_err(
            "refined= holds the refinement's rounds: refine=True asks for them",
        ));
    }
    py.detach(|| {
            let sphere = rounds.finish(inner, &paper.counts, shifted)?;
            let mut given = given.into_iter();
            let views = rounds.refine(inner, sphere, |round| match given.next() {
                Some((a, kind, counts)) if a == asked(round) && kind == round.kind() => Ok(counts),
                _ => Err(slabscope::Error::invalid(
                    "refined",
                    "rounds",
                    "the refinement's rounds in the order they were asked for, each (axes, samples, sum)",
                )),
            })?;
            match given.next() {
                None => Ok(views),
                Some(_) => Err(slabscope::Error::invalid(
                    "refined",
                    "more rounds",
                    "the refinement's rounds alone: it asked for fewer",
                )),
            }
    })
    .or_py()
}
