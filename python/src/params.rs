//! Keyword arguments in the CLI's words and with its defaults: `bins=32` for `--bins 32`,
//! `no_shading=True` for `--no-shading`, `dtype` for `--type`. Each call takes its keywords from
//! one dictionary, so a misspelt keyword is an error naming it, not a silent default.

use std::path::PathBuf;

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slabscope::analysis::AxisBy;
use slabscope::geometry::AxisChoice;
use slabscope::render::{CameraParams, Colormap, Gap, Mode, Preset, TransferChoice};
use slabscope::volume::background::BackgroundRule;
use slabscope::volume::io::{RawOptions, default_max_memory, parse_bytes};
use slabscope::volume::{Endian, Resolution, VoxelType};
use slabscope::{
    AnalysisParams, LoadOptions, Method, RenderParams, SamplingParams, Stop, ViewParams,
};

use crate::errors::{invalid, repr};

/// The keyword arguments of one call, taken one by one.
pub struct Kwargs<'py> {
    dict: Bound<'py, PyDict>,
    call: &'static str,
}

impl<'py> Kwargs<'py> {
    /// The keywords `given` to `call` (a copy: the caller's dictionary is left alone).
    pub fn new(
        py: Python<'py>,
        call: &'static str,
        given: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Self> {
        let dict = match given {
            Some(d) => d.copy()?,
            None => PyDict::new(py),
        };
        Ok(Self { dict, call })
    }

    /// Takes keyword `name`: `None` when it is missing or `None`.
    pub fn get<T: for<'a> FromPyObject<'a, 'py>>(&self, name: &str) -> PyResult<Option<T>> {
        let Some(value) = self.dict.get_item(name)? else {
            return Ok(None);
        };
        self.dict.del_item(name)?;
        if value.is_none() {
            return Ok(None);
        }
        value.extract::<T>().map(Some).map_err(|e| {
            let e: PyErr = e.into();
            PyTypeError::new_err(format!(
                "{}(): {name}={}: {}",
                self.call,
                repr(&value),
                e.value(value.py())
            ))
        })
    }

    /// Takes keyword `name`, or `default`.
    pub fn or<T: for<'a> FromPyObject<'a, 'py>>(&self, name: &str, default: T) -> PyResult<T> {
        Ok(self.get(name)?.unwrap_or(default))
    }

    /// Takes a keyword that is a word of `words` (its value in the library), or `default`.
    pub fn word<T: Copy>(&self, name: &str, words: &[(&str, T)], default: T) -> PyResult<T> {
        let Some(given) = self.get::<String>(name)? else {
            return Ok(default);
        };
        words
            .iter()
            .find(|(w, _)| *w == given)
            .map(|(_, v)| *v)
            .ok_or_else(|| {
                let all: Vec<&str> = words.iter().map(|(w, _)| *w).collect();
                invalid(
                    name,
                    format!("{given:?}"),
                    &format!("one of {}", all.join(", ")),
                )
            })
    }

    /// Fails on any keyword not taken, as Python does for a function's unknown keyword.
    pub fn finish(self) -> PyResult<()> {
        match self.dict.keys().iter().next() {
            None => Ok(()),
            Some(key) => Err(PyTypeError::new_err(format!(
                "{}() got an unexpected keyword argument {}",
                self.call,
                key.repr()?
            ))),
        }
    }
}

/// The load options: `dims`, `dtype`, `spacing`, `endian`, `offset` for raw files,
/// `max_memory`, `volume`, `channel`, `series`, `include_localizers`, `resample`, `show_phi`,
/// `label_image`.
pub fn load_options(kw: &Kwargs<'_>) -> PyResult<LoadOptions> {
    let voxel_type = match kw.get::<Bound<'_, PyAny>>("dtype")? {
        None => None,
        Some(d) => Some(voxel_type(&d)?),
    };
    let series = match kw.get::<Bound<'_, PyAny>>("series")? {
        None => None,
        Some(s) => Some(s.str()?.to_string()),
    };
    Ok(LoadOptions {
        max_memory: max_memory(kw, default_max_memory())?,
        raw: RawOptions {
            dims: kw.get("dims")?,
            voxel_type,
            spacing: kw.get("spacing")?,
            endian: match kw.get::<String>("endian")?.as_deref() {
                None => None,
                Some("little") => Some(Endian::Little),
                Some("big") => Some(Endian::Big),
                Some(other) => {
                    return Err(invalid(
                        "endian",
                        format!("{other:?}"),
                        "\"little\" or \"big\"",
                    ));
                }
            },
            offset: kw.get("offset")?,
        },
        volume: kw.or("volume", 0)?,
        channel: kw.or("channel", 0)?,
        series,
        include_localizers: kw.or("include_localizers", false)?,
        resample: kw.or("resample", false)?,
        show_phi: kw.or("show_phi", false)?,
        label_image: kw.get("label_image")?,
    })
}

/// `max_memory`: bytes as a number or as text (`"8G"`), or `default`.
pub fn max_memory(kw: &Kwargs<'_>, default: u64) -> PyResult<u64> {
    let Some(given) = kw.get::<Bound<'_, PyAny>>("max_memory")? else {
        return Ok(default);
    };
    if let Ok(n) = given.extract::<u64>() {
        return Ok(n);
    }
    given
        .extract::<String>()
        .ok()
        .and_then(|t| parse_bytes(&t))
        .ok_or_else(|| {
            invalid(
                "max_memory",
                repr(&given),
                "bytes, e.g. 8_000_000_000 or \"8G\"",
            )
        })
}

/// A voxel type from a NumPy dtype (or anything `numpy.dtype` takes) or the CLI's names.
pub fn voxel_type(given: &Bound<'_, PyAny>) -> PyResult<VoxelType> {
    if let Ok(name) = given.extract::<String>()
        && let Some(t) = VoxelType::parse(&name)
    {
        return Ok(t);
    }
    let numpy = given.py().import("numpy")?;
    let name: String = numpy
        .getattr("dtype")?
        .call1((given,))
        .and_then(|d| d.getattr("name")?.extract())
        .map_err(|_| invalid("dtype", repr(given), "a NumPy dtype"))?;
    VoxelType::parse(&name).ok_or_else(|| {
        invalid(
            "dtype",
            &name,
            "uint8, int8, uint16, int16, uint32, int32, float32 or float64",
        )
    })
}

/// The NumPy dtype name of a voxel type.
pub fn numpy_name(t: VoxelType) -> &'static str {
    match t {
        VoxelType::U8 => "uint8",
        VoxelType::I8 => "int8",
        VoxelType::U16 => "uint16",
        VoxelType::I16 => "int16",
        VoxelType::U32 => "uint32",
        VoxelType::I32 => "int32",
        VoxelType::F32 => "float32",
        VoxelType::F64 => "float64",
    }
}

/// The analysis keywords of `analyze`, with the CLI's defaults: `bins`, `block`, `level`,
/// `ray_spacing`, `sample_spacing`, `phases`, `phase_subset`, `refine`, `axis`, `axis_by`,
/// `gain`, `method`, `slabs`, `threshold`, `background`; `views` runs the view search for a
/// named axis too.
pub fn analysis_params(kw: &Kwargs<'_>) -> PyResult<AnalysisParams> {
    let bins: usize = kw.or("bins", 32)?;
    if !(2..=255).contains(&bins) {
        return Err(invalid("bins", bins, "2 to 255"));
    }
    let axis = match kw.get::<Bound<'_, PyAny>>("axis")? {
        None => AxisChoice::Best,
        Some(a) => axis_choice(&a)?,
    };
    let slabs: Option<usize> = kw.get("slabs")?;
    let threshold: Option<f64> = kw.get("threshold")?;
    let stop = match (slabs, threshold) {
        (Some(_), Some(_)) => {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "slabs= and threshold= cannot both be given: one stops the partition",
            ));
        }
        (_, Some(t)) if !(t.is_finite() && (0.0..=1e6).contains(&t)) => {
            return Err(invalid("threshold", t, "a number from 0 to 1000000"));
        }
        (_, Some(t)) => Stop::Threshold(t),
        (k, None) => Stop::Slabs(k.unwrap_or(4)),
    };
    let background = match kw.get::<Bound<'_, PyAny>>("background")? {
        None => BackgroundRule::Auto,
        Some(b) => background(&b)?,
    };
    Ok(AnalysisParams {
        view: ViewParams {
            sampling: SamplingParams {
                bins,
                ray_spacing: kw.get("ray_spacing")?,
                sample_spacing: kw.get("sample_spacing")?,
            },
            block: kw.or("block", 3)?,
            level: kw.or("level", 1)?,
            phases: kw.or("phases", 8)?,
            phase_subset: kw.or("phase_subset", slabscope::view::DEFAULT_PHASE_SUBSET)?,
            refine: kw.or("refine", false)?,
            ..ViewParams::default()
        },
        axis,
        search_views: kw.or("views", false)?,
        method: kw.word(
            "method",
            &[
                ("topdown", Method::TopDown),
                ("bottomup", Method::BottomUp),
                ("optimal", Method::Optimal),
            ],
            Method::TopDown,
        )?,
        stop,
        background,
        axis_by: kw.word(
            "axis_by",
            &[("entropy", AxisBy::Entropy), ("gain", AxisBy::Gain)],
            AxisBy::Entropy,
        )?,
        gain: kw.or("gain", false)?,
        explain: None,
    })
}

/// An axis as the CLI's `--axis` takes it, or a direction as three numbers.
fn axis_choice(given: &Bound<'_, PyAny>) -> PyResult<AxisChoice> {
    let text = match given.extract::<[f64; 3]>() {
        Ok([x, y, z]) => format!("{x},{y},{z}"),
        Err(_) => given.extract::<String>().map_err(|_| {
            invalid(
                "axis",
                repr(given),
                "best, x, y, z, axial, coronal, sagittal or a direction (dx, dy, dz)",
            )
        })?,
    };
    text.parse().map_err(|_| {
        invalid(
            "axis",
            format!("{text:?}"),
            "best, x, y, z, axial, coronal, sagittal or a direction (dx, dy, dz)",
        )
    })
}

/// The background rule: `"auto"`, `"none"` or a value.
fn background(given: &Bound<'_, PyAny>) -> PyResult<BackgroundRule> {
    if let Ok(v) = given.extract::<f64>() {
        return if v.is_finite() {
            Ok(BackgroundRule::Below(v as f32))
        } else {
            Err(invalid(
                "background",
                v,
                "\"auto\", \"none\" or a finite value",
            ))
        };
    }
    match given.extract::<String>().ok().as_deref() {
        Some("auto") => Ok(BackgroundRule::Auto),
        Some("none") => Ok(BackgroundRule::None),
        _ => Err(invalid(
            "background",
            repr(given),
            "\"auto\", \"none\" or a value",
        )),
    }
}

/// `resolution`: `"full"` (the default, the paper's method), `"auto"` or a pyramid level.
pub fn resolution(kw: &Kwargs<'_>) -> PyResult<Resolution> {
    let Some(given) = kw.get::<Bound<'_, PyAny>>("resolution")? else {
        return Ok(Resolution::Full);
    };
    given
        .str()?
        .to_string()
        .parse()
        .map_err(crate::errors::to_py)
}

/// The look keywords: `tf` (auto, ct-bone, ct-soft, mri), `colormap`, `window`.
pub fn look(kw: &Kwargs<'_>) -> PyResult<TransferChoice> {
    let window: Option<(f32, f32)> = kw.get("window")?;
    if let Some((lo, hi)) = window
        && !(lo.is_finite() && hi.is_finite() && lo < hi)
    {
        return Err(invalid(
            "window",
            format!("({lo}, {hi})"),
            "(lo, hi) with lo below hi",
        ));
    }
    Ok(TransferChoice {
        preset: kw.word(
            "tf",
            &[
                ("auto", Preset::Auto),
                ("ct-bone", Preset::CtBone),
                ("ct-soft", Preset::CtSoft),
                ("mri", Preset::Mri),
            ],
            Preset::Auto,
        )?,
        colormap: kw.word(
            "colormap",
            &[
                ("grey", Colormap::Grey),
                ("bone", Colormap::Bone),
                ("hot", Colormap::Hot),
                ("viridis", Colormap::Viridis),
            ],
            Colormap::Grey,
        )?,
        window,
    })
}

/// A picture size `(width, height)`, as `--size WxH` takes it.
pub fn size(kw: &Kwargs<'_>, default: (u32, u32)) -> PyResult<(u32, u32)> {
    let (w, h) = kw.or("size", default)?;
    if w == 0 || h == 0 || u64::from(w) * u64::from(h) > slabscope::render::MAX_PIXELS {
        return Err(invalid(
            "size",
            format!("({w}, {h})"),
            "a size between (1, 1) and (8192, 8192)",
        ));
    }
    Ok((w, h))
}

/// A number keyword within `lo..=hi`, or `default`.
fn within(kw: &Kwargs<'_>, name: &str, default: f64, (lo, hi): (f64, f64)) -> PyResult<f64> {
    let v: f64 = kw.or(name, default)?;
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(invalid(name, v, &format!("a number from {lo} to {hi}")))
    }
}

/// The render keywords, as `render`'s flags: `mode`, the look, `azimuth`, `elevation`, `zoom`,
/// `perspective`, `highlight`, `solo`, `step`, `no_shading`, `no_outlines`, `no_labels`; and the
/// layout's `gap` and `spread`.
pub fn render_params(
    kw: &Kwargs<'_>,
    (width, height): (u32, u32),
) -> PyResult<(RenderParams, Gap, f64)> {
    let look = look(kw)?;
    let highlight: Option<usize> = kw.get("highlight")?;
    let solo: bool = kw.or("solo", false)?;
    if solo && highlight.is_none() {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "solo=True needs highlight=SLAB",
        ));
    }
    let params = RenderParams {
        width,
        height,
        mode: kw.word(
            "mode",
            &[("cut", Mode::Cut), ("dvr", Mode::Dvr), ("mip", Mode::Mip)],
            Mode::Cut,
        )?,
        preset: look.preset,
        colormap: look.colormap,
        window: look.window,
        camera: CameraParams {
            azimuth: within(kw, "azimuth", 30.0, (-360.0, 360.0))?,
            elevation: within(kw, "elevation", 20.0, (-90.0, 90.0))?,
            zoom: within(kw, "zoom", 1.0, (0.05, 50.0))?,
            perspective: kw.or("perspective", false)?,
        },
        shading: !kw.or("no_shading", false)?,
        step: within(kw, "step", 1.0, (0.05, 10.0))?,
        outlines: !kw.or("no_outlines", false)?,
        labels: !kw.or("no_labels", false)?,
        highlight,
        fade: highlight.is_some(),
        solo,
        ..RenderParams::default()
    };
    let gap = kw.word(
        "gap",
        &[("uniform", Gap::Uniform), ("similarity", Gap::Similarity)],
        Gap::Similarity,
    )?;
    let spread = within(kw, "spread", slabscope::render::DEFAULT_SPREAD, (0.0, 10.0))?;
    Ok((params, gap, spread))
}

/// A path given as `str` or `os.PathLike`.
pub fn path(given: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    given.extract::<PathBuf>().map_err(|_| {
        PyTypeError::new_err(format!(
            "expected a path (str or os.PathLike), got {}",
            given
                .get_type()
                .name()
                .map_or_else(|_| "?".into(), |n| n.to_string())
        ))
    })
}
