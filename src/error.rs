//! The library's error type: one enum grouped by concern, every message naming the file and the
//! problem. Errors are data: the parameter's name and value, the bytes needed and allowed; their
//! `Display` names no flag, and `Error::in_terms` (in `params`, which knows each parameter's flag
//! and keyword) words them in a front end's terms: command-line flags or Python's keywords.

use std::path::{Path, PathBuf};

use crate::geometry::InvalidParameter;

pub mod names;

/// Everything that can go wrong in slabscope's library.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Reading or writing a file failed at the operating-system level.
    #[error("{}: {}", shown(path), self.detail())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// What the operating system said (part of the message, so not repeated as a source).
        error: std::io::Error,
    },
    /// The file is not a valid volume of the format it claims, or its header contradicts itself or its data.
    #[error("{}: {}", shown(path), self.detail())]
    Format {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong, quoting the offending value.
        message: String,
    },
    /// The file holds fewer bytes of voxel data than its header promises.
    #[error("{}: {}", shown(path), self.detail())]
    Truncated {
        /// The file holding the voxel data.
        path: PathBuf,
        /// Bytes of voxel data the header describes.
        expected: u64,
        /// Bytes actually there.
        found: u64,
    },
    /// Loading would need more memory than the limit allows; nothing was allocated.
    #[error("{}: {}", shown(path), self.detail())]
    TooLarge {
        /// The file concerned.
        path: PathBuf,
        /// What would have been allocated, e.g. "a 4096x4096x4096 f32 volume".
        what: String,
        /// Bytes needed.
        needed: u64,
        /// Bytes allowed.
        limit: u64,
        /// Whether the limit is the machine's own (its memory, or the system refused the
        /// allocation), which no memory budget lifts.
        machine: bool,
        /// Whether the bytes are voxels to decode, which a scratch folder on disk could hold
        /// instead (`LoadOptions::scratch`, not given).
        disk: bool,
    },
    /// The format is recognised but this variant of it is not supported.
    #[error("{}: {}", shown(path), self.detail())]
    Unsupported {
        /// The file concerned.
        path: PathBuf,
        /// What is not supported.
        message: String,
    },
    /// Headerless raw data whose description is incomplete: the raw options that must be given.
    #[error("{}: {}", shown(path), self.detail())]
    RawUndescribed {
        /// The file concerned.
        path: PathBuf,
        /// The raw options missing: `dims`, `type`.
        missing: &'static [&'static str],
        /// What is known of the data, and any hint from its size or name.
        detail: String,
    },
    /// A DICOM folder holds several series and none was named, the one named is not there, or
    /// every image was a localizer left out.
    #[error("{}: {}", shown(path), self.detail())]
    Series {
        /// The folder (or file).
        path: PathBuf,
        /// What is wrong, with the series listed.
        message: String,
        /// Whether localizers, left out, were all there was.
        localizers: bool,
    },
    /// A file that would be written exists already and overwriting was not asked for.
    #[error("{}: {}", shown(path), self.detail())]
    Exists {
        /// The file that exists.
        path: PathBuf,
    },
    /// A file that would be written exists and is not a regular file (a device, a FIFO, a
    /// folder): it is never replaced, whether overwriting was asked for or not.
    #[error("{}: {}", shown(path), self.detail())]
    NotRegularFile {
        /// The file that exists.
        path: PathBuf,
    },
    /// A parameter outside its domain, such as zero bins or a zero axis.
    #[error("{parameter} {value}: expected {expected}")]
    InvalidParameter {
        /// The parameter's name, as the library's parameter types spell it (`bins`, `slabs`,
        /// `ray_spacing`, ...).
        parameter: &'static str,
        /// The value given, as text.
        value: String,
        /// What it must be, e.g. "between 2 and 255".
        expected: String,
    },
    /// A parameter left at its default whose default does not fit the volume (the default of 4
    /// slabs in a volume 3 slices thick): the front end says how to give another value.
    #[error("the default of {value} {parameter} does not fit: {expected}")]
    DefaultUnfit {
        /// The parameter's name.
        parameter: &'static str,
        /// Its default, as text.
        value: String,
        /// What would fit.
        expected: String,
    },
    /// A value valid in itself that does not fit what it applies to: a slab to highlight
    /// beyond the slabs found, a picture too small for the faces of its slabs.
    #[error("{parameter} {value}: {problem}")]
    Unfit {
        /// The parameter's name.
        parameter: &'static str,
        /// The value given, as data (each front end writes a size its own way).
        value: Value,
        /// What is wrong with it here.
        problem: String,
    },
    /// Two parameters given together that exclude each other.
    #[error("{} and {} cannot both be given", parameters[0], parameters[1])]
    Conflicting {
        /// The two parameters' names.
        parameters: [&'static str; 2],
    },
    /// A parameter given without another that it needs (`solo` without `highlight`).
    #[error("{parameter} needs {needed}")]
    Needs {
        /// The parameter given.
        parameter: &'static str,
        /// The parameter it needs.
        needed: &'static str,
    },
    /// A parameter that does not fit the pyramid level the memory budget moved the analysis to
    /// (4 slabs of a level 3 slices thick), though it fits the level asked for: the budget is
    /// the cause, and the front end says how to raise it.
    #[error("{cause}, because {note}")]
    TooCoarse {
        /// What the budget said of the level it chose.
        note: String,
        /// The parameter's error on that level.
        cause: Box<Error>,
    },
    /// Encoding an output (a PNG) failed.
    #[error("encoding failed: {0}")]
    Encode(String),
    /// The volume cannot be analysed as asked: it is constant, or one slice thick along the axis.
    #[error("{0}")]
    Degenerate(String),
    /// Nothing to work on was found where the user pointed (no volume under the folders given).
    #[error("{0}")]
    NotFound(String),
    /// The computation was cancelled through its cancellation flag.
    #[error("cancelled")]
    Cancelled,
}

/// A parameter's value in an error, as data: a front end writes it in its own syntax.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Value {
    /// A whole number.
    Whole(u64),
    /// A picture's size, width and height in pixels.
    Size(u32, u32),
}

impl std::fmt::Display for Value {
    /// The command line's syntax: `5`, `640x480`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Whole(n) => write!(f, "{n}"),
            Self::Size(w, h) => write!(f, "{w}x{h}"),
        }
    }
}

/// A path as messages show it: escaped by the one rule of [`names`] (on one line, nothing raw
/// that a terminal would act on, non-UTF-8 bytes as `\xHH`).
pub fn shown(path: &Path) -> String {
    names::path(path)
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An I/O error about `path`.
    pub fn io(path: &Path, error: std::io::Error) -> Self {
        Self::Io {
            path: path.to_path_buf(),
            error,
        }
    }

    /// A format error about `path`.
    pub fn format(path: &Path, message: impl Into<String>) -> Self {
        Self::Format {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }

    /// An invalid-parameter error: `parameter` was `value`, and should be `expected`.
    pub fn invalid(
        parameter: &'static str,
        value: impl std::fmt::Display,
        expected: impl Into<String>,
    ) -> Self {
        Self::InvalidParameter {
            parameter,
            value: value.to_string(),
            expected: expected.into(),
        }
    }

    /// The file this error is about, when it names one.
    pub fn path(&self) -> Option<&Path> {
        match self {
            Self::Io { path, .. }
            | Self::Format { path, .. }
            | Self::Truncated { path, .. }
            | Self::TooLarge { path, .. }
            | Self::Unsupported { path, .. }
            | Self::RawUndescribed { path, .. }
            | Self::Series { path, .. }
            | Self::Exists { path }
            | Self::NotRegularFile { path } => Some(path),
            _ => None,
        }
    }

    /// What this error says of the file it names ([`path`](Self::path)), without naming it:
    /// its message after the file's name and `": "`; an error that names no file, its whole
    /// message.
    #[must_use]
    pub fn detail(&self) -> String {
        match self {
            Self::Io { error, .. } => error.to_string(),
            Self::Format { message, .. } | Self::Series { message, .. } => message.clone(),
            Self::Truncated {
                expected, found, ..
            } => format!("truncated voxel data: expected {expected} bytes, found {found}"),
            Self::TooLarge {
                what,
                needed,
                limit,
                ..
            } => format!(
                "{what} needs {}, over the memory limit of {}",
                human_bytes(*needed),
                human_bytes(*limit)
            ),
            Self::Unsupported { message, .. } => format!("unsupported: {message}"),
            Self::RawUndescribed {
                missing, detail, ..
            } => format!("{detail}: its {} must be given", missing.join(" and ")),
            Self::Exists { .. } => "already exists".into(),
            Self::NotRegularFile { .. } => {
                "not a regular file: slabscope writes only regular files".into()
            }
            _ => self.to_string(),
        }
    }

    /// This error's message in a list whose line names `file` already: without the file when
    /// it is the one the error names, else whole.
    #[must_use]
    pub fn within(&self, file: &Path) -> String {
        if self.path() == Some(file) {
            self.detail()
        } else {
            self.to_string()
        }
    }

    /// This error, reported about `named`, the file the user gave, when it is about another
    /// file that `named` led to (a detached header's data file, a folder's slice): the message
    /// then names both, the user's first.
    #[must_use]
    pub fn reached_from(self, named: &Path) -> Self {
        match self.path() {
            Some(p) if p != named => Self::Format {
                path: named.to_path_buf(),
                message: format!("{}: {}", shown(p), self.detail()),
            },
            _ => self,
        }
    }

    /// An unsupported-variant error about `path`.
    pub fn unsupported(path: &Path, message: impl Into<String>) -> Self {
        Self::Unsupported {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

impl From<InvalidParameter> for Error {
    /// Geometry's rejection as the crate's: the same parameter, value and expectation, so the
    /// same message.
    fn from(e: InvalidParameter) -> Self {
        Self::InvalidParameter {
            parameter: e.parameter,
            value: e.value,
            expected: e.expected,
        }
    }
}

/// A byte count for people: "1.5 GiB (1610612736 bytes)" above a KiB, "12 bytes" below.
#[must_use]
pub fn human_bytes(bytes: u64) -> String {
    if bytes < 1024 {
        return format!("{bytes} bytes");
    }
    format!("{} ({bytes} bytes)", short_bytes(bytes))
}

/// `bytes` in the largest binary unit that keeps the value at least 1, without the exact count
/// [`human_bytes`] adds: "1.5 GiB".
pub fn short_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["KiB", "MiB", "GiB", "TiB", "PiB"];
    if bytes < 1024 {
        return format!("{bytes} bytes");
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    format!("{value:.1} {}", UNITS[unit])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn human_bytes_picks_the_unit() {
        assert_eq!(human_bytes(12), "12 bytes");
        assert_eq!(human_bytes(1536), "1.5 KiB (1536 bytes)");
        assert_eq!(human_bytes(3 << 30), "3.0 GiB (3221225472 bytes)");
    }

    #[test]
    fn geometry_rejections_keep_their_message() {
        let e = "w".parse::<crate::geometry::Axis>().unwrap_err();
        let text = e.to_string();
        assert_eq!(text, "axis w: expected x, y, z or a direction DX,DY,DZ");
        assert_eq!(Error::from(e).to_string(), text);
    }

    #[test]
    fn messages_name_the_file() {
        let e = Error::Truncated {
            path: "a/b.nrrd".into(),
            expected: 100,
            found: 40,
        };
        assert_eq!(
            e.to_string(),
            "a/b.nrrd: truncated voxel data: expected 100 bytes, found 40"
        );
    }
}
