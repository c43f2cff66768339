//! The render request: the exploded view of an analysis's slabs, or the strip of their faces,
//! drawn from the level the analysis partitioned.

use tiny_skia::Pixmap;

use crate::error::{Error, Result, Value};
use crate::geometry::min_spacing;
use crate::params::Scene;
use crate::partition::Partition;
use crate::progress::Monitor;
use crate::render::{Layout, Renderer, Stack, TransferChoice, slice};

use super::Analysed;

/// A picture of an analysis's slabs: what it shows and how.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderRequest {
    /// The camera, look, size and gaps of the exploded view; of it, the strip of faces takes
    /// only the size and the look.
    pub scene: Scene,
    /// Instead of the exploded view, the faces of every slab: its last slice above its first, a
    /// column a slab, fit into the size (`render --faces`).
    pub faces: bool,
}

/// The room around the tiles of the strip of faces, pixels: a gap before every column and after
/// the last, and 12 in height (a gap above, between and below the two rows).
const FACES_GAP: u32 = 4;

/// The tile each face of `slabs` slabs is fit into, in a strip of `(width, height)` pixels: an
/// error about `size` when a tile would be under 8 pixels either way.
pub fn faces_tile((width, height): (u32, u32), slabs: usize) -> Result<(u32, u32)> {
    let k = u32::try_from(slabs).unwrap_or(u32::MAX);
    let tile = (
        width.saturating_sub(FACES_GAP * k.saturating_add(1)) / k.max(1),
        height.saturating_sub(3 * FACES_GAP) / 2,
    );
    if tile.0 < 8 || tile.1 < 8 {
        return Err(Error::Unfit {
            parameter: "size",
            value: Value::Size(width, height),
            problem: format!("too small for the faces of {k} slabs"),
        });
    }
    Ok(tile)
}

impl RenderRequest {
    /// The picture of `analysed`'s slabs, drawn from the level it partitioned.
    pub fn render(&self, analysed: &Analysed, monitor: &Monitor) -> Result<Pixmap> {
        self.draw(analysed.level(), &analysed.analysis.partition, monitor)
    }

    /// The picture of `part`'s slabs of `level` (the volume or pyramid level partitioned). A
    /// slab to highlight past the slabs is an error about `highlight`.
    pub fn draw(
        &self,
        level: &crate::volume::Volume,
        part: &Partition,
        monitor: &Monitor,
    ) -> Result<Pixmap> {
        let params = &self.scene.params;
        if self.faces {
            let look = TransferChoice {
                preset: params.preset,
                colormap: params.colormap,
                window: params.window,
            };
            let tile = faces_tile((params.width, params.height), part.slabs.len())?;
            monitor.check()?;
            let renderer = Renderer::new(level)?;
            let transfer = renderer.transfer(look, min_spacing(level.spacing()))?;
            return slice::faces(level, &transfer, &Stack::of(part), &part.slabs, tile);
        }
        if let Some(h) = params.highlight
            && h >= part.slabs.len()
        {
            return Err(Error::Unfit {
                parameter: "highlight",
                value: Value::Whole(h as u64),
                problem: format!(
                    "there are only {} slabs (numbered from 0)",
                    part.slabs.len()
                ),
            });
        }
        let layout = Layout::exploded(part, self.scene.gap, self.scene.spread);
        let image = Renderer::new(level)?.render(&layout, params, monitor)?;
        Ok(image.pixmap)
    }
}
