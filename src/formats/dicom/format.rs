//! How a file's samples are stored, from its parsed header: the pixel format its frames share.

use dicom_dictionary_std::tags;
use dicom_object::InMemDicomObject;

use super::elements::{int, text, uint};

/// How a file's samples are stored and meant to be seen.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct PixelFormat {
    /// Rows of a frame.
    pub rows: u16,
    /// Columns of a frame.
    pub cols: u16,
    /// Bits each sample occupies: 8, 16 or 32.
    pub allocated: u16,
    /// Bits of it that hold the value (the low ones).
    pub stored: u16,
    /// Two's complement samples.
    pub signed: bool,
    /// Samples per pixel: 1 (grey) or 3 (colour).
    pub samples: u16,
    /// Colour samples stored plane by plane (else pixel by pixel).
    pub planar: bool,
    /// The photometric interpretation, e.g. `MONOCHROME2`.
    pub photometric: String,
    /// Frames in the file.
    pub frames: u32,
}

impl PixelFormat {
    /// Bytes of one frame, as stored natively (`YBR_FULL_422` keeps two samples a pixel: each
    /// pair of pixels shares its colour).
    pub fn frame_bytes(&self) -> u64 {
        let samples = if self.subsampled() {
            2
        } else {
            u64::from(self.samples)
        };
        u64::from(self.rows) * u64::from(self.cols) * samples * u64::from(self.allocated / 8)
    }

    /// Whether the colour is subsampled horizontally (`YBR_FULL_422`: Y1 Y2 Cb Cr).
    pub fn subsampled(&self) -> bool {
        self.samples == 3 && self.photometric == "YBR_FULL_422"
    }

    /// Whether the display shows the lowest value white (MONOCHROME1).
    pub fn inverted(&self) -> bool {
        self.photometric == "MONOCHROME1"
    }

    /// Whether the samples are colour.
    pub fn colour(&self) -> bool {
        self.samples == 3
    }

    /// Why slabscope cannot read these samples, if it cannot.
    pub fn problem(&self) -> Option<String> {
        if self.rows == 0 || self.cols == 0 {
            return Some(format!("image of {}x{} pixels", self.cols, self.rows));
        }
        if !matches!(self.allocated, 8 | 16 | 32) {
            return Some(format!(
                "{} bits allocated per sample (slabscope reads 8, 16 and 32)",
                self.allocated
            ));
        }
        if self.stored == 0 || self.stored > self.allocated {
            return Some(format!(
                "{} bits stored in {} allocated",
                self.stored, self.allocated
            ));
        }
        match (self.samples, self.photometric.as_str()) {
            (1, "MONOCHROME1" | "MONOCHROME2")
            | (3, "RGB" | "YBR_FULL" | "YBR_FULL_422" | "YBR_RCT" | "YBR_ICT") => None,
            (1, "PALETTE COLOR") => Some(
                "palette colour images (PALETTE COLOR) hold indices into a colour table, not \
                 intensities"
                    .into(),
            ),
            (s, p) => Some(format!(
                "photometric interpretation {:?} with {s} samples per pixel",
                p.chars().take(24).collect::<String>()
            )),
        }
    }
}

/// The pixel format `obj` states.
pub(super) fn pixel_format(obj: &InMemDicomObject) -> PixelFormat {
    let allocated = uint(obj, tags::BITS_ALLOCATED).unwrap_or(0);
    PixelFormat {
        rows: uint(obj, tags::ROWS).unwrap_or(0),
        cols: uint(obj, tags::COLUMNS).unwrap_or(0),
        allocated,
        stored: uint(obj, tags::BITS_STORED).unwrap_or(allocated),
        signed: uint(obj, tags::PIXEL_REPRESENTATION) == Some(1),
        samples: uint(obj, tags::SAMPLES_PER_PIXEL).unwrap_or(1),
        planar: uint(obj, tags::PLANAR_CONFIGURATION) == Some(1),
        photometric: text(obj, tags::PHOTOMETRIC_INTERPRETATION)
            .unwrap_or_else(|| "MONOCHROME2".into())
            .to_ascii_uppercase(),
        frames: int(obj, tags::NUMBER_OF_FRAMES)
            .and_then(|n| u32::try_from(n).ok())
            .filter(|&n| n > 0)
            .unwrap_or(1),
    }
}
