//! Reading one DICOM file safely: a walk over every element header, in the file's own byte
//! order and VR encoding, that checks each declared length against what encloses it and the
//! bytes that are really there before a byte of it is kept. What the walk keeps is the data set
//! up to the pixel data, which dicom-object then parses from memory (it sizes its buffers by the
//! declared lengths, so it only ever sees lengths the walk has proven), and where the pixel data
//! lies. The walk over element headers is `walk`, the readers of the values it reaches are
//! `values`, and what the encodings are is `syntax`.

mod syntax;
mod values;
mod walk;

use std::io::{BufReader, Read};
use std::path::Path;

pub(super) use self::syntax::{Syntax, syntax_name};
use self::syntax::{is_vr, known_vr};
use self::walk::{Fault, Walk};
use crate::error::{Error, Result};

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

/// Walks the file at `path`, keeping its data set up to the pixel data; with `pixels`, reads
/// the encapsulated fragments or inflated pixels too. Everything kept is charged to `budget`.
pub(super) fn read(path: &Path, budget: u64, pixels: bool) -> Result<Part> {
    let file = crate::formats::Source::new(path).open()?;
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
