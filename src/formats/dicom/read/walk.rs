//! The element walk: every element header of a data set read in the file's own byte order and
//! VR encoding, each declared length checked against what encloses it and the bytes that are
//! really there, and everything kept charged to a budget.

use std::io::{BufReader, Read};
use std::path::Path;

use dicom_core::Tag;

use super::syntax::{dictionary_sequence, is_vr, known_vr, long_length, text_vr};
use crate::error::Error;

/// How deep sequences may nest: real files nest a few levels (enhanced multi-frame: three).
pub(super) const MAX_NESTING: usize = 32;

/// Bytes charged per element on top of its value: what the parsed element costs in memory.
pub(super) const ELEMENT_COST: u64 = 96;

/// Bytes charged per value of a multi-valued text element (each becomes its own string).
pub(super) const VALUE_COST: u64 = 40;

/// The largest file meta group read.
const MAX_META: u64 = 1 << 16;

const PIXEL_DATA: Tag = Tag(0x7FE0, 0x0010);
pub(super) const ITEM: Tag = Tag(0xFFFE, 0xE000);
const ITEM_END: Tag = Tag(0xFFFE, 0xE00D);
pub(super) const SEQUENCE_END: Tag = Tag(0xFFFE, 0xE0DD);
pub(super) const UNDEFINED: u32 = u32::MAX;

/// What went wrong in a walk, before it is tied to its file.
#[derive(Debug)]
pub(super) enum Fault {
    /// Reading the file failed.
    Io(std::io::Error),
    /// The bytes break the standard, as the message says.
    Format(String),
    /// What would be kept (the first number) is over the budget (the second).
    TooLarge(u64, u64),
}

impl Fault {
    /// The error this fault is, in the file at `path`.
    pub(super) fn into_error(self, path: &Path) -> Error {
        match self {
            Self::Io(e) => Error::io(path, e),
            Self::Format(m) => Error::format(path, m),
            Self::TooLarge(needed, limit) => Error::TooLarge {
                path: path.to_path_buf(),
                what: "its DICOM header".into(),
                needed,
                limit,
                machine: false,
                disk: false,
            },
        }
    }
}

/// What a step of the walk gives, or its fault.
pub(super) type Walked<T> = std::result::Result<T, Fault>;

/// A format fault with `message`.
pub(super) fn bad<T>(message: impl Into<String>) -> Walked<T> {
    Err(Fault::Format(message.into()))
}

/// An open sequence or item during the walk.
#[derive(Clone, Copy, Debug)]
struct Open {
    /// Where it ends (`None`: at its delimiter).
    end: Option<u64>,
    /// A sequence (holding items) or an item (holding elements).
    sequence: bool,
    /// Whether the elements inside are explicit VR (an undefined-length UN holds implicit ones).
    explicit: bool,
}

/// An element or item whose tag the walk has just kept: the tag, the byte it starts at, and
/// where what holds it ends (its value may not run past that).
#[derive(Clone, Copy, Debug)]
struct Reached {
    tag: Tag,
    at: u64,
    limit: u64,
}

/// A walk over the bytes of one file (or its inflated data set): where it is, what it has kept,
/// and what that has cost.
pub(super) struct Walk<R> {
    /// Where the bytes come from.
    pub(super) reader: BufReader<R>,
    /// Bytes read from `reader` to look at but not yet taken.
    pub(super) ahead: Vec<u8>,
    /// Bytes taken so far.
    pub(super) pos: u64,
    /// How many bytes there are (`u64::MAX`: unknown, as in an inflated stream).
    pub(super) len: u64,
    budget: u64,
    spent: u64,
    /// The data set's bytes kept so far.
    pub(super) kept: Vec<u8>,
}

impl<R: Read> Walk<R> {
    /// A walk from the start of `reader`, which holds `len` bytes, keeping at most `budget`.
    pub(super) fn new(reader: BufReader<R>, len: u64, budget: u64) -> Self {
        Self {
            reader,
            ahead: Vec::new(),
            pos: 0,
            len,
            budget,
            spent: 0,
            kept: Vec::new(),
        }
    }

    /// Copies the next bytes into `buf` without taking them: as many as there are, up to its
    /// length.
    pub(super) fn peek_into(&mut self, buf: &mut [u8]) -> Walked<usize> {
        while self.ahead.len() < buf.len() {
            let mut more = [0u8; 16];
            let want = (buf.len() - self.ahead.len()).min(more.len());
            match self.reader.read(&mut more[..want]) {
                Ok(0) => break,
                Ok(n) => self.ahead.extend_from_slice(&more[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(Fault::Io(e)),
            }
        }
        let n = self.ahead.len().min(buf.len());
        buf[..n].copy_from_slice(&self.ahead[..n]);
        Ok(n)
    }

    /// Takes `n` bytes into `out` (`None`: skips them), growing it only as the bytes arrive;
    /// returns how many there were.
    fn take(&mut self, n: u64, out: Option<&mut Vec<u8>>) -> Walked<u64> {
        let early = (self.ahead.len() as u64).min(n) as usize;
        let mut rest = (&mut self.reader).take(n - early as u64);
        let got = if let Some(out) = out {
            out.extend(self.ahead.drain(..early));
            rest.read_to_end(out).map_err(Fault::Io)? as u64
        } else {
            self.ahead.drain(..early);
            std::io::copy(&mut rest, &mut std::io::sink()).map_err(Fault::Io)?
        } + early as u64;
        self.pos += got;
        Ok(got)
    }

    /// Skips `n` bytes of the header; the file ending first is an error.
    pub(super) fn skip(&mut self, n: u64) -> Walked<()> {
        if self.take(n, None)? < n {
            return bad(format!("file ends inside its header at byte {}", self.pos));
        }
        Ok(())
    }

    /// Charges `bytes` to the budget; going over it is an error.
    pub(super) fn charge(&mut self, bytes: u64) -> Walked<()> {
        self.spent = self.spent.saturating_add(bytes);
        if self.spent > self.budget {
            return Err(Fault::TooLarge(self.spent, self.budget));
        }
        Ok(())
    }

    /// Reads exactly `n` bytes into `out`: `Ok(false)` when the file ended first.
    pub(super) fn take_into(&mut self, n: u64, out: &mut Vec<u8>) -> Walked<bool> {
        Ok(self.take(n, Some(out))? == n)
    }

    /// Reads `n` bytes into the kept data set; the file ending first is an error.
    pub(super) fn keep(&mut self, n: u64, what: &str) -> Walked<()> {
        let mut kept = std::mem::take(&mut self.kept);
        let whole = self.take_into(n, &mut kept);
        self.kept = kept;
        if !whole? {
            return bad(format!("file ends inside {what}"));
        }
        Ok(())
    }

    /// The last `n` bytes kept.
    pub(super) fn last(&self, n: usize) -> &[u8] {
        &self.kept[self.kept.len() - n..]
    }

    /// The file meta group (explicit VR little endian, group 2): its transfer syntax UID, if it
    /// states one.
    pub(super) fn meta(&mut self) -> Walked<Option<String>> {
        let start = self.kept.len();
        let mut uid = None;
        loop {
            let mut peek = [0u8; 8];
            if self.peek_into(&mut peek)? < 8 || peek[..2] != [2, 0] {
                break;
            }
            if self.pos >= MAX_META {
                return bad(format!("file meta group longer than {MAX_META} bytes"));
            }
            self.keep(6, "the file meta group")?;
            let h = self.last(6);
            let element = u16::from_le_bytes([h[2], h[3]]);
            let vr = [h[4], h[5]];
            if !is_vr(&vr) {
                return bad("file meta group is not explicit VR");
            }
            let len = if long_length(vr) {
                self.keep(6, "the file meta group")?;
                let h = self.last(4);
                u32::from_le_bytes([h[0], h[1], h[2], h[3]])
            } else {
                self.keep(2, "the file meta group")?;
                let h = self.last(2);
                u32::from(u16::from_le_bytes([h[0], h[1]]))
            };
            if u64::from(len) > MAX_META {
                return bad(format!(
                    "file meta element (0002,{element:04X}) claims {len} bytes"
                ));
            }
            let at = self.kept.len();
            self.keep(u64::from(len), "the file meta group")?;
            if element == 0x0010 {
                let text = String::from_utf8_lossy(&self.kept[at..]);
                let text = text.trim_end_matches(['\0', ' ']);
                // Quoted in messages, so checked first: a UID is at most 64 digits and dots.
                if text.len() > 64 || !text.chars().all(|c| c.is_ascii_digit() || c == '.') {
                    return bad("the transfer syntax in the file meta group is not a UID");
                }
                uid = Some(text.to_string());
            }
        }
        self.kept.truncate(start);
        Ok(uid.filter(|u| !u.is_empty()))
    }

    /// Walks the data set, keeping it, up to the top-level pixel data (its header left unread:
    /// `Ok(true)`) or its end (`Ok(false)`).
    pub(super) fn dataset(&mut self, explicit: bool, big: bool) -> Walked<bool> {
        let mut open: Vec<Open> = Vec::new();
        loop {
            self.close_ended(&mut open)?;
            let explicit_here = open.last().map_or(explicit, |o| o.explicit);
            let mut tag = [0u8; 4];
            let got = self.peek_into(&mut tag)?;
            if got == 0 && open.is_empty() {
                return Ok(false);
            }
            if got < 4 {
                return bad(format!(
                    "file ends inside an element header at byte {}",
                    self.pos
                ));
            }
            let tag = Tag(u16_at(&tag[..2], big), u16_at(&tag[2..], big));
            if open.is_empty() && tag == PIXEL_DATA {
                return Ok(true);
            }
            let at = self.pos;
            self.charge(ELEMENT_COST)?;
            self.keep(4, "an element header")?;
            let limit = open.iter().filter_map(|o| o.end).min().unwrap_or(self.len);
            let reached = Reached { tag, at, limit };
            if tag.0 == 0xFFFE {
                self.item_tag(reached, big, &mut open)?;
            } else {
                self.element(reached, explicit_here, big, &mut open)?;
            }
        }
    }

    /// Closes the sequences and items of defined length that end here; one that ended before
    /// here had an element run past it.
    fn close_ended(&self, open: &mut Vec<Open>) -> Walked<()> {
        while let Some(top) = open.last() {
            match top.end {
                Some(end) if self.pos == end => {
                    open.pop();
                }
                Some(end) if self.pos > end => {
                    return bad(format!(
                        "an element runs past the end of its sequence or item at byte {end}"
                    ));
                }
                _ => break,
            }
        }
        Ok(())
    }

    /// Reads the rest of an item, item delimiter or sequence delimiter, opening or closing
    /// what it opens or closes; one where none belongs is an error.
    fn item_tag(&mut self, reached: Reached, big: bool, open: &mut Vec<Open>) -> Walked<()> {
        let Reached { tag, at, limit } = reached;
        self.keep(4, "an item header")?;
        let len = u32_at(self.last(4), big);
        match (tag, open.last().copied()) {
            (ITEM, Some(o)) if o.sequence => {
                let end = self.end_of(len, limit, tag)?;
                open.push(Open {
                    end,
                    sequence: false,
                    explicit: o.explicit,
                });
            }
            (ITEM_END, Some(o)) if !o.sequence && o.end.is_none() => {
                open.pop();
            }
            (SEQUENCE_END, Some(o)) if o.sequence && o.end.is_none() => {
                open.pop();
            }
            _ => {
                return bad(format!(
                    "misplaced item tag ({:04X},{:04X}) at byte {at}",
                    tag.0, tag.1
                ));
            }
        }
        Ok(())
    }

    /// Reads the rest of an element (its header `explicit` VR or not): a sequence is opened,
    /// nested encapsulated pixel data skipped, any other value kept.
    fn element(
        &mut self,
        reached: Reached,
        explicit: bool,
        big: bool,
        open: &mut Vec<Open>,
    ) -> Walked<()> {
        let Reached { tag, at, limit } = reached;
        if open.last().is_some_and(|o| o.sequence) {
            return bad(format!(
                "element ({:04X},{:04X}) at byte {at} is in a sequence but not in an item",
                tag.0, tag.1
            ));
        }
        let (vr, len) = self.element_header(explicit, big)?;
        let sequence = match vr {
            Some(vr) => &vr == b"SQ" || (&vr == b"UN" && len == UNDEFINED),
            None => len == UNDEFINED || dictionary_sequence(tag),
        };
        if open.len() >= MAX_NESTING {
            return bad(format!("sequences nest deeper than {MAX_NESTING}"));
        }
        if tag == PIXEL_DATA && len == UNDEFINED {
            // Encapsulated pixel data in a nested item (an icon): its fragments are
            // values, not elements.
            self.nested_fragments(big)?;
        } else if sequence {
            let end = self.end_of(len, limit, tag)?;
            // An undefined-length UN holds implicit VR little endian elements.
            let explicit = explicit && vr.is_some_and(|v| &v == b"SQ");
            open.push(Open {
                end,
                sequence: true,
                explicit,
            });
        } else if len == UNDEFINED {
            return bad(format!(
                "element ({:04X},{:04X}) at byte {at} has an undefined length",
                tag.0, tag.1
            ));
        } else {
            self.end_of(len, limit, tag)?;
            self.value(u64::from(len), vr.is_none_or(text_vr))?;
        }
        Ok(())
    }

    /// The VR (when explicit) and the length of the element whose tag was just kept.
    fn element_header(&mut self, explicit: bool, big: bool) -> Walked<(Option<[u8; 2]>, u32)> {
        if !explicit {
            self.keep(4, "an element header")?;
            return Ok((None, u32_at(self.last(4), big)));
        }
        self.keep(2, "an element header")?;
        // An unknown VR is read as UN, as dicom-parser reads it.
        let mut vr = [self.last(2)[0], self.last(2)[1]];
        if !known_vr(vr) {
            vr = *b"UN";
        }
        if long_length(vr) {
            self.keep(6, "an element header")?;
            Ok((Some(vr), u32_at(self.last(4), big)))
        } else {
            self.keep(2, "an element header")?;
            Ok((Some(vr), u32::from(u16_at(self.last(2), big))))
        }
    }

    /// Where a value of `len` bytes starting here ends, checked against the end of what holds
    /// it (`None`: undefined length).
    pub(super) fn end_of(&self, len: u32, limit: u64, tag: Tag) -> Walked<Option<u64>> {
        if len == UNDEFINED {
            return Ok(None);
        }
        let end = self.pos + u64::from(len);
        if end > limit {
            let left = limit.saturating_sub(self.pos);
            return bad(format!(
                "element ({:04X},{:04X}) at byte {} claims {len} bytes where {left} are left",
                tag.0,
                tag.1,
                self.pos.saturating_sub(8)
            ));
        }
        Ok(Some(end))
    }
}

/// The `u16` at the start of `b`, in the byte order `big` says.
pub(super) fn u16_at(b: &[u8], big: bool) -> u16 {
    let a = [b[0], b[1]];
    if big {
        u16::from_be_bytes(a)
    } else {
        u16::from_le_bytes(a)
    }
}

/// The `u32` at the start of `b`, in the byte order `big` says.
pub(super) fn u32_at(b: &[u8], big: bool) -> u32 {
    let a = [b[0], b[1], b[2], b[3]];
    if big {
        u32::from_be_bytes(a)
    } else {
        u32::from_le_bytes(a)
    }
}
