//! Library errors as Python exceptions, worded in keyword arguments where the CLI names flags.

use pyo3::exceptions::{
    PyException, PyFileExistsError, PyFileNotFoundError, PyKeyboardInterrupt, PyOSError,
    PyPermissionError, PyRuntimeError, PyValueError,
};
use pyo3::prelude::*;
use slabscope::Error;
use slabscope::error::names::controls;
use slabscope::params::Terms;

pyo3::create_exception!(
    slabscope,
    VolumeError,
    PyException,
    "A file slabscope cannot read as a volume, or a volume it cannot analyse: the message names \
     the file and the problem."
);

/// The one-line message of `e`, worded by the library in keyword arguments (`bins=1`, the
/// keyword that lifts a limit or allows an overwrite), control characters escaped.
pub fn message(e: &Error) -> String {
    controls(&e.in_terms(Terms::Keywords)).into_owned()
}

/// `e` as the Python exception a user catches: `FileNotFoundError` and the other `OSError`s for
/// files that cannot be opened, `ValueError` for bad parameters, `KeyboardInterrupt` for a
/// cancelled call, [`VolumeError`] for a file or volume slabscope cannot work with.
pub fn to_py(e: Error) -> PyErr {
    let text = message(&e);
    match &e {
        Error::Io { error, .. } => match error.kind() {
            std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(text),
            std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(text),
            _ => PyOSError::new_err(text),
        },
        Error::NotFound(_) => PyFileNotFoundError::new_err(text),
        Error::Exists { .. } => PyFileExistsError::new_err(text),
        Error::NotRegularFile { .. } => PyOSError::new_err(text),
        Error::InvalidParameter { .. }
        | Error::DefaultUnfit { .. }
        | Error::Unfit { .. }
        | Error::Conflicting { .. }
        | Error::Needs { .. }
        | Error::TooCoarse { .. } => PyValueError::new_err(text),
        Error::Cancelled => PyKeyboardInterrupt::new_err("cancelled"),
        Error::Encode(_) => PyRuntimeError::new_err(text),
        _ => VolumeError::new_err(text),
    }
}

/// Fails, naming the file, when `volume`'s voxels are read from a map whose file was cut short
/// under it: what a call computed from them is wrong (the module recovers from the fault
/// instead of ending the interpreter: `install_fault_recovery`).
pub fn intact(volume: &slabscope::Volume) -> PyResult<()> {
    volume.data().check_intact().map_err(to_py)
}

/// A `ValueError` for parameter `name` (the library's name, which the library words as its
/// keyword) given `value` as Python shows it, which should be `expected`: the library's
/// [`Error::InvalidParameter`] in Python's terms, so that Python words no error of its own.
pub fn invalid(name: &'static str, value: impl std::fmt::Display, expected: &str) -> PyErr {
    to_py(Error::invalid(name, value, expected))
}

/// Results of the library as Python results.
pub trait OrPy<T> {
    /// The error as a Python exception.
    fn or_py(self) -> PyResult<T>;
}

impl<T> OrPy<T> for slabscope::Result<T> {
    fn or_py(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}

/// How Python shows `o`, for messages.
pub fn repr(o: &Bound<'_, PyAny>) -> String {
    o.repr().map_or_else(|_| "?".into(), |r| r.to_string())
}
