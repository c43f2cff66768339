//! Every parameter a user sets, defined once: its name (which is also Python's keyword), its
//! command-line flag, its help, what values it takes and its default. The front ends hold no
//! parameter of their own: the CLI makes its flags from these entries (`cli::params`), Python its
//! keywords, defaults and signatures, and both hand the values given, as text, to [`Given`],
//! which parses them here into the library's parameter types (`AnalysisParams`, `LoadOptions`,
//! `RenderParams`, ...). An error about a parameter carries its name
//! ([`Error::InvalidParameter`]); a front end words it in its [`Terms`] ([`Error::in_terms`],
//! which looks the entry up): the flag on the command line, the keyword in Python. No error text
//! is matched anywhere.

mod build;
mod choices;
pub mod table;
mod terms;
pub mod text;

use std::collections::BTreeMap;

pub use build::Scene;
pub use choices::Choice;
pub use terms::Terms;

use crate::error::{Error, Result};

/// One user-facing parameter.
#[derive(Clone, Copy, Debug)]
pub struct Param {
    /// The library's name: in errors, and Python's keyword unless [`keyword`](Self::keyword)
    /// differs.
    pub name: &'static str,
    /// The command line's long flag, without its dashes.
    pub flag: &'static str,
    /// Python's keyword.
    pub keyword: &'static str,
    /// The placeholder of the value in the CLI's help (`None`: the name in capitals).
    pub value_name: Option<&'static str>,
    /// One paragraph, no final full stop: the CLI's help and Python's docstring.
    pub help: &'static str,
    /// What values it takes, and its default.
    pub takes: Takes,
    /// Parameters that cannot be given together with this one (`slabs` and `threshold`): its
    /// default applies only when none of them is given, so the CLI's help does not show it.
    pub conflicts: &'static [&'static str],
    /// A parameter this one needs (`solo` needs `highlight`).
    pub requires: Option<&'static str>,
}

/// What values a parameter takes, and its default.
#[derive(Clone, Copy, Debug)]
pub enum Takes {
    /// On or off (a flag without a value), off by default.
    Switch,
    /// A whole number from `min` to `max`.
    Count {
        /// The smallest value.
        min: u64,
        /// The largest value.
        max: u64,
        /// The default.
        default: Option<u64>,
    },
    /// A finite number from `min` to `max`.
    Number {
        /// The smallest value.
        min: f64,
        /// The largest value.
        max: f64,
        /// The default.
        default: Option<f64>,
    },
    /// A finite number above zero, with no default (the library works one out).
    Positive,
    /// One word of a list.
    Words {
        /// The words and what each means, in the order the help lists them.
        words: fn() -> Vec<Word>,
        /// The default word.
        default: &'static str,
    },
    /// Text in a syntax of its own (an axis, a size, a byte count).
    Text {
        /// Whether a text is valid.
        valid: fn(&str) -> bool,
        /// What a valid text is, for errors.
        expected: &'static str,
        /// The default, as text.
        default: Option<&'static str>,
        /// Whether a value may begin with `-` (a negative number).
        hyphens: bool,
    },
}

/// One word a [`Takes::Words`] parameter takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Word {
    /// The word.
    pub word: &'static str,
    /// What it means, no final full stop.
    pub help: &'static str,
}

impl Param {
    /// The default as text, as the CLI's help shows it and [`Given`] reads it.
    #[must_use]
    pub fn default_text(&self) -> Option<String> {
        match self.takes {
            Takes::Switch | Takes::Positive => None,
            Takes::Count { default, .. } => default.map(|d| d.to_string()),
            Takes::Number { default, .. } => default.map(|d| d.to_string()),
            Takes::Words { default, .. } => Some(default.to_string()),
            Takes::Text { default, .. } => default.map(str::to_string),
        }
    }

    /// What a value must be, for errors: "2 to 255", "a number from 0 to 10", "one of cut,
    /// dvr, mip".
    #[must_use]
    pub fn expected(&self) -> String {
        match self.takes {
            Takes::Switch => "true or false".into(),
            Takes::Count { min, max, .. } if max == u64::MAX => {
                format!("a whole number from {min}")
            }
            Takes::Count { min, max, .. } => format!("{min} to {max}"),
            Takes::Number { min, max, .. } => format!("a number from {min} to {max}"),
            Takes::Positive => "a positive number".into(),
            Takes::Words { words, .. } => {
                let all: Vec<&str> = words().iter().map(|w| w.word).collect();
                format!("one of {}", all.join(", "))
            }
            Takes::Text { expected, .. } => expected.into(),
        }
    }

    /// `text` checked against what the parameter takes: `Err` says what it should be.
    pub fn check(&self, text: &str) -> Result<(), String> {
        let t = text.trim();
        let valid = match self.takes {
            Takes::Switch => matches!(t, "true" | "false"),
            Takes::Count { min, max, .. } => {
                t.parse::<u64>().is_ok_and(|v| (min..=max).contains(&v))
            }
            Takes::Number { min, max, .. } => t
                .parse::<f64>()
                .is_ok_and(|v| v.is_finite() && (min..=max).contains(&v)),
            Takes::Positive => t.parse::<f64>().is_ok_and(|v| v.is_finite() && v > 0.0),
            Takes::Words { words, .. } => words().iter().any(|w| w.word == t),
            Takes::Text { valid, .. } => valid(text),
        };
        if valid { Ok(()) } else { Err(self.expected()) }
    }

    /// The error for `value` given to this parameter.
    #[must_use]
    pub fn invalid(&self, value: impl std::fmt::Display) -> Error {
        Error::invalid(self.name, value, self.expected())
    }
}

/// The entry named `name` (the library's name of a parameter), among every entry.
#[must_use]
pub fn find(name: &str) -> Option<&'static Param> {
    table::all().find(|p| p.name == name)
}

/// The values given for some parameters, as text, by their names; what is not given takes its
/// default. The CLI fills it from its command line, Python from its keywords.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Given {
    values: BTreeMap<&'static str, String>,
}

impl Given {
    /// Nothing given: every parameter at its default.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Gives `text` for parameter `p` (a switch: `"true"`).
    pub fn set(&mut self, p: &'static Param, text: impl Into<String>) {
        self.values.insert(p.name, text.into());
    }

    /// This, with `text` given for `p`.
    #[must_use]
    pub fn with(mut self, p: &'static Param, text: impl Into<String>) -> Self {
        self.set(p, text);
        self
    }

    /// This, with the values given in `other` too (`other`'s where both give one).
    pub fn extend(&mut self, other: &Self) {
        self.values
            .extend(other.values.iter().map(|(k, v)| (*k, v.clone())));
    }

    /// Whether `p` was given.
    #[must_use]
    pub fn has(&self, p: &Param) -> bool {
        self.values.contains_key(p.name)
    }

    /// The text given for `p`, or its default; `None` when neither.
    fn text(&self, p: &Param) -> Option<String> {
        self.values
            .get(p.name)
            .cloned()
            .or_else(|| p.default_text())
    }

    /// The text of `p`, checked.
    fn checked(&self, p: &Param) -> Result<Option<String>> {
        match self.text(p) {
            None => Ok(None),
            Some(t) => match p.check(&t) {
                Ok(()) => Ok(Some(t.trim().to_string())),
                Err(expected) => Err(Error::invalid(p.name, t, expected)),
            },
        }
    }

    /// A switch: whether it is on.
    pub fn switch(&self, p: &Param) -> Result<bool> {
        Ok(self.checked(p)?.is_some_and(|t| t == "true"))
    }

    /// A count (or a positive or bounded number) parsed as `T`.
    pub fn value<T: std::str::FromStr>(&self, p: &Param) -> Result<Option<T>> {
        self.checked(p)?
            .map(|t| t.parse::<T>().map_err(|_| p.invalid(&t)))
            .transpose()
    }

    /// A count or number that has a default.
    pub fn number<T: std::str::FromStr>(&self, p: &Param) -> Result<T> {
        self.value(p)?.ok_or_else(|| p.invalid("nothing"))
    }

    /// A picture's size `(width, height)`.
    pub fn size(&self, p: &Param) -> Result<(u32, u32)> {
        self.parsed(p, text::size)?
            .ok_or_else(|| p.invalid("nothing"))
    }

    /// A word, as the library's enum.
    pub fn word<T: Choice>(&self, p: &Param) -> Result<T> {
        let t = self.checked(p)?.unwrap_or_default();
        T::from_word(&t).ok_or_else(|| p.invalid(&t))
    }

    /// Text of a syntax of its own, parsed by `parse` (`None` when it fails, which `check`
    /// already refused).
    pub fn parsed<T>(&self, p: &Param, parse: impl Fn(&str) -> Option<T>) -> Result<Option<T>> {
        self.checked(p)?
            .map(|t| parse(&t).ok_or_else(|| p.invalid(&t)))
            .transpose()
    }

    /// The error raised with these values, reworded when it is about a parameter not given:
    /// the default did not fit ([`Error::DefaultUnfit`]), and the front end says how to give
    /// another.
    #[must_use]
    pub fn blame(&self, e: Error) -> Error {
        match e {
            Error::InvalidParameter {
                parameter,
                value,
                expected,
            } if find(parameter).is_some_and(|p| !self.has(p)) => Error::DefaultUnfit {
                parameter,
                value,
                expected,
            },
            e => e,
        }
    }
}
