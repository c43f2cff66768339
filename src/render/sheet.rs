//! Contact sheets: many volumes on one picture, each a cell with its exploded view and its three
//! orthogonal mid slices, numbered in order.

use tiny_skia::{Color, Pixmap};

use super::overlay::draw_digits;
use super::slice::{SliceParams, slice};
use super::{
    DEFAULT_SPREAD, Gap, Layout, MAX_PIXELS, RenderParams, Renderer, TransferChoice, paste_centred,
};
use crate::error::{Error, Result};
use crate::geometry::min_spacing;
use crate::partition::Partition;
use crate::progress::Monitor;
use crate::volume::Volume;

/// Gap between cells, pixels.
const GAP: u32 = 6;

/// Colour of a cell's number, and of the number of a volume that failed.
const NUMBER: [u8; 4] = [255, 220, 90, 255];
const FAILED: [u8; 4] = [235, 80, 70, 255];

/// A cell's size for tiles of `tile` pixels: the exploded view `tile` square, the three slices
/// in a 2×2 grid of the same size beside it.
pub fn cell_size(tile: u32) -> (u32, u32) {
    (2 * tile, tile)
}

/// The size of a sheet of `count` cells of `tile` pixels in `columns` columns.
pub fn sheet_size(count: usize, tile: u32, columns: usize) -> (u64, u64) {
    let (w, h) = cell_size(tile);
    let columns = columns.clamp(1, count.max(1)) as u64;
    let rows = (count as u64).div_ceil(columns);
    (
        columns * u64::from(w + GAP) + u64::from(GAP),
        rows * u64::from(h + GAP) + u64::from(GAP),
    )
}

/// Checks that a sheet of `count` cells fits an image.
pub fn check_sheet(count: usize, tile: u32, columns: usize) -> Result<()> {
    let (w, h) = sheet_size(count, tile, columns);
    if w.saturating_mul(h) > MAX_PIXELS || w > u64::from(u32::MAX) || h > u64::from(u32::MAX) {
        return Err(Error::invalid(
            "sheet",
            format!("{count} volumes"),
            format!("a sheet of at most {MAX_PIXELS} pixels: fewer volumes (shard them)"),
        ));
    }
    Ok(())
}

/// One volume's cell: its exploded view along `partition`, and its mid slices across z, y and
/// x (as radiologists read them when the orientation is known).
pub fn cell(
    volume: &Volume,
    partition: &Partition,
    tile: u32,
    monitor: &Monitor,
) -> Result<Pixmap> {
    let renderer = Renderer::new(volume)?;
    let look = TransferChoice {
        preset: super::Preset::Auto,
        colormap: super::Colormap::Grey,
        window: None,
    };
    let (w, h) = cell_size(tile);
    let mut out =
        Pixmap::new(w, h).ok_or_else(|| Error::invalid("tile", tile, "a tile that fits"))?;
    out.fill(Color::from_rgba8(12, 12, 18, 255));
    let params = RenderParams {
        width: tile,
        height: tile,
        labels: false,
        ..RenderParams::default()
    };
    let layout = Layout::exploded(partition, Gap::Similarity, DEFAULT_SPREAD);
    let view = renderer.render(&layout, &params, monitor)?;
    paste_centred(&mut out, &view.pixmap, (0, 0, tile, tile));
    let transfer = renderer.transfer(look, min_spacing(volume.spacing()))?;
    let half = tile / 2;
    let slice_params = SliceParams {
        fit: (half.saturating_sub(2).max(1), half.saturating_sub(2).max(1)),
        letters: false,
        ..SliceParams::default()
    };
    let (dims, spacing) = (volume.dims(), volume.spacing());
    for (k, m) in [2usize, 1, 0].into_iter().enumerate() {
        let mut axis = [0.0; 3];
        axis[m] = 1.0;
        let middle = (dims[m] - 1) as f64 * spacing[m] / 2.0;
        let s = slice(volume, &transfer, axis, middle, &slice_params)?;
        let (cx, cy) = (tile + (k as u32 % 2) * half, (k as u32 / 2) * half);
        paste_centred(&mut out, &s.pixmap, (cx, cy, half, half));
    }
    Ok(out)
}

/// The sheet: `cells` in order, `columns` a row, each numbered from 1 in its corner (a volume
/// that could not be drawn is an empty cell with its number in red).
pub fn sheet(cells: &[Option<Pixmap>], tile: u32, columns: usize) -> Result<Pixmap> {
    check_sheet(cells.len(), tile, columns)?;
    let (w, h) = sheet_size(cells.len(), tile, columns);
    let mut out = Pixmap::new(w as u32, h as u32)
        .ok_or_else(|| Error::invalid("sheet", format!("{w}x{h}"), "a sheet that fits"))?;
    out.fill(Color::from_rgba8(30, 30, 38, 255));
    let (cw, ch) = cell_size(tile);
    let columns = columns.clamp(1, cells.len().max(1));
    let scale = (tile as f32 / 80.0).clamp(1.0, 3.0).round();
    for (i, c) in cells.iter().enumerate() {
        let x = GAP + (i % columns) as u32 * (cw + GAP);
        let y = GAP + (i / columns) as u32 * (ch + GAP);
        let colour = match c {
            Some(image) => {
                paste_centred(&mut out, image, (x, y, cw, ch));
                NUMBER
            }
            None => FAILED,
        };
        let text = (i + 1).to_string();
        draw_digits(
            &mut out,
            &text,
            x as f32 + 3.0,
            y as f32 + 3.0,
            scale,
            colour,
        );
    }
    Ok(out)
}
