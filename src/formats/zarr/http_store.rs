//! A store read over HTTP, in place: its metadata fetched once and kept ([`Remote`]), its chunks
//! through a read-only zarrs store ([`HttpStore`]) that asks the server for the bytes zarrs asks
//! (a whole chunk, a shard's index, an inner chunk's range), each answer held to the budget
//! before it is read and each chunk weighed before it is decoded, as the local store's are.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use zarrs::storage::byte_range::{ByteRange, ByteRangeIterator};
use zarrs::storage::{Bytes, MaybeBytesIterator, ReadableStorageTraits, StorageError, StoreKey};

use super::failure::Failure;
use super::guard::Guard;
use crate::formats::remote::http::{Client, Span};
use crate::formats::remote::{Failed, Url, is_metadata, join};

/// A remote store: its client, and its metadata files as fetched (absent ones too).
#[derive(Debug)]
pub struct Remote {
    client: Client,
    metadata: Mutex<HashMap<String, Option<Arc<[u8]>>>>,
}

impl Remote {
    /// The store at `url`; a chunk answered 403 is missing (the fill value) when
    /// `forbidden_missing` (`--missing-as-fill`), else an error; its chunks kept in `disk`
    /// (`--cache DIR`) when given.
    pub fn new(
        url: Url,
        forbidden_missing: bool,
        disk: Option<Arc<crate::formats::remote::cache::Disk>>,
    ) -> Result<Self, String> {
        Ok(Self {
            client: Client::new(url)?
                .forbidden_as_missing(forbidden_missing)
                .cached(disk),
            metadata: Mutex::new(HashMap::new()),
        })
    }

    /// The store's URL.
    pub fn url(&self) -> &Url {
        self.client.url()
    }

    /// The metadata file `key` of the store (at most `limit` bytes), fetched once; `None` when
    /// the server has none.
    pub fn metadata(&self, key: &str, limit: u64) -> Result<Option<Arc<[u8]>>, String> {
        let cached = self
            .metadata
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .get(key)
            .cloned();
        if let Some(known) = cached {
            return Ok(known);
        }
        let got: Option<Arc<[u8]>> = self.client.get(key, Span::All, limit)?.map(Arc::from);
        self.metadata
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .insert(key.to_string(), got.clone());
        Ok(got)
    }
}

/// Bytes answered, with the span of the object they are and the object's size as far as known.
type Answered = (Bytes, (u64, u64), u64);

/// A read-only zarrs store over the node `prefix` of a remote store.
#[derive(Debug)]
pub struct HttpStore {
    remote: Arc<Remote>,
    prefix: String,
    /// The most bytes one answer may hold.
    max_file: u64,
    /// What the chunks of the array read may decode to.
    guard: Guard,
}

impl HttpStore {
    /// The store of the node `prefix` of `remote`, each answer at most `max_file` bytes, each
    /// chunk weighed by `guard`.
    pub fn new(remote: Arc<Remote>, prefix: &str, max_file: u64, guard: Guard) -> Self {
        Self {
            remote,
            prefix: prefix.to_string(),
            max_file,
            guard,
        }
    }

    /// The bytes `range` of `key`, with the span of the object they are (start, end) and the
    /// object's size as far as the answer tells it (what the guard needs to know a shard's index
    /// from a chunk); `None` when there is no such key.
    fn range(&self, key: &str, range: ByteRange) -> Result<Option<Answered>, StorageError> {
        if is_metadata(key) {
            let bytes = self
                .remote
                .metadata(key, self.max_file)
                .map_err(StorageError::Other)?;
            return Ok(bytes.map(|b| {
                let n = b.len() as u64;
                (Bytes::from(b.to_vec()), (0, n), n)
            }));
        }
        let span = match range {
            ByteRange::FromStart(0, None) => Span::All,
            ByteRange::FromStart(start, length) => Span::From(start, length),
            ByteRange::Suffix(n) => Span::Suffix(n),
        };
        let got = self.remote.client.get(key, span, self.max_file);
        let Some(bytes) = got.map_err(unread)? else {
            return Ok(None);
        };
        let n = bytes.len() as u64;
        let (at, size) = match span {
            // The whole object, or its last bytes: their own object as far as is known.
            Span::All | Span::Suffix(_) => ((0, n), n),
            Span::From(start, _) => ((start, start + n), u64::MAX),
        };
        Ok(Some((Bytes::from(bytes), at, size)))
    }
}

/// A request's failure, for zarrs: typed when it names its key ([`Failure::Unread`]).
fn unread(failed: Failed) -> StorageError {
    match failed {
        Failed::At { key, problem } => Failure::Unread { key, problem }.into(),
        Failed::Refused(why) => StorageError::Other(why),
    }
}

impl ReadableStorageTraits for HttpStore {
    fn get_partial_many<'a>(
        &'a self,
        key: &StoreKey,
        byte_ranges: ByteRangeIterator<'a>,
    ) -> Result<MaybeBytesIterator<'a>, StorageError> {
        let full = join(&self.prefix, key.as_str());
        let mut out: Vec<Result<Bytes, StorageError>> = Vec::new();
        for range in byte_ranges {
            let Some((bytes, at, size)) = self.range(&full, range)? else {
                return Ok(None);
            };
            self.guard
                .check(key.as_str(), at, size, &bytes)
                .map_err(Failure::Refused)?;
            out.push(Ok(bytes));
        }
        Ok(Some(Box::new(out.into_iter())))
    }

    fn size_key(&self, key: &StoreKey) -> Result<Option<u64>, StorageError> {
        let full = join(&self.prefix, key.as_str());
        self.remote.client.size(&full).map_err(unread)
    }

    fn supports_get_partial(&self) -> bool {
        true
    }
}
