//! The TUI's export: the view, the analysis and the labels of the partition on screen, written to
//! the current folder under names not taken yet.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use slabscope::analysis::Plan;
use slabscope::budget::Budget;
use slabscope::formats::write_atomic;
use slabscope::partition::LabelRoom;
use slabscope::render::{ImageOutput, encode};
use slabscope::request::RenderRequest;
use slabscope::{Analysis, AnalysisReport, Monitor, Partition, Volume};

use crate::tui::event::ExportRequest;

/// Writes the view (PNG), the analysis (JSON) and the labels (NRRD) of the request's partition
/// to the current folder under names not taken yet; says what it wrote.
///
/// Within `max_memory` bytes: the labels are refused before anything is written when a plane of
/// them does not fit beside the volume; the background's mask (a bit a voxel) is held in memory
/// when it fits beside that plane, else in a mapped scratch file.
pub(super) fn export(
    full: &Volume,
    r: &ExportRequest,
    max_memory: u64,
    monitor: &Monitor,
) -> slabscope::Result<String> {
    // A preview's partition is of its pyramid level, and says so.
    let level = full.coarser(r.level);
    let volume = level.as_ref();
    let part = Partition::new(&r.histories, r.method, r.position, monitor)?;
    let room = labels_room(
        Path::new(&r.name),
        full,
        &level,
        part.slabs.len(),
        max_memory,
    )?;
    let stem = Path::new(&r.name)
        .file_stem()
        .map_or_else(|| "builtin".into(), |s| s.to_string_lossy().into_owned());
    let png = free_name(&format!("{stem}-slabscope"), "png");
    let json = free_name(&format!("{stem}-slabscope"), "json");
    let labels = free_name(&format!("{stem}-slabscope-labels"), "nrrd");
    let picture = RenderRequest {
        scene: r
            .look
            .scene((1280, 960), r.highlight.filter(|&h| h < part.slabs.len())),
        faces: false,
    };
    let image = picture.draw(volume, &part, monitor)?;
    write_new(&png, &encode(&image, ImageOutput::Png)?)?;
    let analysis = Analysis {
        views: r.views.clone(),
        gain: r.gain.as_ref().map(|(g, _)| g.clone()),
        axis_by: r.gain.as_ref().and_then(|&(_, by)| by),
        notes: slabscope::analysis::notes(volume, volume, &r.view_params, &part),
        partition: part,
        explain: None,
    };
    let report = AnalysisReport::new(&r.name, full, &r.view_params, &analysis)?.computed_on(volume);
    let text = slabscope::report::to_json(&report)?;
    write_new(&json, text.as_bytes())?;
    // At the working volume's shape, whatever level the preview's partition is of, a few
    // planes at a time (gzip-compressed NRRD, by the name).
    let labelled = (full, volume, &analysis.partition);
    slabscope::report::write_labels(&labels, labelled, room, false, monitor)?;
    Ok(format!(
        "wrote {}, {} and {}",
        slabscope::error::shown(&png),
        slabscope::error::shown(&json),
        slabscope::error::shown(&labels)
    ))
}

/// The working memory for writing the labels of a partition of `level` into `slabs` slabs at
/// `full`'s shape within `max_memory` bytes, as the CLI's `--export-labels` weighs it
/// ([`Budget::labels`]): the room for chunks of planes and where the background's mask is
/// held; an error naming the volume at `path` when not even a plane fits.
fn labels_room(
    path: &Path,
    full: &Volume,
    level: &Arc<Volume>,
    slabs: usize,
    max_memory: u64,
) -> slabscope::Result<LabelRoom> {
    let plan = Plan::at(Arc::clone(level));
    Budget::new(max_memory).labels(path, full, &plan, slabs)
}

/// Writes `bytes` to `path`, which must not exist.
fn write_new(path: &Path, bytes: &[u8]) -> slabscope::Result<()> {
    use std::io::Write;
    write_atomic(path, false, |mut file| file.write_all(bytes))
}

/// `stem.ext` in the current folder, or `stem-1.ext`, `stem-2.ext`, … when taken.
fn free_name(stem: &str, ext: &str) -> PathBuf {
    let name = |i: u32| {
        if i == 0 {
            PathBuf::from(format!("{stem}.{ext}"))
        } else {
            PathBuf::from(format!("{stem}-{i}.{ext}"))
        }
    };
    (0..u32::MAX)
        .map(name)
        .find(|p| !p.exists())
        .unwrap_or_else(|| name(u32::MAX))
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::labels_room;
    use slabscope::volume::phantom;

    /// The labels' room is the CLI's: the background mask of every voxel (a bit each) in memory
    /// beside a plane of labels and the volume when it fits, else in a scratch file; refused in
    /// one line naming the volume when not even a plane fits.
    #[test]
    fn the_labels_are_weighed_against_the_budget_before_anything_is_written() {
        let full = phantom::body([64, 64, 80], 1).unwrap();
        let level = full.coarser(1);
        let path = Path::new("body.nii");
        let held = full.memory_bytes() + level.memory_bytes();
        let mask = (full.len() as u64).div_ceil(64) * 8;
        let plane = 64 * 64;
        let room = |max| labels_room(path, &full, &level, 4, max);
        let in_memory = room(held + mask + plane).unwrap();
        assert_eq!((in_memory.chunk, in_memory.mask_in_memory), (plane, true));
        let mapped = room(held + mask + plane - 1).unwrap();
        assert_eq!(
            (mapped.chunk, mapped.mask_in_memory),
            (mask + plane - 1, false)
        );
        assert_eq!(room(held + plane).unwrap().chunk, plane);
        let refused = room(held + plane - 1).unwrap_err();
        let text = refused.to_string();
        assert!(text.starts_with("body.nii: "), "{text}");
        assert!(text.contains("a plane of the labels"), "{text}");
        assert!(!text.contains('\n'), "{text}");
    }
}
