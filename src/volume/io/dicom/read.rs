//! Reading one DICOM file safely: a walk over every element header, in the file's own byte
//! order and VR encoding, that checks each declared length against what encloses it and the
//! bytes that are really there before a byte of it is kept. What the walk keeps is the data set
//! up to the pixel data, which dicom-object then parses from memory (it sizes its buffers by the
//! declared lengths, so it only ever sees lengths the walk has proven), and where the pixel data
//! lies.

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

use dicom_core::dictionary::{DataDictionary, DataDictionaryEntry, VirtualVr};
use dicom_core::{Tag, VR};
use dicom_dictionary_std::StandardDataDictionary;

use crate::error::{Error, Result};

/// How deep sequences may nest: real files nest a few levels (enhanced multi-frame: three).
pub(super) const MAX_NESTING: usize = 32;

/// Bytes charged per element on top of its value: what the parsed element costs in memory.
const ELEMENT_COST: u64 = 96;

/// Bytes charged per value of a multi-valued text element (each becomes its own string).
const VALUE_COST: u64 = 40;

/// The largest file meta group read.
const MAX_META: u64 = 1 << 16;

const PIXEL_DATA: Tag = Tag(0x7FE0, 0x0010);
const ITEM: Tag = Tag(0xFFFE, 0xE000);
const ITEM_END: Tag = Tag(0xFFFE, 0xE00D);
const SEQUENCE_END: Tag = Tag(0xFFFE, 0xE0DD);
const UNDEFINED: u32 = u32::MAX;

/// How a file's data set is encoded: its transfer syntax.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Syntax {
    /// The transfer syntax UID.
    pub uid: String,
    /// The data set is explicit VR (else implicit): as it is encoded, which a few writers make
    /// differ from what the UID says.
    pub explicit: bool,
    /// Big endian (the retired explicit VR big endian).
    pub big: bool,
    /// The data set after the meta group is a deflate stream.
    pub deflated: bool,
    /// The pixel data is encapsulated (compressed fragments).
    pub encapsulated: bool,
}

impl Syntax {
    /// The syntax `uid` names, or why slabscope cannot read it.
    pub fn from_uid(uid: &str) -> std::result::Result<Self, String> {
        let (explicit, big, deflated, encapsulated) = match uid {
            "1.2.840.10008.1.2" => (false, false, false, false),
            "1.2.840.10008.1.2.1" => (true, false, false, false),
            "1.2.840.10008.1.2.2" => (true, true, false, false),
            "1.2.840.10008.1.2.1.99" => (true, false, true, false),
            // JPEG baseline, extended (8 bits), lossless (process 14 and its first-order
            // prediction), RLE, encapsulated uncompressed.
            "1.2.840.10008.1.2.4.50"
            | "1.2.840.10008.1.2.4.51"
            | "1.2.840.10008.1.2.4.57"
            | "1.2.840.10008.1.2.4.70"
            | "1.2.840.10008.1.2.5"
            | "1.2.840.10008.1.2.1.98" => (true, false, false, true),
            _ => return Err(unsupported_syntax(uid)),
        };
        Ok(Self {
            uid: uid.to_string(),
            explicit,
            big,
            deflated,
            encapsulated,
        })
    }

    /// The syntax the data set is parsed in: how it is encoded (explicit little endian once
    /// inflated).
    pub fn dataset_uid(&self) -> &'static str {
        match (self.explicit, self.big) {
            (false, _) => "1.2.840.10008.1.2",
            (true, false) => "1.2.840.10008.1.2.1",
            (true, true) => "1.2.840.10008.1.2.2",
        }
    }

    /// The syntax's name, as the standard gives it.
    pub fn name(&self) -> String {
        syntax_name(&self.uid)
    }
}

/// The name of the transfer syntax `uid`, or the UID itself when unknown.
pub(super) fn syntax_name(uid: &str) -> String {
    use dicom_encoding::TransferSyntaxIndex;
    dicom_transfer_syntax_registry::TransferSyntaxRegistry
        .get(uid)
        .map_or_else(|| uid.to_string(), |ts| format!("{} ({uid})", ts.name()))
}

fn unsupported_syntax(uid: &str) -> String {
    let known = match uid {
        "1.2.840.10008.1.2.4.80" | "1.2.840.10008.1.2.4.81" => "JPEG-LS",
        "1.2.840.10008.1.2.4.90"
        | "1.2.840.10008.1.2.4.91"
        | "1.2.840.10008.1.2.4.92"
        | "1.2.840.10008.1.2.4.93" => "JPEG 2000",
        u if u.starts_with("1.2.840.10008.1.2.4.20") => "High-Throughput JPEG 2000",
        u if u.starts_with("1.2.840.10008.1.2.4.11") => "JPEG XL",
        u if u.starts_with("1.2.840.10008.1.2.4.10") => "video (MPEG or HEVC)",
        _ => "",
    };
    let name = syntax_name(uid);
    format!(
        "transfer syntax {name}{}: slabscope decodes native (uncompressed), deflated, RLE, JPEG \
         baseline, 8-bit extended and lossless JPEG",
        if known.is_empty() || name.contains(known) {
            String::new()
        } else {
            format!(", {known},")
        }
        .trim_end_matches(',')
    )
}

/// Where a file's pixel data is.
#[derive(Clone, Debug, Default)]
pub(super) enum Pixels {
    /// The file has none.
    #[default]
    None,
    /// Native pixel data at this byte offset of the file, this long.
    Native {
        /// Byte offset in the file.
        offset: u64,
        /// Declared length.
        len: u64,
    },
    /// Native pixel data in a deflated file, not read (a header scan).
    Deflated,
    /// Native pixel data inflated into memory (a deflated file).
    Inflated(Vec<u8>),
    /// Encapsulated pixel data, not read (a header scan).
    Encapsulated,
    /// Encapsulated pixel data: the basic offset table and the fragments.
    Fragments(Vec<u32>, Vec<Vec<u8>>),
}

/// One file, walked: the data set up to the pixel data, and where the pixels are.
#[derive(Debug)]
pub(super) struct Part {
    /// The data set's bytes before the pixel data (inflated when the file is deflated).
    pub dataset: Vec<u8>,
    /// The transfer syntax of the file.
    pub syntax: Syntax,
    /// The pixel data.
    pub pixels: Pixels,
}

/// Whether the bytes at the start of a file say DICOM: `DICM` after the 128-byte preamble or
/// at the start, or a file meta group with no preamble.
pub(super) fn sniff(head: &[u8]) -> bool {
    head.get(128..132) == Some(b"DICM")
        || head.starts_with(b"DICM")
        || (head.len() >= 8 && head[..2] == [2, 0] && head[3] == 0 && is_vr(&head[4..6]))
}

/// The syntax of a file whose meta group names `uid` (or none) and whose data set starts with
/// `first`: the UID's, read as the data set is really encoded (some writers put implicit VR
/// under an explicit UID, as pydicom and dcmtk accept), or, without a UID, as the data set says.
fn encoding(uid: Option<&str>, first: &[u8]) -> std::result::Result<Syntax, String> {
    let looks_explicit = first.len() == 6 && known_vr([first[4], first[5]]);
    let Some(uid) = uid else {
        let big = first.len() >= 2 && first[0] == 0 && first[1] != 0;
        return Syntax::from_uid(match (big, looks_explicit) {
            (true, _) => "1.2.840.10008.1.2.2",
            (false, true) => "1.2.840.10008.1.2.1",
            (false, false) => "1.2.840.10008.1.2",
        });
    };
    let mut syntax = Syntax::from_uid(uid)?;
    if !syntax.deflated && !syntax.big && first.len() == 6 {
        syntax.explicit = looks_explicit;
    }
    Ok(syntax)
}

/// Whether the bytes start like a data set with no meta group: the first tag in group 8
/// (either byte order).
fn bare(head: &[u8]) -> bool {
    head.len() >= 8 && (head[..2] == [8, 0] || head[..2] == [0, 8])
}

fn is_vr(b: &[u8]) -> bool {
    b.len() == 2 && b[0].is_ascii_uppercase() && b[1].is_ascii_uppercase()
}

/// Walks the file at `path`, keeping its data set up to the pixel data; with `pixels`, reads
/// the encapsulated fragments or inflated pixels too. Everything kept is charged to `budget`.
pub(super) fn read(path: &Path, budget: u64, pixels: bool) -> Result<Part> {
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    let mut walk = Walk::new(BufReader::new(file), len, budget);
    let fail = |e: Fault| e.into_error(path);
    let mut head = [0u8; 132];
    let got = walk.peek_into(&mut head).map_err(fail)?;
    let head = &head[..got];
    if head.get(128..132) == Some(b"DICM") {
        walk.skip(132).map_err(fail)?;
    } else if head.starts_with(b"DICM") {
        walk.skip(4).map_err(fail)?;
    } else if !sniff(head) && !bare(head) {
        return Err(Error::format(
            path,
            "not a DICOM file (no DICM marker, no file meta group, no data set)",
        ));
    }
    let uid = walk.meta().map_err(fail)?;
    let mut first = [0u8; 6];
    let got = walk.peek_into(&mut first).map_err(fail)?;
    let syntax =
        encoding(uid.as_deref(), &first[..got]).map_err(|m| Error::unsupported(path, m))?;
    if syntax.deflated {
        // The bytes looked ahead at are the stream's first.
        let rest = std::io::Cursor::new(walk.ahead).chain(walk.reader);
        let inflated = flate2::bufread::DeflateDecoder::new(BufReader::new(rest));
        // The inflated length is unknown: the budget bounds it, and values are read as they
        // arrive, never sized by their claims.
        let mut inner = Walk::new(BufReader::new(inflated), u64::MAX, budget);
        let found = inner.dataset(true, false).map_err(fail)?;
        let pixels = match (found, pixels) {
            (false, _) => Pixels::None,
            (true, true) => inner.native_in_memory().map_err(fail)?,
            (true, false) => Pixels::Deflated,
        };
        return Ok(Part {
            dataset: inner.kept,
            syntax,
            pixels,
        });
    }
    let found = walk.dataset(syntax.explicit, syntax.big).map_err(fail)?;
    let dataset = std::mem::take(&mut walk.kept);
    let pixels = if !found {
        Pixels::None
    } else if syntax.encapsulated {
        if pixels {
            walk.fragments(syntax.explicit).map_err(fail)?
        } else {
            Pixels::Encapsulated
        }
    } else {
        walk.native_at(syntax.explicit, syntax.big).map_err(fail)?
    };
    Ok(Part {
        dataset,
        syntax,
        pixels,
    })
}

/// What went wrong in a walk, before it is tied to its file.
#[derive(Debug)]
enum Fault {
    Io(std::io::Error),
    Format(String),
    TooLarge(u64, u64),
}

impl Fault {
    fn into_error(self, path: &Path) -> Error {
        match self {
            Self::Io(e) => Error::io(path, e),
            Self::Format(m) => Error::format(path, m),
            Self::TooLarge(needed, limit) => Error::TooLarge {
                path: path.to_path_buf(),
                what: "its DICOM header".into(),
                needed,
                limit,
            },
        }
    }
}

type Walked<T> = std::result::Result<T, Fault>;

fn bad<T>(message: impl Into<String>) -> Walked<T> {
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

struct Walk<R> {
    reader: BufReader<R>,
    /// Bytes read from `reader` to look at but not yet taken.
    ahead: Vec<u8>,
    pos: u64,
    len: u64,
    budget: u64,
    spent: u64,
    kept: Vec<u8>,
}

impl<R: Read> Walk<R> {
    fn new(reader: BufReader<R>, len: u64, budget: u64) -> Self {
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
    fn peek_into(&mut self, buf: &mut [u8]) -> Walked<usize> {
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

    fn skip(&mut self, n: u64) -> Walked<()> {
        if self.take(n, None)? < n {
            return bad(format!("file ends inside its header at byte {}", self.pos));
        }
        Ok(())
    }

    fn charge(&mut self, bytes: u64) -> Walked<()> {
        self.spent = self.spent.saturating_add(bytes);
        if self.spent > self.budget {
            return Err(Fault::TooLarge(self.spent, self.budget));
        }
        Ok(())
    }

    /// Reads exactly `n` bytes into `out`: `Ok(false)` when the file ended first.
    fn take_into(&mut self, n: u64, out: &mut Vec<u8>) -> Walked<bool> {
        Ok(self.take(n, Some(out))? == n)
    }

    /// Reads `n` bytes into the kept data set; the file ending first is an error.
    fn keep(&mut self, n: u64, what: &str) -> Walked<()> {
        let mut kept = std::mem::take(&mut self.kept);
        let whole = self.take_into(n, &mut kept);
        self.kept = kept;
        if !whole? {
            return bad(format!("file ends inside {what}"));
        }
        Ok(())
    }

    fn last(&self, n: usize) -> &[u8] {
        &self.kept[self.kept.len() - n..]
    }

    /// The file meta group (explicit VR little endian, group 2): its transfer syntax UID, if it
    /// states one.
    fn meta(&mut self) -> Walked<Option<String>> {
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
    fn dataset(&mut self, explicit: bool, big: bool) -> Walked<bool> {
        let mut open: Vec<Open> = Vec::new();
        loop {
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
            let inside = open.last().copied();
            let explicit_here = inside.map_or(explicit, |o| o.explicit);
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
            if tag.0 == 0xFFFE {
                self.keep(4, "an item header")?;
                let len = u32_at(self.last(4), big);
                match (tag, inside) {
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
            } else {
                if inside.is_some_and(|o| o.sequence) {
                    return bad(format!(
                        "element ({:04X},{:04X}) at byte {at} is in a sequence but not in an item",
                        tag.0, tag.1
                    ));
                }
                let (vr, len) = self.element_header(explicit_here, big)?;
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
                    let explicit = explicit_here && vr.is_some_and(|v| &v == b"SQ");
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
            }
        }
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

    /// Keeps a value of `len` bytes, charged with what it costs parsed (a text value's every
    /// part becomes a string of its own).
    fn value(&mut self, len: u64, text: bool) -> Walked<()> {
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

    /// Where a value of `len` bytes starting here ends, checked against the end of what holds
    /// it (`None`: undefined length).
    fn end_of(&self, len: u32, limit: u64, tag: Tag) -> Walked<Option<u64>> {
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

    /// Skips (keeping) the fragments of encapsulated pixel data nested in an item.
    fn nested_fragments(&mut self, big: bool) -> Walked<()> {
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
    fn fragments(&mut self, explicit: bool) -> Walked<Pixels> {
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
    fn native_at(&mut self, explicit: bool, big: bool) -> Walked<Pixels> {
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
    fn native_in_memory(&mut self) -> Walked<Pixels> {
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

fn u16_at(b: &[u8], big: bool) -> u16 {
    let a = [b[0], b[1]];
    if big {
        u16::from_be_bytes(a)
    } else {
        u16::from_le_bytes(a)
    }
}

fn u32_at(b: &[u8], big: bool) -> u32 {
    let a = [b[0], b[1], b[2], b[3]];
    if big {
        u32::from_be_bytes(a)
    } else {
        u32::from_le_bytes(a)
    }
}

/// Explicit VRs with a 4-byte length (after two reserved bytes).
const LONG_VRS: [&[u8; 2]; 13] = [
    b"OB", b"OD", b"OF", b"OL", b"OV", b"OW", b"SQ", b"SV", b"UC", b"UN", b"UR", b"UT", b"UV",
];

/// Explicit VRs with a 2-byte length.
const SHORT_VRS: [&[u8; 2]; 21] = [
    b"AE", b"AS", b"AT", b"CS", b"DA", b"DS", b"DT", b"FL", b"FD", b"IS", b"LO", b"LT", b"PN",
    b"SH", b"SL", b"SS", b"ST", b"TM", b"UI", b"UL", b"US",
];

/// VRs whose values are text, split at backslashes into many values.
const TEXT_VRS: [&[u8; 2]; 13] = [
    b"AE", b"AS", b"CS", b"DA", b"DS", b"DT", b"IS", b"LO", b"PN", b"SH", b"TM", b"UC", b"UI",
];

fn long_length(vr: [u8; 2]) -> bool {
    LONG_VRS.contains(&&vr)
}

/// The value representations the standard defines.
fn known_vr(vr: [u8; 2]) -> bool {
    long_length(vr) || SHORT_VRS.contains(&&vr)
}

fn text_vr(vr: [u8; 2]) -> bool {
    TEXT_VRS.contains(&&vr)
}

/// Whether the dictionary says `tag` holds a sequence (for implicit VR files).
fn dictionary_sequence(tag: Tag) -> bool {
    StandardDataDictionary
        .by_tag(tag)
        .is_some_and(|e| e.vr() == VirtualVr::Exact(VR::SQ))
}
