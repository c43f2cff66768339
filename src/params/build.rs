//! The library's parameter types made from the values given: the one place that knows which
//! entry feeds which field.

use super::table::{
    ARRAY, AXIS, AXIS_BY, BACKGROUND, BINS, BLOCK, CACHE, CHANNEL, COLORMAP, DIMS, ELEVATION,
    ENDIAN, ENDPOINT, GAIN, GAP, HIGHLIGHT, INCLUDE_LOCALIZERS, LABEL_IMAGE, LEVEL, MAX_MEMORY,
    METHOD, MISSING_AS_FILL, MODE, NO_LABELS, NO_OUTLINES, NO_SHADING, OFFSET, PAPER, PERSPECTIVE,
    PHASE_SUBSET, PHASES, RAY_SPACING, REFINE, RESAMPLE, SAMPLE_SPACING, SCRATCH, SERIES, SHOW_PHI,
    SLABS, SOLO, SPACING, SPREAD, STEP, TF, THREADS, THRESHOLD, TYPE, VOLUME, WINDOW, ZOOM,
};
use super::{Given, text};
use crate::analysis::AnalysisParams;
use crate::error::{Error, Result};
use crate::formats::{
    DicomOptions, LoadOptions, PartOptions, RawOptions, ZarrOptions, default_max_memory,
};
use crate::geometry::AxisChoice;
use crate::geometry::lattice::SamplingParams;
use crate::partition::Stop;
use crate::render::{CameraParams, Gap, RenderParams, TransferChoice};
use crate::view::ViewParams;
use crate::volume::Resolution;
use crate::volume::background::BackgroundRule;

impl Given {
    /// The first of two conflicting parameters both given, as an error.
    fn conflict(&self) -> Result<()> {
        for p in super::table::all() {
            for other in p.conflicts {
                if self.has(p) && self.values.contains_key(other) {
                    return Err(Error::Conflicting {
                        parameters: [p.name, super::find(other).map_or("", |o| o.name)],
                    });
                }
            }
            if let Some(needed) = p.requires
                && self.switch(p)?
                && !self.values.contains_key(needed)
            {
                return Err(Error::Needs {
                    parameter: p.name,
                    needed,
                });
            }
        }
        Ok(())
    }

    /// The analysis's parameters.
    pub fn analysis(&self) -> Result<AnalysisParams> {
        self.conflict()?;
        let stop = match self.value::<f64>(&THRESHOLD)? {
            Some(t) => Stop::Threshold(t),
            None => Stop::Slabs(self.number(&SLABS)?),
        };
        // The paper's way: its single lattice, every voxel counted.
        let paper = self.switch(&PAPER)?;
        Ok(AnalysisParams {
            view: ViewParams {
                sampling: SamplingParams {
                    bins: self.number(&BINS)?,
                    ray_spacing: self.value(&RAY_SPACING)?,
                    sample_spacing: self.value(&SAMPLE_SPACING)?,
                },
                block: self.number(&BLOCK)?,
                level: self.number(&LEVEL)?,
                phases: if paper { 0 } else { self.number(&PHASES)? },
                phase_subset: self.number(&PHASE_SUBSET)?,
                refine: self.switch(&REFINE)?,
                ..ViewParams::default()
            },
            axis: self.parsed(&AXIS, text::axis)?.unwrap_or(AxisChoice::Best),
            search_views: self.switch(&super::table::VIEWS)?,
            method: self.word(&METHOD)?,
            stop,
            background: if paper {
                BackgroundRule::None
            } else {
                self.parsed(&BACKGROUND, text::background)?
                    .unwrap_or(BackgroundRule::Auto)
            },
            axis_by: self.word(&AXIS_BY)?,
            gain: self.switch(&GAIN)?,
            explain: None,
        })
    }

    /// The pyramid level asked for.
    pub fn resolution(&self) -> Result<Resolution> {
        Ok(self
            .parsed(&super::table::RESOLUTION, text::resolution)?
            .unwrap_or(Resolution::Full))
    }

    /// The pyramid level asked for, and whether it was named (not left to the default): every
    /// voxel asked for by name is computed on every voxel even beyond the memory budget
    /// (`Purpose::Analysis`'s `every_voxel`).
    pub fn resolution_named(&self) -> Result<(Resolution, bool)> {
        Ok((self.resolution()?, self.has(&super::table::RESOLUTION)))
    }

    /// Triage's shard `(K, N)`, when one was given.
    pub fn shard(&self) -> Result<Option<(u64, u64)>> {
        self.parsed(&super::table::SHARD, text::shard)
    }

    /// How to read the input.
    pub fn load(&self) -> Result<LoadOptions> {
        Ok(LoadOptions {
            max_memory: self
                .parsed(&MAX_MEMORY, text::bytes)?
                .unwrap_or_else(default_max_memory),
            raw: RawOptions {
                dims: self.parsed(&DIMS, text::dims)?,
                voxel_type: self.parsed(&TYPE, text::voxel_type)?,
                spacing: self.parsed(&SPACING, text::spacing)?,
                endian: self.parsed(&ENDIAN, text::endian)?,
                offset: self.value(&OFFSET)?,
            },
            part: PartOptions {
                volume: self.number(&VOLUME)?,
                channel: self.number(&CHANNEL)?,
                array: self.parsed(&ARRAY, text::any)?,
            },
            dicom: DicomOptions {
                series: self.parsed(&SERIES, text::any)?,
                include_localizers: self.switch(&INCLUDE_LOCALIZERS)?,
                resample: self.switch(&RESAMPLE)?,
                show_phi: self.switch(&SHOW_PHI)?,
            },
            zarr: ZarrOptions {
                label_image: self.parsed(&LABEL_IMAGE, text::any)?,
                endpoint: self.parsed(&ENDPOINT, text::any)?,
                missing_as_fill: self.switch(&MISSING_AS_FILL)?,
                cache: self
                    .parsed(&CACHE, text::any)?
                    .map(std::path::PathBuf::from),
            },
            scratch: self.scratch()?,
            cancel: crate::progress::Cancel::never(),
        })
    }

    /// The scratch folder given, which must be one that exists (checked when the options are
    /// made, not when a volume first needs it).
    fn scratch(&self) -> Result<Option<std::path::PathBuf>> {
        let Some(dir) = self.parsed(&SCRATCH, text::any)? else {
            return Ok(None);
        };
        if !std::path::Path::new(&dir).is_dir() {
            return Err(Error::InvalidParameter {
                parameter: "scratch",
                expected: "an existing folder".into(),
                value: dir,
            });
        }
        Ok(Some(dir.into()))
    }

    /// The most threads the work may run on (`None`: one a core).
    pub fn threads(&self) -> Result<Option<usize>> {
        self.value(&THREADS)
    }

    /// A pool of at most [`threads`](Self::threads) threads for the work, when a number was
    /// given (the caller runs the work in it with `install`).
    pub fn thread_pool(&self) -> Result<Option<rayon::ThreadPool>> {
        let Some(n) = self.threads()? else {
            return Ok(None);
        };
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map(Some)
            .map_err(|e| Error::Degenerate(format!("a pool of {n} threads: {e}")))
    }

    /// How values become colours.
    pub fn look(&self) -> Result<TransferChoice> {
        Ok(TransferChoice {
            preset: self.word(&TF)?,
            colormap: self.word(&COLORMAP)?,
            window: self.parsed(&WINDOW, text::window)?,
        })
    }

    /// What a render shows and how, for a `width × height` picture.
    pub fn scene(&self, width: u32, height: u32) -> Result<Scene> {
        self.conflict()?;
        let look = self.look()?;
        let highlight = self.value(&HIGHLIGHT)?;
        let params = RenderParams {
            width,
            height,
            mode: self.word(&MODE)?,
            preset: look.preset,
            colormap: look.colormap,
            window: look.window,
            camera: CameraParams {
                azimuth: self.number(&super::table::AZIMUTH)?,
                elevation: self.number(&ELEVATION)?,
                zoom: self.number(&ZOOM)?,
                perspective: self.switch(&PERSPECTIVE)?,
            },
            shading: !self.switch(&NO_SHADING)?,
            step: self.number(&STEP)?,
            outlines: !self.switch(&NO_OUTLINES)?,
            labels: !self.switch(&NO_LABELS)?,
            highlight,
            fade: highlight.is_some(),
            solo: self.switch(&SOLO)?,
            ..RenderParams::default()
        };
        Ok(Scene {
            params,
            gap: self.word(&GAP)?,
            spread: self.number(&SPREAD)?,
        })
    }
}

/// What a render shows and how: the renderer's parameters and the exploded layout's gaps.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The renderer's parameters.
    pub params: RenderParams,
    /// How the gaps between slabs are sized.
    pub gap: Gap,
    /// The total gap as a fraction of the stack's length.
    pub spread: f64,
}

impl Default for Scene {
    /// The scene of a front end that sets what it shows itself (the TUI): the renderer's
    /// defaults, similarity gaps and the default spread, as the parameter table's defaults give
    /// them (a test holds the two the same).
    fn default() -> Self {
        Self {
            params: RenderParams::default(),
            gap: Gap::Similarity,
            spread: crate::render::DEFAULT_SPREAD,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::table;

    #[test]
    fn nothing_given_is_the_librarys_defaults() {
        let given = Given::new();
        assert_eq!(given.analysis().unwrap(), AnalysisParams::default());
        assert_eq!(given.look().unwrap(), TransferChoice::default());
        let scene = given.scene(640, 480).unwrap();
        assert_eq!(scene.params, RenderParams::default());
        assert_eq!(scene.gap, Gap::Similarity);
        assert_eq!(scene.spread, crate::render::DEFAULT_SPREAD);
        assert_eq!(scene, Scene::default());
        let load = given.load().unwrap();
        assert_eq!(load.raw, RawOptions::default());
        assert_eq!((load.part.volume, load.part.channel), (0, 0));
    }

    #[test]
    fn values_given_reach_their_fields() {
        let given = Given::new()
            .with(&table::BINS, "64")
            .with(&table::METHOD, "bottomup")
            .with(&table::THRESHOLD, "0.25")
            .with(&table::BACKGROUND, "-1000")
            .with(&table::REFINE, "true");
        let p = given.analysis().unwrap();
        assert_eq!(p.view.sampling.bins, 64);
        assert_eq!(p.method, crate::partition::Method::BottomUp);
        assert_eq!(p.stop, Stop::Threshold(0.25));
        assert_eq!(p.background, BackgroundRule::Below(-1000.0));
        assert!(p.view.refine);
        let load = Given::new()
            .with(&table::DIMS, "4x5x6")
            .with(&table::TYPE, "uint16")
            .with(&table::MAX_MEMORY, "1G")
            .load()
            .unwrap();
        assert_eq!(load.raw.dims, Some([4, 5, 6]));
        assert_eq!(load.raw.voxel_type, Some(crate::volume::VoxelType::U16));
        assert_eq!(load.max_memory, 1 << 30);
    }

    #[test]
    fn errors_carry_the_parameter() {
        let e = Given::new().with(&table::BINS, "1").analysis().unwrap_err();
        assert_eq!(e.to_string(), "bins 1: expected 2 to 255");
        let e = Given::new()
            .with(&table::MODE, "x")
            .scene(9, 9)
            .unwrap_err();
        assert_eq!(e.to_string(), "mode x: expected one of cut, dvr, mip");
        let both = Given::new()
            .with(&table::SLABS, "3")
            .with(&table::THRESHOLD, "0.1");
        assert!(matches!(
            both.analysis(),
            Err(Error::Conflicting {
                parameters: ["slabs", "threshold"]
            })
        ));
        let solo = Given::new().with(&table::SOLO, "true").scene(9, 9);
        assert!(matches!(
            solo,
            Err(Error::Needs {
                parameter: "solo",
                needed: "highlight"
            })
        ));
    }

    #[test]
    fn the_commands_own_entries_parse_and_refuse() {
        assert_eq!(Given::new().shard().unwrap(), None);
        let shard = |t: &str| Given::new().with(&table::SHARD, t).shard();
        assert_eq!(shard("3/10").unwrap(), Some((3, 10)));
        assert_eq!(shard("3,10").unwrap(), Some((3, 10)));
        assert_eq!(shard("10/10").unwrap(), Some((10, 10)));
        for bad in ["4/3", "0/3", "1/0", "3", "a/b"] {
            assert_eq!(
                shard(bad).unwrap_err().to_string(),
                format!("shard {bad}: expected K/N with 1 <= K <= N, e.g. 3/10")
            );
        }
        // `analyze`'s and `render`'s timeout has no default; triage's is a minute.
        assert_eq!(Given::new().value::<f64>(&table::TIMEOUT).unwrap(), None);
        assert_eq!(
            Given::new().number::<f64>(&table::TRIAGE_TIMEOUT).unwrap(),
            60.0
        );
        let e = Given::new()
            .with(&table::TIMEOUT, "86400.5")
            .value::<f64>(&table::TIMEOUT)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "timeout 86400.5: expected a number from 0.1 to 86400"
        );
        let switches = Given::new().with(&table::FACES, "true");
        assert!(switches.switch(&table::FACES).unwrap());
        assert!(!switches.switch(&table::NO_LETTERS).unwrap());
    }

    #[test]
    fn a_default_that_does_not_fit_is_blamed_on_the_default() {
        let e = Error::invalid("slabs", 4, "at most 3");
        let blamed = Given::new().blame(e);
        assert_eq!(
            blamed.to_string(),
            "the default of 4 slabs does not fit: at most 3"
        );
        let e = Error::invalid("slabs", 4, "at most 3");
        let given = Given::new().with(&table::SLABS, "4");
        assert!(matches!(given.blame(e), Error::InvalidParameter { .. }));
    }
}
