//! Where a store lives: a local folder (its files opened inside its tree, as `store.rs` does)
//! or, with the `remote` feature, a URL read over HTTP (`http_store.rs`). The metadata reader
//! and the dataset reader name the store's nodes and files by their keys (`""` for the store's
//! root, `labels/cells/0/.zarray`) and ask the root for them, so that neither knows which it is.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde_json::Value;
use zarrs::storage::ReadableStorageTraits;

use super::guard::Guard;
use super::store::{self, LocalStore};
use crate::error::{Error, Result};
use crate::formats::remote;

/// The most bytes of one metadata file read.
pub const MAX_JSON: u64 = 16 << 20;

/// A store's root.
#[derive(Clone, Debug)]
pub enum Root {
    /// A local folder, and its tree (canonical) that every file read lies in.
    Local {
        /// The folder as named.
        dir: PathBuf,
        /// Its canonical path.
        tree: PathBuf,
    },
    /// A store read over HTTP.
    #[cfg(feature = "remote")]
    Remote(Arc<super::http_store::Remote>),
}

impl Root {
    /// The root of the store `dir`: a folder, or a URL ([`remote::is_url`]; an `s3://` one at
    /// the endpoint `opts` name, a chunk answered 403 missing when they say so, its chunks kept
    /// in the cache folder they name).
    pub fn open(dir: &Path, opts: &super::ZarrOptions) -> Result<Self> {
        let Some(text) = dir.to_str().filter(|_| remote::is_url(dir)) else {
            return Ok(Self::Local {
                dir: dir.to_path_buf(),
                tree: store::tree(dir)?,
            });
        };
        let url = remote::Url::parse_at(text, opts.endpoint.as_deref())
            .map_err(|m| Error::format(&remote::shown_text(text), m))?;
        #[cfg(feature = "remote")]
        {
            let shown = url.shown();
            let disk = match &opts.cache {
                Some(folder) => Some(Arc::new(
                    remote::cache::Disk::open(folder, remote::cache::DISK_CAP)
                        .map_err(|m| Error::format(folder, m))?,
                )),
                None => None,
            };
            let remote = super::http_store::Remote::new(url, opts.missing_as_fill, disk)
                .map_err(|m| Error::format(&shown, m))?;
            Ok(Self::Remote(Arc::new(remote)))
        }
        #[cfg(not(feature = "remote"))]
        Err(Error::unsupported(
            &url.shown(),
            "this slabscope was built without the `remote` feature: it reads no URLs \
             (download the store, or build with the feature)",
        ))
    }

    /// Whether the store is read over the network.
    pub fn is_remote(&self) -> bool {
        !matches!(self, Self::Local { .. })
    }

    /// The bytes of a budget of `max_memory` left for the voxels read: all of it for a local
    /// folder; for a store at a URL, less the share the answers to its chunk requests kept in
    /// memory may take (`remote::cache::MEMORY_SHARE`), as the budget's planner leaves it.
    pub fn room(&self, max_memory: u64) -> u64 {
        match self {
            Self::Local { .. } => max_memory,
            #[cfg(feature = "remote")]
            Self::Remote(_) => max_memory - max_memory / remote::cache::MEMORY_SHARE,
        }
    }

    /// The node or file `key` as messages name it: a path in the folder, or a URL.
    pub fn shown(&self, key: &str) -> PathBuf {
        match self {
            Self::Local { dir, .. } if key.is_empty() => dir.clone(),
            Self::Local { dir, .. } => dir.join(key),
            #[cfg(feature = "remote")]
            Self::Remote(r) => PathBuf::from(remote::join(&r.url().to_string(), key)),
        }
    }

    /// The bytes of the metadata file `key` (at most [`MAX_JSON`]); `None` when there is none.
    fn bytes(&self, key: &str) -> std::result::Result<Option<Arc<[u8]>>, String> {
        match self {
            Self::Local { tree, .. } => {
                let file = match store::open_inside(tree, Path::new(key)) {
                    Ok(file) => file,
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
                    Err(e) => return Err(format!("{}: {e}", name(key))),
                };
                let mut text = Vec::new();
                file.take(MAX_JSON + 1)
                    .read_to_end(&mut text)
                    .map_err(|e| format!("{}: {e}", name(key)))?;
                Ok(Some(text.into()))
            }
            #[cfg(feature = "remote")]
            Self::Remote(r) => r.metadata(key, MAX_JSON + 1),
        }
    }

    /// The JSON of the metadata file `key`; `None` when there is none.
    pub fn json(&self, key: &str) -> std::result::Result<Option<Value>, String> {
        let Some(text) = self.bytes(key)? else {
            return Ok(None);
        };
        if text.len() as u64 > MAX_JSON {
            return Err(format!(
                "{}: more than {} MiB of metadata",
                name(key),
                MAX_JSON >> 20
            ));
        }
        serde_json::from_slice(&text).map(Some).map_err(|e| {
            if text.trim_ascii_start().starts_with(b"<") {
                format!(
                    "{}: an HTML page where JSON was expected (is the URL the store's own?)",
                    name(key)
                )
            } else {
                format!("{}: not JSON ({e})", name(key))
            }
        })
    }

    /// Whether the file `key` exists.
    #[cfg_attr(not(feature = "remote"), allow(clippy::unnecessary_wraps))]
    pub fn has(&self, key: &str) -> std::result::Result<bool, String> {
        match self {
            Self::Local { dir, .. } => Ok(dir.join(key).exists()),
            #[cfg(feature = "remote")]
            Self::Remote(_) => Ok(self.bytes(key)?.is_some()),
        }
    }

    /// The zarrs store of the node `node` (an image), each of its files at most `max_file`
    /// bytes, each chunk weighed by `guard`.
    pub fn storage(
        &self,
        node: &str,
        max_file: u64,
        guard: Guard,
    ) -> Arc<dyn ReadableStorageTraits> {
        match self {
            Self::Local { tree, .. } => {
                Arc::new(LocalStore::new(tree, Path::new(node), max_file).with_guard(guard))
            }
            #[cfg(feature = "remote")]
            Self::Remote(r) => Arc::new(super::http_store::HttpStore::new(
                Arc::clone(r),
                node,
                max_file,
                guard,
            )),
        }
    }
}

/// The file name of `key` inside its store, for messages.
fn name(key: &str) -> &str {
    key.rsplit('/').next().unwrap_or(key)
}
