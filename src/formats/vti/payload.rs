//! The bytes of a VTK XML array: base64 text decoded as it is read ([`Base64`]), a header of one
//! byte count or, compressed, of the zlib or LZ4 blocks' sizes, and the blocks decompressed one
//! at a time ([`Blocks`]). Every size the header claims is checked against the array's own size and the
//! bytes the file holds before anything is allocated.

use std::io::{BufReader, Error as IoError, ErrorKind, Read};

use flate2::bufread::ZlibDecoder;

use crate::volume::Endian;

/// An I/O error of invalid data saying `what`.
fn invalid(what: String) -> IoError {
    IoError::new(ErrorKind::InvalidData, what)
}

/// Base64 text decoded as it is read, whitespace skipped; a group padded with `=` may be
/// followed by another (VTK encodes a compressed array's header and its blocks apart).
pub(super) struct Base64<'a> {
    text: &'a [u8],
    at: usize,
    /// The last group's bytes, how many it holds, and how many were given.
    held: [u8; 3],
    held_len: usize,
    at_held: usize,
}

impl<'a> Base64<'a> {
    pub(super) fn new(text: &'a [u8]) -> Self {
        Self {
            text,
            at: 0,
            held: [0; 3],
            held_len: 0,
            at_held: 0,
        }
    }

    /// The next group of four characters decoded into `held`; false at the end of the text.
    fn group(&mut self) -> std::io::Result<bool> {
        let mut sixes = [0u8; 4];
        let mut n = 0;
        let mut pad = 0;
        while n < 4 {
            let Some(&c) = self.text.get(self.at) else {
                return match n {
                    0 => Ok(false),
                    _ => Err(invalid("base64 text ends inside a group".into())),
                };
            };
            self.at += 1;
            let six = match c {
                b'A'..=b'Z' => c - b'A',
                b'a'..=b'z' => c - b'a' + 26,
                b'0'..=b'9' => c - b'0' + 52,
                b'+' => 62,
                b'/' => 63,
                b'=' if n >= 2 => {
                    pad += 1;
                    0
                }
                c if c.is_ascii_whitespace() => continue,
                _ => {
                    return Err(invalid(format!(
                        "{:?} at character {} is not base64",
                        char::from(c),
                        self.at - 1
                    )));
                }
            };
            if pad > 0 && c != b'=' {
                return Err(invalid("base64 padding inside a group".into()));
            }
            sixes[n] = six;
            n += 1;
        }
        let word = sixes.iter().fold(0u32, |w, &s| (w << 6) | u32::from(s));
        self.held = [(word >> 16) as u8, (word >> 8) as u8, word as u8];
        self.held_len = 3 - pad;
        self.at_held = 0;
        Ok(true)
    }
}

impl Read for Base64<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let mut done = 0;
        while done < buf.len() {
            if self.at_held == self.held_len {
                if !self.group()? {
                    break;
                }
                continue;
            }
            let n = (self.held_len - self.at_held).min(buf.len() - done);
            buf[done..done + n].copy_from_slice(&self.held[self.at_held..self.at_held + n]);
            self.at_held += n;
            done += n;
        }
        Ok(done)
    }
}

/// How an array's header words are read: their size and byte order.
#[derive(Clone, Copy, Debug)]
pub(super) struct Words {
    /// 4 (`UInt32`) or 8 (`UInt64`).
    pub size: usize,
    pub endian: Endian,
}

impl Words {
    /// The next header word of `input`.
    pub(super) fn read(self, input: &mut impl Read) -> std::io::Result<u64> {
        let mut b = [0u8; 8];
        let word = &mut b[..self.size];
        input.read_exact(word).map_err(|e| match e.kind() {
            ErrorKind::UnexpectedEof => {
                IoError::new(ErrorKind::UnexpectedEof, "the array ends inside its header")
            }
            _ => e,
        })?;
        if self.endian == Endian::Big {
            word.reverse();
        }
        Ok(u64::from_le_bytes(b))
    }
}

/// The most bytes one byte of an LZ4 block decodes to, with room for the block's last literals.
const LZ4_MOST: u64 = 256;

/// How an array's blocks are compressed (the file's `compressor`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Compressor {
    /// `vtkZLibDataCompressor`: each block a zlib stream.
    Zlib,
    /// `vtkLZ4DataCompressor`: each block an LZ4 block (no frame).
    Lz4,
}

impl Compressor {
    /// Its name in messages.
    pub(super) fn name(self) -> &'static str {
        match self {
            Self::Zlib => "zlib",
            Self::Lz4 => "lz4",
        }
    }
}

/// The compressed blocks of an array, decompressed one at a time as they are read: a zlib block
/// as a stream (none of it held whole, compressed or not: one block may be the whole array, and
/// the volume it is read into is held beside it), an LZ4 block whole (LZ4's block format has no
/// stream).
pub(super) struct Blocks<R> {
    stage: Stage<R>,
    compressor: Compressor,
    /// Each block's compressed size.
    sizes: Vec<u64>,
    block_size: u64,
    last_size: u64,
    next: usize,
    compressed: Vec<u8>,
    block: Vec<u8>,
    at: usize,
}

/// Where the reading of [`Blocks`] is: between blocks (or in an LZ4 block, held whole), or in a
/// zlib block, decoded as it is read.
enum Stage<R> {
    Between(R),
    Zlib(Inflating<R>),
    /// Only while one stage is made into the other.
    Moving,
}

/// A zlib block being decoded: block `i`, of `size` bytes decoded, `made` of them given.
struct Inflating<R> {
    inflate: std::io::Take<ZlibDecoder<BufReader<std::io::Take<R>>>>,
    i: usize,
    size: u64,
    made: u64,
}

/// The compressed bytes a zlib block's decoder reads ahead.
const ZLIB_BUFFER: usize = 1 << 15;

impl<R: Read> Blocks<R> {
    /// Reads the compression header of `input` (the number of blocks, the block size, the last
    /// block's size, then each block's compressed size), checked against `expected`, the
    /// array's size in bytes, and `max_blocks`, the most blocks `input` can hold and memory can
    /// list.
    pub(super) fn new(
        mut input: R,
        compressor: Compressor,
        words: Words,
        expected: u64,
        max_blocks: u64,
    ) -> Result<Self, String> {
        let mut word = || words.read(&mut input).map_err(|e| e.to_string());
        let (count, block_size, last) = (word()?, word()?, word()?);
        let last_size = if last == 0 { block_size } else { last };
        let total = match count {
            0 => Some(0),
            n => (n - 1)
                .checked_mul(block_size)
                .and_then(|t| t.checked_add(last_size)),
        };
        let name = compressor.name();
        if total != Some(expected) || last_size > block_size {
            return Err(format!(
                "its {name} header says {count} blocks of {block_size} bytes, the last {last} \
                 bytes: expected {expected} bytes in all"
            ));
        }
        if count > max_blocks {
            return Err(format!(
                "its {name} header says {count} blocks, more than the file or the memory limit holds"
            ));
        }
        let sizes = (0..count)
            .map(|_| word())
            .collect::<Result<Vec<u64>, String>>()?;
        Ok(Self {
            stage: Stage::Between(input),
            compressor,
            sizes,
            block_size,
            last_size,
            next: 0,
            compressed: Vec::new(),
            block: Vec::new(),
            at: 0,
        })
    }

    /// The bytes the blocks hold in buffers now (their decoders' state aside).
    #[cfg(test)]
    fn held(&self) -> usize {
        let zlib = match &self.stage {
            Stage::Zlib(z) => z.inflate.get_ref().get_ref().capacity(),
            _ => 0,
        };
        self.compressed.capacity() + self.block.capacity() + zlib
    }

    /// The bytes an LZ4 block is held in, whole, beside its compressed bytes (LZ4's blocks have
    /// no stream): the largest block and the largest compressed block; `None` for zlib, whose
    /// blocks are streams.
    pub(super) fn held_whole(&self) -> Option<u64> {
        (self.compressor == Compressor::Lz4).then(|| {
            let compressed = self.sizes.iter().copied().max().unwrap_or(0);
            self.block_size.saturating_add(compressed)
        })
    }

    /// The decoded size of block `i`.
    fn size(&self, i: usize) -> u64 {
        if i + 1 == self.sizes.len() {
            self.last_size
        } else {
            self.block_size
        }
    }

    /// Starts the next block: a zlib block's decoder set on its compressed bytes, an LZ4 block
    /// decompressed whole into `block`.
    fn start(&mut self) -> std::io::Result<()> {
        let i = self.next;
        let size = self.size(i);
        self.next += 1;
        let Stage::Between(input) = std::mem::replace(&mut self.stage, Stage::Moving) else {
            return Err(invalid("blocks read out of order".into()));
        };
        if self.compressor == Compressor::Zlib {
            let compressed = BufReader::with_capacity(ZLIB_BUFFER, input.take(self.sizes[i]));
            self.stage = Stage::Zlib(Inflating {
                inflate: ZlibDecoder::new(compressed).take(size),
                i,
                size,
                made: 0,
            });
            return Ok(());
        }
        let mut input = input;
        let read = self.lz4(&mut input, i, size);
        self.stage = Stage::Between(input);
        read
    }

    /// Decompresses LZ4 block `i`, of `size` bytes decoded, from `input` into `block`.
    fn lz4(&mut self, input: &mut R, i: usize, size: u64) -> std::io::Result<()> {
        self.compressed.clear();
        input
            .take(self.sizes[i])
            .read_to_end(&mut self.compressed)?;
        if (self.compressed.len() as u64) < self.sizes[i] {
            return Err(IoError::new(
                ErrorKind::UnexpectedEof,
                format!("lz4 block {i} is cut short"),
            ));
        }
        // An LZ4 byte decodes to at most 255 bytes (a match's length grows by 255 a byte): a
        // block claiming more than its bytes can hold is refused before room is made for it.
        let most = (self.compressed.len() as u64).saturating_mul(LZ4_MOST);
        if size > most {
            return Err(invalid(format!(
                "lz4 block {i} of {} bytes cannot decompress to {size}",
                self.compressed.len()
            )));
        }
        self.block.clear();
        self.block
            .resize(usize::try_from(size).unwrap_or(usize::MAX), 0);
        let made = lz4_flex::block::decompress_into(&self.compressed, &mut self.block)
            .map_err(|e| invalid(format!("lz4 block {i}: {e}")))?;
        self.block.truncate(made);
        self.at = 0;
        if made as u64 != size {
            return Err(invalid(format!(
                "lz4 block {i} decompresses to {made} bytes, not {size}"
            )));
        }
        Ok(())
    }

    /// Ends the zlib block being read, once its decoder gives no more: checked to have given
    /// exactly its size, from exactly its compressed bytes.
    fn end_zlib(&mut self) -> std::io::Result<()> {
        let Stage::Zlib(z) = std::mem::replace(&mut self.stage, Stage::Moving) else {
            return Ok(());
        };
        let (i, made, size) = (z.i, z.made, z.size);
        if made != size {
            return Err(invalid(format!(
                "zlib block {i} decompresses to {made} bytes, not {size}"
            )));
        }
        let mut rest = z.inflate.into_inner().into_inner().into_inner();
        // Bytes of the block after its stream (read ahead or not) are skipped.
        std::io::copy(&mut rest, &mut std::io::sink())?;
        if rest.limit() > 0 {
            return Err(IoError::new(
                ErrorKind::UnexpectedEof,
                format!("zlib block {i} is cut short"),
            ));
        }
        self.stage = Stage::Between(rest.into_inner());
        Ok(())
    }
}

impl<R: Read> Read for Blocks<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        loop {
            if let Stage::Zlib(z) = &mut self.stage {
                if buf.is_empty() {
                    return Ok(0);
                }
                let i = z.i;
                let n = z
                    .inflate
                    .read(buf)
                    .map_err(|e| invalid(format!("zlib block {i}: {e}")))?;
                if n > 0 {
                    z.made += n as u64;
                    return Ok(n);
                }
                self.end_zlib()?;
            } else if self.at < self.block.len() {
                let n = buf.len().min(self.block.len() - self.at);
                buf[..n].copy_from_slice(&self.block[self.at..self.at + n]);
                self.at += n;
                return Ok(n);
            } else if self.next == self.sizes.len() {
                return Ok(0);
            } else {
                self.start()?;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decoded(text: &str) -> std::io::Result<Vec<u8>> {
        let mut out = Vec::new();
        Base64::new(text.as_bytes()).read_to_end(&mut out)?;
        Ok(out)
    }

    #[test]
    fn base64_groups_padded_in_the_middle_and_whitespace() {
        assert_eq!(decoded("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decoded(" aGk=\n  aGVsbG8=").unwrap(), b"hihello");
        assert_eq!(decoded("YQ==YWJj").unwrap(), b"aabc");
        assert_eq!(decoded("").unwrap(), b"");
        assert!(decoded("aGV").is_err());
        assert!(decoded("a===").is_err());
        assert!(decoded("aG=s").is_err());
        assert!(decoded("aG<s").is_err());
    }

    #[test]
    fn blocks_check_their_header_against_the_array() {
        let words = Words {
            size: 4,
            endian: Endian::Little,
        };
        let header = |w: &[u32]| -> Vec<u8> { w.iter().flat_map(|v| v.to_le_bytes()).collect() };
        // Two blocks of 4 bytes, the last of 2: 6 bytes, not 10.
        let e = Blocks::new(
            &header(&[2, 4, 2, 9, 9])[..],
            Compressor::Zlib,
            words,
            10,
            100,
        )
        .err();
        assert!(
            e.unwrap()
                .contains("its zlib header says 2 blocks of 4 bytes")
        );
        // A billion blocks the file cannot hold.
        let e = Blocks::new(
            &header(&[1 << 30, 1, 0])[..],
            Compressor::Lz4,
            words,
            1 << 30,
            100,
        )
        .err();
        assert!(
            e.unwrap()
                .contains("more than the file or the memory limit holds")
        );
    }

    #[test]
    fn an_lz4_block_claiming_more_than_its_bytes_hold_is_refused_before_room_is_made() {
        let words = Words {
            size: 4,
            endian: Endian::Little,
        };
        // One block of 1 MiB, compressed to 2 bytes.
        let mut input: Vec<u8> = [1u32, 1 << 20, 0, 2]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        input.extend_from_slice(&[0x10, 0x00]);
        let mut blocks = Blocks::new(&input[..], Compressor::Lz4, words, 1 << 20, 100).unwrap();
        let e = blocks.read(&mut [0u8; 16]).unwrap_err().to_string();
        assert_eq!(e, "lz4 block 0 of 2 bytes cannot decompress to 1048576");
        assert!(blocks.block.capacity() < 1 << 20);
        // The same bytes decoded exactly: a block of one literal, `A`.
        let mut input: Vec<u8> = [1u32, 1, 0, 2]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        input.extend_from_slice(&[0x10, b'A']);
        let mut blocks = Blocks::new(&input[..], Compressor::Lz4, words, 1, 100).unwrap();
        let mut out = Vec::new();
        blocks.read_to_end(&mut out).unwrap();
        assert_eq!(out, b"A");
    }

    /// One zlib block of 8 MiB (of `byte`), its header and its compressed bytes.
    fn one_zlib_block(byte: u8) -> Vec<u8> {
        let block = vec![byte; 8 << 20];
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
        std::io::Write::write_all(&mut z, &block).unwrap();
        let z = z.finish().unwrap();
        let mut input: Vec<u8> = [1u32, 8 << 20, 0, u32::try_from(z.len()).unwrap()]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        input.extend_from_slice(&z);
        input
    }

    #[test]
    fn a_zlib_block_is_decoded_as_it_is_read_none_of_it_held_whole() {
        let words = Words {
            size: 4,
            endian: Endian::Little,
        };
        // A block that is the whole array (8 MiB) read a MiB at a time: the blocks hold the
        // decoder's read-ahead only, not the block (8 MiB and its compressed bytes before).
        let input = one_zlib_block(7);
        let mut blocks = Blocks::new(&input[..], Compressor::Zlib, words, 8 << 20, 100).unwrap();
        let mut buf = vec![0u8; 1 << 20];
        let mut total = 0;
        let mut most = 0;
        loop {
            let n = blocks.read(&mut buf).unwrap();
            if n == 0 {
                break;
            }
            assert!(buf[..n].iter().all(|&b| b == 7));
            total += n;
            most = most.max(blocks.held());
        }
        assert_eq!(total, 8 << 20);
        assert!(most <= ZLIB_BUFFER, "{most} bytes held");
        // Cut short, and a block that decodes to less than its header says: refused.
        let e = Blocks::new(
            &input[..input.len() - 3],
            Compressor::Zlib,
            words,
            8 << 20,
            100,
        )
        .unwrap()
        .read_to_end(&mut Vec::new())
        .unwrap_err();
        assert!(e.to_string().starts_with("zlib block 0"), "{e}");
        let mut input = one_zlib_block(1);
        input[4..8].copy_from_slice(&(9u32 << 20).to_le_bytes());
        let e = Blocks::new(&input[..], Compressor::Zlib, words, 9 << 20, 100)
            .unwrap()
            .read_to_end(&mut Vec::new())
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "zlib block 0 decompresses to 8388608 bytes, not 9437184"
        );
    }
}
