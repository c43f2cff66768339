//! The partition counted in parts (issue #44), for `slabscope.dask.analyze_array`, so that no
//! task holds the whole volume (the background's rounds before it are in `layers.rs`): the
//! partition's two rounds over strips of the slice stack's rows (`PartitionPart`, which adds with `+` and pickles as bytes),
//! each task holding the box of voxels its rows read; `PartitionSplit`, on the client, finishes
//! the view search from its parts, names the axis and the strips, and assembles the `Analysis`.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use slabscope::analysis::{AnalysisParams, Plan, analyze_with_partition, partition_axis};
use slabscope::partition::{SlabJoints, SlabsFound, SliceCounts, StackSplit};
use slabscope::request::Analysed;
use slabscope::view::ViewSearch;
use slabscope::volume::background::Background;
use slabscope::volume::background::parts::ChunkMask;
use slabscope::volume::pyramid::Finest;
use slabscope::volume::{SlabGrid, VoxelBox, Voxels};

use crate::errors::OrPy;
use crate::layers::with_layer;
use crate::params::Kwargs;
use crate::parts::{Refined, ViewPart, empty, grid, views_of};
use crate::volume::Volume;

/// The counts of one pass of the partition over some strips of the stack's rows.
#[pyclass(module = "slabscope")]
pub struct PartitionPart {
    counts: PassCounts,
}

/// A pass's counts: the first's (the slices) or the second's (the slabs' boundaries).
#[derive(Clone)]
enum PassCounts {
    Slices(SliceCounts),
    Joints(SlabJoints),
}

#[pymethods]
impl PartitionPart {
    /// The pass: 0 for the slices' counts, 1 for the slabs' boundaries'.
    #[getter]
    fn round(&self) -> u8 {
        match self.counts {
            PassCounts::Slices(_) => 0,
            PassCounts::Joints(_) => 1,
        }
    }

    fn __add__(&self, other: &Self) -> PyResult<Self> {
        let mut sum = Self {
            counts: self.counts.clone(),
        };
        sum.add(other)?;
        Ok(sum)
    }

    /// `total += part`: `part` added in place.
    fn __iadd__(&mut self, other: PyRef<'_, Self>) -> PyResult<()> {
        self.add(&other)
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let bytes = match &self.counts {
            PassCounts::Slices(c) => c.to_bytes(),
            PassCounts::Joints(j) => j.to_bytes(),
        };
        crate::pickle::reduced(py, "_partition_part_of", (PyBytes::new(py, &bytes),))
    }
}

impl PartitionPart {
    fn add(&mut self, other: &Self) -> PyResult<()> {
        match (&mut self.counts, &other.counts) {
            (PassCounts::Slices(a), PassCounts::Slices(b)) => a.add(b.clone()).or_py(),
            (PassCounts::Joints(a), PassCounts::Joints(b)) => a.add(b).or_py(),
            _ => Err(PyValueError::new_err(
                "PartitionPart + PartitionPart: parts of the two passes",
            )),
        }
    }
}

/// Unpickles a `PartitionPart`: the bytes of either pass, told apart by their name.
#[pyfunction]
pub fn _partition_part_of(bytes: &[u8]) -> PyResult<PartitionPart> {
    let counts = if bytes.starts_with(b"SLABSJ") {
        PassCounts::Joints(SlabJoints::from_bytes(bytes).map_err(PyValueError::new_err)?)
    } else {
        PassCounts::Slices(SliceCounts::from_bytes(bytes).map_err(PyValueError::new_err)?)
    };
    Ok(PartitionPart { counts })
}

/// What every strip's task is told of the background: the rule's threshold (None: no
/// background) and the masks of the layers around its box (a found background's).
type Told = (Option<f32>, Vec<Vec<u8>>);

/// A box a strip's task holds: the planes along z of the layer it was cut from, its origin
/// and its size (`[x, y, z]`).
type Held = ((usize, usize), [usize; 3], [usize; 3]);

/// A strip's counts, one pass of the partition along `axis`: the first (`slabs` None) or the
/// second, given the slabs the first found (positional, as every argument before the analysis
/// keywords `params`, whose names they may share: `axis`, `slabs`). `voxels` holds the voxels
/// of the strip's `boxes` one after another, each x fastest, read in C order (a box's
/// `[z, y, x]` array as it is, or all of them raveled and joined), a box a layer of the array as
/// `PartitionSplit.strips` names them. Boxes that miss a voxel the rows read are
/// refused: it would read as zero.
#[pyfunction]
#[pyo3(signature = (voxels, boxes, rows, axis, dims, spacing, dtype, range, background, slabs=None, /, **params))]
#[allow(clippy::too_many_arguments)]
pub fn _count_strip(
    py: Python<'_>,
    voxels: &Bound<'_, PyAny>,
    boxes: Vec<Held>,
    rows: (usize, usize),
    axis: [f64; 3],
    dims: [usize; 3],
    spacing: [f64; 3],
    dtype: &str,
    range: (f32, f32, u64),
    background: Told,
    slabs: Option<Vec<(usize, usize)>>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<PartitionPart> {
    let grid = grid(dims, spacing, dtype, range);
    let t = StripTask::new(
        py,
        voxels,
        boxes,
        rows,
        axis,
        (&grid, dtype),
        background,
        params,
    )?;
    let none = slabscope::progress::Monitor::none();
    let counts = py
        .detach(|| {
            crate::run::in_pool(t.pool.as_deref(), || match slabs {
                None => (t.split)
                    .count(&t.volume, &t.background, t.rows.clone(), &none)
                    .map(PassCounts::Slices),
                Some(slabs) => (t.split)
                    .count_boundaries(&t.volume, &t.background, t.rows.clone(), &slabs, &none)
                    .map(PassCounts::Joints),
            })
        })
        .or_py()?;
    Ok(PartitionPart { counts })
}

/// A strip's first-pass counts as [`_count_strip`] gives them, and its runs kept for the second
/// pass ([`_strip_joints`]) when they take no more memory than its voxels (else None: the second
/// pass then cuts the strip from its voxels again).
#[pyfunction]
#[pyo3(signature = (voxels, boxes, rows, axis, dims, spacing, dtype, range, background, /, **params))]
#[allow(clippy::too_many_arguments)]
pub fn _count_strip_keeping(
    py: Python<'_>,
    voxels: &Bound<'_, PyAny>,
    boxes: Vec<Held>,
    rows: (usize, usize),
    axis: [f64; 3],
    dims: [usize; 3],
    spacing: [f64; 3],
    dtype: &str,
    range: (f32, f32, u64),
    background: Told,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<(PartitionPart, Option<StripRuns>)> {
    let grid = grid(dims, spacing, dtype, range);
    let t = StripTask::new(
        py,
        voxels,
        boxes,
        rows,
        axis,
        (&grid, dtype),
        background,
        params,
    )?;
    let none = slabscope::progress::Monitor::none();
    let (counts, runs) = py
        .detach(|| {
            crate::run::in_pool(t.pool.as_deref(), || {
                (t.split).count_keeping(&t.volume, &t.background, t.rows.clone(), &none)
            })
        })
        .or_py()?;
    let runs = (runs.held_bytes() <= t.voxel_bytes).then_some(StripRuns { runs });
    let counts = PassCounts::Slices(counts);
    Ok((PartitionPart { counts }, runs))
}

/// A strip's second-pass counts from the runs its first pass kept: the joint histograms of
/// consecutive `slabs`, as [`_count_strip`] gives them from the strip's voxels.
#[pyfunction]
#[pyo3(signature = (runs, slabs, /, **params))]
pub fn _strip_joints(
    py: Python<'_>,
    runs: &StripRuns,
    slabs: Vec<(usize, usize)>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<PartitionPart> {
    let pool = crate::parts::task_threads(py, params)?;
    let none = slabscope::progress::Monitor::none();
    let joints = py
        .detach(|| crate::run::in_pool(pool.as_deref(), || runs.runs.joints(&slabs, &none)))
        .or_py()?;
    let counts = PassCounts::Joints(joints);
    Ok(PartitionPart { counts })
}

/// A strip's columns as runs, kept on the worker that cut it between the partition's passes;
/// pickles as bytes (should Dask move it), and tells Dask the memory it holds.
#[pyclass(module = "slabscope", frozen)]
pub struct StripRuns {
    runs: slabscope::partition::StripRuns,
}

#[pymethods]
impl StripRuns {
    /// The strip's rows.
    #[getter]
    fn rows(&self) -> (usize, usize) {
        let rows = self.runs.rows();
        (rows.start, rows.end)
    }

    /// The bytes the runs hold (what `sys.getsizeof` and so Dask's memory count see).
    fn __sizeof__(&self) -> usize {
        self.runs.held_bytes()
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let bytes = PyBytes::new(py, &self.runs.to_bytes());
        crate::pickle::reduced(py, "_strip_runs_of", (bytes,))
    }
}

/// Unpickles `StripRuns`.
#[pyfunction]
pub fn _strip_runs_of(bytes: &[u8]) -> PyResult<StripRuns> {
    let runs = slabscope::partition::StripRuns::from_bytes(bytes).map_err(PyValueError::new_err)?;
    Ok(StripRuns { runs })
}

/// What a strip's task counts from: the volume of its boxes, the split, the whole volume's
/// background as far as the task knows it, its rows, its threads and its voxels' bytes.
struct StripTask {
    volume: slabscope::Volume,
    split: StackSplit,
    background: Background,
    rows: std::ops::Range<usize>,
    pool: Option<std::sync::Arc<rayon::ThreadPool>>,
    voxel_bytes: usize,
}

impl StripTask {
    /// The task of `rows` from its boxes' `voxels`, checked against its budget and against the
    /// voxels its rows read.
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        voxels: &Bound<'_, PyAny>,
        boxes: Vec<Held>,
        rows: (usize, usize),
        axis: [f64; 3],
        (grid, dtype): (&SlabGrid, &str),
        background: Told,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let held: Vec<(std::ops::Range<usize>, VoxelBox)> = (boxes.iter())
            .map(|&((a, b), origin, size)| (a..b, VoxelBox { origin, size }))
            .collect();
        let total: usize = held.iter().map(|(_, b)| b.len()).sum();
        let voxel_bytes = total * grid.voxel_type.size();
        check_room(py, params, &held, voxel_bytes, &background.1, rows)?;
        // Read in C order, one run of every box's voxels: a box [z, y, x] is x fastest so.
        let voxels = &voxels.call_method1("reshape", ((-1isize, 1, 1),))?;
        let volume = with_layer!(voxels, dtype, |v| {
            if v.len() != total {
                return Err(PyValueError::new_err(format!(
                    "{} voxels for boxes of {total}",
                    v.len()
                )));
            }
            let mut at = 0;
            let pieces: Vec<_> = (held.iter())
                .map(|&(_, b)| {
                    at += b.len();
                    (b, &v[at - b.len()..at])
                })
                .collect();
            slabscope::Volume::of_boxes(grid, &pieces).or_py()?
        });
        let analysis = analysis_of(py, params)?;
        let split = StackSplit::new(&volume, axis, &analysis.partition()).or_py()?;
        let rows = rows.0..rows.1;
        check_held(&split, &volume, &rows, &held)?;
        let masks = (background.1.iter())
            .map(|b| ChunkMask::from_bytes(b))
            .collect::<Result<Vec<_>, _>>()
            .or_py()?;
        let background =
            Background::in_part(grid.dims, analysis.background, background.0, &masks).or_py()?;
        let pool = crate::parts::task_threads(py, params)?;
        Ok(Self {
            volume,
            split,
            background,
            rows,
            pool,
            voxel_bytes,
        })
    }
}

/// An error unless what a strip's task holds fits its `max_memory=` (if given): its boxes'
/// voxels (`bytes`) twice, as given and as copied into the volume it counts, and its layers'
/// masks (their bits, copied into a mask of the grid).
fn check_room(
    py: Python<'_>,
    params: Option<&Bound<'_, PyDict>>,
    held: &[(std::ops::Range<usize>, VoxelBox)],
    bytes: usize,
    masks: &[Vec<u8>],
    rows: (usize, usize),
) -> PyResult<()> {
    let holds = 2 * bytes as u64 + 2 * masks.iter().map(|m| m.len() as u64).sum::<u64>();
    crate::params::within_task_budget(py, params, holds, |budget| {
        let planes: usize = held.iter().map(|(p, _)| p.len()).sum();
        format!(
            "the strip of rows {}..{} holds {holds} bytes (its voxels in {} boxes across {planes} \
             planes, as given and copied, and their layers' masks), beyond the task's budget of \
             {budget} (chunks of fewer planes along z, so more and thinner strips, or raise \
             max_memory=)",
            rows.0,
            rows.1,
            held.len()
        )
    })
}

/// An error unless the boxes `held` (each with the planes of its layer) hold every voxel the
/// samples of `rows` read: each layer's voxels in its box, and every plane read in a layer.
fn check_held(
    split: &StackSplit,
    volume: &slabscope::Volume,
    rows: &std::ops::Range<usize>,
    held: &[(std::ops::Range<usize>, VoxelBox)],
) -> PyResult<()> {
    let planes: Vec<_> = held.iter().map(|(p, _)| p.clone()).collect();
    let needed = split.voxel_boxes(volume, rows, &planes).or_py()?;
    for ((p, b), need) in held.iter().zip(needed) {
        if let Some(need) = need
            && !contains(*b, need)
        {
            return Err(PyValueError::new_err(format!(
                "rows {}..{} read the voxels of {need:?} in planes {}..{}, not all in the {b:?} given",
                rows.start, rows.end, p.start, p.end
            )));
        }
    }
    let Some(whole) = split.voxel_box(volume, rows).or_py()? else {
        return Ok(());
    };
    let (mut z, end) = (whole.origin[2], whole.origin[2] + whole.size[2]);
    while z < end {
        let Some((p, _)) = held.iter().find(|(p, _)| p.contains(&z)) else {
            return Err(PyValueError::new_err(format!(
                "rows {}..{} read plane {z}, in none of the layers given",
                rows.start, rows.end
            )));
        };
        z = p.end;
    }
    Ok(())
}

/// Whether box `a` holds box `b`.
fn contains(a: VoxelBox, b: VoxelBox) -> bool {
    (0..3).all(|m| a.origin[m] <= b.origin[m] && b.origin[m] + b.size[m] <= a.origin[m] + a.size[m])
}

/// The analysis keywords `params` (the others `analyze_array` takes are read by the client).
pub(crate) fn analysis_of(
    py: Python<'_>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<AnalysisParams> {
    let kw = Kwargs::new(py, "analyze_array", params)?;
    Ok(crate::params::analysis_params(&kw)?.0)
}

/// Whether the analysis keywords `params` run the view search: no axis given, or the views
/// asked for beside one.
#[pyfunction]
#[pyo3(signature = (**params))]
pub fn _runs_search(py: Python<'_>, params: Option<&Bound<'_, PyDict>>) -> PyResult<bool> {
    Ok(analysis_of(py, params)?.runs_search())
}

/// The client's side of the partition in parts: the view search finished from its parts, the
/// axis, the stack's split into strips, and once the first pass is in, the slabs it found.
#[pyclass(module = "slabscope")]
pub struct PartitionSplit {
    grid: SlabGrid,
    params: AnalysisParams,
    views: Option<ViewSearch>,
    axis: [f64; 3],
    split: StackSplit,
    found: Option<SlabsFound>,
}

/// A strip as `PartitionSplit.strips` names it: its rows, and the boxes of voxels they read, a
/// layer each (the layer's index, the box's origin and size, `[x, y, z]`).
type Strip = ((usize, usize), Vec<(usize, [usize; 3], [usize; 3])>);

#[pymethods]
impl PartitionSplit {
    /// The split of the volume of `probe`'s geometry (any volume of it: its spacing and affine
    /// are read), dims `[x, y, z]`, held type `dtype` and finite `range`, by the analysis
    /// keywords `params`, along the axis they name or the best of the view search finished from
    /// its rounds' sums (`paper`, `shifted`, `refined` as `_analyze_with_parts` takes them).
    /// Keywords that do not run in parts are refused: `explain`, the gain ranking, a resolution
    /// other than every voxel.
    #[new]
    #[pyo3(signature = (probe, dims, dtype, range, paper=None, shifted=None, refined=None, /, **params))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        probe: &Bound<'_, Volume>,
        dims: [usize; 3],
        dtype: &str,
        range: (f32, f32, u64),
        paper: Option<PyRef<'_, ViewPart>>,
        shifted: Option<PyRef<'_, ViewPart>>,
        refined: Option<Vec<Refined<'_>>>,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let geometry = probe.get().inner(py)?;
        let mut grid = grid(dims, geometry.spacing(), dtype, range);
        grid.transform = *geometry.transform();
        let volume = empty(&grid)?;
        let analysis = checked(py, params)?;
        let views = match &paper {
            Some(paper) => {
                let rounds = crate::parts::rounds(py, &volume, params)?;
                let shifted = shifted.as_deref();
                Some(views_of(py, &rounds, &volume, paper, shifted, refined)?)
            }
            None => None,
        };
        let axis = partition_axis(&volume, &analysis, views.as_ref()).or_py()?;
        let split = StackSplit::new(&volume, axis, &analysis.partition()).or_py()?;
        Ok(Self {
            grid,
            params: analysis,
            views,
            axis,
            split,
            found: None,
        })
    }

    /// The axis the partition runs along (a unit physical direction).
    #[getter]
    fn axis(&self) -> (f64, f64, f64) {
        (self.axis[0], self.axis[1], self.axis[2])
    }

    /// The stack's rows cut in `count` strips (fewer when there are fewer rows), each with the
    /// boxes of voxels its task holds, one a layer of `planes` along z it reads (the layer's
    /// index among them, the box's origin and size).
    fn strips(&self, count: usize, planes: Vec<(usize, usize)>) -> PyResult<Vec<Strip>> {
        let volume = empty(&self.grid)?;
        let planes: Vec<_> = planes.iter().map(|&(a, b)| a..b).collect();
        (self.split.strips(count).into_iter())
            .map(|rows| {
                let boxes = self.split.voxel_boxes(&volume, &rows, &planes).or_py()?;
                let held = (boxes.into_iter().enumerate())
                    .filter_map(|(k, b)| b.map(|b| (k, b.origin, b.size)))
                    .collect();
                Ok(((rows.start, rows.end), held))
            })
            .collect()
    }

    /// The slabs the first pass's `counts` (every strip's added) find, kept for `analysis`;
    /// `background` is the threshold a found background's rounds gave and how many voxels the
    /// background holds (the layers' counts added), for its report.
    fn slabs(
        &mut self,
        py: Python<'_>,
        counts: &PartitionPart,
        background: (Option<f32>, usize),
    ) -> PyResult<Vec<(usize, usize)>> {
        let PassCounts::Slices(counts) = &counts.counts else {
            return Err(PyValueError::new_err(
                "slabs: the first pass's counts, not the second's",
            ));
        };
        let volume = empty(&self.grid)?;
        let none = slabscope::progress::Monitor::none();
        let len = self.grid.dims.iter().product();
        let (value, count) = background;
        let background = Background::summarized(self.params.background, value, count, len);
        let found = py
            .detach(|| (self.split).slabs(&volume, &background, counts.clone(), &none))
            .or_py()?;
        let slabs = found.slabs.clone();
        self.found = Some(found);
        Ok(slabs)
    }

    /// The analysis: the slabs found, with the NMI at their boundaries from the second pass's
    /// `joints` (every strip's added; None for a single slab), named `name`. Its volume holds no
    /// voxel (its grid alone): `to_dict()`, the views, slabs and partition are there; labels and
    /// pictures need a volume of the voxels.
    #[pyo3(signature = (joints, name, /, **params))]
    fn analysis(
        &self,
        py: Python<'_>,
        joints: Option<&PartitionPart>,
        name: String,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<crate::analysis::Analysis> {
        let found = (self.found.as_ref())
            .ok_or_else(|| PyValueError::new_err("analysis: the slabs are not found yet"))?;
        let joints = match joints.map(|j| &j.counts) {
            None => None,
            Some(PassCounts::Joints(j)) => Some(j.clone()),
            Some(PassCounts::Slices(_)) => {
                return Err(PyValueError::new_err(
                    "analysis: the second pass's counts, not the first's",
                ));
            }
        };
        let partition = self.split.finish(found, joints).or_py()?;
        let volume = empty(&self.grid)?;
        let analysis =
            analyze_with_partition(&volume, &self.params, self.views.clone(), partition).or_py()?;
        let analysed = Analysed {
            params: self.params.clone(),
            plan: Plan::at(std::sync::Arc::new(volume.clone())),
            analysis,
        };
        let json = slabscope::report::to_json(&analysed.report(&name, &volume).or_py()?).or_py()?;
        let g = &self.grid;
        let finest = Finest {
            dims: g.dims,
            spacing: g.spacing,
            transform: g.transform,
        };
        let held = Bound::new(py, Volume::of_grid(finest, g.voxel_type, name))?;
        let params = match params {
            Some(d) => d.copy()?,
            None => PyDict::new(py),
        };
        crate::analysis::Analysis::pending(py, held.unbind(), params.unbind(), json)
    }
}

/// The analysis keywords of `params`, every keyword `analyze_array` passes on checked as
/// `analyze` checks them; those that do not run in parts refused.
fn checked(py: Python<'_>, params: Option<&Bound<'_, PyDict>>) -> PyResult<AnalysisParams> {
    let kw = Kwargs::new(py, "analyze_array", params)?;
    let (analysis, _) = crate::params::analysis_params(&kw)?;
    if let Some(explain) = kw.get::<Bound<'_, PyAny>>("explain")?
        && explain.is_truthy()?
    {
        return Err(PyValueError::new_err(
            "explain: not in parts (its numbers read the voxels where they are): analyze a Volume",
        ));
    }
    let (resolution, _) = crate::params::resolution(&kw)?;
    if resolution != slabscope::volume::Resolution::Full {
        return Err(PyValueError::new_err(
            "resolution: analyze_array counts every voxel (\"full\"); for a coarser level, analyze \
             a Volume of that level",
        ));
    }
    crate::params::max_memory(&kw, 0)?;
    crate::params::thread_count(&kw)?;
    kw.finish()?;
    Ok(analysis)
}
