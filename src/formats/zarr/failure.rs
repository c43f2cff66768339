//! Why a store could not give a chunk, as a typed value: the stores ([`super::store`],
//! [`super::http_store`]) hand it to zarrs inside the `std::io::Error` of a
//! `StorageError::IOError`, and the dataset reader finds it again by its type in the chain of
//! sources of zarrs' error, so that no error's text is read to word the message (one way in).
//! Its words are the ones the stores said before: zarrs' error shows them unchanged.

use std::fmt;
use std::sync::Arc;

use zarrs::storage::StorageError;

/// Why a store could not give a chunk.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Failure {
    /// The guard refused the chunk: the message names it (`chunk s0/0/0 decodes to more ...`).
    Refused(String),
    /// The file `key` (named from where the store is, a label image's `labels/NAME/` before
    /// the array's key when read over HTTP) could not be read: `problem`.
    Unread {
        /// The file as the store names it.
        key: String,
        /// What went wrong, in words.
        problem: String,
    },
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Refused(message) => f.write_str(message),
            Self::Unread { key, problem } => write!(f, "{key}: {problem}"),
        }
    }
}

impl std::error::Error for Failure {}

/// The failure inside the `std::io::Error` zarrs carries: its source is the failure, so that
/// walking the sources of zarrs' error (whose wrappers are transparent, each handing on its
/// inner error's source) reaches it.
#[derive(Debug)]
struct Carried(Failure);

impl fmt::Display for Carried {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for Carried {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.0)
    }
}

impl From<Failure> for StorageError {
    fn from(failure: Failure) -> Self {
        StorageError::IOError(Arc::new(std::io::Error::other(Carried(failure))))
    }
}

/// The failure a store gave, found in the sources of `error` (zarrs' error for a chunk);
/// `None` when the error is zarrs' own.
pub fn find<'e>(error: &'e (dyn std::error::Error + 'static)) -> Option<&'e Failure> {
    std::iter::successors(Some(error), |e| e.source()).find_map(|e| e.downcast_ref::<Failure>())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failure_is_found_again_through_zarrs_errors_and_shown_unchanged() {
        let failure = Failure::Unread {
            key: "labels/cells/s0/c/0".into(),
            problem: "HTTP 403 Forbidden".into(),
        };
        let error = zarrs::array::ArrayError::StorageError(failure.clone().into());
        assert_eq!(error.to_string(), "labels/cells/s0/c/0: HTTP 403 Forbidden");
        assert_eq!(find(&error), Some(&failure));
        let refused = Failure::Refused("chunk s0/0 decodes to more than the 8 bytes".into());
        let codec = zarrs::array::ArrayError::CodecError(zarrs::array::CodecError::StorageError(
            refused.clone().into(),
        ));
        assert_eq!(
            codec.to_string(),
            "chunk s0/0 decodes to more than the 8 bytes"
        );
        assert_eq!(find(&codec), Some(&refused));
        let other = zarrs::array::ArrayError::StorageError(StorageError::Other(
            "chunk s0/0 decodes to more".into(),
        ));
        assert_eq!(find(&other), None, "words alone are not a failure");
    }
}
