//! The value readers: what the walk does once it has reached a value (an element's, or the
//! pixel data's), each read only as far as the bytes really there and the budget allow.

use std::io::Read;

use dicom_core::Tag;

use super::Pixels;
use super::syntax::long_length;
use super::walk::{
    ELEMENT_COST, ITEM, SEQUENCE_END, UNDEFINED, VALUE_COST, Walk, Walked, bad, u16_at, u32_at,
};

impl<R: Read> Walk<R> {
    /// Keeps a value of `len` bytes, charged with what it costs parsed (a text value's every
    /// part becomes a string of its own).
    pub(super) fn value(&mut self, len: u64, text: bool) -> Walked<()> {
        let start = self.kept.len();
        self.charge(len)?;
        self.keep(len, "an element value")?;
        if text {
            #[allow(clippy::naive_bytecount)] // a header's few values
            let values = self.kept[start..].iter().filter(|&&b| b == b'\\').count();
            self.charge(values as u64 * VALUE_COST)?;
        }
        Ok(())
    }

    /// Skips (keeping) the fragments of encapsulated pixel data nested in an item.
    pub(super) fn nested_fragments(&mut self, big: bool) -> Walked<()> {
        loop {
            self.keep(8, "an item header")?;
            let h = self.last(8).to_vec();
            let tag = Tag(u16_at(&h[..2], big), u16_at(&h[2..4], big));
            let len = u32_at(&h[4..], big);
            match tag {
                SEQUENCE_END => return Ok(()),
                ITEM if len != UNDEFINED => {
                    self.end_of(len, self.len, tag)?;
                    self.charge(u64::from(len))?;
                    self.keep(u64::from(len), "a pixel data fragment")?;
                }
                _ => return bad("malformed encapsulated pixel data"),
            }
        }
    }

    /// Reads the header of the top-level pixel data element: its VR (when explicit) and length.
    fn pixel_header(&mut self, explicit: bool, big: bool) -> Walked<u32> {
        let mut h = Vec::new();
        let n = if explicit { 12 } else { 8 };
        if !self.take_into(n, &mut h)? {
            return bad("file ends inside the pixel data header");
        }
        let len = if explicit {
            if long_length([h[4], h[5]]) {
                u32_at(&h[8..12], big)
            } else {
                let short = u32::from(u16_at(&h[6..8], big));
                return bad(format!(
                    "pixel data with VR {}{} and a short length ({short})",
                    h[4] as char, h[5] as char
                ));
            }
        } else {
            u32_at(&h[4..8], big)
        };
        Ok(len)
    }

    /// The fragments of the encapsulated pixel data that starts here.
    pub(super) fn fragments(&mut self, explicit: bool) -> Walked<Pixels> {
        let len = self.pixel_header(explicit, false)?;
        if len != UNDEFINED {
            return bad("encapsulated pixel data with a defined length");
        }
        let mut table = Vec::new();
        let mut fragments = Vec::new();
        let mut first = true;
        loop {
            let mut h = Vec::new();
            if !self.take_into(8, &mut h)? {
                return bad("file ends inside the pixel data");
            }
            let tag = Tag(u16_at(&h[..2], false), u16_at(&h[2..4], false));
            let len = u32_at(&h[4..], false);
            match tag {
                SEQUENCE_END => break,
                ITEM if len != UNDEFINED => {
                    self.end_of(len, self.len, tag)?;
                    self.charge(u64::from(len) + ELEMENT_COST)?;
                    let mut value = Vec::new();
                    if !self.take_into(u64::from(len), &mut value)? {
                        return bad("file ends inside a pixel data fragment");
                    }
                    if first {
                        table = value
                            .chunks_exact(4)
                            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                            .collect();
                    } else {
                        fragments.push(value);
                    }
                    first = false;
                }
                _ => return bad("malformed encapsulated pixel data"),
            }
        }
        Ok(Pixels::Fragments(table, fragments))
    }

    /// Native pixel data that starts here: where it is in the file.
    pub(super) fn native_at(&mut self, explicit: bool, big: bool) -> Walked<Pixels> {
        let len = self.pixel_header(explicit, big)?;
        if len == UNDEFINED {
            return bad("native pixel data with an undefined length");
        }
        Ok(Pixels::Native {
            offset: self.pos,
            len: u64::from(len),
        })
    }

    /// Native pixel data that starts here, read into memory (bounded by the budget).
    pub(super) fn native_in_memory(&mut self) -> Walked<Pixels> {
        let len = self.pixel_header(true, false)?;
        if len == UNDEFINED {
            return bad("native pixel data with an undefined length");
        }
        self.charge(u64::from(len))?;
        let mut data = Vec::new();
        self.take_into(u64::from(len), &mut data)?;
        Ok(Pixels::Inflated(data))
    }
}
