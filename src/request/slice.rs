//! The slice request: one slice across the slab axis, oriented as radiologists read it, as
//! `slabscope slice` writes it.

use tiny_skia::Pixmap;

use crate::analysis::{AnalysisParams, chosen_axis};
use crate::error::Result;
use crate::progress::Monitor;
use crate::render::TransferChoice;
use crate::render::slice::{SliceParams, numbered};
use crate::volume::Volume;

/// One slice across an axis: which axis, which slice, and how it is drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct SliceRequest {
    /// The axis asked for (`axis`: a named one, or the view search's best) and how the slices
    /// are cut along it (the sampling and the background).
    pub params: AnalysisParams,
    /// The axis already found (an analysis's), a unit physical direction: no view search runs.
    pub axis: Option<[f64; 3]>,
    /// The slice, counted from 0 along the axis; the middle one when `None`.
    pub index: Option<usize>,
    /// How values become colours.
    pub look: TransferChoice,
    /// The size the slice is fit into, and its orientation letters.
    pub picture: SliceParams,
}

impl SliceRequest {
    /// The axis the slice is across: the one already found, else the one `params` names, else
    /// the best of the view search by entropy rate on `volume` (no partition is made).
    pub fn axis(&self, volume: &Volume, monitor: &Monitor) -> Result<[f64; 3]> {
        match self.axis {
            Some(axis) => Ok(axis),
            None => chosen_axis(volume, &self.params, monitor),
        }
    }

    /// Finds the axis ([`axis`](Self::axis)) and keeps it in the request, so that what follows
    /// ([`slices`](Self::slices), [`run`](Self::run)) runs no view search again.
    pub fn find_axis(&mut self, volume: &Volume, monitor: &Monitor) -> Result<[f64; 3]> {
        let axis = self.axis(volume, monitor)?;
        self.axis = Some(axis);
        Ok(axis)
    }

    /// How many slices `volume` has across [`axis`](Self::axis), cut as this request cuts
    /// them: what `index` counts.
    pub fn slices(&self, volume: &Volume, monitor: &Monitor) -> Result<usize> {
        let axis = self.axis(volume, monitor)?;
        let (_, slices, _, _) =
            crate::partition::slice_geometry(volume, axis, &self.params.stack())?;
        Ok(slices)
    }

    /// The slice of `volume` across [`axis`](Self::axis): an index past the slices there is
    /// an error about `index`.
    pub fn run(&self, volume: &Volume, monitor: &Monitor) -> Result<Pixmap> {
        let axis = self.axis(volume, monitor)?;
        let stack = self.params.stack();
        let image = numbered(volume, axis, &stack, self.index, self.look, &self.picture)?;
        Ok(image.pixmap)
    }
}
