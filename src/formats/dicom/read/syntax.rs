//! How a DICOM file is encoded: its transfer syntax (which slabscope reads, and what each is
//! called) and the value representations an element header may name.

use dicom_core::dictionary::{DataDictionary, DataDictionaryEntry, VirtualVr};
use dicom_core::{Tag, VR};
use dicom_dictionary_std::StandardDataDictionary;

/// How a file's data set is encoded: its transfer syntax.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(in crate::formats::dicom) struct Syntax {
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
            // prediction), JPEG 2000 (lossless only, and lossy), JPEG XL (lossless, JPEG
            // recompression, and lossy), RLE, encapsulated uncompressed.
            "1.2.840.10008.1.2.4.50"
            | "1.2.840.10008.1.2.4.51"
            | "1.2.840.10008.1.2.4.57"
            | "1.2.840.10008.1.2.4.70"
            | "1.2.840.10008.1.2.4.90"
            | "1.2.840.10008.1.2.4.91"
            | "1.2.840.10008.1.2.4.110"
            | "1.2.840.10008.1.2.4.111"
            | "1.2.840.10008.1.2.4.112"
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
pub(in crate::formats::dicom) fn syntax_name(uid: &str) -> String {
    use dicom_encoding::TransferSyntaxIndex;
    dicom_transfer_syntax_registry::TransferSyntaxRegistry
        .get(uid)
        .map_or_else(|| uid.to_string(), |ts| format!("{} ({uid})", ts.name()))
}

/// Why slabscope cannot read the syntax `uid`, naming it and what is read instead.
fn unsupported_syntax(uid: &str) -> String {
    let known = match uid {
        "1.2.840.10008.1.2.4.80" | "1.2.840.10008.1.2.4.81" => "JPEG-LS",
        "1.2.840.10008.1.2.4.92" | "1.2.840.10008.1.2.4.93" => "JPEG 2000 Part 2",
        u if u.starts_with("1.2.840.10008.1.2.4.20") => "High-Throughput JPEG 2000",
        u if u.starts_with("1.2.840.10008.1.2.4.10") => "video (MPEG or HEVC)",
        _ => "",
    };
    let name = syntax_name(uid);
    format!(
        "transfer syntax {name}{}: slabscope decodes native (uncompressed), deflated, RLE, JPEG \
         baseline, 8-bit extended and lossless JPEG, JPEG 2000 and JPEG XL",
        if known.is_empty() || name.contains(known) {
            String::new()
        } else {
            format!(", {known},")
        }
        .trim_end_matches(',')
    )
}

/// Whether the two bytes look like a VR: two capital letters.
pub(super) fn is_vr(b: &[u8]) -> bool {
    b.len() == 2 && b[0].is_ascii_uppercase() && b[1].is_ascii_uppercase()
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

/// Whether an explicit element of VR `vr` has a 4-byte length.
pub(super) fn long_length(vr: [u8; 2]) -> bool {
    LONG_VRS.contains(&&vr)
}

/// The value representations the standard defines.
pub(super) fn known_vr(vr: [u8; 2]) -> bool {
    long_length(vr) || SHORT_VRS.contains(&&vr)
}

/// Whether values of VR `vr` are text, split at backslashes.
pub(super) fn text_vr(vr: [u8; 2]) -> bool {
    TEXT_VRS.contains(&&vr)
}

/// Whether the dictionary says `tag` holds a sequence (for implicit VR files).
pub(super) fn dictionary_sequence(tag: Tag) -> bool {
    StandardDataDictionary
        .by_tag(tag)
        .is_some_and(|e| e.vr() == VirtualVr::Exact(VR::SQ))
}
