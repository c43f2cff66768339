//! The flags several commands share: how to read a file, and how to analyse it (view search and
//! partition). `slabscope [FILE]` takes the same analysis flags as `analyze`. Both are the
//! library's parameter entries (`slabscope::params`), made flags by [`super::params`].

use slabscope::params::text;
use slabscope::{AnalysisParams, LoadOptions};

use super::params::{self, Flags};

/// How to read the input: needed only for headerless raw files, and to change the memory limit.
pub type LoadArgs = Flags<params::Load>;

/// How to find the most structured view and the slabs along it.
pub type AnalysisArgs = Flags<params::Analysis>;

/// The tour's own flags: paper mode.
pub type TourArgs = Flags<params::Tour>;

impl TourArgs {
    /// Whether the tour runs in paper mode (`--paper`).
    pub fn paper(&self) -> bool {
        self.given.has(&slabscope::params::table::PAPER)
    }
}

impl LoadArgs {
    /// The library's load options.
    pub fn options(&self) -> slabscope::Result<LoadOptions> {
        self.given.load()
    }

    /// `--threads`: the most threads the work runs on (`None`: one a core).
    pub fn threads(&self) -> slabscope::Result<Option<usize>> {
        self.given.threads()
    }
}

impl AnalysisArgs {
    /// Runs the analysis of `volume` (read from `name`) with a progress bar; an error names the
    /// file, and a slab count the user did not give is not blamed on `--slabs`.
    pub fn analyze(
        &self,
        name: &str,
        plan: &slabscope::Plan,
        search_views: bool,
    ) -> anyhow::Result<slabscope::Analysis> {
        self.analyze_with(name, plan, &self.params(search_views)?)
    }

    /// [`analyze`](Self::analyze) with these arguments' `params`, amended by the caller.
    pub fn analyze_with(
        &self,
        name: &str,
        plan: &slabscope::Plan,
        params: &AnalysisParams,
    ) -> anyhow::Result<slabscope::Analysis> {
        let views = plan.views.as_ref();
        if let Some(heavy) = params.heavy_work(views.dims(), views.spacing()) {
            eprintln!(
                "slabscope: note: {name}: {heavy}: it may take long; --timeout SECONDS bounds it"
            );
        }
        super::progress::with_bar(|monitor| slabscope::analyze_planned(plan, params, monitor))
            .map_err(|e| {
                let e = slabscope::budget::blame(plan, self.given.blame(e));
                anyhow::Error::from(e).context(name.to_string())
            })
    }

    /// The library's parameters; `search_views` runs the view search even for a named axis.
    pub fn params(&self, search_views: bool) -> slabscope::Result<AnalysisParams> {
        Ok(AnalysisParams {
            search_views,
            ..self.given.analysis()?
        })
    }
}

/// A parser of numbers in `lo..=hi`, for float options.
pub fn within(lo: f64, hi: f64) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync {
    move |s: &str| match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!("{s:?} is not a number from {lo} to {hi}")),
    }
}

pub use text::pair;

/// Parses `NXxNYxNZ`.
pub fn parse_dims_arg(s: &str) -> Result<[usize; 3], String> {
    text::dims(s).ok_or_else(|| format!("{s:?} is not NXxNYxNZ, e.g. 256x256x113"))
}
