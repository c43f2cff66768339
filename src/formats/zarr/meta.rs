//! OME-Zarr metadata, read by hand from the group's JSON (`.zattrs` for NGFF 0.4 on Zarr v2,
//! `zarr.json`'s `attributes.ome` for 0.5 on Zarr v3): the first image's axes and datasets with
//! their scales and translations, the label images beside it, and each array's shape, type,
//! chunking and codecs as `info` shows them.

use serde_json::Value;

use super::root::Root;
use crate::formats::remote::join;

use crate::volume::VoxelType;

/// The most axes an image may have (NGFF allows five).
const MAX_AXES: usize = 5;

/// What kind of axis a named axis is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AxisKind {
    /// `time` (`--volume N` picks a point).
    Time,
    /// `channel` (`--channel N` picks one).
    Channel,
    /// `space`: one of the volume's axes.
    Space,
    /// Any other type, named.
    Other(String),
}

/// One axis of an image.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Its name (`x`, `y`, `z`, `c`, `t` by convention).
    pub name: String,
    /// Its type.
    pub kind: AxisKind,
    /// Its unit as written, if any.
    pub unit: Option<String>,
}

/// One resolution level of an image: its array's path and its transform.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// The array's path in the store.
    pub path: String,
    /// Per axis, the scale (the dataset's times the image's).
    pub scale: Vec<f64>,
    /// Per axis, the translation (zero where none is given).
    pub translation: Vec<f64>,
}

/// The image of an OME-Zarr group.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// The NGFF version (`0.4`, `0.5`).
    pub version: String,
    /// The Zarr format (2 or 3).
    pub zarr_format: u8,
    /// How many multiscales the group lists (the first is read).
    pub multiscales: usize,
    /// The axes, in the arrays' order.
    pub axes: Vec<Axis>,
    /// The levels, finest first.
    pub datasets: Vec<Dataset>,
    /// Whether the image is a label image (`image-label` metadata).
    pub label: bool,
}

/// A Zarr array's metadata as read.
#[derive(Clone, Debug, PartialEq)]
pub struct ArrayMeta {
    /// The shape, in the array's axis order.
    pub shape: Vec<u64>,
    /// The data type as the file names it.
    pub dtype: String,
    /// The chunk shape (the shard's, when sharded).
    pub chunks: Vec<u64>,
    /// The inner chunk shape of a sharded array.
    pub inner: Option<Vec<u64>>,
    /// The codecs (or v2 filters and compressor), by name, in the order applied when writing.
    pub codecs: Vec<String>,
    /// The codecs of a sharded array's inner chunks, by name.
    pub inner_codecs: Vec<String>,
    /// Whether a sharded array's shard index is at the start of each shard (else the end).
    pub index_at_start: bool,
}

impl ArrayMeta {
    /// The voxel type of the data type, or what is wrong with it.
    pub fn voxel_type(&self) -> Result<VoxelType, String> {
        let name = self.dtype.trim_start_matches(['<', '>', '|', '=']);
        Ok(match name {
            "uint8" | "u1" => VoxelType::U8,
            "int8" | "i1" => VoxelType::I8,
            "uint16" | "u2" => VoxelType::U16,
            "int16" | "i2" => VoxelType::I16,
            "uint32" | "u4" => VoxelType::U32,
            "int32" | "i4" => VoxelType::I32,
            "float32" | "f4" => VoxelType::F32,
            "float64" | "f8" => VoxelType::F64,
            _ => {
                return Err(format!(
                    "data type {:?} (slabscope reads 8-, 16- and 32-bit integers and 32- and \
                     64-bit floats)",
                    self.dtype
                ));
            }
        })
    }
}

/// The attributes of the group or array `node` of the store `root`, with its Zarr format:
/// `zarr.json`'s `attributes` (v3) or `.zattrs` (v2); `None` when `node` is no Zarr node.
pub fn attributes(root: &Root, node: &str) -> Result<Option<(u8, Value)>, String> {
    if let Some(meta) = root.json(&join(node, "zarr.json"))? {
        let attrs = meta.get("attributes").cloned().unwrap_or(Value::Null);
        return Ok(Some((3, attrs)));
    }
    let attrs = root.json(&join(node, ".zattrs"))?;
    let is_v2 =
        attrs.is_some() || root.has(&join(node, ".zgroup"))? || root.has(&join(node, ".zarray"))?;
    Ok(is_v2.then(|| (2, attrs.unwrap_or(Value::Null))))
}

/// The OME fields of a node's attributes: `ome` (0.5) or the attributes themselves (0.4).
fn ome_fields(attrs: &Value) -> &Value {
    attrs.get("ome").unwrap_or(attrs)
}

/// The label images a group of labels lists (`labels/`'s `labels`); none when there is no such
/// group, an error when it cannot be read.
pub fn label_names(root: &Root, image: &str) -> Result<Vec<String>, String> {
    let attrs = match attributes(root, &join(image, "labels")) {
        Ok(Some((_, attrs))) => attrs,
        Ok(None) => return Ok(Vec::new()),
        Err(e) => return Err(format!("labels/{e}")),
    };
    Ok(ome_fields(&attrs)
        .get("labels")
        .and_then(Value::as_array)
        .map(|names| {
            names
                .iter()
                .filter_map(Value::as_str)
                .map(str::to_owned)
                .collect()
        })
        .unwrap_or_default())
}

/// What a Zarr group that is not an image is, when it is a known container: said so that the
/// user can name the image in it.
pub fn container(attrs: &Value) -> Option<String> {
    let ome = ome_fields(attrs);
    if is_bioformats2raw(attrs) {
        return Some(
            "a bioformats2raw container of images: name one in it (its folder 0, 1, ...)".into(),
        );
    }
    if ome.get("plate").is_some() {
        return Some("an HCS plate: name one image in it (a folder ROW/COLUMN/FIELD)".into());
    }
    if ome.get("well").is_some() {
        return Some("an HCS well: name one image in it (its folder 0, 1, ...)".into());
    }
    None
}

/// Whether `attrs` are those of a bioformats2raw container (its images in groups `0`, `1`, ...).
pub fn is_bioformats2raw(attrs: &Value) -> bool {
    let key = "bioformats2raw.layout";
    attrs.get(key).is_some() || ome_fields(attrs).get(key).is_some()
}

/// The first image of the `multiscales` in `attrs` (of a group in Zarr format `zarr_format`).
pub fn image(attrs: &Value, zarr_format: u8) -> Result<Image, String> {
    let ome = ome_fields(attrs);
    let Some(all) = ome.get("multiscales").and_then(Value::as_array) else {
        return Err(container(attrs).unwrap_or_else(|| {
            "a Zarr group without OME-Zarr `multiscales` metadata".to_string()
        }));
    };
    let first = all
        .first()
        .ok_or("`multiscales` is empty: the group names no image")?;
    let version = ome
        .get("version")
        .or_else(|| first.get("version"))
        .and_then(Value::as_str)
        .unwrap_or("")
        .to_string();
    if !matches!(version.as_str(), "0.4" | "0.5") {
        return Err(format!(
            "OME-Zarr version {version:?} (slabscope reads 0.4 and 0.5)"
        ));
    }
    let axes = axes(first)?;
    let outer = transforms(first.get("coordinateTransformations"), axes.len())
        .map_err(|e| format!("multiscales[0]: {e}"))?;
    let datasets = first
        .get("datasets")
        .and_then(Value::as_array)
        .filter(|d| !d.is_empty())
        .ok_or("multiscales[0] lists no datasets")?
        .iter()
        .enumerate()
        .map(|(i, d)| dataset(d, axes.len(), &outer).map_err(|e| format!("datasets[{i}]: {e}")))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Image {
        version,
        zarr_format,
        multiscales: all.len(),
        axes,
        datasets,
        label: ome.get("image-label").is_some(),
    })
}

/// The axes of a multiscales entry.
fn axes(multiscale: &Value) -> Result<Vec<Axis>, String> {
    let list = multiscale
        .get("axes")
        .and_then(Value::as_array)
        .ok_or("multiscales[0] has no `axes`")?;
    if !(2..=MAX_AXES).contains(&list.len()) {
        return Err(format!(
            "{} axes (OME-Zarr images have 2 to {MAX_AXES})",
            list.len()
        ));
    }
    let axes: Vec<Axis> = list
        .iter()
        .map(|a| {
            let name = a.get("name").and_then(Value::as_str).unwrap_or("");
            let kind = match a.get("type").and_then(Value::as_str) {
                Some("time") => AxisKind::Time,
                Some("channel") => AxisKind::Channel,
                Some("space") => AxisKind::Space,
                Some(other) => AxisKind::Other(other.to_string()),
                None => match name {
                    "t" => AxisKind::Time,
                    "c" => AxisKind::Channel,
                    "x" | "y" | "z" => AxisKind::Space,
                    _ => AxisKind::Other(String::new()),
                },
            };
            Axis {
                name: name.to_string(),
                kind,
                unit: a.get("unit").and_then(Value::as_str).map(str::to_owned),
            }
        })
        .collect();
    let spatial = axes.iter().filter(|a| a.kind == AxisKind::Space).count();
    if !(2..=3).contains(&spatial) {
        return Err(format!(
            "{spatial} spatial axes (an image has 2 or 3: y and x, or z, y and x)"
        ));
    }
    if axes[axes.len() - spatial..]
        .iter()
        .any(|a| a.kind != AxisKind::Space)
    {
        return Err("the spatial axes are not the last ones, as OME-Zarr orders them".into());
    }
    Ok(axes)
}

/// A dataset: its path and its transform composed with the image's `outer` one.
fn dataset(d: &Value, n: usize, outer: &(Vec<f64>, Vec<f64>)) -> Result<Dataset, String> {
    let path = d
        .get("path")
        .and_then(Value::as_str)
        .filter(|p| !p.is_empty())
        .ok_or("no `path`")?;
    let (scale, translation) = transforms(d.get("coordinateTransformations"), n)?;
    Ok(Dataset {
        path: path.to_string(),
        scale: (0..n).map(|k| scale[k] * outer.0[k]).collect(),
        translation: (0..n)
            .map(|k| translation[k] * outer.0[k] + outer.1[k])
            .collect(),
    })
}

/// The scale and translation of a list of coordinate transformations over `n` axes (identity
/// where none is given).
fn transforms(list: Option<&Value>, n: usize) -> Result<(Vec<f64>, Vec<f64>), String> {
    let (mut scale, mut translation) = (vec![1.0; n], vec![0.0; n]);
    let Some(list) = list else {
        return Ok((scale, translation));
    };
    let list = list
        .as_array()
        .ok_or("coordinateTransformations is not a list")?;
    for t in list {
        let kind = t.get("type").and_then(Value::as_str).unwrap_or("");
        let values = |field: &str| -> Result<Vec<f64>, String> {
            if t.get("path").is_some() {
                return Err(format!(
                    "a {kind} read from a file (`path`) is not supported"
                ));
            }
            let v: Option<Vec<f64>> = t
                .get(field)
                .and_then(Value::as_array)
                .and_then(|a| a.iter().map(Value::as_f64).collect::<Option<_>>());
            match v {
                Some(v) if v.len() == n && v.iter().all(|x| x.is_finite()) => Ok(v),
                _ => Err(format!("its {field} is not {n} finite numbers")),
            }
        };
        match kind {
            "identity" => {}
            "scale" => {
                let s = values("scale")?;
                if s.iter().any(|&x| x <= 0.0) {
                    return Err(format!("scale {s:?} is not positive"));
                }
                scale = s;
            }
            "translation" => translation = values("translation")?,
            other => {
                return Err(format!(
                    "coordinate transformation {other:?} is not supported"
                ));
            }
        }
    }
    Ok((scale, translation))
}

/// The metadata of the array `node` of the store `root`, of Zarr format 2 (`.zarray`) or 3
/// (`zarr.json`), the store's (a remote store is asked only for its format's file).
pub fn array(root: &Root, node: &str, zarr_format: u8) -> Result<ArrayMeta, String> {
    if zarr_format == 3 {
        let v3 = root
            .json(&join(node, "zarr.json"))?
            .ok_or("no array metadata (zarr.json)")?;
        return array_v3(&v3);
    }
    let v2 = root
        .json(&join(node, ".zarray"))?
        .ok_or("no array metadata (.zarray)")?;
    let list = |field: &str| numbers(v2.get(field)).ok_or(format!(".zarray has no {field}"));
    let mut codecs: Vec<String> = v2
        .get("filters")
        .and_then(Value::as_array)
        .map(|f| f.iter().map(codec_v2).collect())
        .unwrap_or_default();
    if let Some(c) = v2.get("compressor").filter(|c| !c.is_null()) {
        codecs.push(codec_v2(c));
    }
    Ok(ArrayMeta {
        shape: list("shape")?,
        dtype: v2
            .get("dtype")
            .map(|d| d.as_str().map_or_else(|| d.to_string(), str::to_owned))
            .unwrap_or_default(),
        chunks: list("chunks")?,
        inner: None,
        codecs,
        inner_codecs: Vec::new(),
        index_at_start: false,
    })
}

/// A v2 filter's or compressor's name (Blosc with its inner compressor).
fn codec_v2(c: &Value) -> String {
    let id = c.get("id").and_then(Value::as_str).unwrap_or("?");
    match c.get("cname").and_then(Value::as_str) {
        Some(inner) => format!("{id}/{inner}"),
        None => id.to_string(),
    }
}

/// A v3 array's metadata.
fn array_v3(node: &Value) -> Result<ArrayMeta, String> {
    if node.get("node_type").and_then(Value::as_str) != Some("array") {
        return Err("zarr.json describes no array".into());
    }
    let shape = numbers(node.get("shape")).ok_or("zarr.json has no shape")?;
    let chunks = numbers(node.pointer("/chunk_grid/configuration/chunk_shape"))
        .ok_or("zarr.json has no regular chunk grid")?;
    let list = node.get("codecs").and_then(Value::as_array);
    let mut inner = None;
    let mut codecs = Vec::new();
    let mut inner_codecs = Vec::new();
    let mut index_at_start = false;
    for c in list.into_iter().flatten() {
        let name = c.get("name").and_then(Value::as_str).unwrap_or("?");
        if name == "sharding_indexed" {
            inner = numbers(c.pointer("/configuration/chunk_shape"));
            inner_codecs = c
                .pointer("/configuration/codecs")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
                .map(|i| {
                    i.get("name")
                        .and_then(Value::as_str)
                        .unwrap_or("?")
                        .to_string()
                })
                .collect::<Vec<_>>();
            index_at_start = c
                .pointer("/configuration/index_location")
                .and_then(Value::as_str)
                == Some("start");
            codecs.push(format!("sharding({})", inner_codecs.join(", ")));
        } else {
            codecs.push(name.to_string());
        }
    }
    Ok(ArrayMeta {
        shape,
        dtype: node
            .get("data_type")
            .map(|d| d.as_str().map_or_else(|| d.to_string(), str::to_owned))
            .unwrap_or_default(),
        chunks,
        inner,
        codecs,
        inner_codecs,
        index_at_start,
    })
}

/// A JSON list of non-negative integers.
fn numbers(v: Option<&Value>) -> Option<Vec<u64>> {
    v?.as_array()?.iter().map(Value::as_u64).collect()
}

/// Millimetres per OME-NGFF length unit (UDUNITS-2 names); `None` for any other.
pub fn mm_per(unit: &str) -> Option<f64> {
    Some(match unit {
        "angstrom" => 1e-7,
        "attometer" => 1e-15,
        "centimeter" => 10.0,
        "decimeter" => 100.0,
        "exameter" => 1e21,
        "femtometer" => 1e-12,
        "foot" => 304.8,
        "gigameter" => 1e12,
        "hectometer" => 1e5,
        "inch" => 25.4,
        "kilometer" => 1e6,
        "megameter" => 1e9,
        "meter" => 1e3,
        "micrometer" => 1e-3,
        "mile" => 1_609_344.0,
        "millimeter" => 1.0,
        "nanometer" => 1e-6,
        "parsec" => 3.085_677_581_491_367e19,
        "petameter" => 1e18,
        "picometer" => 1e-9,
        "terameter" => 1e15,
        "yard" => 914.4,
        "yoctometer" => 1e-21,
        "yottameter" => 1e27,
        "zeptometer" => 1e-18,
        "zettameter" => 1e24,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn v04(axes: &Value, datasets: &Value) -> Value {
        json!({"multiscales": [{"version": "0.4", "axes": axes, "datasets": datasets}]})
    }

    #[test]
    fn scales_compose_and_axes_take_their_types() {
        let attrs = json!({"ome": {"version": "0.5", "multiscales": [{
            "axes": [{"name": "c", "type": "channel"}, {"name": "z", "type": "space", "unit": "micrometer"},
                     {"name": "y"}, {"name": "x", "type": "space"}],
            "datasets": [{"path": "0", "coordinateTransformations": [
                {"type": "scale", "scale": [1, 2, 0.5, 0.5]},
                {"type": "translation", "translation": [0, 10, 0, 1]}]}],
            "coordinateTransformations": [{"type": "scale", "scale": [1, 3, 1, 1]}]
        }]}});
        let image = image(&attrs, 3).unwrap();
        assert_eq!(image.version, "0.5");
        assert_eq!(image.axes[0].kind, AxisKind::Channel);
        assert_eq!(image.axes[2].kind, AxisKind::Space, "y by its name");
        assert_eq!(image.axes[1].unit.as_deref(), Some("micrometer"));
        let d = &image.datasets[0];
        assert_eq!(d.scale, vec![1.0, 6.0, 0.5, 0.5]);
        assert_eq!(d.translation, vec![0.0, 30.0, 0.0, 1.0]);
    }

    #[test]
    fn what_cannot_be_read_is_named() {
        let xyz = json!([{"name": "z"}, {"name": "y"}, {"name": "x"}]);
        let err = |attrs: Value| image(&attrs, 2).unwrap_err();
        assert!(err(json!({})).contains("without OME-Zarr"));
        assert!(err(json!({"bioformats2raw.layout": 3})).contains("bioformats2raw"));
        assert!(err(json!({"plate": {}})).contains("HCS plate"));
        assert!(err(v04(&xyz, &json!([]))).contains("no datasets"));
        let bad_scale = json!([{"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 0, 1]}]}]);
        assert!(err(v04(&xyz, &bad_scale)).contains("not positive"));
        let short = json!([{"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 1]}]}]);
        assert!(err(v04(&xyz, &short)).contains("not 3 finite numbers"));
        let one = json!([{"name": "x"}, {"name": "c"}]);
        assert!(err(v04(&one, &json!([{"path": "0"}]))).contains("1 spatial axes"));
        let order = json!([{"name": "z"}, {"name": "c"}, {"name": "y"}, {"name": "x"}]);
        assert!(err(v04(&order, &json!([{"path": "0"}]))).contains("not the last"));
        let old =
            json!({"multiscales": [{"version": "0.3", "axes": xyz, "datasets": [{"path": "0"}]}]});
        assert!(err(old).contains("version \"0.3\""));
    }

    #[test]
    fn units_in_millimetres() {
        assert_eq!(mm_per("micrometer"), Some(1e-3));
        assert_eq!(mm_per("meter"), Some(1e3));
        assert_eq!(mm_per("inch"), Some(25.4));
        assert_eq!(mm_per("furlong"), None);
    }

    #[test]
    fn types_by_either_format_s_name() {
        let meta = |dtype: &str| ArrayMeta {
            shape: vec![1],
            dtype: dtype.into(),
            chunks: vec![1],
            inner: None,
            codecs: vec![],
            inner_codecs: vec![],
            index_at_start: false,
        };
        assert_eq!(meta("<u2").voxel_type(), Ok(VoxelType::U16));
        assert_eq!(meta("int16").voxel_type(), Ok(VoxelType::I16));
        assert_eq!(meta(">f8").voxel_type(), Ok(VoxelType::F64));
        assert!(meta("complex64").voxel_type().is_err());
        assert!(meta("|b1").voxel_type().is_err());
    }
}
