//! The library's parameter entries as flags: each entry becomes a clap argument with its flag,
//! help, placeholder, default and check, and the values given on the command line are handed
//! back to the library as text ([`Given`]), which parses them. No flag is defined here.

use std::marker::PhantomData;

use clap::builder::{PossibleValue, PossibleValuesParser};
use clap::parser::ValueSource;
use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches};
use slabscope::params::{Given, Param, Takes, table};

/// The flag of `p`.
fn arg(p: &'static Param) -> Arg {
    let mut a = Arg::new(p.name).long(p.flag).help(p.help);
    for rival in p.conflicts {
        a = a.conflicts_with(rival);
    }
    if let Some(needed) = p.requires {
        a = a.requires(needed);
    }
    if matches!(p.takes, Takes::Switch) {
        return a.action(ArgAction::SetTrue);
    }
    let placeholder = p
        .value_name
        .map_or_else(|| p.name.to_uppercase(), str::to_string);
    let mut a = a.action(ArgAction::Set).value_name(placeholder);
    a = match p.takes {
        Takes::Count { min: 0, max, .. } if max == u64::MAX => {
            a.value_parser(clap::value_parser!(u64))
        }
        Takes::Count { max, .. } if max == u64::MAX => a.value_parser(checked(p)),
        Takes::Count { min, max, .. } => a.value_parser(clap::value_parser!(u64).range(min..=max)),
        Takes::Words { words, .. } => a.value_parser(PossibleValuesParser::new(
            words()
                .into_iter()
                .map(|w| PossibleValue::new(w.word).help(w.help)),
        )),
        Takes::Number { min, .. } => a.value_parser(checked(p)).allow_negative_numbers(min < 0.0),
        Takes::Text { hyphens, .. } => a.value_parser(checked(p)).allow_hyphen_values(hyphens),
        Takes::Switch | Takes::Positive => a.value_parser(checked(p)),
    };
    // A default that applies only when no rival is given is not shown as the flag's.
    if p.conflicts.is_empty()
        && let Some(default) = p.default_text()
    {
        a = a.default_value(default);
    }
    a
}

/// The value parser of `p`: the library's check, worded as clap words a refusal.
fn checked(p: &'static Param) -> impl Fn(&str) -> Result<String, String> + Clone + Send + Sync {
    move |s: &str| match p.check(s) {
        Ok(()) => Ok(s.to_string()),
        Err(expected) => Err(format!("{s:?} is not {expected}")),
    }
}

/// The values of `params` given on the command line (defaults are the library's to apply).
fn given(m: &ArgMatches, params: &[&'static Param], into: &mut Given) {
    for &p in params {
        if m.value_source(p.name) != Some(ValueSource::CommandLine) {
            continue;
        }
        if matches!(p.takes, Takes::Switch) {
            into.set(p, "true");
        } else if let Some(raw) = m.get_raw(p.name).and_then(|mut v| v.next()) {
            into.set(p, raw.to_string_lossy());
        }
    }
}

/// A set of entries that a command takes together.
pub trait Set: std::fmt::Debug + Clone + Default + 'static {
    /// The entries, in the help's order.
    fn params() -> Vec<&'static Param>;
}

/// The flags of one set of entries and, once parsed, the values given for them.
#[derive(Debug, Clone, Default)]
pub struct Flags<S: Set> {
    /// The values given on the command line.
    pub given: Given,
    set: PhantomData<S>,
}

impl<S: Set> FromArgMatches for Flags<S> {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let mut flags = Self::default();
        flags.update_from_arg_matches(m)?;
        Ok(flags)
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        given(m, &S::params(), &mut self.given);
        Ok(())
    }
}

impl<S: Set> Args for Flags<S> {
    fn augment_args(cmd: Command) -> Command {
        cmd.args(S::params().into_iter().map(arg))
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

/// A [`Set`] of the table's entries.
macro_rules! set {
    ($(#[$doc:meta])* $name:ident => $params:expr) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Default)]
        pub struct $name;

        impl Set for $name {
            fn params() -> Vec<&'static Param> {
                $params
            }
        }
    };
}

set!(
    /// The analysis: view search and partition.
    Analysis => table::ANALYSIS.to_vec()
);
set!(
    /// The tour's own: paper mode.
    Tour => table::TOUR.to_vec()
);
set!(
    /// How to read the input.
    Load => table::LOAD.to_vec()
);
set!(
    /// How values become colours.
    Look => table::LOOK.to_vec()
);
set!(
    /// Whether the view search runs for a named axis too.
    Views => vec![&table::VIEWS]
);
set!(
    /// The pyramid level to compute on.
    Resolution => vec![&table::RESOLUTION]
);
set!(
    /// The size of a rendered picture.
    RenderSize => vec![&table::RENDER_SIZE]
);
set!(
    /// The size a slice is scaled to fit.
    SliceSize => vec![&table::SLICE_SIZE]
);
set!(
    /// Which slice.
    Index => vec![&table::INDEX]
);
set!(
    /// What a render shows and how: the mode, the look, the camera and the layout.
    Scene => [table::SCENE_FIRST, table::LOOK, table::SCENE].concat()
);
set!(
    /// The faces of every slab instead of the exploded view.
    Faces => vec![&table::FACES]
);
set!(
    /// No orientation letters on a slice.
    NoLetters => vec![&table::NO_LETTERS]
);
set!(
    /// A bound on the whole run.
    Timeout => vec![&table::TIMEOUT]
);
set!(
    /// Triage's shard and lattice.
    Shard => vec![&table::SHARD, &table::FULL]
);
set!(
    /// The size of the sheet's pictures.
    Tile => vec![&table::TILE]
);
set!(
    /// A bound on each volume of a triage.
    TriageTimeout => vec![&table::TRIAGE_TIMEOUT]
);
