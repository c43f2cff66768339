//! Library errors as Python exceptions, worded in keyword arguments where the CLI names flags.

use pyo3::exceptions::{
    PyException, PyFileExistsError, PyFileNotFoundError, PyKeyboardInterrupt, PyOSError,
    PyPermissionError, PyRuntimeError, PyValueError,
};
use pyo3::prelude::*;
use slabscope::Error;
use slabscope::error::names::controls;
use slabscope::error::shown;

pyo3::create_exception!(
    slabscope,
    VolumeError,
    PyException,
    "A file slabscope cannot read as a volume, or a volume it cannot analyse: the message names \
     the file and the problem."
);

/// The keyword of the library's parameter `name` (`ray_spacing`, `dtype` for `type`), or the
/// name itself when no keyword stands for it.
fn keyword(name: &str) -> &str {
    slabscope::params::find(name).map_or(name, |p| p.keyword)
}

/// The one-line message of `e`, with the keyword that lifts a limit or allows an overwrite.
pub fn message(e: &Error) -> String {
    let text = match e {
        Error::InvalidParameter {
            parameter,
            value,
            expected,
        } => format!("{}={value}: expected {expected}", keyword(parameter)),
        Error::DefaultUnfit { parameter, .. } => {
            let placeholder = slabscope::params::find(parameter)
                .and_then(|p| p.value_name)
                .unwrap_or("VALUE");
            format!(
                "{e} ({}={placeholder} asks for another)",
                keyword(parameter)
            )
        }
        Error::Unfit {
            parameter,
            value,
            problem,
        } => {
            let value = match value {
                slabscope::error::Value::Size(w, h) => format!("({w}, {h})"),
                slabscope::error::Value::Whole(n) => n.to_string(),
            };
            format!("{}={value}: {problem}", keyword(parameter))
        }
        Error::Conflicting { parameters: [a, b] } => {
            format!("{}= and {}= cannot both be given", keyword(a), keyword(b))
        }
        Error::Needs { parameter, needed } => {
            format!("{}= needs {}= too", keyword(parameter), keyword(needed))
        }
        Error::TooCoarse { note, cause } => format!(
            "{}, because {note} (raise it with {}=)",
            message(cause),
            keyword("max_memory")
        ),
        Error::TooLarge {
            machine: true,
            disk: true,
            ..
        } => format!("{e} (decode it to disk with {}=)", keyword("scratch")),
        Error::TooLarge { machine: true, .. } => e.to_string(),
        Error::TooLarge { disk: true, .. } => format!(
            "{e} (raise it with {}=, or decode it to disk with {}=)",
            keyword("max_memory"),
            keyword("scratch")
        ),
        Error::TooLarge { .. } => format!("{e} (raise it with {}=)", keyword("max_memory")),
        Error::RawUndescribed {
            path,
            missing,
            detail,
        } => {
            let keywords: Vec<String> = missing
                .iter()
                .filter_map(|m| slabscope::params::find(m))
                .map(|p| match p.value_name {
                    Some(v) if v.contains([',', 'x']) => {
                        format!("{}=({})", p.keyword, v.replace(['x', ','], ", "))
                    }
                    _ => format!("{}= ({})", p.keyword, p.expected()),
                })
                .collect();
            format!("{}: {detail}: give {}", shown(path), keywords.join(" and "))
        }
        Error::Exists { .. } => format!("{e} (force=True overwrites it)"),
        Error::Series {
            localizers: true, ..
        } => format!("{e} ({}=True keeps them)", keyword("include_localizers")),
        Error::Series { .. } => format!("{e} (pick one with {0}=N or {0}=UID)", keyword("series")),
        _ => e.to_string(),
    };
    controls(&text).into_owned()
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

/// A `ValueError` for keyword `name` given `value`, which should be `expected`.
pub fn invalid(name: &str, value: impl std::fmt::Display, expected: &str) -> PyErr {
    PyValueError::new_err(controls(&format!("{name}={value}: expected {expected}")).into_owned())
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
