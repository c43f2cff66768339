//! What this tool's defaults change from the paper, for one axis: its entropy rate on the
//! paper's single lattice beside the mean over shifted lattices the defaults rank by, and the
//! voxels counted with every voxel in (the paper) beside the background left out (the defaults).

use serde::Serialize;

use crate::error::Result;
use crate::progress::Monitor;
use crate::view::{DEFAULT_PHASES, PhaseStats, ViewParams, evaluate};
use crate::volume::Volume;
use crate::volume::background::{Background, BackgroundRule};

/// The paper's numbers beside the defaults' for one axis.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModeLesson {
    /// The canonical unit axis.
    pub axis: [f64; 3],
    /// `h` on the paper's single lattice, bits per sample.
    pub paper_h: f64,
    /// `h` over the shifted lattices the defaults average (the paper's among them).
    pub phases: Option<PhaseStats>,
    /// The volume's voxels: `v_T` with every voxel counted, as the paper does.
    pub voxels: u64,
    /// The voxels the default rule finds to be background (connected to the border).
    pub background: u64,
}

impl ModeLesson {
    /// `v_T` with the background left out, as the defaults do.
    pub fn without_background(&self) -> u64 {
        self.voxels - self.background
    }
}

/// The paper's numbers beside the defaults' for `axis` of `volume`, measured with the view
/// search's `params` (the defaults' phases when `params` has none).
pub fn mode_lesson(
    volume: &Volume,
    axis: [f64; 3],
    params: &ViewParams,
    monitor: &Monitor,
) -> Result<ModeLesson> {
    let params = ViewParams {
        phases: if params.phases == 0 {
            DEFAULT_PHASES
        } else {
            params.phases
        },
        ..params.clone()
    };
    let rate = evaluate(volume, &params, axis, monitor)?;
    let background = Background::find(volume, BackgroundRule::Auto, monitor)?;
    let voxels = volume.len() as u64;
    Ok(ModeLesson {
        axis: rate.axis,
        paper_h: rate.entropy_rate,
        phases: rate.phases,
        voxels,
        background: (background.fraction * voxels as f64).round() as u64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::phantom;

    #[test]
    fn the_paper_lattice_is_among_the_phases_and_air_is_background() {
        let volume = phantom::body([24, 24, 40], 1).unwrap();
        let params = ViewParams::default();
        let m = mode_lesson(&volume, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap();
        let alone = evaluate(
            &volume,
            &ViewParams::paper(),
            [0.0, 0.0, 1.0],
            &Monitor::none(),
        );
        assert_eq!(m.paper_h, alone.unwrap().entropy_rate);
        let phases = m.phases.unwrap();
        assert_eq!(phases.n, DEFAULT_PHASES);
        assert!(phases.min <= m.paper_h && m.paper_h <= phases.max);
        assert_eq!(m.voxels, 24 * 24 * 40);
        assert!(m.background > 0 && m.without_background() < m.voxels);
    }
}
