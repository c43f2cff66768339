//! DICOM files the tests write or edit: explicit VR little endian data sets walked element by
//! element (the fixtures edited here hold no sequence), an element replaced or put in its
//! place, new files written whole, and Siemens CSA2 headers. The Siemens mosaic files made from
//! the repository's `tests/data/dicom/mosaic/asc/` (pydicom's, see its `make.py`) are here too,
//! for `tests/it/mosaic.rs` and the mutation harness alike.

use super::dicom_data;

/// A data element: its tag (group, element), VR and value.
#[derive(Clone, Debug)]
pub struct Element {
    pub tag: (u16, u16),
    pub vr: [u8; 2],
    pub value: Vec<u8>,
}

/// Whether `vr` has a 4-byte length (after two reserved bytes) in explicit VR.
fn long(vr: [u8; 2]) -> bool {
    [
        b"OB", b"OD", b"OF", b"OL", b"OV", b"OW", b"SQ", b"UC", b"UN", b"UR", b"UT",
    ]
    .contains(&&vr)
}

/// The bytes of `e`, its value padded to an even length (UI with NUL, text with a space,
/// binary values with NUL).
pub fn encode(e: &Element) -> Vec<u8> {
    let mut value = e.value.clone();
    if value.len() % 2 == 1 {
        let text = !long(e.vr) && !matches!(&e.vr, b"US" | b"UL" | b"SS" | b"SL" | b"FL" | b"FD");
        value.push(if text && &e.vr != b"UI" { b' ' } else { 0 });
    }
    let mut b = Vec::new();
    b.extend(e.tag.0.to_le_bytes());
    b.extend(e.tag.1.to_le_bytes());
    b.extend(e.vr);
    if long(e.vr) {
        b.extend([0, 0]);
        b.extend(u32::try_from(value.len()).unwrap().to_le_bytes());
    } else {
        b.extend(u16::try_from(value.len()).unwrap().to_le_bytes());
    }
    b.extend(value);
    b
}

/// The elements of `bytes` from `at` on.
fn walk(bytes: &[u8], mut at: usize) -> Vec<Element> {
    let mut out = Vec::new();
    while at + 8 <= bytes.len() {
        let word = |k: usize| u16::from_le_bytes([bytes[at + k], bytes[at + k + 1]]);
        let (tag, vr) = ((word(0), word(2)), [bytes[at + 4], bytes[at + 5]]);
        let (head, len) = if long(vr) {
            (
                12,
                u32::from_le_bytes(bytes[at + 8..at + 12].try_into().unwrap()) as usize,
            )
        } else {
            (8, usize::from(word(6)))
        };
        let value = bytes[at + head..at + head + len].to_vec();
        out.push(Element { tag, vr, value });
        at += head + len;
    }
    out
}

/// The preamble, `DICM` and meta group of `bytes` (a file as pydicom writes it), and the
/// elements of its data set.
pub fn split(bytes: &[u8]) -> (Vec<u8>, Vec<Element>) {
    assert_eq!(&bytes[128..132], b"DICM");
    let meta = walk(bytes, 132)
        .into_iter()
        .take_while(|e| e.tag.0 == 2)
        .map(|e| encode(&e).len())
        .sum::<usize>();
    let end = 132 + meta;
    (bytes[..end].to_vec(), walk(bytes, end))
}

/// `meta` followed by `elements`, in tag order.
pub fn join(meta: &[u8], mut elements: Vec<Element>) -> Vec<u8> {
    elements.sort_by_key(|e| e.tag);
    let mut out = meta.to_vec();
    for e in &elements {
        out.extend(encode(e));
    }
    out
}

/// The value of element `tag` of `bytes`.
pub fn value(bytes: &[u8], tag: (u16, u16)) -> Option<Vec<u8>> {
    split(bytes)
        .1
        .into_iter()
        .find(|e| e.tag == tag)
        .map(|e| e.value)
}

/// `bytes` with element `tag` set to `value` of `vr`: replaced where it is, else put in its
/// place.
pub fn with(bytes: &[u8], tag: (u16, u16), vr: [u8; 2], value: &[u8]) -> Vec<u8> {
    let (meta, mut elements) = split(bytes);
    elements.retain(|e| e.tag != tag);
    elements.push(Element {
        tag,
        vr,
        value: value.to_vec(),
    });
    join(&meta, elements)
}

/// A new file: a preamble, `DICM`, a meta group naming explicit VR little endian, and
/// `elements`.
pub fn file(elements: Vec<Element>) -> Vec<u8> {
    let class = b"1.2.840.10008.5.1.4.1.1.7".to_vec();
    let meta: Vec<Element> = [
        ((2, 1), *b"OB", vec![0, 1]),
        ((2, 2), *b"UI", class),
        ((2, 3), *b"UI", b"2.25.1".to_vec()),
        ((2, 0x10), *b"UI", b"1.2.840.10008.1.2.1".to_vec()),
    ]
    .into_iter()
    .map(|(tag, vr, value)| Element { tag, vr, value })
    .collect();
    let body: Vec<u8> = meta.iter().flat_map(encode).collect();
    let mut out = vec![0u8; 128];
    out.extend(b"DICM");
    out.extend(encode(&Element {
        tag: (2, 0),
        vr: *b"UL",
        value: u32::try_from(body.len()).unwrap().to_le_bytes().to_vec(),
    }));
    out.extend(body);
    join(&out, elements)
}

/// An element of a new file.
pub fn el(group: u16, element: u16, vr: [u8; 2], value: &[u8]) -> Element {
    Element {
        tag: (group, element),
        vr,
        value: value.to_vec(),
    }
}

/// A CSA2 header ("SV10") of `tags`, each a name and its items, as Siemens writes it.
pub fn csa2(tags: &[(&str, &[&str])]) -> Vec<u8> {
    let mut out = b"SV10\x04\x03\x02\x01".to_vec();
    out.extend(i32::try_from(tags.len()).unwrap().to_le_bytes());
    out.extend(77i32.to_le_bytes());
    for (name, items) in tags {
        let mut t = vec![0u8; 84];
        t[..name.len()].copy_from_slice(name.as_bytes());
        t[64..68].copy_from_slice(&1i32.to_le_bytes());
        t[68..70].copy_from_slice(b"UN");
        t[76..80].copy_from_slice(&i32::try_from(items.len()).unwrap().to_le_bytes());
        t[80..84].copy_from_slice(&77i32.to_le_bytes());
        out.extend(t);
        for item in *items {
            let len = i32::try_from(item.len()).unwrap();
            for w in [len, len, 77, len] {
                out.extend(w.to_le_bytes());
            }
            out.extend(item.as_bytes());
            out.resize(out.len().div_ceil(4) * 4, 0);
        }
    }
    out
}

/// Time point `t` (0 to 2) of the repository's mosaic series `asc`: one mosaic of 7 slices.
pub fn asc(t: usize) -> Vec<u8> {
    std::fs::read(dicom_data(&format!("mosaic/asc/t{t}.dcm"))).unwrap()
}

/// The three time points of `asc` as the frames of one file: `NumberOfFrames` 3, the pixel
/// data of each file in turn.
pub fn mosaic_frames() -> Vec<u8> {
    let mut pixels = Vec::new();
    for t in 0..3 {
        pixels.extend(value(&asc(t), (0x7FE0, 0x10)).unwrap());
    }
    let one = with(&asc(0), (0x28, 0x08), *b"IS", b"3 ");
    with(&one, (0x7FE0, 0x10), *b"OW", &pixels)
}

/// The first time point of `asc` with a CSA series header (0029,1020) whose
/// `MrPhoenixProtocol` holds `protocol` (an `### ASCCONV BEGIN` block, say).
pub fn mosaic_protocol(protocol: &str) -> Vec<u8> {
    let header = csa2(&[
        ("UsedPatientWeight", &["70 "]),
        ("MrPhoenixProtocol", &[protocol]),
    ]);
    with(&asc(0), (0x29, 0x1020), *b"OB", &header)
}

/// An ASCCONV block of a few lines as Siemens writes them, with `lines` among them.
pub fn ascconv(lines: &str) -> String {
    format!(
        "<XProtocol> {{ }}\n### ASCCONV BEGIN object=MrProtDataImpl@MrProtocolData version=51130001 ###\n\
         ulVersion = 0x14b44b6\nsSliceArray.lSize = 7\n{lines}sSliceArray.ucMode = 0x2\n\
         ### ASCCONV END ###\n"
    )
}

/// A DICOM file of `frames` frames of 2x2 32-bit samples (`signed`: i32), each `pixels`, with
/// `rescale`'s elements (slope, intercept) where given.
pub fn dicom32(
    pixels: &[u32],
    frames: usize,
    signed: bool,
    rescale: Option<(&str, &str)>,
) -> Vec<u8> {
    let us = |v: u16| v.to_le_bytes().to_vec();
    let words: Vec<u8> = pixels
        .repeat(frames)
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let mut elements = vec![
        el(0x08, 0x60, *b"CS", b"OT"),
        el(0x20, 0x0E, *b"UI", b"2.25.32"),
        el(0x28, 0x02, *b"US", &us(1)),
        el(0x28, 0x04, *b"CS", b"MONOCHROME2"),
        el(0x28, 0x08, *b"IS", frames.to_string().as_bytes()),
        el(0x28, 0x10, *b"US", &us(2)),
        el(0x28, 0x11, *b"US", &us(2)),
        el(0x28, 0x100, *b"US", &us(32)),
        el(0x28, 0x101, *b"US", &us(32)),
        el(0x28, 0x102, *b"US", &us(31)),
        el(0x28, 0x103, *b"US", &us(u16::from(signed))),
        el(0x7FE0, 0x10, *b"OW", &words),
    ];
    if let Some((slope, intercept)) = rescale {
        elements.push(el(0x28, 0x1052, *b"DS", intercept.as_bytes()));
        elements.push(el(0x28, 0x1053, *b"DS", slope.as_bytes()));
    }
    file(elements)
}
