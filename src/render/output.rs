//! A finished render: the image with its camera and depth, and the formats pictures are written
//! in (PNG, JPEG), with the pasting that sheets and slices build on.

use tiny_skia::Pixmap;

use super::Camera;
use crate::error::{Error, Result};

/// A rendered image and the camera that made it.
pub struct Image {
    /// RGBA pixels (opaque, so premultiplied equals straight).
    pub pixmap: Pixmap,
    /// The camera, to project world points into the image.
    pub camera: Camera,
    /// Per pixel, row by row: how far along its ray the image turns half opaque, mm (infinite
    /// where it never does), to tell what is in front of what.
    pub depth: Vec<f32>,
    /// The colour window the transfer function used.
    pub window: (f32, f32),
    /// The pyramid level the render read (0: every voxel; docs/design.md §5).
    pub pyramid_level: usize,
}

impl Image {
    /// The image as PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>> {
        encode(&self.pixmap, ImageOutput::Png)
    }

    /// The image encoded as `format` asks.
    pub fn encode(&self, format: ImageOutput) -> Result<Vec<u8>> {
        encode(&self.pixmap, format)
    }
}

/// `pixmap` (opaque) encoded as `format` asks.
pub fn encode(pixmap: &Pixmap, format: ImageOutput) -> Result<Vec<u8>> {
    match format {
        ImageOutput::Png => pixmap
            .encode_png()
            .map_err(|e| Error::Encode(format!("PNG: {e}"))),
        ImageOutput::Jpeg => {
            let rgb: Vec<u8> = pixmap
                .data()
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            let mut out = Vec::new();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, JPEG_QUALITY)
                .encode(
                    &rgb,
                    pixmap.width(),
                    pixmap.height(),
                    image::ExtendedColorType::Rgb8,
                )
                .map_err(|e| Error::Encode(format!("JPEG: {e}")))?;
            Ok(out)
        }
    }
}

/// Draws `image` centred in the area `(x, y, width, height)` of `canvas` (its top left within the
/// area when it is larger); returns where its top left went.
pub fn paste_centred(
    canvas: &mut Pixmap,
    image: &Pixmap,
    (x, y, width, height): (u32, u32, u32, u32),
) -> (u32, u32) {
    let at = (
        x + width.saturating_sub(image.width()) / 2,
        y + height.saturating_sub(image.height()) / 2,
    );
    canvas.draw_pixmap(
        at.0 as i32,
        at.1 as i32,
        image.as_ref(),
        &tiny_skia::PixmapPaint::default(),
        tiny_skia::Transform::identity(),
        None,
    );
    at
}

/// JPEG quality of [`ImageOutput::Jpeg`]: high, as a picture for a report should be.
const JPEG_QUALITY: u8 = 92;

/// The image formats renders are written in, chosen by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageOutput {
    /// `.png`: lossless.
    Png,
    /// `.jpg` or `.jpeg`.
    Jpeg,
}

impl ImageOutput {
    /// The format the name of `path` asks for; an unknown extension is an error, found before
    /// any work is done.
    pub fn for_path(path: &std::path::Path) -> Result<Self> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("jpg" | "jpeg") => Ok(Self::Jpeg),
            _ => Err(Error::unsupported(
                path,
                "pictures are written as .png, .jpg or .jpeg, chosen by the extension",
            )),
        }
    }
}
