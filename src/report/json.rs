//! Reports written as pretty JSON straight from their values, with no tree of them made first
//! (a report of a long volume's bottom-up history holds hundreds of thousands of numbers, and a
//! `serde_json::Value` of each takes ten times its text). What a tree would change is done on
//! the way: `-0.0` written as `0.0`, an `f32` written as the `f64` it is, and a raw fragment (a
//! reader's details) re-indented where it stands.

use std::io;

use serde::Serialize;
use serde_json::ser::{Formatter, PrettyFormatter};

/// `value` as pretty JSON, `-0.0` written as `0.0`, every raw fragment laid out as its parsed
/// value would be.
pub(super) fn pretty(value: &impl Serialize) -> serde_json::Result<String> {
    let mut out = Vec::with_capacity(4096);
    let mut ser = serde_json::Serializer::with_formatter(&mut out, Report::default());
    value.serialize(&mut ser)?;
    // The serializer writes JSON text: UTF-8 by construction.
    Ok(String::from_utf8(out).unwrap_or_default())
}

/// Zero's sign dropped: a direction component that is zero has no sign worth printing.
fn unsigned(v: f64) -> f64 {
    if v == 0.0 { 0.0 } else { v }
}

/// The pretty layout, with the depth kept for raw fragments.
#[derive(Default)]
struct Report {
    pretty: PrettyFormatter<'static>,
    depth: usize,
}

macro_rules! delegate {
    ($($name:ident),*) => {$(
        fn $name<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
            self.pretty.$name(w)
        }
    )*};
}

impl Formatter for Report {
    fn write_f64<W: ?Sized + io::Write>(&mut self, w: &mut W, value: f64) -> io::Result<()> {
        self.pretty.write_f64(w, unsigned(value))
    }

    fn write_f32<W: ?Sized + io::Write>(&mut self, w: &mut W, value: f32) -> io::Result<()> {
        self.write_f64(w, f64::from(value))
    }

    fn begin_array<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.depth += 1;
        self.pretty.begin_array(w)
    }

    fn end_array<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.depth -= 1;
        self.pretty.end_array(w)
    }

    fn begin_object<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.depth += 1;
        self.pretty.begin_object(w)
    }

    fn end_object<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.depth -= 1;
        self.pretty.end_object(w)
    }

    fn begin_array_value<W: ?Sized + io::Write>(
        &mut self,
        w: &mut W,
        first: bool,
    ) -> io::Result<()> {
        self.pretty.begin_array_value(w, first)
    }

    fn begin_object_key<W: ?Sized + io::Write>(
        &mut self,
        w: &mut W,
        first: bool,
    ) -> io::Result<()> {
        self.pretty.begin_object_key(w, first)
    }

    delegate!(end_array_value, begin_object_value, end_object_value);

    fn write_raw_fragment<W: ?Sized + io::Write>(
        &mut self,
        w: &mut W,
        fragment: &str,
    ) -> io::Result<()> {
        let value: serde_json::Value = serde_json::from_str(fragment).map_err(io::Error::other)?;
        let text = pretty(&value).map_err(io::Error::other)?;
        let indent = format!("\n{}", "  ".repeat(self.depth));
        w.write_all(text.replace('\n', &indent).as_bytes())
    }
}
