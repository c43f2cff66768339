//! The decoded size of every chunk, checked before `zarrs` decodes it: its codecs decode into
//! buffers sized by what the data says (zstd's frame header, Blosc's) or grown to whatever the
//! stream holds (gzip, zlib), so a chunk of a few kilobytes could otherwise claim gigabytes.
//! A chunk, or each chunk inside a shard, may decode to at most its chunk's bytes. The whole
//! chain is weighed ([`super::chain`]): every codec of it (gzip inside gzip, zstd inside gzip),
//! every frame and member, each stage streamed into nothing and stopped past its bound, never
//! held. A shard inside a shard, a codec applied to whole shards, and a compressor inside Blosc
//! are refused with the array's metadata: their decoded sizes are not weighed.

use super::chain::{Over, Stage, weigh};
use super::meta::ArrayMeta;

/// How the chunks of one array are weighed.
#[derive(Clone, Debug)]
pub struct Guard {
    /// The key prefix of the array's chunks (`s0/`).
    prefix: String,
    /// The codec chain of the chunks (of the inner chunks, when sharded), in the order applied
    /// when writing.
    stages: Vec<Stage>,
    /// The most bytes a chunk (an inner chunk, when sharded) decodes to.
    limit: u64,
    /// For a sharded array: the shard index's bytes and whether it is at the end.
    index: Option<(u64, bool)>,
}

/// The stages of `codecs`, or why they are not read: a compressor inside Blosc (Blosc's header
/// weighs only its own output).
fn stages(codecs: &[String]) -> Result<Vec<Stage>, String> {
    let stages: Vec<Stage> = codecs.iter().map(|c| Stage::of(c)).collect();
    if let Some(at) = stages.iter().position(|s| *s == Stage::Blosc)
        && stages[..at].iter().any(|s| *s != Stage::Same)
    {
        return Err(format!(
            "codecs {}: a codec inside blosc is not read (its decoded size cannot be weighed)",
            codecs.join(", ")
        ));
    }
    Ok(stages)
}

impl Guard {
    /// The guard of the array `meta` under `prefix` (its path in the store), of `size`-byte
    /// elements; an error for a chain whose decoded size cannot be weighed.
    pub fn new(prefix: &str, meta: &ArrayMeta, size: u64) -> Result<Self, String> {
        let bytes = |shape: &[u64]| {
            shape
                .iter()
                .try_fold(size, |a, &n| a.checked_mul(n))
                .unwrap_or(u64::MAX)
        };
        let prefix = if prefix.is_empty() {
            String::new()
        } else {
            format!("{}/", prefix.trim_end_matches('/'))
        };
        let Some(inner) = &meta.inner else {
            return Ok(Self {
                prefix,
                stages: stages(&meta.codecs)?,
                limit: bytes(&meta.chunks),
                index: None,
            });
        };
        if meta.inner_codecs.iter().any(|c| c.starts_with("sharding")) {
            return Err(
                "a shard inside a shard is not read (its chunks' decoded sizes cannot \
                        be weighed)"
                    .into(),
            );
        }
        let after = meta
            .codecs
            .iter()
            .skip_while(|c| !c.starts_with("sharding"));
        if after.skip(1).any(|c| Stage::of(c) != Stage::Same) {
            return Err(format!(
                "codecs {}: a codec applied to whole shards is not read (its decoded size \
                 cannot be weighed)",
                meta.codecs.join(", ")
            ));
        }
        let per_shard: u64 = meta
            .chunks
            .iter()
            .zip(inner)
            .map(|(&s, &c)| s.div_ceil(c.max(1)))
            .product();
        // Offset and length (u64 each) per inner chunk, and a crc32c.
        let index = per_shard.saturating_mul(16).saturating_add(4);
        Ok(Self {
            prefix,
            stages: stages(&meta.inner_codecs)?,
            limit: bytes(inner),
            index: Some((index, !meta.index_at_start)),
        })
    }

    /// Checks the bytes `range` (start, and whether it runs to the end) of the file of `key`,
    /// of `file_size` bytes, read as `bytes`: nothing for metadata or the shard index.
    pub fn check(
        &self,
        key: &str,
        range: (u64, u64),
        file_size: u64,
        bytes: &[u8],
    ) -> Result<(), String> {
        let Some(name) = key.strip_prefix(&self.prefix) else {
            return Ok(());
        };
        if name.contains("zarr.json") || name.starts_with(".z") || name.contains("/.z") {
            return Ok(());
        }
        let Some((index, at_end)) = self.index else {
            return self.weigh(key, bytes);
        };
        let index_range = if at_end {
            (file_size.saturating_sub(index), file_size)
        } else {
            (0, index)
        };
        if range == index_range {
            return Ok(());
        }
        if range == (0, file_size) {
            // A whole shard: each inner chunk its index names.
            return self.weigh_shard(key, bytes, index, at_end);
        }
        self.weigh(key, bytes)
    }

    /// Checks every inner chunk of the whole shard `bytes`.
    fn weigh_shard(&self, key: &str, bytes: &[u8], index: u64, at_end: bool) -> Result<(), String> {
        let len = bytes.len() as u64;
        if index > len {
            return Ok(()); // zarrs reports the short shard
        }
        let at = if at_end { len - index } else { 0 } as usize;
        let table = &bytes[at..at + index as usize - 4];
        for entry in table.chunks_exact(16) {
            let offset = u64::from_le_bytes(entry[..8].try_into().unwrap_or_default());
            let size = u64::from_le_bytes(entry[8..].try_into().unwrap_or_default());
            if offset == u64::MAX && size == u64::MAX {
                continue; // an empty inner chunk
            }
            match offset.checked_add(size) {
                Some(end) if end <= len => {
                    self.weigh(key, &bytes[offset as usize..end as usize])?;
                }
                _ => return Ok(()), // zarrs reports the bad index
            }
        }
        Ok(())
    }

    /// Checks that one chunk's `bytes` decode to at most the limit, through every stage of its
    /// chain.
    fn weigh(&self, key: &str, bytes: &[u8]) -> Result<(), String> {
        let limit = self.limit;
        let over = |decoded: &str| {
            Err(format!(
                "chunk {key} {decoded} than the {limit} bytes of its chunk"
            ))
        };
        // A zstd frame read first that states more is refused unread; its number is not
        // quoted (no error quotes a file's bytes).
        // (A checksum is appended: the frame still starts the bytes.)
        let outer = self
            .stages
            .iter()
            .rev()
            .find(|s| !matches!(s, Stage::Same | Stage::Checksum));
        if outer == Some(&Stage::Zstd)
            && let Ok(Some(n)) = zstd::zstd_safe::get_frame_content_size(bytes)
            && n > limit
        {
            return over("says it decodes to more");
        }
        // Any stage's output may exceed the chunk's bytes by what compression adds.
        let slack = limit.saturating_add(limit / 64).saturating_add(4096);
        match weigh(&self.stages, bytes, limit, slack) {
            Ok(()) => Ok(()),
            Err(Over::Says) => over("says it decodes to more"),
            Err(Over::Decodes) => over("decodes to more"),
            Err(Over::Window) => Err(format!(
                "chunk {key} asks for a zstd window of more memory than a chunk of {limit} \
                 bytes needs"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use super::*;

    fn meta(codecs: &[&str]) -> ArrayMeta {
        ArrayMeta {
            shape: vec![8, 8],
            dtype: "uint8".into(),
            chunks: vec![4, 4],
            inner: None,
            codecs: codecs.iter().map(|c| (*c).to_string()).collect(),
            inner_codecs: Vec::new(),
            index_at_start: false,
        }
    }

    fn gzip(bytes: &[u8]) -> Vec<u8> {
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        e.write_all(bytes).unwrap();
        e.finish().unwrap()
    }

    #[test]
    fn a_chunk_that_inflates_past_its_size_is_refused() {
        let guard = Guard::new("s0", &meta(&["bytes", "gzip"]), 1).unwrap();
        let fits = gzip(&[7u8; 16]);
        assert!(guard.check("s0/c/0/0", (0, 0), 0, &fits).is_ok());
        let bomb = gzip(&vec![0u8; 1 << 20]);
        let e = guard.check("s0/c/0/0", (0, 0), 0, &bomb).unwrap_err();
        assert!(e.contains("decodes to more than the 16 bytes"), "{e}");
        assert!(
            guard.check("s0/zarr.json", (0, 0), 0, &bomb).is_ok(),
            "metadata"
        );
        assert!(
            guard.check("labels/x", (0, 0), 0, &bomb).is_ok(),
            "another array"
        );
    }

    #[test]
    fn stated_sizes_are_read_from_the_headers() {
        let zstd = Guard::new("0", &meta(&["bytes", "zstd", "crc32c"]), 1).unwrap();
        let big = zstd::bulk::compress(&[1u8; 64], 3).unwrap();
        let e = zstd.check("0/0.0", (0, 0), 0, &big).unwrap_err();
        assert!(e.contains("says it decodes to more"), "{e}");
        assert!(
            !e.contains("64,") && !e.contains(" 64 "),
            "no number of the file's: {e}"
        );
        let small = zstd::bulk::compress(&[1u8; 16], 3).unwrap();
        assert!(zstd.check("0/0.0", (0, 0), 0, &small).is_ok());
        let blosc = Guard::new("0", &meta(&["blosc/lz4"]), 1).unwrap();
        let mut header = vec![2u8, 1, 1, 1];
        header.extend(1_000_000u32.to_le_bytes());
        header.extend([0u8; 8]);
        assert!(blosc.check("0/0.0", (0, 0), 0, &header).is_err());
    }

    #[test]
    fn every_inner_chunk_of_a_whole_shard_is_weighed() {
        let mut m = meta(&[]);
        m.chunks = vec![4, 4];
        m.inner = Some(vec![4, 2]);
        m.inner_codecs = vec!["bytes".into(), "gzip".into()];
        let guard = Guard::new("s0", &m, 1).unwrap();
        let (a, b) = (gzip(&[1u8; 8]), gzip(&vec![0u8; 4096]));
        let mut shard = a.clone();
        shard.extend(&b);
        for (offset, len) in [(0, a.len()), (a.len(), b.len())] {
            shard.extend((offset as u64).to_le_bytes());
            shard.extend((len as u64).to_le_bytes());
        }
        shard.extend([0u8; 4]);
        let n = shard.len() as u64;
        let e = guard.check("s0/c/0/0", (0, n), n, &shard).unwrap_err();
        assert!(e.contains("more than the 8 bytes"), "{e}");
        // The index alone, read at the end, is not a chunk.
        assert!(
            guard
                .check("s0/c/0/0", (n - 36, n), n, &shard[..36])
                .is_ok()
        );
    }
}
