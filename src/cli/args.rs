//! The flags several commands share: how to read a file, and how to analyse it (view search and
//! partition). `slabscope [FILE]` takes the same analysis flags as `analyze`. Both are the
//! library's parameter entries (`slabscope::params`), made flags by [`super::params`].

use slabscope::params::text;
use slabscope::request::{Analysed, AnalysisRequest, Level, Planned};
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
        Ok(LoadOptions {
            cancel: super::progress::load_cancel(),
            ..self.given.load()?
        })
    }

    /// `--threads`: the most threads the work runs on (`None`: one a core).
    pub fn threads(&self) -> slabscope::Result<Option<usize>> {
        self.given.threads()
    }
}

impl AnalysisArgs {
    /// The analysis request of these arguments at `level` within `max_memory` bytes;
    /// `search_views` runs the view search even for a named axis.
    pub fn request(
        &self,
        search_views: bool,
        level: Level,
        max_memory: u64,
    ) -> slabscope::Result<AnalysisRequest> {
        Ok(AnalysisRequest {
            level,
            given: Some(self.given.clone()),
            ..AnalysisRequest::new(self.params(search_views)?, max_memory)
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

/// Runs the analysis `planned` of the volume read from `name` with a progress bar, said first
/// when it asks for much work; an error names the file.
pub fn analyze(name: &str, planned: Planned<'_>) -> anyhow::Result<Analysed> {
    if let Some(heavy) = planned.heavy_work() {
        eprintln!(
            "slabscope: note: {name}: {heavy}: it may take long; --timeout SECONDS bounds it"
        );
    }
    super::progress::with_bar(|monitor| planned.run(monitor))
        .map_err(|e| anyhow::Error::from(e).context(name.to_string()))
}

/// Parses `NXxNYxNZ`.
pub fn parse_dims_arg(s: &str) -> Result<[usize; 3], String> {
    text::dims(s).ok_or_else(|| format!("{s:?} is not NXxNYxNZ, e.g. 256x256x113"))
}
