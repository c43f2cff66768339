//! A store at a URL whose pyramid holds coarser datasets, read as a notebook uses it: `load`
//! reads its metadata and its coarsest dataset only (level 0's grid and type, so the volume's
//! shape, spacing, affine and dtype), level 0 is read when first needed (its voxels, range,
//! missing count, labels, pictures), and `analyze` at a coarser `resolution` reads the coarsest
//! dataset that serves the level, never level 0, as `slabscope analyze URL --resolution auto`
//! does ([`slabscope::formats::load_serving`]).

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slabscope::LoadOptions;
use slabscope::geometry::world::WorldTransform;
use slabscope::volume::pyramid::Finest;
use slabscope::volume::{Resolution, VoxelType};

use crate::params::{Kwargs, load_options};
use crate::run;
use crate::volume::Volume;

/// What is known of a store at a URL whose level 0 is not read yet, or of a volume counted in
/// parts across a cluster whose voxels are held nowhere here (`path` None).
pub struct Unread {
    /// The URL as given; None for a volume counted in parts.
    path: Option<PathBuf>,
    /// Level 0's grid, from the store's metadata.
    pub finest: Finest,
    /// The stored voxel type (the coarsest dataset's, as read).
    pub voxel_type: VoxelType,
    /// The format read (None for a volume counted in parts).
    pub format: Option<slabscope::Format>,
    /// The notes of level 0's read, once read.
    pub notes: OnceLock<Vec<String>>,
    /// The resolution last analysed below level 0, the dataset read for it and its read's notes.
    serving: Mutex<Option<Served>>,
}

/// A coarser dataset read for a resolution: the resolution, the dataset and its read's notes.
type Served = (Resolution, Arc<slabscope::Volume>, Vec<String>);

/// Why a volume counted in parts has no voxels to give.
const NOWHERE: &str = "counted in parts across a cluster (slabscope.dask.analyze_array), its \
     voxels are held nowhere here: for labels or pictures, analyze a Volume of them \
     (slabscope.load, Volume.from_array)";

/// What `load` reads of `file`: level 0, or for a store at a URL with a coarser dataset, that
/// store's grid without level 0 ([`Unread`]).
pub enum Read {
    /// Level 0, read.
    Level0(slabscope::Loaded),
    /// A store at a URL, level 0 not read.
    Unread(Unread),
}

/// Reads `file` as `load` does: a store at a URL holding a coarser dataset by its metadata and
/// coarsest dataset only (no chunk of level 0), anything else whole.
pub fn read(py: Python<'_>, file: &Path, opts: &LoadOptions) -> PyResult<Read> {
    if slabscope::formats::remote::is_url(file) {
        let coarsest = run::loading(py, |cancel| {
            let opts = LoadOptions {
                cancel,
                ..opts.clone()
            };
            slabscope::formats::load_preview(file, &opts, 0)
        })?;
        let finest = coarsest.as_ref().and_then(|c| {
            let v = &c.volume;
            (v.unread_finest()).map(|f| (f.clone(), v.voxel_type(), c.format))
        });
        if let Some((finest, voxel_type, format)) = finest {
            return Ok(Read::Unread(Unread {
                path: Some(file.to_path_buf()),
                finest,
                voxel_type,
                format: Some(format),
                notes: OnceLock::new(),
                serving: Mutex::new(None),
            }));
        }
    }
    let loaded = run::loading(py, |cancel| {
        slabscope::load(
            file,
            &LoadOptions {
                cancel,
                ..opts.clone()
            },
        )
    })?;
    Ok(Read::Level0(loaded))
}

impl Unread {
    /// `load`'s options from the keywords it was given, `kept`, and the pool of its `threads`.
    fn options(
        py: Python<'_>,
        kept: &Py<PyDict>,
    ) -> PyResult<(LoadOptions, Option<rayon::ThreadPool>)> {
        let kw = Kwargs::new(py, "load", Some(kept.bind(py)))?;
        let options = load_options(&kw)?;
        kw.finish()?;
        Ok(options)
    }

    /// What is known of a volume of `finest`'s grid and `voxel_type` counted in parts across a
    /// cluster: no voxel, and nowhere to read them from.
    pub fn nowhere(finest: Finest, voxel_type: VoxelType) -> Self {
        Self {
            path: None,
            finest,
            voxel_type,
            format: None,
            notes: OnceLock::new(),
            serving: Mutex::new(None),
        }
    }

    /// Whether its voxels can be read (a store's), or are held nowhere.
    pub fn readable(&self) -> bool {
        self.path.is_some()
    }

    /// Level 0, read now with `load`'s keywords `kept`, and its notes.
    pub fn level0(&self, py: Python<'_>, kept: &Py<PyDict>) -> PyResult<slabscope::Volume> {
        let Some(path) = &self.path else {
            return Err(PyValueError::new_err(NOWHERE));
        };
        let (opts, pool) = Self::options(py, kept)?;
        let _threads = run::Threads::bound(pool);
        let loaded = run::loading(py, |cancel| {
            slabscope::load(path, &LoadOptions { cancel, ..opts })
        })?;
        let _ = self.notes.set(loaded.notes);
        Ok(loaded.volume)
    }

    /// The store's coarsest dataset that serves the pyramid level `resolution` picks, read
    /// without level 0 (kept for the next analysis at the same resolution); `None` when
    /// `resolution` picks level 0.
    pub fn serving(
        &self,
        py: Python<'_>,
        kept: &Py<PyDict>,
        resolution: Resolution,
    ) -> PyResult<Option<Arc<slabscope::Volume>>> {
        let Some(path) = self
            .path
            .as_ref()
            .filter(|_| resolution != Resolution::Full)
        else {
            return Ok(None);
        };
        let last = || self.serving.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some((r, v, _)) = last().as_ref()
            && *r == resolution
        {
            return Ok(Some(Arc::clone(v)));
        }
        let (opts, pool) = Self::options(py, kept)?;
        let _threads = run::Threads::bound(pool);
        let served = run::loading(py, |cancel| {
            let opts = LoadOptions { cancel, ..opts };
            slabscope::formats::load_serving(path, &opts, resolution)
        })?;
        Ok(served.map(|loaded| {
            let volume = Arc::new(loaded.volume);
            *last() = Some((resolution, Arc::clone(&volume), loaded.notes));
            volume
        }))
    }

    /// The notes of the coarser dataset last read for an analysis.
    pub fn served_notes(&self) -> Vec<String> {
        let last = self.serving.lock().unwrap_or_else(PoisonError::into_inner);
        last.as_ref().map(|s| s.2.clone()).unwrap_or_default()
    }
}

impl Volume {
    /// Level 0: held, or of a store at a URL read now (once).
    pub fn inner(&self, py: Python<'_>) -> PyResult<&Arc<slabscope::Volume>> {
        if let Some(v) = self.level0.get() {
            return Ok(v);
        }
        let (Some(unread), Some((_, kept))) = (&self.unread, &self.file) else {
            let nowhere = self.unread.as_ref().is_some_and(|u| !u.readable());
            return Err(PyValueError::new_err(format!(
                "volume {:?}: {}",
                self.name,
                if nowhere {
                    NOWHERE
                } else {
                    "its voxels are not held"
                }
            )));
        };
        let read = unread.level0(py, kept)?;
        Ok(self.level0.get_or_init(|| Arc::new(read)))
    }

    /// Level 0's dimensions, spacing and voxel-to-world transform, known without reading it.
    pub fn grid(&self, py: Python<'_>) -> PyResult<([usize; 3], [f64; 3], WorldTransform)> {
        if let (None, Some(u)) = (self.level0.get(), &self.unread) {
            let f = &u.finest;
            return Ok((f.dims, f.spacing, f.transform));
        }
        let v = self.inner(py)?;
        Ok((v.dims(), v.spacing(), *v.transform()))
    }

    /// The stored voxel type, known without reading level 0.
    pub fn voxel_type(&self, py: Python<'_>) -> PyResult<VoxelType> {
        match (self.level0.get(), &self.unread) {
            (None, Some(u)) => Ok(u.voxel_type),
            _ => Ok(self.inner(py)?.voxel_type()),
        }
    }

    /// The volume an analysis at `resolution` runs on: of a store at a URL whose level 0 is
    /// read lazily, the coarsest dataset that serves the level (as the CLI reads it, whether
    /// or not level 0 has been read since); else level 0.
    pub fn analysed(
        &self,
        py: Python<'_>,
        resolution: Resolution,
    ) -> PyResult<Arc<slabscope::Volume>> {
        if let (Some(unread), Some((_, kept))) = (&self.unread, &self.file)
            && let Some(served) = unread.serving(py, kept, resolution)?
        {
            return Ok(served);
        }
        Ok(Arc::clone(self.inner(py)?))
    }

    /// The notes of level 0's read, once read lazily.
    pub fn level0_notes(&self) -> Vec<String> {
        (self.unread.as_ref())
            .and_then(|u| u.notes.get().cloned())
            .unwrap_or_default()
    }

    /// The notes of the coarser dataset last read for an analysis below level 0.
    pub fn served_notes(&self) -> Vec<String> {
        self.unread
            .as_ref()
            .map(|u| u.served_notes())
            .unwrap_or_default()
    }
}
