//! `slabscope render FILE -o OUT.png` and `slabscope preview FILE`: the exploded view as a PNG,
//! or printed inline in the terminal.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Result, bail};
use clap::{Args, ValueEnum};
use image::{DynamicImage, RgbaImage};
use slabscope::analysis::within_memory;
use slabscope::geometry::min_spacing;
use slabscope::render::{
    CameraParams, Colormap, Gap, Layout, Mode, Preset, RenderParams, Renderer, Stack,
    TransferChoice, encode, slice,
};
use tiny_skia::Pixmap;

use super::args::{AnalysisArgs, LoadArgs, pair, within};
use super::progress::with_bar;
use crate::term::{self, Graphics, Protocol};

/// What the render shows and how.
#[derive(Debug, Args, Clone)]
pub struct ViewOptions {
    /// Cut faces (the cross-section at every cut, the volume rendered behind), plain direct
    /// volume rendering, or maximum intensity projection.
    #[arg(long, value_enum, default_value_t = ModeArg::Cut)]
    pub mode: ModeArg,
    #[command(flatten)]
    pub look: LookArgs,
    /// Camera angle around the slab axis, degrees.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true, value_parser = within(-360.0, 360.0))]
    pub azimuth: f64,
    /// Camera angle above the slab planes, degrees.
    #[arg(long, default_value_t = 20.0, allow_negative_numbers = true, value_parser = within(-90.0, 90.0))]
    pub elevation: f64,
    /// Magnification (1 fits the scene).
    #[arg(long, default_value_t = 1.0, value_parser = within(0.05, 50.0))]
    pub zoom: f64,
    /// Perspective projection instead of orthographic.
    #[arg(long)]
    pub perspective: bool,
    /// Gaps between slabs: all equal, or wider where neighbouring slabs are less alike.
    #[arg(long, value_enum, default_value_t = GapArg::Similarity)]
    pub gap: GapArg,
    /// Total gap as a fraction of the stack's length.
    #[arg(long, default_value_t = slabscope::render::DEFAULT_SPREAD, value_parser = within(0.0, 10.0))]
    pub spread: f64,
    /// Show this slab normally and the others faint.
    #[arg(long, value_name = "SLAB")]
    pub highlight: Option<usize>,
    /// Show only the highlighted slab.
    #[arg(long, requires = "highlight")]
    pub solo: bool,
    /// Sample distance along rays, in smallest voxel spacings.
    #[arg(long, default_value_t = 1.0, value_parser = within(0.05, 10.0))]
    pub step: f64,
    /// No gradient shading.
    #[arg(long)]
    pub no_shading: bool,
    /// No slab outlines.
    #[arg(long)]
    pub no_outlines: bool,
    /// No slab numbers.
    #[arg(long)]
    pub no_labels: bool,
}

/// How values become colours.
#[derive(Debug, Args, Clone)]
pub struct LookArgs {
    /// Transfer function (auto: windowed on what is not background, CT in a soft-tissue
    /// window, label volumes in distinct colours).
    #[arg(long = "tf", value_enum, default_value_t = PresetArg::Auto)]
    pub preset: PresetArg,
    /// Colour map.
    #[arg(long, value_enum, default_value_t = ColormapArg::Grey)]
    pub colormap: ColormapArg,
    /// Window LO,HI: grey from LO to HI and opacity rising across it (replaces the preset's).
    #[arg(long, value_name = "LO,HI", value_parser = parse_window, allow_hyphen_values = true)]
    pub window: Option<(f32, f32)>,
}

impl LookArgs {
    /// The library's look.
    pub fn look(&self) -> TransferChoice {
        TransferChoice {
            preset: match self.preset {
                PresetArg::Auto => Preset::Auto,
                PresetArg::CtBone => Preset::CtBone,
                PresetArg::CtSoft => Preset::CtSoft,
                PresetArg::Mri => Preset::Mri,
            },
            colormap: match self.colormap {
                ColormapArg::Grey => Colormap::Grey,
                ColormapArg::Bone => Colormap::Bone,
                ColormapArg::Hot => Colormap::Hot,
                ColormapArg::Viridis => Colormap::Viridis,
            },
            window: self.window,
        }
    }
}

/// Render modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ModeArg {
    /// Direct volume rendering with each slab's cut faces showing the cross-section there.
    Cut,
    /// Direct volume rendering.
    Dvr,
    /// Maximum intensity projection.
    Mip,
}

/// Transfer function presets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PresetArg {
    /// From the histogram.
    Auto,
    /// CT bone (Hounsfield units).
    CtBone,
    /// CT soft tissue (Hounsfield units).
    CtSoft,
    /// MRI, from percentiles.
    Mri,
}

/// Colour maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ColormapArg {
    /// Black to white.
    Grey,
    /// Grey with a cool tint.
    Bone,
    /// Black, red, yellow, white.
    Hot,
    /// Dark blue to yellow.
    Viridis,
}

/// Gap sizing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum GapArg {
    /// All gaps equal.
    Uniform,
    /// Proportional to 1 - NMI of the slabs at each boundary.
    Similarity,
}

impl ViewOptions {
    /// The library's render parameters for a `width × height` image.
    pub fn params(&self, width: u32, height: u32) -> RenderParams {
        let look = self.look.look();
        RenderParams {
            width,
            height,
            mode: match self.mode {
                ModeArg::Cut => Mode::Cut,
                ModeArg::Dvr => Mode::Dvr,
                ModeArg::Mip => Mode::Mip,
            },
            preset: look.preset,
            colormap: look.colormap,
            window: look.window,
            camera: CameraParams {
                azimuth: self.azimuth,
                elevation: self.elevation,
                zoom: self.zoom,
                perspective: self.perspective,
            },
            shading: !self.no_shading,
            step: self.step,
            outlines: !self.no_outlines,
            labels: !self.no_labels,
            highlight: self.highlight,
            fade: self.highlight.is_some(),
            solo: self.solo,
            ..RenderParams::default()
        }
    }

    fn gap(&self) -> Gap {
        match self.gap {
            GapArg::Uniform => Gap::Uniform,
            GapArg::Similarity => Gap::Similarity,
        }
    }
}

/// Arguments of `slabscope render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The volume: a file, or a folder of TIFF slices.
    pub file: PathBuf,
    /// Output picture: PNG, or JPEG for a .jpg or .jpeg name.
    #[arg(short, long, value_name = "OUT.png")]
    pub output: PathBuf,
    /// Image size.
    #[arg(long, value_name = "WxH", default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Overwrite OUT if it exists.
    #[arg(long)]
    pub force: bool,
    /// Instead of the exploded view, the faces of every slab: its last slice above its first,
    /// a column a slab, fit into the size.
    #[arg(long)]
    pub faces: bool,
    /// Stop after this many seconds, with an error saying so.
    #[arg(long, value_name = "SECONDS", value_parser = super::args::within(0.1, 86400.0))]
    pub timeout: Option<f64>,
    #[command(flatten)]
    pub scene: SceneArgs,
}

/// What to show: how to read the volume, find the axis, cut the slabs and render them.
#[derive(Debug, Args)]
pub struct SceneArgs {
    #[command(flatten)]
    pub options: ViewOptions,
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    #[command(flatten)]
    pub load: LoadArgs,
}

/// Arguments of `slabscope preview`.
#[derive(Debug, Args)]
pub struct PreviewArgs {
    /// The volume: a file, or a folder of TIFF slices.
    pub file: PathBuf,
    /// Terminal image protocol (default: detected).
    #[arg(long, value_enum, default_value_t = Protocol::Auto)]
    pub protocol: Protocol,
    #[command(flatten)]
    pub scene: SceneArgs,
}

fn parse_window(s: &str) -> Result<(f32, f32), String> {
    pair::<f32>(s, &[','])
        .filter(|&(lo, hi)| lo.is_finite() && hi.is_finite() && lo < hi)
        .ok_or_else(|| format!("{s:?} is not LO,HI with LO below HI, e.g. -200,1500"))
}

pub(super) fn parse_size(s: &str) -> Result<(u32, u32), String> {
    if !s.contains(['x', 'X']) {
        return Err(format!("{s:?} is not WxH, e.g. 640x480"));
    }
    pair::<u32>(s, &['x', 'X'])
        .filter(|&(w, h)| {
            w > 0 && h > 0 && u64::from(w) * u64::from(h) <= slabscope::render::MAX_PIXELS
        })
        .ok_or_else(|| format!("{s:?} is not a size between 1x1 and 8192x8192"))
}

/// Loads, finds the axis and the slabs, and renders `width × height`: the exploded view, or
/// with `faces` the strip of slab faces.
fn render_file(
    file: &std::path::Path,
    scene: &SceneArgs,
    (width, height): (u32, u32),
    output: Option<(&std::path::Path, bool)>,
    faces: bool,
) -> Result<Pixmap> {
    let loaded = super::load(file, &scene.load)?;
    if let Some((path, force)) = output {
        super::check_outputs(&[path], &loaded.sources, force)?;
    }
    // An analysis beyond the memory budget runs on a pyramid level, and the picture is drawn
    // from that level.
    let (level, budget_note) = within_memory(&loaded.volume, 0, scene.load.options().max_memory)?;
    if let Some(note) = budget_note {
        super::note(file, &note);
    }
    let volume = level.as_ref();
    let part = scene
        .analysis
        .analyze(
            &slabscope::error::shown(file),
            &slabscope::Plan::at(Arc::clone(&level)),
            false,
        )?
        .partition;
    let options = &scene.options;
    if faces {
        let renderer = Renderer::new(volume)?;
        let transfer = renderer.transfer(options.look.look(), min_spacing(volume.spacing()))?;
        let k = part.slabs.len() as u32;
        let tile = (
            width.saturating_sub(4 * (k + 1)) / k.max(1),
            height.saturating_sub(12) / 2,
        );
        if tile.0 < 8 || tile.1 < 8 {
            bail!("--size {width}x{height}: too small for the faces of {k} slabs");
        }
        return Ok(slice::faces(
            volume,
            &transfer,
            &Stack::of(&part),
            &part.slabs,
            tile,
        )?);
    }
    if let Some(h) = options.highlight
        && h >= part.slabs.len()
    {
        bail!(
            "--highlight {h}: there are only {} slabs (numbered from 0)",
            part.slabs.len()
        );
    }
    let layout = Layout::exploded(&part, options.gap(), options.spread);
    let renderer = Renderer::new(volume)?;
    let image =
        with_bar(|monitor| renderer.render(&layout, &options.params(width, height), monitor))?;
    Ok(image.pixmap)
}

pub fn run_render(args: &RenderArgs) -> Result<()> {
    if let Some(t) = args.timeout {
        super::progress::stop_after(t);
    }
    let format = super::picture_output(&args.output, &args.file, args.force)?;
    let image = render_file(
        &args.file,
        &args.scene,
        args.size,
        Some((&args.output, args.force)),
        args.faces,
    )?;
    super::write_new(&args.output, &encode(&image, format)?, args.force)
}

pub fn run_preview(args: &PreviewArgs) -> Result<()> {
    if !std::io::stdout().is_terminal() {
        bail!(
            "standard output is not a terminal, so there is nowhere to show the picture: \
             `slabscope render FILE -o OUT.png` writes it to a file"
        );
    }
    let (cols, rows) = crossterm::terminal::size()?;
    if cols < 10 || rows < 6 {
        bail!("the terminal is {cols}x{rows}: too small for a preview");
    }
    // The terminal's answers are read in raw mode, so that none is echoed.
    crossterm::terminal::enable_raw_mode()?;
    let caps = term::detect(args.protocol, &mut std::io::stdout());
    crossterm::terminal::disable_raw_mode()?;
    let caps = caps?;
    if let Some(note) = &caps.note {
        eprintln!("slabscope: note: {note}");
    }
    let cells = (cols, rows - 2);
    let image = render_file(&args.file, &args.scene, caps.image_size(cells), None, false)?;
    let (w, h) = (image.width(), image.height());
    let rgba = RgbaImage::from_raw(w, h, image.data().to_vec())
        .ok_or_else(|| anyhow::anyhow!("render buffer has the wrong size"))?;
    if caps.graphics == Graphics::Blocks {
        // viuer draws half-blocks well; the other protocols go through our own encoder, which
        // knows tmux and the terminal's sizes.
        let config = viuer::Config {
            width: Some(u32::from(cols)),
            height: Some(u32::from(cells.1)),
            absolute_offset: false,
            use_kitty: false,
            use_iterm: false,
            use_sixel: false,
            ..viuer::Config::default()
        };
        viuer::print(&DynamicImage::ImageRgba8(rgba), &config)?;
        return Ok(());
    }
    let covered = (
        w.div_ceil(u32::from(caps.cell.0)) as u16,
        h.div_ceil(u32::from(caps.cell.1)) as u16,
    );
    let encoded = term::image::encode(&rgba, covered, &caps).map_err(|e| anyhow::anyhow!(e))?;
    let mut out = std::io::stdout().lock();
    out.write_all(placed(encoded.sequence().unwrap_or_default(), covered.1).as_bytes())?;
    out.flush()?;
    Ok(())
}

/// The picture `seq` printed at the cursor with the cursor left on the line below its `rows`:
/// room made first (so that drawing scrolls nothing), the cursor saved and restored around the
/// picture, whatever the terminal does with it after a sixel.
fn placed(seq: &str, rows: u16) -> String {
    format!(
        "{}\x1b[{rows}A\x1b7{seq}\x1b8\x1b[{rows}B\r",
        "\n".repeat(usize::from(rows))
    )
}
