//! `slabscope render FILE -o OUT.png` and `slabscope preview FILE`: the exploded view as a PNG,
//! or printed inline in the terminal.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use image::{DynamicImage, RgbaImage};
use slabscope::params::{Scene, table};
use slabscope::render::{TransferChoice, encode};
use slabscope::request::{Level, RenderRequest};
use tiny_skia::Pixmap;

use super::args::{AnalysisArgs, LoadArgs};
use super::params::{self, Flags};
use super::progress::with_bar;
use crate::term::{self, Graphics, Protocol};

/// What the render shows and how: the library's scene entries, made flags.
pub type ViewOptions = Flags<params::Scene>;

/// How values become colours.
pub type LookArgs = Flags<params::Look>;

impl LookArgs {
    /// The library's look.
    pub fn look(&self) -> slabscope::Result<TransferChoice> {
        self.given.look()
    }
}

impl ViewOptions {
    /// The library's scene for a `width × height` image.
    pub fn scene(&self, width: u32, height: u32) -> Result<Scene> {
        Ok(self.given.scene(width, height)?)
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
    #[command(flatten)]
    pub size: Flags<params::RenderSize>,
    /// Overwrite OUT if it exists.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub faces: Flags<params::Faces>,
    #[command(flatten)]
    pub timeout: Flags<params::Timeout>,
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
    let max_memory = scene.load.options()?.max_memory;
    let request = scene.analysis.request(false, Level::Picture, max_memory)?;
    let planned = request.plan(&loaded.volume)?;
    if let Some(note) = &planned.plan.note {
        super::note(file, note);
    }
    let analysed = super::args::analyze(&slabscope::error::shown(file), planned)?;
    let request = RenderRequest {
        scene: scene.options.scene(width, height)?,
        faces,
    };
    Ok(with_bar(|monitor| request.render(&analysed, monitor))?)
}

pub fn run_render(args: &RenderArgs) -> Result<()> {
    super::progress::stop_after_given(&args.timeout)?;
    let format = super::picture_output(&args.output, &args.file, args.force)?;
    let image = render_file(
        &args.file,
        &args.scene,
        args.size.given.size(&table::RENDER_SIZE)?,
        Some((&args.output, args.force)),
        args.faces.given.switch(&table::FACES)?,
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
        eprintln!(
            "slabscope: note: {}",
            slabscope::error::names::controls(note)
        );
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
