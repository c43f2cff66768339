//! The library's errors worded in a front end's terms: each sentence that names a parameter
//! written once, here, and the parameter named by its entry ([`find`]): its flag on the command
//! line (`--bins 1`), its keyword in Python (`bins=1`). The CLI and Python choose their
//! [`Terms`] and call [`Error::in_terms`]; neither words an error of its own.

use super::find;
use crate::error::{Error, Value, shown};

/// How a front end names parameters and writes their values in its messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Terms {
    /// The command line's: `--bins 1`, `--size 30x30`, `--series N|UID`, `--force`.
    Flags,
    /// Python's keyword arguments: `bins=1`, `size=(30, 30)`, `series=N or series=UID`,
    /// `force=True`.
    Keywords,
}

impl Terms {
    /// Parameter `name` on its own: `--max-memory`, `max_memory=`; a name with no entry as it
    /// is (`name`, `name=`).
    #[must_use]
    pub fn name(self, name: &str) -> String {
        let p = find(name);
        match self {
            Self::Flags => p.map_or_else(|| name.to_string(), |p| format!("--{}", p.flag)),
            Self::Keywords => format!("{}=", p.map_or(name, |p| p.keyword)),
        }
    }

    /// Parameter `name` given `value` (already written in these terms): `--bins 1`, `bins=1`.
    #[must_use]
    pub fn given(self, name: &str, value: &str) -> String {
        match self {
            Self::Flags => format!("{} {value}", self.name(name)),
            Self::Keywords => format!("{}{value}", self.name(name)),
        }
    }

    /// A value in an error, written in these terms: `30x30` or `(30, 30)`.
    #[must_use]
    pub fn value(self, value: Value) -> String {
        match (self, value) {
            (Self::Keywords, Value::Size(w, h)) => format!("({w}, {h})"),
            _ => value.to_string(),
        }
    }

    /// A switch turned on: `--include-localizers`, `include_localizers=True`.
    #[must_use]
    pub fn switch(self, name: &str) -> String {
        match self {
            Self::Flags => self.name(name),
            Self::Keywords => self.given(name, "True"),
        }
    }

    /// Parameter `name` given its placeholder (`VALUE` when it has none), to say how to give
    /// it: `--series N|UID` and `--dims NXxNYxNZ` on the command line; in Python each of the
    /// alternatives (`series=N or series=UID`), a placeholder of several numbers as a tuple
    /// (`dims=(NX, NY, NZ)`).
    #[must_use]
    pub fn placeholder(self, name: &str) -> String {
        let placeholder = find(name).and_then(|p| p.value_name).unwrap_or("VALUE");
        match self {
            Self::Flags => self.given(name, placeholder),
            Self::Keywords => placeholder
                .split('|')
                .map(|alternative| self.given(name, &tuple(alternative)))
                .collect::<Vec<_>>()
                .join(" or "),
        }
    }

    /// The folder to decode voxels into: `--scratch DIR`, `scratch=` (Python's messages name
    /// the keyword alone).
    fn scratch(self) -> String {
        match self {
            Self::Flags => self.placeholder("scratch"),
            Self::Keywords => self.name("scratch"),
        }
    }

    /// How to give the raw option `name` a file lacks: its placeholder when the placeholder says
    /// more than the name (`--dims NXxNYxNZ`), else what it takes (`--type (u8, ...)`).
    fn raw_option(self, name: &str) -> Option<String> {
        let p = find(name)?;
        Some(match p.value_name {
            Some(v) if v != p.name.to_uppercase() => self.placeholder(name),
            _ => format!("{} ({})", self.name(name), p.expected()),
        })
    }

    /// What lifts a memory limit, after `e`'s own message, or `None` when nothing does.
    fn too_large(self, machine: bool, disk: bool) -> Option<String> {
        let raise = format!("raise it with {}", self.name("max_memory"));
        let decode = format!("decode it to disk with {}", self.scratch());
        match (machine, disk) {
            (true, true) => Some(decode),
            (true, false) => None,
            (false, true) => Some(format!("{raise}, or {decode}")),
            (false, false) => Some(raise),
        }
    }
}

/// A placeholder of several numbers (`NXxNYxNZ`, `DX,DY,DZ`) as a Python tuple (`(NX, NY, NZ)`);
/// any other as it is.
fn tuple(placeholder: &str) -> String {
    let parts: Vec<&str> = placeholder.split(['x', ',']).collect();
    let numbers = parts.len() > 1
        && parts
            .iter()
            .all(|p| !p.is_empty() && p.chars().all(|c| c.is_ascii_uppercase()));
    if numbers {
        format!("({})", parts.join(", "))
    } else {
        placeholder.to_string()
    }
}

impl Error {
    /// This error's one-line message in `terms`: a parameter named by its flag or keyword, a
    /// value written in the front end's syntax, and how to lift a limit, allow an overwrite or
    /// pick a series. Errors that name no parameter read as their [`Display`](std::fmt::Display).
    #[must_use]
    pub fn in_terms(&self, terms: Terms) -> String {
        match self.path() {
            Some(path) => format!("{}: {}", shown(path), self.detail_in_terms(terms)),
            None => self.detail_in_terms(terms),
        }
    }

    /// This error's message in `terms` in a list whose line names `file` already (triage's
    /// rows): without the file when it is the one the error names, else whole.
    #[must_use]
    pub fn in_terms_within(&self, terms: Terms, file: &std::path::Path) -> String {
        if self.path() == Some(file) {
            self.detail_in_terms(terms)
        } else {
            self.in_terms(terms)
        }
    }

    /// [`in_terms`](Self::in_terms) without the file the error names (its
    /// [`detail`](Self::detail) in `terms`).
    fn detail_in_terms(&self, terms: Terms) -> String {
        let t = terms;
        match self {
            Self::InvalidParameter {
                parameter,
                value,
                expected,
            } => format!("{}: expected {expected}", t.given(parameter, value)),
            Self::DefaultUnfit { parameter, .. } => {
                format!("{self} ({} asks for another)", t.placeholder(parameter))
            }
            Self::Unfit {
                parameter,
                value,
                problem,
            } => format!("{}: {problem}", t.given(parameter, &t.value(*value))),
            Self::Conflicting { parameters: [a, b] } => {
                format!("{} and {} cannot both be given", t.name(a), t.name(b))
            }
            Self::Needs { parameter, needed } => {
                let too = if t == Terms::Keywords { " too" } else { "" };
                format!("{} needs {}{too}", t.name(parameter), t.name(needed))
            }
            Self::TooCoarse { note, cause } => format!(
                "{}, because {note} (raise it with {})",
                cause.in_terms(t),
                t.name("max_memory")
            ),
            Self::TooLarge { machine, disk, .. } => match t.too_large(*machine, *disk) {
                Some(lift) => format!("{} ({lift})", self.detail()),
                None => self.detail(),
            },
            Self::RawUndescribed {
                missing, detail, ..
            } => {
                let give: Vec<String> = missing.iter().filter_map(|m| t.raw_option(m)).collect();
                format!("{detail}: give {}", give.join(" and "))
            }
            // `force` is each command's own, not an entry: named here as each front end spells it.
            Self::Exists { .. } => match t {
                Terms::Flags => format!("{} (use --force to overwrite it)", self.detail()),
                Terms::Keywords => format!("{} (force=True overwrites it)", self.detail()),
            },
            Self::NotRegularFile { .. } if t == Terms::Flags => {
                format!("{}, --force or not", self.detail())
            }
            Self::Series {
                localizers: true, ..
            } => format!(
                "{} ({} keeps them)",
                self.detail(),
                t.switch("include_localizers")
            ),
            Self::Series { .. } => format!(
                "{} (pick one with {})",
                self.detail(),
                t.placeholder("series")
            ),
            _ => self.detail(),
        }
    }
}

#[cfg(test)]
mod tests;
