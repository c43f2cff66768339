//! The protocol in Siemens' CSA series header (element (0029,xx20) of the `SIEMENS CSA HEADER`
//! block: the `MrPhoenixProtocol` text, whose `### ASCCONV BEGIN` ... `### ASCCONV END` block
//! lists the protocol's parameters one a line). slabscope reads one thing of it, as dcm2niix
//! reads it (`siemensCsaAscii` and `readKey` in `console/nii_dicom_batch.cpp`): whether
//! `sSliceArray.ucImageNumb` is set, Siemens' flag for slices numbered in reverse. dcm2niix
//! warns of it on a mosaic ("Assuming mosaics saved in reverse order") and, since no image in
//! the wild was seen to need it, changes neither the voxels nor the geometry (the tiles stay
//! where `SliceNormalVector` places them); slabscope does the same, with a note.

/// The most bytes of a series header searched (real ones hold a protocol of 100 to 300 kB);
/// a larger one is not searched, and a note says so.
pub(super) const MAX_BYTES: usize = 4 << 20;

/// The key dcm2niix looks for (its first occurrence: `sSliceArray.ucImageNumbSag`, `...Tra`
/// and `...Cor` begin with it, and count).
const KEY: &[u8] = b"sSliceArray.ucImageNumb";

/// What the series header says of the slices' numbering.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Numbering {
    /// No series header, no ASCCONV block in it, or `sSliceArray.ucImageNumb` absent or 0.
    Plain,
    /// `sSliceArray.ucImageNumb` set: slices numbered in reverse.
    Reversed,
    /// A series header of this many bytes, beyond [`MAX_BYTES`]: not searched.
    Unread(usize),
}

impl Numbering {
    /// What a load says of it (nothing when the numbering is plain).
    pub fn note(self) -> Option<String> {
        match self {
            Self::Plain => None,
            Self::Reversed => Some(
                "the CSA series header sets sSliceArray.ucImageNumb (Siemens numbered the \
                 slices in reverse): the tiles are placed by SliceNormalVector all the same, as \
                 dcm2niix places them (it warns and changes nothing)"
                    .into(),
            ),
            Self::Unread(bytes) => Some(format!(
                "the CSA series header holds {bytes} bytes (beyond {} MiB): not searched for \
                 sSliceArray.ucImageNumb",
                MAX_BYTES >> 20
            )),
        }
    }
}

/// Where `needle` first occurs in `hay`.
fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// What the series header `header` says of the numbering, by dcm2niix's rule: the text from
/// `### ASCCONV BEGIN` up to `### ASCCONV END` (or the header's end) is searched for the key,
/// and its value is the digits after it up to the end of its line, read as one decimal number
/// (`= 0x1` is 1, `= 0x0` is 0; a number too large for a u64 saturates); set when it is not 0.
pub(super) fn numbering(header: &[u8]) -> Numbering {
    if header.len() > MAX_BYTES {
        return Numbering::Unread(header.len());
    }
    let Some(begin) = find(header, b"### ASCCONV BEGIN") else {
        return Numbering::Plain;
    };
    let block = &header[begin..];
    let block = find(block, b"### ASCCONV END").map_or(block, |end| &block[..end]);
    let Some(at) = find(block, KEY) else {
        return Numbering::Plain;
    };
    let value = block[at + KEY.len()..]
        .iter()
        .take_while(|&&c| c != b'\n')
        .filter(|c| c.is_ascii_digit())
        .fold(0u64, |v, &d| {
            v.saturating_mul(10).saturating_add(u64::from(d - b'0'))
        });
    if value > 0 {
        Numbering::Reversed
    } else {
        Numbering::Plain
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(lines: &str) -> Vec<u8> {
        let mut b = b"SV10\x04\x03\x02\x01binary\0\xff".to_vec();
        b.extend(
            format!("### ASCCONV BEGIN object=MrProtDataImpl ###\n{lines}### ASCCONV END ###\n")
                .bytes(),
        );
        b
    }

    #[test]
    fn the_key_is_read_as_dcm2niix_reads_it() {
        let set = block("sSliceArray.lSize = 7\nsSliceArray.ucImageNumb = 0x1\n");
        assert_eq!(numbering(&set), Numbering::Reversed);
        let zero = block("sSliceArray.ucImageNumb\t = \t0x0\n");
        assert_eq!(numbering(&zero), Numbering::Plain);
        // The per-orientation keys begin with it.
        assert_eq!(
            numbering(&block("sSliceArray.ucImageNumbTra = 0x1\n")),
            Numbering::Reversed
        );
        // Absent, or only after the block's end, or no block at all.
        assert_eq!(
            numbering(&block("sSliceArray.ucMode = 0x2\n")),
            Numbering::Plain
        );
        let mut after = block("");
        after.extend(b"sSliceArray.ucImageNumb = 0x1\n");
        assert_eq!(numbering(&after), Numbering::Plain);
        assert_eq!(
            numbering(b"sSliceArray.ucImageNumb = 0x1\n"),
            Numbering::Plain
        );
        // No end marker: to the end of the header; a value on the next line is not its value.
        let open = b"### ASCCONV BEGIN ###\nsSliceArray.ucImageNumb = 0x1";
        assert_eq!(numbering(open), Numbering::Reversed);
        let next = block("sSliceArray.ucImageNumb =\n1\n");
        assert_eq!(numbering(&next), Numbering::Plain);
        // Digits beyond a u64 saturate.
        let huge = block(&format!("sSliceArray.ucImageNumb = {}\n", "9".repeat(40)));
        assert_eq!(numbering(&huge), Numbering::Reversed);
    }

    #[test]
    fn a_header_beyond_the_limit_is_not_searched() {
        let mut big = block("sSliceArray.ucImageNumb = 0x1\n");
        big.resize(MAX_BYTES + 1, b' ');
        assert_eq!(numbering(&big), Numbering::Unread(MAX_BYTES + 1));
        assert_eq!(
            Numbering::Unread(MAX_BYTES + 1).note().unwrap(),
            "the CSA series header holds 4194305 bytes (beyond 4 MiB): not searched for \
             sSliceArray.ucImageNumb"
        );
        big.truncate(MAX_BYTES);
        assert_eq!(numbering(&big), Numbering::Reversed);
        assert_eq!(Numbering::Plain.note(), None);
    }

    #[test]
    fn every_truncation_is_read_to_where_it_ends() {
        let b = block("sSliceArray.ucImageNumb = 0x1\n");
        let one = find(&b, b"0x1").unwrap() + 2;
        for end in 0..b.len() {
            let reversed = numbering(&b[..end]) == Numbering::Reversed;
            assert_eq!(reversed, end > one, "cut at {end}");
        }
    }
}
