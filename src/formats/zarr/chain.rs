//! A chunk's codec chain decoded as a stream into nothing, each stage's output counted and
//! stopped past its bound: what the guard ([`super::guard`]) weighs before `zarrs` decodes the
//! chunk. Nothing is held but the decoders' own windows, whatever the chain claims: gzip or
//! zstd inside gzip, several zstd frames, several gzip members.

use std::cell::Cell;
use std::io::Read;
use std::rc::Rc;

/// A stage of a chain, as far as weighing needs to know it, in the order applied when writing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    Gzip,
    Zlib,
    Zstd,
    /// Blosc, which states its decoded size in its header (the stage decoded first when
    /// writing, last when reading).
    Blosc,
    /// A checksum appended when writing (4 bytes), stripped when reading.
    Checksum,
    /// A codec that does not change how many bytes there are (`bytes`, `transpose`).
    Same,
}

impl Stage {
    /// The stage of codec `name` (Blosc with its inner compressor after a slash).
    pub fn of(name: &str) -> Self {
        match name.split('/').next().unwrap_or(name) {
            "gzip" => Self::Gzip,
            "zlib" => Self::Zlib,
            "zstd" => Self::Zstd,
            "blosc" => Self::Blosc,
            "crc32c" | "adler32" | "fletcher32" => Self::Checksum,
            _ => Self::Same,
        }
    }
}

/// Why a chunk fails its weighing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Over {
    /// A stage's output ran past its bound.
    Decodes,
    /// Blosc's header states a size past the chunk's.
    Says,
    /// A zstd frame asks for a window (memory held while decoding) past the stage's bound.
    Window,
}

/// Counts the bytes read through it; past `bound`, marks `over` and stops with an error.
struct Counted<R> {
    inner: R,
    left: u64,
    over: Rc<Cell<bool>>,
}

impl<R: Read> Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        if n as u64 > self.left {
            self.over.set(true);
            return Err(std::io::Error::other("past the chunk's size"));
        }
        self.left -= n as u64;
        Ok(n)
    }
}

/// Holds back the last `n` bytes of a stream (a checksum).
struct HoldBack<R> {
    inner: R,
    n: usize,
    held: Vec<u8>,
    done: bool,
}

impl<R: Read> Read for HoldBack<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        while !self.done && self.held.len() <= self.n {
            let mut more = [0u8; 8192];
            let got = self.inner.read(&mut more)?;
            if got == 0 {
                self.done = true;
            }
            self.held.extend_from_slice(&more[..got]);
        }
        let ready = self.held.len().saturating_sub(self.n).min(buf.len());
        buf[..ready].copy_from_slice(&self.held[..ready]);
        self.held.drain(..ready);
        Ok(ready)
    }
}

/// Weighs `bytes` decoded through `stages` (in the order applied when writing): every stage's
/// output may hold at most `slack` bytes, the last (the chunk's bytes) at most `limit`.
/// Errors of the streams themselves are not this check's: `zarrs` reports them in its words.
pub fn weigh(stages: &[Stage], bytes: &[u8], limit: u64, slack: u64) -> Result<(), Over> {
    let over = Rc::new(Cell::new(false));
    let mut reader: Box<dyn Read + '_> = Box::new(bytes);
    let mut blosc = false;
    for stage in stages.iter().rev() {
        reader = match stage {
            Stage::Same => continue,
            Stage::Checksum => Box::new(HoldBack {
                inner: reader,
                n: 4,
                held: Vec::new(),
                done: false,
            }),
            Stage::Gzip => Box::new(flate2::read::MultiGzDecoder::new(reader)),
            Stage::Zlib => Box::new(flate2::read::ZlibDecoder::new(reader)),
            Stage::Zstd => match zstd::stream::read::Decoder::new(reader) {
                Ok(mut d) => {
                    // A window of at most 8 MiB, or of the stage's bound when larger: what
                    // zstd writes for such a chunk (its default for level 19 streamed, or the
                    // content's size), not the 128 MiB a frame may ask for.
                    let log = (64 - slack.leading_zeros()).clamp(23, 27);
                    if d.window_log_max(log).is_err() {
                        return Ok(());
                    }
                    Box::new(d)
                }
                Err(_) => return Ok(()),
            },
            Stage::Blosc => {
                // Its header is read from what the stages before it decode; nothing decodes
                // after it (the guard refuses a chain with a compressor inside Blosc).
                blosc = true;
                break;
            }
        };
        reader = counted(reader, slack, &over);
    }
    let mut reader = counted(reader, if blosc { slack } else { limit }, &over);
    let mut header = [0u8; 16];
    let (got, failed) = read_some(&mut reader, if blosc { &mut header } else { &mut [] });
    if blosc && got >= 8 {
        let stated = u32::from_le_bytes([header[4], header[5], header[6], header[7]]);
        if u64::from(stated) > limit {
            return Err(Over::Says);
        }
    }
    // The stream's own errors are zarrs' to report; only the count and the window matter.
    let failed = match failed {
        Some(e) => Some(e),
        None => std::io::copy(&mut reader, &mut std::io::sink()).err(),
    };
    if over.get() {
        return Err(Over::Decodes);
    }
    match failed {
        Some(e) if is_window_too_large(&e) => Err(Over::Window),
        _ => Ok(()),
    }
}

/// Whether `e` is zstd's refusal of a frame whose window is past the decoder's limit
/// (`ZSTD_error_frameParameter_windowTooLarge`): the zstd crate gives a decoder's error code as
/// an `io::Error` of kind `Other` carrying exactly that code's name, which zstd itself gives
/// here, so no wording is written into this check.
fn is_window_too_large(e: &std::io::Error) -> bool {
    use zstd::zstd_safe::{get_error_name, zstd_sys::ZSTD_ErrorCode};
    // zstd's error codes are the negated enum values, as size_t.
    let code = (ZSTD_ErrorCode::ZSTD_error_frameParameter_windowTooLarge as usize).wrapping_neg();
    e.kind() == std::io::ErrorKind::Other
        && e.get_ref()
            .is_some_and(|inner| inner.to_string() == get_error_name(code))
}

/// `inner`, counted against `bound`, marking `over` past it.
fn counted<'a>(inner: Box<dyn Read + 'a>, bound: u64, over: &Rc<Cell<bool>>) -> Box<dyn Read + 'a> {
    Box::new(Counted {
        inner,
        left: bound,
        over: Rc::clone(over),
    })
}

/// Reads as much of `buf` as the stream gives (less at its end or on an error, returned).
fn read_some(reader: &mut dyn Read, buf: &mut [u8]) -> (usize, Option<std::io::Error>) {
    let mut got = 0;
    while got < buf.len() {
        match reader.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) => return (got, Some(e)),
        }
    }
    (got, None)
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use super::*;

    fn gzip(bytes: &[u8]) -> Vec<u8> {
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        e.write_all(bytes).unwrap();
        e.finish().unwrap()
    }

    #[test]
    fn a_checksum_after_gzip_is_held_back_and_the_stream_still_counted() {
        let stages = [Stage::Same, Stage::Gzip, Stage::Checksum];
        let mut fits = gzip(&[3u8; 64]);
        fits.extend([1, 2, 3, 4]);
        assert_eq!(weigh(&stages, &fits, 64, 4096), Ok(()));
        let mut bomb = gzip(&vec![0u8; 1 << 20]);
        bomb.extend([1, 2, 3, 4]);
        assert_eq!(weigh(&stages, &bomb, 64, 4096), Err(Over::Decodes));
    }

    #[test]
    fn every_stage_is_bounded_and_blosc_s_header_read_through_gzip() {
        // gzip inside gzip: the outer stage fits, the inner does not.
        let nested = gzip(&gzip(&vec![0u8; 1 << 20]));
        let stages = [Stage::Same, Stage::Gzip, Stage::Gzip];
        assert_eq!(
            weigh(&stages, &nested, 64 << 10, 80 << 10),
            Err(Over::Decodes)
        );
        let mut header = vec![2u8, 1, 1, 1];
        header.extend(1_000_000u32.to_le_bytes());
        header.extend([0u8; 8]);
        let stages = [Stage::Blosc, Stage::Gzip];
        assert_eq!(weigh(&stages, &gzip(&header), 64, 4096), Err(Over::Says));
    }

    #[test]
    fn the_window_is_told_by_zstd_s_error_code_not_by_words() {
        use zstd::zstd_safe::{get_error_name, zstd_sys::ZSTD_ErrorCode};
        let name = |c: ZSTD_ErrorCode| get_error_name((c as usize).wrapping_neg());
        let window = name(ZSTD_ErrorCode::ZSTD_error_frameParameter_windowTooLarge);
        let corrupt = name(ZSTD_ErrorCode::ZSTD_error_corruption_detected);
        assert!(is_window_too_large(&std::io::Error::other(window)));
        assert!(!is_window_too_large(&std::io::Error::other(corrupt)));
        // The same words from elsewhere (a file's error of another kind) are not zstd's.
        let elsewhere = std::io::Error::new(std::io::ErrorKind::InvalidData, window);
        assert!(!is_window_too_large(&elsewhere));
        // A window frame inside gzip is refused as one.
        let mut e = zstd::stream::write::Encoder::new(Vec::new(), 3).unwrap();
        e.include_contentsize(false).unwrap();
        e.window_log(27).unwrap();
        e.long_distance_matching(true).unwrap();
        e.write_all(&[5u8; 100]).unwrap();
        let framed = gzip(&e.finish().unwrap());
        let stages = [Stage::Same, Stage::Zstd, Stage::Gzip];
        assert_eq!(
            weigh(&stages, &framed, 64 << 10, 80 << 10),
            Err(Over::Window)
        );
    }

    #[test]
    fn a_zstd_window_past_the_bound_is_refused() {
        let mut e = zstd::stream::write::Encoder::new(Vec::new(), 3).unwrap();
        e.include_contentsize(false).unwrap();
        e.window_log(27).unwrap();
        e.long_distance_matching(true).unwrap();
        e.write_all(&[5u8; 100]).unwrap();
        let frame = e.finish().unwrap();
        let stages = [Stage::Same, Stage::Zstd];
        assert_eq!(
            weigh(&stages, &frame, 64 << 10, 80 << 10),
            Err(Over::Window)
        );
        let small = zstd::bulk::compress(&[5u8; 100], 3).unwrap();
        assert_eq!(weigh(&stages, &small, 64 << 10, 80 << 10), Ok(()));
    }
}
