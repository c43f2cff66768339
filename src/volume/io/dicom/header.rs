//! What series assembly needs of a DICOM file, read from its parsed header: one [`Image`] per
//! frame (a classic file has one; an enhanced multi-frame file describes each frame in its
//! functional groups; a Siemens mosaic one per tile of each frame), and the pixel format shared
//! by the file's frames.

use dicom_core::{Tag, VR};
use dicom_dictionary_std::tags;
use dicom_object::InMemDicomObject;

use super::mosaic::{Mosaic, Tile};

/// How a file's samples are stored and meant to be seen.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct PixelFormat {
    /// Rows of a frame.
    pub rows: u16,
    /// Columns of a frame.
    pub cols: u16,
    /// Bits each sample occupies: 8, 16 or 32.
    pub allocated: u16,
    /// Bits of it that hold the value (the low ones).
    pub stored: u16,
    /// Two's complement samples.
    pub signed: bool,
    /// Samples per pixel: 1 (grey) or 3 (colour).
    pub samples: u16,
    /// Colour samples stored plane by plane (else pixel by pixel).
    pub planar: bool,
    /// The photometric interpretation, e.g. `MONOCHROME2`.
    pub photometric: String,
    /// Frames in the file.
    pub frames: u32,
}

impl PixelFormat {
    /// Bytes of one frame, as stored natively (`YBR_FULL_422` keeps two samples a pixel: each
    /// pair of pixels shares its colour).
    pub fn frame_bytes(&self) -> u64 {
        let samples = if self.subsampled() {
            2
        } else {
            u64::from(self.samples)
        };
        u64::from(self.rows) * u64::from(self.cols) * samples * u64::from(self.allocated / 8)
    }

    /// Whether the colour is subsampled horizontally (`YBR_FULL_422`: Y1 Y2 Cb Cr).
    pub fn subsampled(&self) -> bool {
        self.samples == 3 && self.photometric == "YBR_FULL_422"
    }

    /// Whether the display shows the lowest value white (MONOCHROME1).
    pub fn inverted(&self) -> bool {
        self.photometric == "MONOCHROME1"
    }

    /// Whether the samples are colour.
    pub fn colour(&self) -> bool {
        self.samples == 3
    }

    /// Why slabscope cannot read these samples, if it cannot.
    pub fn problem(&self) -> Option<String> {
        if self.rows == 0 || self.cols == 0 {
            return Some(format!("image of {}x{} pixels", self.cols, self.rows));
        }
        if !matches!(self.allocated, 8 | 16 | 32) {
            return Some(format!(
                "{} bits allocated per sample (slabscope reads 8, 16 and 32)",
                self.allocated
            ));
        }
        if self.stored == 0 || self.stored > self.allocated {
            return Some(format!(
                "{} bits stored in {} allocated",
                self.stored, self.allocated
            ));
        }
        match (self.samples, self.photometric.as_str()) {
            (1, "MONOCHROME1" | "MONOCHROME2")
            | (3, "RGB" | "YBR_FULL" | "YBR_FULL_422" | "YBR_RCT" | "YBR_ICT") => None,
            (1, "PALETTE COLOR") => Some(
                "palette colour images (PALETTE COLOR) hold indices into a colour table, not \
                 intensities"
                    .into(),
            ),
            (s, p) => Some(format!(
                "photometric interpretation {:?} with {s} samples per pixel",
                p.chars().take(24).collect::<String>()
            )),
        }
    }
}

/// One 2D image (a frame) of a file, with what sorts it into a series and a volume.
#[derive(Clone, Debug)]
pub(super) struct Image {
    /// The file's index in the scanned list.
    pub file: usize,
    /// The frame's index in its file.
    pub frame: u32,
    /// `SeriesInstanceUID`.
    pub series_uid: String,
    /// `SeriesNumber`.
    pub series_number: Option<i64>,
    /// `SeriesDescription` (or `ProtocolName`).
    pub description: String,
    /// Modality, e.g. `CT`.
    pub modality: String,
    /// `ImageOrientationPatient`: row then column direction cosines (LPS).
    pub orientation: Option<[f64; 6]>,
    /// `ImagePositionPatient`: the first pixel's centre (LPS mm).
    pub position: Option<[f64; 3]>,
    /// `PixelSpacing`: between rows, then between columns (mm).
    pub pixel_spacing: Option<[f64; 2]>,
    /// `SpacingBetweenSlices`, a fallback when there are no positions.
    pub spacing_between: Option<f64>,
    /// `InstanceNumber`.
    pub instance: Option<i64>,
    /// `EchoNumbers`, or `EchoTime` when there is none: images of different echoes are different
    /// series.
    pub echo: Option<String>,
    /// `TemporalPositionIdentifier` / `TemporalPositionIndex`.
    pub temporal: Option<i64>,
    /// `AcquisitionNumber`.
    pub acquisition: Option<i64>,
    /// `TriggerTime` or the acquisition time, as text, for ordering repeats.
    pub time: Option<String>,
    /// `ImageType` says LOCALIZER (or SCOUT).
    pub localizer: bool,
    /// `ImageType` says DERIVED.
    pub derived: bool,
    /// `RescaleSlope` and `RescaleIntercept`.
    pub rescale: (f64, f64),
    /// `GantryDetectorTilt`, in degrees.
    pub tilt: Option<f64>,
    /// The file's pixel format.
    pub format: PixelFormat,
    /// The tile of a Siemens mosaic frame this image is (its format is the whole frame's).
    pub tile: Option<Tile>,
}

impl Image {
    /// Columns and rows of the image: its tile's, or its frame's.
    pub fn plane(&self) -> [usize; 2] {
        match &self.tile {
            Some(t) => t.plane.map(usize::from),
            None => [usize::from(self.format.cols), usize::from(self.format.rows)],
        }
    }
}

/// The text of element `tag`: its value as a string, or, for a value some converter stored as
/// UN (unknown), its bytes read as text (as dcmtk and pydicom read them).
pub(super) fn text(obj: &InMemDicomObject, tag: Tag) -> Option<String> {
    let e = obj.get(tag)?;
    let t = if e.vr() == VR::UN {
        String::from_utf8_lossy(e.to_bytes().ok()?.as_ref()).into_owned()
    } else {
        e.to_str().ok()?.into_owned()
    };
    let t = t.trim_matches(|c: char| c == '\0' || c.is_whitespace());
    (!t.is_empty()).then(|| t.to_string())
}

/// [`text`] as outputs show it: escaped by the one rule of [`crate::error::names`], so that a
/// field's control characters never reach a terminal (and keys and labels agree everywhere).
fn shown_text(obj: &InMemDicomObject, tag: Tag) -> Option<String> {
    text(obj, tag).map(|t| crate::error::names::text(&t))
}

pub(super) fn floats(obj: &InMemDicomObject, tag: Tag) -> Option<Vec<f64>> {
    let e = obj.get(tag)?;
    let v = if e.vr() == VR::UN {
        text(obj, tag)?
            .split('\\')
            .map(|x| x.trim().parse::<f64>().ok())
            .collect::<Option<Vec<f64>>>()?
    } else {
        e.to_multi_float64().ok()?
    };
    v.iter().all(|x| x.is_finite()).then_some(v)
}

pub(super) fn float(obj: &InMemDicomObject, tag: Tag) -> Option<f64> {
    floats(obj, tag)?.first().copied()
}

fn int(obj: &InMemDicomObject, tag: Tag) -> Option<i64> {
    let e = obj.get(tag)?;
    if e.vr() == VR::UN {
        return text(obj, tag)?.split('\\').next()?.trim().parse().ok();
    }
    e.to_int::<i64>().ok()
}

fn uint(obj: &InMemDicomObject, tag: Tag) -> Option<u16> {
    obj.get(tag)?.to_int::<u16>().ok()
}

/// The first item of the sequence `tag` in `obj`.
fn item(obj: &InMemDicomObject, tag: Tag) -> Option<&InMemDicomObject> {
    obj.get(tag)?.items()?.first()
}

fn array<const N: usize>(v: Option<Vec<f64>>) -> Option<[f64; N]> {
    v.and_then(|v| <[f64; N]>::try_from(v.get(..N)?).ok())
}

/// Geometry and values one frame may override (enhanced files) or the file gives once.
#[derive(Clone, Default)]
struct FrameFields {
    orientation: Option<[f64; 6]>,
    position: Option<[f64; 3]>,
    pixel_spacing: Option<[f64; 2]>,
    spacing_between: Option<f64>,
    rescale: Option<(f64, f64)>,
    temporal: Option<i64>,
}

impl FrameFields {
    /// The fields a data set (or a functional groups item) states directly or in the
    /// enhanced files' macros.
    fn from(obj: &InMemDicomObject) -> Self {
        let orient = item(obj, tags::PLANE_ORIENTATION_SEQUENCE).unwrap_or(obj);
        let pos = item(obj, tags::PLANE_POSITION_SEQUENCE).unwrap_or(obj);
        let measures = item(obj, tags::PIXEL_MEASURES_SEQUENCE).unwrap_or(obj);
        let value = item(obj, tags::PIXEL_VALUE_TRANSFORMATION_SEQUENCE).unwrap_or(obj);
        let content = item(obj, tags::FRAME_CONTENT_SEQUENCE).unwrap_or(obj);
        let slope = float(value, tags::RESCALE_SLOPE);
        let intercept = float(value, tags::RESCALE_INTERCEPT);
        Self {
            orientation: array(floats(orient, tags::IMAGE_ORIENTATION_PATIENT)),
            position: array(floats(pos, tags::IMAGE_POSITION_PATIENT)),
            pixel_spacing: array(floats(measures, tags::PIXEL_SPACING)),
            spacing_between: float(measures, tags::SPACING_BETWEEN_SLICES),
            rescale: (slope.is_some() || intercept.is_some())
                .then(|| (slope.unwrap_or(1.0), intercept.unwrap_or(0.0))),
            temporal: int(content, tags::TEMPORAL_POSITION_INDEX)
                .or_else(|| int(obj, tags::TEMPORAL_POSITION_IDENTIFIER)),
        }
    }

    /// These fields, with those unset taken from `base`.
    fn over(self, base: &Self) -> Self {
        Self {
            orientation: self.orientation.or(base.orientation),
            position: self.position.or(base.position),
            pixel_spacing: self.pixel_spacing.or(base.pixel_spacing),
            spacing_between: self.spacing_between.or(base.spacing_between),
            rescale: self.rescale.or(base.rescale),
            temporal: self.temporal.or(base.temporal),
        }
    }
}

/// The pixel format `obj` states.
pub(super) fn pixel_format(obj: &InMemDicomObject) -> PixelFormat {
    let allocated = uint(obj, tags::BITS_ALLOCATED).unwrap_or(0);
    PixelFormat {
        rows: uint(obj, tags::ROWS).unwrap_or(0),
        cols: uint(obj, tags::COLUMNS).unwrap_or(0),
        allocated,
        stored: uint(obj, tags::BITS_STORED).unwrap_or(allocated),
        signed: uint(obj, tags::PIXEL_REPRESENTATION) == Some(1),
        samples: uint(obj, tags::SAMPLES_PER_PIXEL).unwrap_or(1),
        planar: uint(obj, tags::PLANAR_CONFIGURATION) == Some(1),
        photometric: text(obj, tags::PHOTOMETRIC_INTERPRETATION)
            .unwrap_or_else(|| "MONOCHROME2".into())
            .to_ascii_uppercase(),
        frames: int(obj, tags::NUMBER_OF_FRAMES)
            .and_then(|n| u32::try_from(n).ok())
            .filter(|&n| n > 0)
            .unwrap_or(1),
    }
}

/// The images of a file whose parsed header is `obj`, one per frame, or one per tile of each
/// frame of a `mosaic` (their `file` is 0 until the scan numbers them).
pub(super) fn images(obj: &InMemDicomObject, mosaic: Option<&Mosaic>) -> Vec<Image> {
    let format = pixel_format(obj);
    let image_type: Vec<String> = text(obj, tags::IMAGE_TYPE)
        .map(|t| {
            t.split('\\')
                .map(|s| s.trim().to_ascii_uppercase())
                .collect()
        })
        .unwrap_or_default();
    let echo = text(obj, tags::ECHO_NUMBERS).or_else(|| text(obj, tags::ECHO_TIME));
    let base = FrameFields::from(obj);
    let shared = item(obj, tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE)
        .map_or_else(|| base.clone(), |s| FrameFields::from(s).over(&base));
    let per_frame = obj
        .get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE)
        .and_then(|e| e.items());
    // A classic multi-frame file steps its frames along the normal by SpacingBetweenSlices,
    // or by the offsets of GridFrameOffsetVector (RT dose).
    let offsets = floats(obj, tags::GRID_FRAME_OFFSET_VECTOR);
    let mut out = Vec::with_capacity(format.frames.min(1 << 16) as usize);
    for frame in 0..format.frames {
        let fields = match per_frame.and_then(|p| p.get(frame as usize)) {
            Some(f) => FrameFields::from(f).over(&shared),
            None if per_frame.is_none() && format.frames > 1 => {
                classic_frame(&shared, frame, offsets.as_deref())
            }
            None => shared.clone(),
        };
        let (slope, intercept) = fields.rescale.unwrap_or((1.0, 0.0));
        let image = Image {
            file: 0,
            frame,
            series_uid: shown_text(obj, tags::SERIES_INSTANCE_UID).unwrap_or_default(),
            series_number: int(obj, tags::SERIES_NUMBER),
            description: shown_text(obj, tags::SERIES_DESCRIPTION)
                .or_else(|| shown_text(obj, tags::PROTOCOL_NAME))
                .unwrap_or_default(),
            modality: shown_text(obj, tags::MODALITY).unwrap_or_default(),
            orientation: fields.orientation,
            position: fields.position,
            pixel_spacing: fields.pixel_spacing,
            spacing_between: fields.spacing_between,
            instance: int(obj, tags::INSTANCE_NUMBER),
            echo: echo.clone(),
            temporal: fields.temporal,
            acquisition: int(obj, tags::ACQUISITION_NUMBER),
            time: text(obj, tags::TRIGGER_TIME).or_else(|| text(obj, tags::ACQUISITION_TIME)),
            localizer: image_type.iter().any(|t| t == "LOCALIZER" || t == "SCOUT"),
            derived: image_type.first().is_some_and(|t| t == "DERIVED"),
            rescale: (slope, intercept),
            tilt: float(obj, tags::GANTRY_DETECTOR_TILT),
            format: format.clone(),
            tile: None,
        };
        match mosaic {
            Some(m) => out.extend(tiles(&image, m)),
            None => out.push(image),
        }
    }
    out
}

/// The slices of the mosaic frame `im`: an image a tile, each where it lies.
fn tiles<'a>(im: &'a Image, m: &'a Mosaic) -> impl Iterator<Item = Image> + 'a {
    (0..m.tiles).map(move |k| {
        let mut t = im.clone();
        let mosaic = [im.format.cols, im.format.rows];
        let spacing = im.pixel_spacing.unwrap_or([1.0, 1.0]);
        t.position = match (im.position, im.orientation) {
            (Some(p), Some(o)) => m.position(k, mosaic, p, o, spacing),
            _ => None,
        };
        t.tile = Some(m.tile(k));
        t
    })
}

/// Frame `frame` of a classic multi-frame file: the file's position moved along the normal.
fn classic_frame(fields: &FrameFields, frame: u32, offsets: Option<&[f64]>) -> FrameFields {
    let mut f = fields.clone();
    let step = match offsets {
        Some(o) => o.get(frame as usize).copied(),
        None => fields.spacing_between.map(|s| s * f64::from(frame)),
    };
    f.position = match (fields.position, fields.orientation, step) {
        (Some(p), Some(o), Some(step)) => {
            let n = crate::geometry::cross([o[0], o[1], o[2]], [o[3], o[4], o[5]]);
            Some(std::array::from_fn(|k| p[k] + step * n[k]))
        }
        _ => None,
    };
    f
}

/// The patient-identifying fields of `obj`, named: shown only when asked for.
pub(super) fn patient(obj: &InMemDicomObject) -> Vec<(String, String)> {
    [
        ("patient name", tags::PATIENT_NAME),
        ("patient ID", tags::PATIENT_ID),
        ("birth date", tags::PATIENT_BIRTH_DATE),
        ("sex", tags::PATIENT_SEX),
        ("address", tags::PATIENT_ADDRESS),
        ("accession number", tags::ACCESSION_NUMBER),
        ("institution", tags::INSTITUTION_NAME),
        ("referring physician", tags::REFERRING_PHYSICIAN_NAME),
        ("study date", tags::STUDY_DATE),
    ]
    .into_iter()
    .filter_map(|(name, tag)| Some((name.to_string(), shown_text(obj, tag)?)))
    .collect()
}
