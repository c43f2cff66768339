//! The colour maps, from 0 to 1.

use serde::Serialize;

/// Colour maps from 0 to 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Colormap {
    /// Black to white.
    Grey,
    /// Black, red, yellow, white.
    Hot,
    /// Perceptually uniform dark blue to yellow.
    Viridis,
    /// Bone-like: grey with a warm tint.
    Bone,
}

impl Colormap {
    /// Every colour map, for cycling in the TUI.
    pub const ALL: [Colormap; 4] = [Self::Grey, Self::Bone, Self::Hot, Self::Viridis];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Grey => "grey",
            Self::Hot => "hot",
            Self::Viridis => "viridis",
            Self::Bone => "bone",
        }
    }

    /// The colour at `t` in [0, 1], linear RGB in [0, 1].
    pub fn at(self, t: f32) -> [f32; 3] {
        let t = t.clamp(0.0, 1.0);
        let anchors: &[[f32; 3]] = match self {
            Self::Grey => return [t; 3],
            Self::Hot => &[
                [0.0, 0.0, 0.0],
                [0.9, 0.1, 0.0],
                [1.0, 0.8, 0.1],
                [1.0, 1.0, 1.0],
            ],
            Self::Viridis => &[
                [0.267, 0.005, 0.329],
                [0.229, 0.322, 0.545],
                [0.128, 0.567, 0.551],
                [0.369, 0.789, 0.383],
                [0.993, 0.906, 0.144],
            ],
            Self::Bone => &[
                [0.0, 0.0, 0.0],
                [0.32, 0.32, 0.45],
                [0.65, 0.78, 0.78],
                [1.0, 1.0, 1.0],
            ],
        };
        let x = t * (anchors.len() - 1) as f32;
        let i = (x as usize).min(anchors.len() - 2);
        let f = x - i as f32;
        std::array::from_fn(|c| anchors[i][c] + f * (anchors[i + 1][c] - anchors[i][c]))
    }
}
