//! `slabscope._slabscope`: the Python face of the slabscope library. Every call is a thin layer
//! over the library, worded as the CLI is (its flags as keyword arguments, its defaults), and
//! every long call runs with the GIL released, reports progress and stops on Ctrl-C (`run`).
//! The pure-Python package `slabscope` re-exports it and adds what needs only Python.

mod analysis;
mod errors;
mod foreign;
mod image;
mod layers;
mod lazy;
mod lent;
mod params;
mod parts;
mod pickle;
mod run;
mod split;
mod triage;
mod volume;

use pyo3::prelude::*;

#[pymodule]
fn _slabscope(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    // A file cut short under its map raises VolumeError instead of ending the interpreter.
    slabscope::volume::mapped::install_fault_recovery();
    m.add("VolumeError", py.get_type::<errors::VolumeError>())?;
    m.add("SCHEMA_VERSION", slabscope::SCHEMA_VERSION)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<volume::Volume>()?;
    m.add_class::<analysis::Analysis>()?;
    m.add_class::<image::Image>()?;
    m.add_class::<triage::Triage>()?;
    m.add_class::<parts::ViewPart>()?;
    m.add_class::<split::PartitionPart>()?;
    m.add_class::<split::StripRuns>()?;
    m.add_class::<split::PartitionSplit>()?;
    m.add_function(wrap_pyfunction!(volume::load, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::analyze, m)?)?;
    m.add_function(wrap_pyfunction!(image::render, m)?)?;
    m.add_function(wrap_pyfunction!(image::slice, m)?)?;
    m.add_function(wrap_pyfunction!(triage::triage, m)?)?;
    m.add_function(wrap_pyfunction!(triage::list_volumes, m)?)?;
    m.add_function(wrap_pyfunction!(params::parameters, m)?)?;
    m.add_function(wrap_pyfunction!(pickle::_volume_from_file, m)?)?;
    m.add_function(wrap_pyfunction!(pickle::_volume_from_voxels, m)?)?;
    m.add_function(wrap_pyfunction!(pickle::_analysis_of, m)?)?;
    m.add_function(wrap_pyfunction!(image::_image_of, m)?)?;
    m.add_function(wrap_pyfunction!(triage::_triage_of, m)?)?;
    m.add_function(wrap_pyfunction!(parts::_view_part_of, m)?)?;
    m.add_function(wrap_pyfunction!(parts::_count_view_slab, m)?)?;
    m.add_function(wrap_pyfunction!(parts::_slab_planes, m)?)?;
    m.add_function(wrap_pyfunction!(parts::_view_slabs, m)?)?;
    m.add_function(wrap_pyfunction!(parts::_shifted_samples, m)?)?;
    m.add_function(wrap_pyfunction!(parts::_refine_in_parts, m)?)?;
    m.add_function(wrap_pyfunction!(parts::_analyze_with_parts, m)?)?;
    m.add_function(wrap_pyfunction!(pickle::_volume_of_grid, m)?)?;
    m.add_function(wrap_pyfunction!(split::_partition_part_of, m)?)?;
    m.add_function(wrap_pyfunction!(split::_count_strip, m)?)?;
    m.add_function(wrap_pyfunction!(split::_count_strip_keeping, m)?)?;
    m.add_function(wrap_pyfunction!(split::_strip_joints, m)?)?;
    m.add_function(wrap_pyfunction!(split::_strip_runs_of, m)?)?;
    m.add_function(wrap_pyfunction!(layers::_layer_border, m)?)?;
    m.add_function(wrap_pyfunction!(layers::_background_threshold, m)?)?;
    m.add_function(wrap_pyfunction!(layers::_layer_summary, m)?)?;
    m.add_function(wrap_pyfunction!(layers::_background_answers, m)?)?;
    m.add_function(wrap_pyfunction!(layers::_layer_mask, m)?)?;
    m.add_function(wrap_pyfunction!(layers::_layer_below, m)?)?;
    m.add_function(wrap_pyfunction!(split::_runs_search, m)?)?;
    Ok(())
}
