//! The library's enums a user picks by a word: every value, its word and what it means, once.

use std::str::FromStr;

use super::Word;
use crate::analysis::AxisBy;
use crate::error::Error;
use crate::partition::Method;
use crate::render::{Colormap, Gap, Mode, Preset};

/// An enum a user picks by a word.
pub trait Choice: Copy + PartialEq + 'static {
    /// Every value, in the order the help lists them.
    const ALL: &'static [Self];
    /// The word for the value, on the command line, in Python and in JSON.
    fn word(self) -> &'static str;
    /// What the value means, no final full stop.
    fn help(self) -> &'static str;

    /// The value `word` names (spaces around it allowed).
    fn from_word(word: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|v| v.word() == word.trim())
    }
}

/// The words of `T`, with what each means.
pub fn words<T: Choice>() -> Vec<Word> {
    T::ALL
        .iter()
        .map(|&v| Word {
            word: v.word(),
            help: v.help(),
        })
        .collect()
}

/// The value of `T` that `word` names.
fn parse<T: Choice>(parameter: &'static str, word: &str) -> Result<T, Error> {
    T::from_word(word).ok_or_else(|| {
        let all: Vec<&str> = T::ALL.iter().map(|v| v.word()).collect();
        Error::invalid(parameter, word, format!("one of {}", all.join(", ")))
    })
}

/// `Choice` for an enum: its parameter's name, and each value's word and meaning.
macro_rules! choice {
    ($t:ty, $parameter:literal, [$($v:ident => $word:literal, $help:literal;)+]) => {
        impl Choice for $t {
            const ALL: &'static [Self] = &[$(<$t>::$v),+];
            fn word(self) -> &'static str {
                match self { $(<$t>::$v => $word),+ }
            }
            fn help(self) -> &'static str {
                match self { $(<$t>::$v => $help),+ }
            }
        }
        impl FromStr for $t {
            type Err = Error;
            fn from_str(word: &str) -> Result<Self, Error> {
                parse($parameter, word)
            }
        }
    };
}

choice!(Method, "method", [
    TopDown => "topdown", "Greedy splits by information gain (paper §5.1)";
    BottomUp => "bottomup", "Greedy merges by normalized mutual information (paper §5.2)";
    Optimal => "optimal", "The partition that keeps the most information (dynamic programming)";
]);

choice!(AxisBy, "axis_by", [
    Entropy => "entropy", "The lowest entropy rate (paper §4)";
    Gain => "gain", "The most information kept by the axis's top-down slabs";
]);

choice!(Mode, "mode", [
    Cut => "cut", "Direct volume rendering with each slab's cut faces showing the cross-section there";
    Dvr => "dvr", "Direct volume rendering";
    Mip => "mip", "Maximum intensity projection";
]);

choice!(Preset, "tf", [
    Auto => "auto", "From the histogram";
    CtBone => "ct-bone", "CT bone (Hounsfield units)";
    CtSoft => "ct-soft", "CT soft tissue (Hounsfield units)";
    Mri => "mri", "MRI, from percentiles";
]);

choice!(Colormap, "colormap", [
    Grey => "grey", "Black to white";
    Bone => "bone", "Grey with a cool tint";
    Hot => "hot", "Black, red, yellow, white";
    Viridis => "viridis", "Dark blue to yellow";
]);

choice!(Gap, "gap", [
    Uniform => "uniform", "All gaps equal";
    Similarity => "similarity", "Proportional to 1 - NMI of the slabs at each boundary";
]);

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trips<T: Choice + FromStr<Err = Error> + std::fmt::Debug>() {
        for &v in T::ALL {
            assert_eq!(v.word().parse::<T>().ok(), Some(v));
        }
        assert!("nonsense".parse::<T>().is_err());
    }

    #[test]
    fn every_word_names_its_value() {
        round_trips::<Method>();
        round_trips::<AxisBy>();
        round_trips::<Mode>();
        round_trips::<Preset>();
        round_trips::<Colormap>();
        round_trips::<Gap>();
    }

    #[test]
    fn the_words_agree_with_the_names_reports_use() {
        for &m in Method::ALL {
            assert_eq!(m.word(), m.name());
        }
        for &a in AxisBy::ALL {
            assert_eq!(a.word(), a.name());
        }
        for &p in <Preset as Choice>::ALL {
            assert_eq!(p.word(), p.name());
        }
        for &c in <Colormap as Choice>::ALL {
            assert_eq!(c.word(), c.name());
        }
    }
}
