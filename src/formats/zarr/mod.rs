//! OME-Zarr images (NGFF 0.4 on Zarr v2, 0.5 on Zarr v3) and plain Zarr arrays, from a local
//! folder. The group's metadata is read here (`meta.rs`); the arrays, their codecs (Blosc, zstd,
//! gzip, ...) and sharding by `zarrs`, through a store of our own (`store.rs`) that opens every
//! file as other inputs are opened and weighs it first.
//!
//! The first dataset of the first multiscales image is the volume: its spatial axes (z, y, x in
//! the array's order, or y and x) become the volume's x fastest, its scale and translation the
//! spacing and origin in mm; `--volume N` picks the time point and `--channel N` the channel.

mod chain;
mod coarse;
mod details;
mod failure;
mod guard;
#[cfg(feature = "remote")]
mod http_store;
mod levels;
pub(crate) mod meta;
mod read;
mod root;
mod store;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Serialize;

use self::meta::{ArrayMeta, AxisKind, Image};
use self::root::Root;
use super::data::{one_channel, one_volume};
use super::reader::Reader;
use super::remote::{is_url, join};
use super::{Folder, Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::pyramid;
pub(crate) use coarse::read_serving;

/// What `info` shows of a store: the image read, its axes, levels, chunking and codecs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ZarrInfo {
    /// The NGFF version (`0.4`, `0.5`), null for a plain Zarr array.
    pub version: Option<String>,
    /// The Zarr format: 2 or 3.
    pub zarr_format: u8,
    /// The image read, relative to the store (`""`, or `labels/NAME`).
    pub image: String,
    /// The axes in the arrays' order.
    pub axes: Vec<ZarrAxis>,
    /// The resolution levels, finest first.
    pub levels: Vec<ZarrLevel>,
    /// The data type as the file names it.
    pub data_type: String,
    /// The chunk shape of the level read (the shard's, when sharded), in the axes' order.
    pub chunks: Vec<u64>,
    /// The inner chunk shape of a sharded array.
    pub inner_chunks: Option<Vec<u64>>,
    /// The codecs of the level read, in the order they were applied when writing.
    pub codecs: Vec<String>,
    /// The label images of the store (`--label-image NAME` reads one).
    pub labels: Vec<String>,
}

/// One axis of a store's image.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ZarrAxis {
    /// Its name.
    pub name: String,
    /// `space`, `time`, `channel` or another type as written.
    #[serde(rename = "type")]
    pub kind: String,
    /// Its unit as written.
    pub unit: Option<String>,
}

/// One resolution level of a store's image.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ZarrLevel {
    /// The array's path in the image.
    pub path: String,
    /// Its shape, in the axes' order.
    pub shape: Vec<u64>,
    /// Its scale per axis, in the axes' units.
    pub scale: Vec<f64>,
    /// The pyramid level it is read as (0 for the first), null when it does not lie on the
    /// pyramid's grid (another downsampling), and is not used.
    pub pyramid_level: Option<usize>,
}

/// The options of an OME-Zarr read.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ZarrOptions {
    /// Which label image of the store to read (`labels/NAME`) instead of its image.
    pub label_image: Option<String>,
    /// The endpoint an `s3://` store is read at (`--endpoint`), before the one the environment
    /// names (`AWS_ENDPOINT_URL_S3`, `AWS_ENDPOINT_URL`).
    pub endpoint: Option<String>,
    /// Whether a chunk of a store at a URL that the server refuses (HTTP 403) is read as the
    /// fill value, as a chunk not written (`--missing-as-fill`), rather than an error.
    pub missing_as_fill: bool,
    /// The folder where the chunks of a store at a URL are kept once fetched (`--cache DIR`),
    /// so that reading the store again fetches none it holds; none when not given.
    pub cache: Option<PathBuf>,
}

/// The reader of an OME-Zarr store or a plain Zarr array (a folder).
pub(crate) struct Zarr;

impl Reader for Zarr {
    fn format(&self) -> Format {
        Format::OmeZarr
    }

    fn title(&self) -> &'static str {
        "OME-Zarr"
    }

    fn reads(&self) -> Option<&'static str> {
        Some("OME-Zarr stores")
    }

    fn check_options(&self, path: &Path, is_dir: bool, opts: &LoadOptions) -> Result<()> {
        check_label_image(path, is_dir, opts)
    }

    fn store(&self, dir: &Path) -> bool {
        is_store(dir)
    }

    fn reads_folder(&self, kind: Folder, _opts: &LoadOptions) -> bool {
        kind == Folder::Store
    }

    fn volumes(&self) -> bool {
        true
    }

    fn channels(&self) -> bool {
        true
    }

    fn details_key(&self) -> Option<&'static str> {
        Some("ome_zarr")
    }

    /// Reads through [`Source::path`], the store's folder or URL: a store is no one stream of
    /// bytes but a tree of keys (its metadata, one file or answer a chunk), which `zarrs` reads
    /// by key from a store made of the path (a folder's files) or the URL (ranged requests).
    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source.path(), opts)
    }

    /// The finest of the store's coarser datasets on the pyramid's grid within `max_voxels`,
    /// quantized with its own range (level 0's is not known until level 0 is read).
    fn preview(
        &self,
        source: &Source,
        opts: &LoadOptions,
        max_voxels: usize,
    ) -> Result<Option<Read0>> {
        let path = source.path();
        if !(is_url(path) || (path.is_dir() && is_store(path))) {
            return Ok(None);
        }
        coarse::read_preview(path, opts, max_voxels)
    }
}

/// Fails when `opts` name a label image and `path` (a folder when `is_dir`) is no Zarr store.
fn check_label_image(path: &Path, is_dir: bool, opts: &LoadOptions) -> Result<()> {
    if opts.zarr.label_image.is_some() && !(is_url(path) || (is_dir && is_store(path))) {
        return Err(Error::format(
            path,
            "--label-image names a label image of an OME-Zarr store, and this is none",
        ));
    }
    Ok(())
}

/// Whether the folder `dir` is a Zarr store (a group or an array, of Zarr v2 or v3).
pub fn is_store(dir: &Path) -> bool {
    ["zarr.json", ".zattrs", ".zgroup", ".zarray"]
        .iter()
        .any(|f| dir.join(f).is_file())
}

/// The image a load reads: the store's root node, or one of its label images, with its name.
fn image_node(root: &Root, opts: &LoadOptions) -> Result<(String, String)> {
    let Some(name) = &opts.zarr.label_image else {
        return Ok((String::new(), String::new()));
    };
    let shown = root.shown("");
    let names = meta::label_names(root, "").map_err(|m| Error::format(&shown, m))?;
    if !names.contains(name) {
        let listed = if names.is_empty() {
            "the store has no label images".to_string()
        } else {
            format!("its label images: {}", names.join(", "))
        };
        return Err(Error::format(
            &shown,
            format!("no label image {name:?} ({listed})"),
        ));
    }
    let node = format!("labels/{name}");
    Ok((node.clone(), node))
}

/// The image at the node `node` of the store `root`: an OME-Zarr group's first image, or a
/// plain array as an image of one level with unit scale (its axes t, c, z, y, x counted from the
/// last).
fn read_image(root: &Root, node: &str) -> Result<(Image, Vec<ArrayMeta>)> {
    let shown = root.shown(node);
    let fail = |m: String| Error::format(&shown, m);
    let (zarr_format, attrs) = meta::attributes(root, node).map_err(fail)?.ok_or_else(|| {
        fail(if root.is_remote() {
            "no Zarr store at this URL (no zarr.json, .zattrs, .zgroup or .zarray in it, or \
             for S3 none it may read: public S3 answers 403 for both): slabscope reads Zarr and \
             OME-Zarr stores over HTTP; download a file of another format and name the file"
                .into()
        } else {
            "not a Zarr store (no zarr.json, .zattrs or .zgroup)".into()
        })
    })?;
    let image = match meta::array(root, node, zarr_format) {
        // A plain array: no OME metadata to read.
        Ok(array) => plain_image(&array, zarr_format).map_err(fail)?,
        Err(_) => meta::image(&attrs, zarr_format).map_err(|m| {
            // A server lists nothing: name the container's first image for the user.
            fail(if root.is_remote() && meta::is_bioformats2raw(&attrs) {
                format!(
                    "a bioformats2raw container of images, which cannot be listed over HTTP: \
                     name one of its images, {}/0 for the first (then /1, /2, ...)",
                    shown.display()
                )
            } else {
                m
            })
        })?,
    };
    let arrays = image
        .datasets
        .iter()
        .map(|d| {
            let array = meta::array(root, &join(node, &d.path), zarr_format)
                .map_err(|m| fail(format!("dataset {:?}: {m}", d.path)))?;
            if array.shape.len() != image.axes.len() {
                return Err(fail(format!(
                    "dataset {:?} has {} dimensions but the image {} axes",
                    d.path,
                    array.shape.len(),
                    image.axes.len()
                )));
            }
            Ok(array)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((image, arrays))
}

/// A plain Zarr array as an image of one level.
fn plain_image(array: &ArrayMeta, zarr_format: u8) -> std::result::Result<Image, String> {
    let n = array.shape.len();
    if !(2..=5).contains(&n) {
        return Err(format!(
            "a Zarr array of {n} dimensions (a volume has 2 to 5: [t, c,] z, y, x)"
        ));
    }
    let names = ["t", "c", "z", "y", "x"];
    let axes = names[5 - n..]
        .iter()
        .map(|name| meta::Axis {
            name: (*name).to_string(),
            kind: match *name {
                "t" => AxisKind::Time,
                "c" => AxisKind::Channel,
                _ => AxisKind::Space,
            },
            unit: None,
        })
        .collect();
    Ok(Image {
        version: "none".into(),
        zarr_format,
        multiscales: 1,
        axes,
        datasets: vec![meta::Dataset {
            path: String::new(),
            scale: vec![1.0; n],
            translation: vec![0.0; n],
        }],
        label: false,
    })
}

/// What `info` shows of the store `root`, whose image `image` has its axes as `layout` says.
fn describe(
    image: &Image,
    arrays: &[ArrayMeta],
    layout: &Layout,
    root: &Root,
    name: String,
) -> ZarrInfo {
    let first = &arrays[0];
    ZarrInfo {
        version: (image.version != "none").then(|| image.version.clone()),
        zarr_format: image.zarr_format,
        image: name,
        axes: image
            .axes
            .iter()
            .map(|a| ZarrAxis {
                name: a.name.clone(),
                kind: match &a.kind {
                    AxisKind::Time => "time".into(),
                    AxisKind::Channel => "channel".into(),
                    AxisKind::Space => "space".into(),
                    AxisKind::Other(t) => t.clone(),
                },
                unit: a.unit.clone(),
            })
            .collect(),
        levels: {
            let pyramid = levels::StorePyramid::of(image, arrays, layout);
            (image.datasets.iter().zip(arrays).enumerate())
                .map(|(i, (d, a))| ZarrLevel {
                    path: d.path.clone(),
                    shape: a.shape.clone(),
                    scale: d.scale.clone(),
                    pyramid_level: match i {
                        0 => Some(0),
                        _ => pyramid.level_of(i),
                    },
                })
                .collect()
        },
        data_type: first.dtype.clone(),
        chunks: first.chunks.clone(),
        inner_chunks: first.inner.clone(),
        codecs: first.codecs.clone(),
        // Labels that cannot be listed are not: reading one names what is wrong.
        labels: meta::label_names(root, "").unwrap_or_default(),
    }
}

/// Where the image's axes are: which is time, which channel, and the spatial ones (z, y, x as
/// stored; `None` for the z of a 2-D image).
#[derive(Clone, Debug)]
struct Layout {
    time: Option<usize>,
    channel: Option<usize>,
    spatial: [Option<usize>; 3],
}

impl Layout {
    fn of(image: &Image, shape: &[u64]) -> std::result::Result<Self, String> {
        let find = |kind: AxisKind| image.axes.iter().position(|a| a.kind == kind);
        let first_space = image
            .axes
            .iter()
            .position(|a| a.kind == AxisKind::Space)
            .unwrap_or(0);
        let n = image.axes.len();
        let spatial = if n - first_space == 3 {
            [Some(n - 3), Some(n - 2), Some(n - 1)]
        } else {
            [None, Some(n - 2), Some(n - 1)]
        };
        for (axis, &len) in image.axes.iter().zip(shape) {
            if let AxisKind::Other(kind) = &axis.kind
                && len > 1
            {
                return Err(format!(
                    "axis {:?} ({}) of {len} is neither time, channel nor space",
                    axis.name,
                    if kind.is_empty() { "no type" } else { kind }
                ));
            }
        }
        Ok(Self {
            time: find(AxisKind::Time),
            channel: find(AxisKind::Channel),
            spatial,
        })
    }

    /// The volume's dimensions (x fastest) of an array of `shape`.
    fn dims(&self, shape: &[u64]) -> [usize; 3] {
        let [z, y, x] = self.spatial.map(|a| a.map_or(1, |a| shape[a] as usize));
        [x, y, z]
    }
}

/// A store's image opened: its metadata read and checked against the options, nothing of its
/// voxels read yet.
struct Opened {
    /// Where the store lives.
    root: Root,
    /// The image's node in the store (`""`, or `labels/NAME`).
    node: String,
    /// The image as messages name it.
    image_path: PathBuf,
    image: Image,
    arrays: Vec<ArrayMeta>,
    layout: Layout,
    info: ZarrInfo,
    notes: Vec<String>,
}

impl Opened {
    /// Opens the image of the store at `dir` (or the label image `opts` names).
    fn new(dir: &Path, opts: &LoadOptions) -> Result<Self> {
        let root = Root::open(dir, &opts.zarr)?;
        let (node, name) = image_node(&root, opts)?;
        let image_path = root.shown(&node);
        let (image, arrays) = read_image(&root, &node)?;
        let array = &arrays[0];
        let layout = Layout::of(&image, &array.shape).map_err(|m| Error::format(&image_path, m))?;
        let info = describe(&image, &arrays, &layout, &root, name);
        let dir = &root.shown("");
        let mut notes = Vec::new();
        let count = |axis: Option<usize>| axis.map_or(1, |a| array.shape[a] as usize);
        let (times, channels) = (count(layout.time), count(layout.channel));
        if opts.part.volume >= times {
            return Err(one_volume(dir, times, opts.part.volume));
        }
        if opts.part.channel >= channels {
            return Err(one_channel(dir, channels, opts.part.channel));
        }
        if times > 1 || channels > 1 {
            notes.push(format!(
                "OME-Zarr image of {channels} channel{} and {times} time point{}: read channel {} \
                 at time point {}",
                plural(channels),
                plural(times),
                opts.part.channel,
                opts.part.volume
            ));
        }
        if image.multiscales > 1 {
            notes.push(format!(
                "the store holds {} images (multiscales): read the first",
                image.multiscales
            ));
        }
        Ok(Self {
            root,
            node,
            image_path,
            image,
            arrays,
            layout,
            info,
            notes,
        })
    }

    /// Dataset `i`, to read the time point and channel `opts` picks.
    fn dataset<'a>(&'a self, i: usize, opts: &'a LoadOptions) -> read::Dataset<'a> {
        read::Dataset {
            root: &self.root,
            node: &self.node,
            image: &self.image_path,
            path: &self.image.datasets[i].path,
            meta: &self.arrays[i],
            layout: &self.layout,
            at: [opts.part.volume as u64, opts.part.channel as u64],
            max_memory: opts.max_memory,
            scratch: opts.scratch.as_deref(),
            cancel: &opts.cancel,
        }
    }

    /// The dimensions, spacing and transform of dataset `i`, with notes on units not known.
    fn grid(&self, i: usize, notes: &mut Vec<String>) -> pyramid::Finest {
        let dataset = &self.image.datasets[i];
        let (spacing, origin) = geometry(&self.image, dataset, &self.layout, notes);
        let mut transform = WorldTransform::unknown(spacing);
        for k in 0..3 {
            transform.matrix[k][3] = origin[k];
        }
        let dims = self.layout.dims(&self.arrays[i].shape);
        pyramid::Finest {
            dims,
            spacing,
            transform,
        }
    }

    /// The volume of dataset `i`, with its spacing and origin, and the notes.
    fn read(&self, dir: &Path, i: usize, opts: &LoadOptions) -> Result<Read0> {
        let fail = |m: String| Error::format(&self.image_path, m);
        let mut notes = self.notes.clone();
        let pyramid::Finest {
            dims,
            spacing,
            transform: t,
        } = self.grid(i, &mut notes);
        let stored = self.arrays[i].voxel_type().map_err(fail)?;
        let (voxels, rounded) = self.dataset(i, opts).voxels_counted(dims)?;
        notes.extend(rounded.note(stored.name()));
        let mut read0 = Read0::new(dir, dims, spacing, stored, voxels, notes)?;
        read0 = read0.with_transform(Some(t));
        if self.image.label {
            read0.volume = read0.volume.declared_labels();
        }
        if self.root.is_remote() {
            read0.volume = read0.volume.fetched_remotely();
        }
        read0.format_version.clone_from(&self.info.version);
        read0.details = Some(std::sync::Arc::new(self.info.clone()));
        Ok(read0)
    }
}

/// Loads the image of the store at `dir` (or the label image `opts` names).
fn load(dir: &Path, opts: &LoadOptions) -> Result<Read0> {
    let opened = Opened::new(dir, opts)?;
    let mut read0 = opened.read(dir, 0, opts)?;
    if let Some((source, steps)) =
        levels::StoreLevels::new(&opened.image, &opened.arrays, &opened.dataset(0, opts))
    {
        read0.volume = read0.volume.with_level_source(Arc::new(source), &steps);
    }
    Ok(read0)
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// The spacing and origin (mm, x first) of `dataset`, with notes on units not known.
fn geometry(
    image: &Image,
    dataset: &meta::Dataset,
    layout: &Layout,
    notes: &mut Vec<String>,
) -> ([f64; 3], [f64; 3]) {
    let (mut spacing, mut origin) = ([1.0; 3], [0.0; 3]);
    let mut unknown = Vec::new();
    for (k, axis) in layout.spatial.iter().rev().enumerate() {
        let Some(a) = *axis else { continue };
        let unit = image.axes[a].unit.as_deref();
        let mm = if let Some(Some(mm)) = unit.map(meta::mm_per) {
            mm
        } else {
            unknown.push(format!(
                "{} ({})",
                image.axes[a].name,
                unit.map_or_else(|| "no unit".to_string(), |u| format!("unit {u:?}"))
            ));
            1.0
        };
        spacing[k] = dataset.scale[a] * mm;
        origin[k] = dataset.translation[a] * mm;
    }
    if !unknown.is_empty() {
        unknown.reverse();
        notes.push(format!(
            "axes {} have no known length unit: their scale is read as mm",
            unknown.join(", ")
        ));
    }
    (spacing, origin)
}
