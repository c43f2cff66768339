//! The folder pane's thumbnails drawn with the image protocol in use (sixel, kitty, iTerm2): a
//! column beside the table with each shown row's thumbnail on its own line (one cell high, twice
//! as wide as high in pixels, as the contact-sheet cell triage draws is), and the cursor's large
//! beside it where the pane is wide. Both are one picture, put together from the rows' cells and
//! encoded once for the terminal each time what it shows changes (the rows shown, their order,
//! a thumbnail come in, the cursor), so that scrolling or sorting sends one image and leaves
//! nothing of the last behind. Half-blocks draw no row thumbnails (a row would be two pixels
//! high): the pane shows the cursor's large in half-blocks instead.

use std::cell::RefCell;

use image::imageops::{FilterType, overlay, resize};
use image::{Rgba, RgbaImage};
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::widgets::Widget;

use crate::term::image::{TermImage, encode_as, hide};
use crate::term::{Caps, Graphics};

/// The kitty image id of the thumbnails (the preview has its own, so neither deletes the other).
pub const KITTY_THUMBS_ID: u32 = 7_215_020;

/// The picture's background where there is no thumbnail (the contact sheet's).
const BACKGROUND: Rgba<u8> = Rgba([12, 12, 18, 255]);

/// What the thumbnails' picture shows: a new one is encoded when this changes.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Shown {
    area: Rect,
    /// Per line of the column: the volume whose thumbnail it shows, if it has one.
    rows: Vec<Option<usize>>,
    /// The volume whose thumbnail shows large, and the columns it takes.
    large: Option<(usize, u16)>,
}

/// The thumbnails of a terminal that draws images.
pub struct Thumbs {
    caps: Caps,
    /// What takes the picture away (kitty draws it as a layer of its own); empty elsewhere.
    pub hide: String,
    /// What the last picture showed, and the picture (none where it could not be encoded, which
    /// is not tried again for the same).
    drawn: RefCell<Option<(Shown, Option<TermImage>)>>,
}

/// A line of the column: the volume it is, and its thumbnail if triage has drawn one.
pub type Line<'a> = (usize, Option<&'a RgbaImage>);

impl Thumbs {
    /// Thumbnails for a terminal of `caps`; none for half-blocks.
    pub fn new(caps: &Caps) -> Option<Self> {
        if caps.graphics == Graphics::Blocks {
            return None;
        }
        let hide = match caps.graphics {
            Graphics::Kitty => {
                let seq = format!("\x1b_Ga=d,d=I,i={KITTY_THUMBS_ID},q=2\x1b\\");
                if caps.tmux {
                    crate::term::tmux::wrap(&seq)
                } else {
                    seq
                }
            }
            _ => String::new(),
        };
        Some(Self {
            caps: caps.clone(),
            hide,
            drawn: RefCell::new(None),
        })
    }

    /// The columns a row's thumbnail takes: twice a cell's height in pixels, in cells.
    pub fn row_columns(&self) -> u16 {
        (2 * self.caps.cell.1).div_ceil(self.caps.cell.0.max(1))
    }

    /// The columns a large thumbnail `rows` high takes (twice as wide as high in pixels).
    pub fn large_columns(&self, rows: u16) -> u16 {
        (2 * rows * self.caps.cell.1).div_ceil(self.caps.cell.0.max(1))
    }

    /// Draws into `area`: `lines` from its second line on (the first is the table's header),
    /// and `large` (a volume and its thumbnail) at the right, `large_cols` wide. Takes the
    /// picture away instead while something covers the pane (`covered`).
    pub fn draw(
        &self,
        area: Rect,
        lines: &[Line],
        large: Option<Line>,
        large_cols: u16,
        covered: bool,
        buf: &mut Buffer,
    ) {
        if area.width == 0 || area.height == 0 {
            return;
        }
        if covered {
            *self.drawn.borrow_mut() = None;
            hide(&self.hide, area, buf);
            return;
        }
        let shown = Shown {
            area,
            rows: lines
                .iter()
                .map(|(i, t)| t.is_some().then_some(*i))
                .collect(),
            large: large.and_then(|(i, t)| t.map(|_| (i, large_cols))),
        };
        let mut drawn = self.drawn.borrow_mut();
        if drawn.as_ref().is_none_or(|(s, _)| *s != shown) {
            let cells = (area.width, area.height);
            let picture = compose(
                self.caps.image_size(cells),
                cells,
                lines,
                large.and_then(|(_, t)| t).map(|t| (t, large_cols)),
            );
            let image = encode_as(&picture, cells, &self.caps, KITTY_THUMBS_ID).ok();
            *drawn = Some((shown, image));
        }
        if let Some((_, Some(image))) = drawn.as_ref() {
            image.render(area, buf);
        }
    }
}

/// The picture of `cells` at `size` pixels: each line's thumbnail from the second line on at
/// the left, fitted to the line's height (its width following), and `large` at the right, its
/// given columns wide, fitted to the whole height; the contact sheet's background elsewhere.
pub fn compose(
    (width, height): (u32, u32),
    (cols, rows): (u16, u16),
    lines: &[Line],
    large: Option<(&RgbaImage, u16)>,
) -> RgbaImage {
    let mut out = RgbaImage::from_pixel(width.max(1), height.max(1), BACKGROUND);
    // Pixels a cell, as the terminal's largest image allows.
    let (cw, ch) = (
        f64::from(width) / f64::from(cols.max(1)),
        f64::from(height) / f64::from(rows.max(1)),
    );
    let strip = f64::from(cols.saturating_sub(large.map_or(0, |(_, c)| c + 1))) * cw;
    for (k, (_, thumbnail)) in lines.iter().enumerate() {
        let Some(t) = thumbnail else { continue };
        let y = (k as f64 + 1.0) * ch;
        if y + ch > f64::from(height) + 0.5 {
            break;
        }
        paste_fitted(&mut out, t, (0.0, y, strip, ch));
    }
    if let Some((t, c)) = large {
        let x = f64::from(cols - c) * cw;
        paste_fitted(&mut out, t, (x, 0.0, f64::from(c) * cw, f64::from(height)));
    }
    out
}

/// Pastes `image` scaled to fit the box `(x, y, w, h)` (keeping its aspect), at the box's left
/// and centred in its height.
fn paste_fitted(out: &mut RgbaImage, image: &RgbaImage, (x, y, w, h): (f64, f64, f64, f64)) {
    if image.width() == 0 || image.height() == 0 {
        return;
    }
    let scale = (w / f64::from(image.width())).min(h / f64::from(image.height()));
    let (sw, sh) = (
        (f64::from(image.width()) * scale).floor() as u32,
        (f64::from(image.height()) * scale).floor() as u32,
    );
    if sw == 0 || sh == 0 {
        return;
    }
    let scaled = resize(image, sw, sh, FilterType::Triangle);
    let top = y + (h - f64::from(sh)) / 2.0;
    overlay(out, &scaled, x.round() as i64, top.round() as i64);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plain(w: u32, h: u32, rgb: [u8; 3]) -> RgbaImage {
        RgbaImage::from_pixel(w, h, Rgba([rgb[0], rgb[1], rgb[2], 255]))
    }

    fn sixel() -> Caps {
        Caps {
            graphics: Graphics::Sixel,
            cell: (8, 16),
            ..Caps::blocks()
        }
    }

    /// 12 columns and 4 lines of 8×16 pixels: the header's line empty, each row's thumbnail
    /// (64×32, as triage draws it) fitted to its line, 32×16 at the left; the large at the
    /// right, 4 columns (32 pixels) wide, fitted to the whole height: 32×16 centred in 64.
    #[test]
    fn each_rows_thumbnail_sits_on_its_line_and_the_large_at_the_right() {
        let (red, green, blue) = (
            plain(64, 32, [255, 0, 0]),
            plain(64, 32, [0, 255, 0]),
            plain(64, 32, [0, 0, 255]),
        );
        let lines: [Line; 3] = [(4, Some(&red)), (0, None), (2, Some(&green))];
        let out = compose((96, 64), (12, 4), &lines, Some((&blue, 4)));
        assert_eq!(out.dimensions(), (96, 64));
        let at = |x, y| out.get_pixel(x, y).0;
        let back = BACKGROUND.0;
        // Line 0, the header's: nothing.
        assert_eq!(at(0, 0), back);
        // Line 1 (y 16..32): red, 32 pixels wide.
        assert_eq!(at(0, 16), [255, 0, 0, 255]);
        assert_eq!(at(31, 31), [255, 0, 0, 255]);
        assert_eq!(at(32, 20), back);
        // Line 2: a volume without a thumbnail yet.
        assert_eq!(at(5, 40), back);
        // Line 3 (y 48..64): green.
        assert_eq!(at(10, 50), [0, 255, 0, 255]);
        // The large: x 64..96, 32×16 centred in the height (y 24..40).
        assert_eq!(at(64, 24), [0, 0, 255, 255]);
        assert_eq!(at(95, 39), [0, 0, 255, 255]);
        assert_eq!(at(80, 23), back);
        assert_eq!(at(80, 40), back);
    }

    #[test]
    fn the_picture_is_encoded_again_only_when_what_it_shows_changes() {
        let thumbs = Thumbs::new(&sixel()).unwrap();
        assert_eq!(thumbs.row_columns(), 4);
        assert_eq!(thumbs.large_columns(3), 12);
        let red = plain(64, 32, [255, 0, 0]);
        let area = Rect::new(2, 1, 8, 3);
        let mut buf = Buffer::empty(Rect::new(0, 0, 12, 5));
        thumbs.draw(
            area,
            &[(0, Some(&red)), (1, None)],
            None,
            0,
            false,
            &mut buf,
        );
        let first = buf[(2, 1)].symbol().to_string();
        assert!(
            first.starts_with("\x1bP"),
            "a sixel in the area's first cell"
        );
        let sent = |t: &Thumbs| t.drawn.borrow().as_ref().map(|(s, _)| s.clone());
        let before = sent(&thumbs);
        // The same again: the same picture, not encoded anew.
        thumbs.draw(
            area,
            &[(0, Some(&red)), (1, None)],
            None,
            0,
            false,
            &mut buf,
        );
        assert_eq!(sent(&thumbs), before);
        // The rows in another order: another picture.
        thumbs.draw(
            area,
            &[(1, None), (0, Some(&red))],
            None,
            0,
            false,
            &mut buf,
        );
        assert_ne!(sent(&thumbs), before);
        assert_ne!(buf[(2, 1)].symbol(), first);
        // Covered: nothing drawn, and drawn afresh after.
        let mut covered = Buffer::empty(Rect::new(0, 0, 12, 5));
        thumbs.draw(area, &[(0, Some(&red))], None, 0, true, &mut covered);
        assert!(!covered[(2, 1)].symbol().starts_with('\x1b'));
        assert!(sent(&thumbs).is_none());
    }

    #[test]
    fn half_blocks_draw_no_row_thumbnails_and_kitty_its_own_image() {
        assert!(Thumbs::new(&Caps::blocks()).is_none());
        let kitty = Caps {
            graphics: Graphics::Kitty,
            ..sixel()
        };
        let thumbs = Thumbs::new(&kitty).unwrap();
        assert!(thumbs.hide.contains(&format!("i={KITTY_THUMBS_ID}")));
        let red = plain(64, 32, [255, 0, 0]);
        let mut buf = Buffer::empty(Rect::new(0, 0, 8, 3));
        thumbs.draw(buf.area, &[(0, Some(&red))], None, 0, false, &mut buf);
        let seq = buf[(0, 0)].symbol();
        assert!(seq.contains(&format!("i={KITTY_THUMBS_ID},")), "{seq:.60}");
        assert!(!seq.contains(&format!("i={},", crate::term::image::KITTY_ID)));
    }
}
