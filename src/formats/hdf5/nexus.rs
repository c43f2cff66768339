//! The voxel size a `NeXus` `NXdata` group gives its signal: the spacing of its axis datasets (the
//! coordinates of each voxel along one axis, 1-D, evenly spaced), in the unit of their `units`
//! attributes.
//!
//! Which axis dataset goes with which dimension is the group's `axes` attribute: an array of
//! names (`NeXus` 2014), or one string `z:y:x` (or comma- or space-separated, the older form, also
//! read from the signal's own `axes`). `rust-hdf5` reads a group's attribute as one string: of an
//! array of variable-length strings (h5py's way with a list of names), the first name. So the
//! names are read as far as they go, and the dimensions left are matched to the group's other
//! 1-D datasets by their length (the dimension's, or one more: bin edges), a length shared by
//! several settled by the axis's usual name (`x`, `y`, `z`); a dimension still unmatched leaves
//! the voxel size to the other rules.

use rust_hdf5::{H5Dataset, H5File};

use super::dxchange::mm_per;

/// The voxel size (x, y, z) in mm of the dataset `read` when it is the signal of an `NXdata`
/// group, of spatial shape `zyx` (its last three dimensions), and the note saying where it came
/// from; `None` when the group gives none usable.
pub(super) fn spacing(file: &H5File, read: &str, zyx: [usize; 3]) -> Option<([f64; 3], String)> {
    let read = read.trim_start_matches('/');
    let (group_path, signal) = read.rsplit_once('/').unwrap_or(("", read));
    let group = if group_path.is_empty() {
        file.root_group()
    } else {
        file.root_group().group(group_path).ok()?
    };
    if group.attr_string("NX_class").ok()?.trim() != "NXdata" {
        return None;
    }
    let path_of = |name: &str| {
        if group_path.is_empty() {
            name.to_string()
        } else {
            format!("{group_path}/{name}")
        }
    };
    // 1-D datasets beside the signal: the candidate axes, with their lengths.
    let axes: Vec<(String, usize)> = group
        .dataset_names()
        .ok()?
        .into_iter()
        .filter(|n| n != signal)
        .filter_map(|n| {
            let shape = file.dataset(&path_of(&n)).ok()?.shape();
            (shape.len() == 1).then(|| (n, shape[0]))
        })
        .collect();
    let named = named_axes(file, &group, &path_of(signal));
    let chosen = match_axes(&named, &axes, zyx)?;
    let mut mm = [0.0; 3];
    let mut shown = Vec::new();
    for (k, name) in chosen.iter().enumerate() {
        let ds = file.dataset(&path_of(name)).ok()?;
        let (step, unit) = step(&ds, zyx[k])?;
        mm[2 - k] = step * mm_per(unit.as_deref())?;
        shown.push(format!("{name} {step} {}", unit.as_deref().unwrap_or("µm")));
    }
    let note = format!(
        "voxel size from the NeXus NXdata axes of /{group_path} ({})",
        shown.join(", ")
    );
    Some((mm, crate::error::names::text(&note)))
}

/// The axis names the group's `axes` attribute (else the signal's) gives, as far as they can be
/// read: the last three of several, one (the first dimension's), or none.
fn named_axes(file: &H5File, group: &rust_hdf5::H5Group, signal: &str) -> Vec<String> {
    let text = group.attr_string("axes").ok().or_else(|| {
        file.dataset(signal)
            .ok()?
            .attr("axes")
            .ok()?
            .read_string()
            .ok()
    });
    let names: Vec<String> = text
        .unwrap_or_default()
        .split(|c: char| c == ':' || c == ',' || c.is_whitespace())
        .filter(|n| !n.is_empty())
        .map(str::to_string)
        .collect();
    if names.len() > 3 {
        names[names.len() - 3..].to_vec()
    } else {
        names
    }
}

/// The axis dataset of each dimension (z, y, x) among `axes` (name, length): `named` first
/// (three names, or the first dimension's), then by length, then by the axis's usual name.
fn match_axes(named: &[String], axes: &[(String, usize)], zyx: [usize; 3]) -> Option<[String; 3]> {
    let fits = |name: &str, k: usize| {
        axes.iter()
            .any(|(n, len)| n == name && (*len == zyx[k] || *len == zyx[k] + 1))
    };
    let mut chosen: [Option<String>; 3] = [None, None, None];
    if named.len() == 3 {
        for k in 0..3 {
            chosen[k] = fits(&named[k], k).then(|| named[k].clone());
        }
    } else if let Some(first) = named.first() {
        chosen[0] = fits(first, 0).then(|| first.clone());
    }
    for (k, usual) in ["z", "y", "x"].into_iter().enumerate() {
        if chosen[k].is_some() {
            continue;
        }
        let taken = |n: &String| chosen.iter().flatten().any(|c| c == n);
        let free: Vec<&String> = axes
            .iter()
            .filter(|(n, len)| !taken(n) && (*len == zyx[k] || *len == zyx[k] + 1))
            .map(|(n, _)| n)
            .collect();
        chosen[k] = match free.as_slice() {
            [one] => Some((*one).clone()),
            several => several
                .iter()
                .find(|n| n.eq_ignore_ascii_case(usual))
                .map(|n| (*n).clone()),
        };
    }
    let [z, y, x] = chosen;
    Some([z?, y?, x?])
}

/// The step between the evenly spaced coordinates of the axis dataset `ds` of a dimension of
/// `n` voxels (its length `n`, or `n + 1` bin edges), and its `units`; `None` when there are
/// fewer than two, or they are not evenly spaced (to 1e-6 of the step).
fn step(ds: &H5Dataset, n: usize) -> Option<(f64, Option<String>)> {
    let values = ds.read_numeric_as::<f64>().ok()?;
    if values.len() < 2 || (values.len() != n && values.len() != n + 1) {
        return None;
    }
    #[allow(clippy::cast_precision_loss)] // a dataset's length
    let step = (values[values.len() - 1] - values[0]) / (values.len() - 1) as f64;
    let even = values
        .windows(2)
        .all(|w| ((w[1] - w[0]) - step).abs() <= 1e-6 * step.abs());
    let unit = ds.attr("units").ok().and_then(|a| a.read_string().ok());
    (even && step.is_finite() && step != 0.0).then_some((step.abs(), unit))
}
