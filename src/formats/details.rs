//! What a reader tells of a file besides its volume (a DICOM series, an OME-Zarr store's levels,
//! an MRC map's mode), in a form no caller needs the format to use: `info`'s lines, the JSON
//! object under the reader's key, the label a list gives the volume. Each reader fills its own
//! type; the shared types ([`Loaded`](super::Loaded)) hold it as a [`Details`] trait object.

use std::any::Any;
use std::collections::BTreeMap;
use std::fmt::Debug;

use serde::Serialize;
use serde::ser::{SerializeMap, Serializer};
use serde_json::Value;
use serde_json::value::RawValue;

use super::Format;

/// What a reader tells of the file it read besides the volume.
pub trait Details: Any + Debug + Send + Sync {
    /// The words after the format's name on `info`'s format line (`OME-Zarr 0.4 on Zarr v2`);
    /// `None` leaves the line to the format's version.
    fn format_words(&self) -> Option<String> {
        None
    }

    /// `info`'s lines, each a label (at most 11 characters) and its text, every name read from
    /// the file escaped by the one rule ([`crate::error::names`]).
    fn lines(&self) -> Vec<(String, String)>;

    /// The value `info --json` gives under the reader's key (its `Reader::details_key`).
    fn json(&self) -> Value;

    /// The value a `triage` row gives under the reader's key, where its rows carry one (its
    /// `Reader::in_rows`): JSON text, its keys in the order they are written.
    fn row_json(&self) -> Option<Box<RawValue>> {
        None
    }

    /// What a list adds after the volume's path to name it among the file's (` [series 3 "CT"]`).
    fn label(&self) -> Option<String> {
        None
    }
}

/// What `info --json` gives of `details`, read as `format`: every reader's key, null but for
/// `format`'s reader's.
pub(super) fn info_json(
    format: Format,
    details: Option<&dyn Details>,
) -> BTreeMap<&'static str, Value> {
    super::registry::details_keys()
        .map(|(of, key, _)| {
            let value = details
                .filter(|_| of == format)
                .map_or(Value::Null, Details::json);
            (key, value)
        })
        .collect()
}

/// What a `triage` row gives of a volume's details, serialized as the entries of the row's
/// object: the key of each reader whose rows carry its details, null but for the reader that
/// read the volume; and the label a list gives it.
#[derive(Clone, Debug)]
pub struct RowDetails {
    entries: Vec<(&'static str, Option<Box<RawValue>>)>,
    label: Option<String>,
}

impl RowDetails {
    /// The row's details of a volume read as `format` (none: a volume that was not read).
    pub(super) fn of(format: Option<Format>, details: Option<&dyn Details>) -> Self {
        let entries = super::registry::details_keys()
            .filter(|&(_, _, in_rows)| in_rows)
            .map(|(of, key, _)| {
                let raw = details
                    .filter(|_| Some(of) == format)
                    .and_then(Details::row_json);
                (key, raw)
            })
            .collect();
        Self {
            entries,
            label: details.and_then(Details::label),
        }
    }

    /// The row's details of a volume that could not be read: every key null.
    #[must_use]
    pub fn none() -> Self {
        Self::of(None, None)
    }

    /// What a list adds after the volume's path to name it (` [series 3 "CT"]`).
    #[must_use]
    pub fn label(&self) -> Option<&str> {
        self.label.as_deref()
    }
}

impl Serialize for RowDetails {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.entries.len()))?;
        for (key, value) in &self.entries {
            map.serialize_entry(key, value)?;
        }
        map.end()
    }
}

/// `value` as JSON, for [`Details::json`]: null if it cannot be written (no details type fails).
pub(crate) fn json_of(value: &impl Serialize) -> Value {
    serde_json::to_value(value).unwrap_or(Value::Null)
}

/// `value` as JSON text, its keys in the order serde writes them, for [`Details::row_json`].
pub(crate) fn raw_of(value: &impl Serialize) -> Option<Box<RawValue>> {
    serde_json::value::to_raw_value(value).ok()
}
