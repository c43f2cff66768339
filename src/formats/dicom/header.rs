//! What series assembly needs of a DICOM file, read from its parsed header: one [`Image`] per
//! frame (a classic file has one; an enhanced multi-frame file describes each frame in its
//! functional groups; a Siemens mosaic one per tile of each frame, its frames time points at
//! one position), each with the pixel format the file's frames share (`format`).

use dicom_dictionary_std::tags;
use dicom_object::InMemDicomObject;

use super::elements::{array, float, floats, int, item, shown_text, text};
use super::format::{PixelFormat, pixel_format};
use super::mosaic::{Mosaic, Tile};

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
    // or by the offsets of GridFrameOffsetVector (RT dose); a mosaic's frames are its time
    // points, each holding every slice, at the file's position.
    let offsets = floats(obj, tags::GRID_FRAME_OFFSET_VECTOR);
    let mut out = Vec::with_capacity(format.frames.min(1 << 16) as usize);
    for frame in 0..format.frames {
        let fields = match per_frame.and_then(|p| p.get(frame as usize)) {
            Some(f) => FrameFields::from(f).over(&shared),
            None if per_frame.is_none() && format.frames > 1 && mosaic.is_none() => {
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
