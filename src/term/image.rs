//! Images for the terminal: an RGBA picture encoded for the protocol the terminal speaks (sixel,
//! iTerm2, kitty, or half-blocks), wrapped for tmux where needed, and placed in a ratatui buffer.
//!
//! An escape-sequence image rides in the first cell of its area (which ratatui then writes as
//! one character wide); the other cells are skipped, so ratatui never writes over the picture.
//! A new picture changes the first cell, so ratatui sends it; an unchanged one is not sent
//! again. Sixel and iTerm2 pictures are opaque and cover their whole area, so nothing is erased
//! before them (erasing first flashes the terminal's background for a frame).

use std::fmt::Write as _;
use std::num::NonZeroU16;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use image::RgbaImage;
use ratatui::buffer::{Buffer, CellDiffOption};
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::widgets::Widget;

use super::{Caps, Graphics, tmux};

/// The kitty image id slabscope draws with.
pub const KITTY_ID: u32 = 7_215_019;

/// Bytes of base64 per kitty chunk (the protocol's limit).
const KITTY_CHUNK: usize = 4096;

/// A picture ready for the terminal.
#[derive(Clone, Debug, PartialEq)]
pub struct TermImage {
    payload: Payload,
    /// The cells it covers, `(columns, rows)`.
    pub cells: (u16, u16),
    /// The bytes it sends to the terminal.
    pub bytes: usize,
}

#[derive(Clone, Debug, PartialEq)]
enum Payload {
    /// Per cell, the colours of its upper and lower half.
    Blocks(Vec<(Color, Color)>),
    /// One escape sequence that draws the picture at the cursor.
    Escape(String),
}

/// Encodes `image` to cover `cells` on a terminal with `caps`. For half-blocks the image must be
/// `cells.0 × 2·cells.1` pixels; for the others it is drawn at its own size from the area's
/// top-left corner.
pub fn encode(image: &RgbaImage, cells: (u16, u16), caps: &Caps) -> Result<TermImage, String> {
    encode_as(image, cells, caps, KITTY_ID)
}

/// [`encode`], a kitty picture with the image id `kitty_id` (a picture of its own, which neither
/// replaces nor is replaced by one of another id).
pub fn encode_as(
    image: &RgbaImage,
    cells: (u16, u16),
    caps: &Caps,
    kitty_id: u32,
) -> Result<TermImage, String> {
    let seq = match caps.graphics {
        Graphics::Blocks => return Ok(blocks(image, cells)),
        Graphics::Sixel => sixel(image, caps.colors)?,
        Graphics::Iterm => iterm(image)?,
        Graphics::Kitty => kitty(image, caps.tmux, kitty_id),
    };
    let seq = match caps.graphics {
        // kitty's chunks are wrapped one by one.
        Graphics::Kitty => seq,
        _ if caps.tmux => tmux::wrap(&seq),
        _ => seq,
    };
    Ok(TermImage {
        bytes: seq.len(),
        payload: Payload::Escape(seq),
        cells,
    })
}

impl TermImage {
    /// The escape sequence that draws the picture at the cursor (none for half-blocks).
    pub fn sequence(&self) -> Option<&str> {
        match &self.payload {
            Payload::Escape(seq) => Some(seq),
            Payload::Blocks(_) => None,
        }
    }
}

/// What takes the picture away where it is drawn as a layer of its own (kitty), for the cell
/// where it stood while something else covers its area; empty elsewhere.
pub fn hide_sequence(caps: &Caps) -> String {
    match caps.graphics {
        Graphics::Kitty => {
            let seq = format!("\x1b_Ga=d,d=I,i={KITTY_ID},q=2\x1b\\");
            if caps.tmux { tmux::wrap(&seq) } else { seq }
        }
        _ => String::new(),
    }
}

fn blocks(image: &RgbaImage, (cols, rows): (u16, u16)) -> TermImage {
    let pixel = |x: u32, y: u32| {
        image
            .get_pixel_checked(x, y)
            .map_or(Color::Reset, |p| Color::Rgb(p[0], p[1], p[2]))
    };
    let cells = (0..u32::from(rows))
        .flat_map(|r| (0..u32::from(cols)).map(move |c| (c, r)))
        .map(|(c, r)| (pixel(c, 2 * r), pixel(c, 2 * r + 1)))
        .collect();
    TermImage {
        payload: Payload::Blocks(cells),
        cells: (cols, rows),
        bytes: usize::from(cols) * usize::from(rows) * 40,
    }
}

fn sixel(image: &RgbaImage, colors: u16) -> Result<String, String> {
    let options = icy_sixel::EncodeOptions {
        max_colors: colors.min(256),
        ..icy_sixel::EncodeOptions::default()
    };
    #[allow(deprecated)]
    icy_sixel::sixel_encode(
        image.as_raw(),
        image.width() as usize,
        image.height() as usize,
        &options,
    )
    .map_err(|e| format!("sixel encoding failed: {e}"))
}

fn png(image: &RgbaImage) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new_with_quality(
        &mut out,
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::Adaptive,
    )
    .write_image(
        image.as_raw(),
        image.width(),
        image.height(),
        image::ExtendedColorType::Rgba8,
    )
    .map_err(|e| format!("PNG encoding failed: {e}"))?;
    Ok(out)
}

use image::ImageEncoder as _;

fn iterm(image: &RgbaImage) -> Result<String, String> {
    let png = png(image)?;
    Ok(format!(
        "\x1b]1337;File=inline=1;size={};width={}px;height={}px;preserveAspectRatio=0;doNotMoveCursor=1:{}\x07",
        png.len(),
        image.width(),
        image.height(),
        BASE64.encode(&png)
    ))
}

/// kitty: the previous picture deleted, the new one sent in chunks of zlib-compressed RGBA and
/// placed at the cursor without moving it. Each chunk is its own passthrough inside tmux.
fn kitty(image: &RgbaImage, in_tmux: bool, id: u32) -> String {
    let data = BASE64.encode(zlib(image.as_raw()));
    let chunks: Vec<&str> = data
        .as_bytes()
        .chunks(KITTY_CHUNK)
        .map(|c| std::str::from_utf8(c).unwrap_or_default())
        .collect();
    let wrap = |s: String| if in_tmux { tmux::wrap(&s) } else { s };
    let mut out = wrap(format!("\x1b_Ga=d,d=I,i={id},q=2\x1b\\"));
    for (i, chunk) in chunks.iter().enumerate() {
        let more = u8::from(i + 1 < chunks.len());
        let mut seq = String::from("\x1b_G");
        if i == 0 {
            let _ = write!(
                seq,
                "a=T,f=32,o=z,i={id},s={},v={},C=1,q=2,",
                image.width(),
                image.height()
            );
        }
        let _ = write!(seq, "m={more};{chunk}\x1b\\");
        out.push_str(&wrap(seq));
    }
    out
}

fn zlib(raw: &[u8]) -> Vec<u8> {
    use std::io::Write as _;
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    let _ = z.write_all(raw);
    z.finish().unwrap_or_default()
}

/// Writes `seq` (a [`hide_sequence`]) into the first cell of `area`, which then takes one column
/// as a blank would, so that the rest of the area is drawn as usual.
pub fn hide(seq: &str, area: Rect, buf: &mut Buffer) {
    if let Some(cell) = buf.cell_mut((area.x, area.y)) {
        cell.set_symbol(&format!("{seq} "))
            .set_diff_option(ONE_WIDE);
    }
}

/// One character wide, whatever the symbol's text: the first cell of an escape-sequence image.
const ONE_WIDE: CellDiffOption = CellDiffOption::ForcedWidth(NonZeroU16::MIN);

impl Widget for &TermImage {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let (cols, rows) = (self.cells.0.min(area.width), self.cells.1.min(area.height));
        match &self.payload {
            Payload::Blocks(colors) => {
                for r in 0..rows {
                    for c in 0..cols {
                        let (top, bottom) =
                            colors[usize::from(r) * usize::from(self.cells.0) + usize::from(c)];
                        if let Some(cell) = buf.cell_mut((area.x + c, area.y + r)) {
                            cell.set_char('▀').set_fg(top).set_bg(bottom);
                        }
                    }
                }
            }
            Payload::Escape(seq) => {
                if cols < self.cells.0 || rows < self.cells.1 {
                    // Cut off, it would be drawn over whatever lies beyond the area.
                    return;
                }
                for r in 0..rows {
                    for c in 0..cols {
                        if let Some(cell) = buf.cell_mut((area.x + c, area.y + r)) {
                            if (c, r) == (0, 0) {
                                cell.set_symbol(seq).set_diff_option(ONE_WIDE);
                            } else {
                                cell.set_diff_option(CellDiffOption::Skip);
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use image::Rgba;

    use super::*;

    fn gradient(w: u32, h: u32) -> RgbaImage {
        RgbaImage::from_fn(w, h, |x, y| Rgba([(x * 9) as u8, (y * 7) as u8, 90, 255]))
    }

    fn caps(graphics: Graphics, tmux: bool) -> Caps {
        Caps {
            graphics,
            tmux,
            ..Caps::blocks()
        }
    }

    #[test]
    fn a_sixel_in_tmux_has_no_lone_escape_inside_the_passthrough() {
        let img = encode(&gradient(16, 12), (2, 1), &caps(Graphics::Sixel, true)).unwrap();
        let Payload::Escape(seq) = &img.payload else {
            panic!()
        };
        assert!(seq.starts_with("\x1bPtmux;\x1b\x1bP") && seq.ends_with("\x1b\x1b\\\x1b\\"));
        let body = &seq[7..seq.len() - 2];
        assert!(!body.replace("\x1b\x1b", "").contains('\x1b'));
        assert_eq!(img.bytes, seq.len());
    }

    #[test]
    fn kitty_sends_chunks_each_wrapped_in_tmux() {
        let big = RgbaImage::from_fn(300, 200, |x, y| {
            Rgba([
                (x * 31 % 251) as u8,
                (y * 17 % 241) as u8,
                ((x * y) % 239) as u8,
                255,
            ])
        });
        let plain = kitty(&big, false, KITTY_ID);
        let chunks = plain.matches("\x1b_G").count();
        assert!(chunks > 2, "{chunks}");
        assert!(plain.starts_with(&format!("\x1b_Ga=d,d=I,i={KITTY_ID}")));
        assert!(plain.contains("a=T,f=32,o=z,") && plain.contains(",C=1,"));
        assert_eq!(plain.matches("m=0;").count(), 1, "one last chunk");
        let wrapped = kitty(&big, true, KITTY_ID);
        assert_eq!(wrapped.matches("\x1bPtmux;").count(), chunks);
        // The base64 inside reassembles into the zlib stream of the pixels.
        let data: String = plain
            .split("\x1b_G")
            .filter_map(|c| c.split_once(';').map(|(_, d)| d.trim_end_matches("\x1b\\")))
            .collect();
        let z = BASE64.decode(data).unwrap();
        let mut raw = Vec::new();
        std::io::Read::read_to_end(&mut flate2::read::ZlibDecoder::new(&z[..]), &mut raw).unwrap();
        assert_eq!(raw, big.into_raw());
    }

    #[test]
    fn iterm_sends_the_png_and_its_size() {
        let img = encode(&gradient(20, 10), (2, 1), &caps(Graphics::Iterm, false)).unwrap();
        let Payload::Escape(seq) = &img.payload else {
            panic!()
        };
        assert!(seq.starts_with("\x1b]1337;File=inline=1;size="));
        assert!(seq.contains(";width=20px;height=10px;") && seq.ends_with('\x07'));
    }

    #[test]
    fn escape_images_ride_in_the_first_cell_and_skip_the_rest() {
        let img = encode(&gradient(16, 12), (4, 2), &caps(Graphics::Sixel, false)).unwrap();
        let mut buf = Buffer::empty(Rect::new(0, 0, 6, 3));
        (&img).render(Rect::new(1, 1, 5, 2), &mut buf);
        assert!(buf[(1, 1)].symbol().starts_with("\x1bP"));
        assert_eq!(buf[(2, 1)].diff_option, CellDiffOption::Skip);
        assert_eq!(buf[(4, 2)].diff_option, CellDiffOption::Skip);
        assert_eq!(
            buf[(5, 2)].diff_option,
            CellDiffOption::None,
            "outside the image"
        );
        let mut small = Buffer::empty(Rect::new(0, 0, 3, 3));
        (&img).render(small.area, &mut small);
        assert_eq!(small[(0, 0)].symbol(), " ", "a cut-off sixel is not drawn");
    }

    #[test]
    fn half_blocks_show_two_pixels_a_cell() {
        let img = encode(&gradient(3, 4), (3, 2), &Caps::blocks()).unwrap();
        let mut buf = Buffer::empty(Rect::new(0, 0, 3, 2));
        (&img).render(buf.area, &mut buf);
        let c = &buf[(2, 1)];
        assert_eq!(c.symbol(), "▀");
        assert_eq!(
            (c.fg, c.bg),
            (Color::Rgb(18, 14, 90), Color::Rgb(18, 21, 90))
        );
    }
}
