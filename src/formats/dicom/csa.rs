//! Siemens' CSA image header (private element (0029,xx10) of the `SIEMENS CSA HEADER` block):
//! a list of named tags, each a list of text items. Both layouts are read: CSA2 (`SV10`), as
//! dcm2niix's `readCSAImageHeader` reads it (an item's length is its second word), and the old
//! CSA1, as SPM reads it (an item's length is its first word less the first tag's item count).
//! Every count and length is checked against the bytes there are before it is used, so a
//! hostile header is an error, never a read past its end.

/// The most tags a header may claim (nibabel's limit; real headers hold about a hundred).
pub(super) const MAX_TAGS: u32 = 1000;

/// The most items one tag may claim.
const MAX_ITEMS: u32 = 1000;

/// Bytes of a tag's description: name (64), VM, VR (4), syngo data type, items, a check word.
const TAG_BYTES: usize = 84;

/// Bytes of an item's description: four 32-bit words.
const ITEM_BYTES: usize = 16;

/// A parsed CSA header: each tag's name and its items' text (empty items kept).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Csa {
    tags: Vec<(String, Vec<String>)>,
}

impl Csa {
    /// The items of the tag `name`.
    fn items(&self, name: &str) -> Option<&[String]> {
        self.tags
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, items)| items.as_slice())
    }

    /// The first item of the tag `name` as a finite number.
    pub fn number(&self, name: &str) -> Option<f64> {
        self.numbers::<1>(name).map(|[v]| v)
    }

    /// The first `N` items of the tag `name`, each a finite number.
    pub fn numbers<const N: usize>(&self, name: &str) -> Option<[f64; N]> {
        let items = self.items(name)?;
        let mut out = [0.0; N];
        for (slot, item) in out.iter_mut().zip(items.get(..N)?) {
            *slot = item.trim().parse::<f64>().ok().filter(|v| v.is_finite())?;
        }
        Some(out)
    }
}

/// A little-endian reader over the header's bytes that refuses to read past them.
struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len());
        let Some(end) = end else {
            return Err(format!(
                "{what} at byte {} runs past the header's {} bytes",
                self.at,
                self.data.len()
            ));
        };
        let out = &self.data[self.at..end];
        self.at = end;
        Ok(out)
    }

    fn word(&mut self, what: &str) -> Result<i32, String> {
        let b = self.take(4, what)?;
        Ok(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// Skips the padding after `len` bytes of an item, up to the end at most.
    fn pad(&mut self, len: usize) {
        let pad = (4 - len % 4) % 4;
        self.at = (self.at + pad).min(self.data.len());
    }
}

/// Text up to the first NUL, read as Latin-1 (as nibabel reads it).
fn text(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    b[..end].iter().map(|&c| char::from(c)).collect()
}

/// Parses the CSA header `data`; fails, saying where, on any count or length it cannot hold.
pub(super) fn parse(data: &[u8]) -> Result<Csa, String> {
    let mut b = Bytes { data, at: 0 };
    let csa2 = data.starts_with(b"SV10");
    if csa2 {
        b.take(8, "the SV10 signature")?;
    }
    let claimed = b.word("the tag count")?;
    let check = b.word("the check word")?;
    let count = u32::try_from(claimed)
        .ok()
        .filter(|n| (1..=MAX_TAGS).contains(n))
        .ok_or_else(|| format!("{claimed} tags claimed (1 to {MAX_TAGS} are read)"))?;
    if csa2 && check != 77 {
        return Err(format!("check word {check}, not 77"));
    }
    // No more tags than the bytes could describe: a claim is never a loop's bound alone.
    if (count as usize).saturating_mul(TAG_BYTES) > data.len() - b.at {
        return Err(format!(
            "{count} tags claimed by a header of {} bytes",
            data.len()
        ));
    }
    let mut tags = Vec::with_capacity(count as usize);
    let mut first_items = None;
    for _ in 0..count {
        let head = b.take(TAG_BYTES, "a tag")?;
        let name = text(&head[..64]);
        let word =
            |at: usize| i32::from_le_bytes([head[at], head[at + 1], head[at + 2], head[at + 3]]);
        let n = u32::try_from(word(76))
            .ok()
            .filter(|&n| n <= MAX_ITEMS)
            .ok_or_else(|| format!("tag {name:?} claims {} items", word(76)))?;
        let base = *first_items.get_or_insert(n);
        let items = if csa2 {
            items_csa2(&mut b, n)?
        } else {
            items_csa1(&mut b, n, base)
        };
        tags.push((name, items));
    }
    Ok(Csa { tags })
}

/// The `n` items of a CSA2 tag: each length (the second word) within the header.
fn items_csa2(b: &mut Bytes, n: u32) -> Result<Vec<String>, String> {
    let mut items = Vec::new();
    for _ in 0..n {
        b.take(4, "an item")?;
        let len = b.word("an item")?;
        b.take(8, "an item")?;
        let len = usize::try_from(len).map_err(|_| format!("an item of {len} bytes"))?;
        items.push(text(b.take(len, "an item's value")?));
        b.pad(len);
    }
    Ok(items)
}

/// The items of a CSA1 tag claiming `n`: each length is its first word less `base` (the first
/// tag's item count); an item whose length is negative or overreaches ends the tag (as SPM and
/// nibabel read it).
fn items_csa1(b: &mut Bytes, n: u32, base: u32) -> Vec<String> {
    let mut items = Vec::new();
    for _ in 0..n {
        let Ok(head) = b.take(ITEM_BYTES, "an item") else {
            break;
        };
        let first = i64::from(i32::from_le_bytes([head[0], head[1], head[2], head[3]]));
        let Ok(len) = usize::try_from(first - i64::from(base)) else {
            break;
        };
        let Ok(value) = b.take(len, "an item's value") else {
            break;
        };
        items.push(text(value));
        b.pad(len);
    }
    items
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tag(name: &str, n: i32) -> Vec<u8> {
        let mut t = vec![0u8; TAG_BYTES];
        t[..name.len()].copy_from_slice(name.as_bytes());
        t[64..68].copy_from_slice(&1i32.to_le_bytes());
        t[68..70].copy_from_slice(b"FD");
        t[76..80].copy_from_slice(&n.to_le_bytes());
        t[80..84].copy_from_slice(&77i32.to_le_bytes());
        t
    }

    /// A CSA2 header of `tags` (name, items).
    fn csa2(tags: &[(&str, &[&str])]) -> Vec<u8> {
        let mut out = b"SV10\x04\x03\x02\x01".to_vec();
        out.extend((tags.len() as i32).to_le_bytes());
        out.extend(77i32.to_le_bytes());
        for (name, items) in tags {
            out.extend(tag(name, items.len() as i32));
            for item in *items {
                let len = item.len() as i32;
                for w in [len, len, 77, len] {
                    out.extend(w.to_le_bytes());
                }
                out.extend(item.as_bytes());
                out.resize(out.len().div_ceil(4) * 4, 0);
            }
        }
        out
    }

    /// A CSA1 header of `tags`: item lengths offset by the first tag's item count.
    fn csa1(tags: &[(&str, &[&str])]) -> Vec<u8> {
        let base = tags[0].1.len() as i32;
        let mut out = Vec::new();
        out.extend((tags.len() as i32).to_le_bytes());
        out.extend(77i32.to_le_bytes());
        for (name, items) in tags {
            out.extend(tag(name, items.len() as i32));
            for item in *items {
                let len = item.len() as i32;
                for w in [len + base, len, 77, len] {
                    out.extend(w.to_le_bytes());
                }
                out.extend(item.as_bytes());
                out.resize(out.len().div_ceil(4) * 4, 0);
            }
        }
        out
    }

    const TAGS: &[(&str, &[&str])] = &[
        ("EchoLinePosition", &["32 ", "", ""]),
        ("NumberOfImagesInMosaic", &["7\0", ""]),
        ("SliceNormalVector", &["0.1", "-0.2", "0.97467943448"]),
    ];

    #[test]
    fn both_layouts_give_the_numbers() {
        for bytes in [csa2(TAGS), csa1(TAGS)] {
            let csa = parse(&bytes).unwrap();
            assert_eq!(csa.number("NumberOfImagesInMosaic"), Some(7.0));
            assert_eq!(
                csa.numbers::<3>("SliceNormalVector"),
                Some([0.1, -0.2, 0.974_679_434_48])
            );
            assert_eq!(csa.number("EchoLinePosition"), Some(32.0));
            assert_eq!(csa.number("Missing"), None);
        }
    }

    #[test]
    fn hostile_counts_and_lengths_are_errors() {
        let mut many = csa2(TAGS);
        many[8..12].copy_from_slice(&1_000_000i32.to_le_bytes());
        assert!(parse(&many).unwrap_err().contains("1000000 tags"));
        let mut fits = csa2(TAGS);
        fits[8..12].copy_from_slice(&900i32.to_le_bytes());
        assert!(
            parse(&fits)
                .unwrap_err()
                .contains("900 tags claimed by a header")
        );
        let mut zero = csa2(TAGS);
        zero[8..12].copy_from_slice(&0i32.to_le_bytes());
        assert!(parse(&zero).is_err());
        let mut items = csa2(TAGS);
        items[16 + 76..16 + 80].copy_from_slice(&(-5i32).to_le_bytes());
        assert!(parse(&items).unwrap_err().contains("-5 items"));
        // An item claiming more bytes than there are.
        let mut long = csa2(TAGS);
        let at = 16 + TAG_BYTES + 4;
        long[at..at + 4].copy_from_slice(&i32::MAX.to_le_bytes());
        assert!(parse(&long).unwrap_err().contains("runs past"));
        let mut check = csa2(TAGS);
        check[12] = 78;
        assert!(parse(&check).unwrap_err().contains("check word"));
    }

    #[test]
    fn every_truncation_and_every_byte_is_safe() {
        for bytes in [csa2(TAGS), csa1(TAGS)] {
            for end in 0..bytes.len() {
                let _ = parse(&bytes[..end]);
            }
            for at in 0..bytes.len() {
                for v in [0u8, 0x7f, 0x80, 0xff] {
                    let mut b = bytes.clone();
                    b[at] = v;
                    let _ = parse(&b);
                }
            }
        }
    }
}
