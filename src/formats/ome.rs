//! OME-TIFF metadata: the OME-XML in the first page's `ImageDescription` says how the pages are
//! ordered over z, channel and time (`DimensionOrder`, `SizeZ/C/T`) and the physical voxel sizes
//! with their units (`PhysicalSizeX/Y/Z`, default µm as the schema says).

/// The most OME-XML read, bytes (the description of a large plate is far below it).
const MAX_XML: usize = 16 << 20;

/// What the OME-XML says of the first image's pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct OmePixels {
    /// Width and height of a plane.
    pub size_xy: [usize; 2],
    /// Sizes along z, c and t.
    pub size_zct: [usize; 3],
    /// Which of z (0), c (1) and t (2) varies fastest among the pages, then next, then slowest.
    pub order: [usize; 3],
    /// Voxel sizes in mm (`None` where not given).
    pub spacing: [Option<f64>; 3],
    /// How many images the file holds (the first is read).
    pub images: usize,
}

impl OmePixels {
    /// The page that holds plane `z` of channel `c` at time `t`.
    pub fn page(&self, zct: [usize; 3]) -> usize {
        let [a, b, c] = self.order;
        zct[a] + self.size_zct[a] * (zct[b] + self.size_zct[b] * zct[c])
    }

    /// How many pages the image spans.
    pub fn pages(&self) -> usize {
        self.size_zct.iter().product()
    }
}

/// Millimetres per OME length unit (the units of the OME schema that a voxel may be measured
/// in); `None` for a unit slabscope does not know.
fn mm_per(unit: &str) -> Option<f64> {
    Some(match unit {
        "pm" => 1e-9,
        "Å" => 1e-7,
        "nm" => 1e-6,
        "µm" | "um" | "μm" => 1e-3,
        "mm" => 1.0,
        "cm" => 10.0,
        "dm" => 100.0,
        "m" => 1e3,
        "in" => 25.4,
        "mil" => 0.0254,
        "pt" => 25.4 / 72.0,
        _ => return None,
    })
}

/// The order of z (0), c (1) and t (2) among the pages, fastest first, of a `DimensionOrder`.
fn dimension_order(order: &str) -> Result<[usize; 3], String> {
    let rest: Vec<usize> = match order.strip_prefix("XY") {
        Some(rest) if rest.len() == 3 => rest.chars().filter_map(|c| "ZCT".find(c)).collect(),
        _ => Vec::new(),
    };
    match rest[..] {
        [a, b, c] if a != b && b != c && a != c => Ok([a, b, c]),
        _ => Err(format!(
            "OME-XML DimensionOrder=\"{order}\" is not XY then Z, C and T"
        )),
    }
}

/// The OME pixels of `description` when it is OME-XML (`Ok(None)` when it is not); an error
/// says what in it slabscope cannot use.
pub fn parse(description: &str) -> Result<Option<OmePixels>, String> {
    let trimmed = description.trim_start();
    if !(trimmed.starts_with("<?xml") || trimmed.starts_with("<OME")) || !trimmed.contains("<OME") {
        return Ok(None);
    }
    if description.len() > MAX_XML {
        return Err(format!(
            "an OME-XML description of {} bytes; at most {MAX_XML} are read",
            description.len()
        ));
    }
    let doc = roxmltree::Document::parse(description).map_err(|e| format!("OME-XML: {e}"))?;
    let images: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("Image"))
        .collect();
    let pixels = images
        .first()
        .and_then(|i| i.children().find(|n| n.has_tag_name("Pixels")))
        .ok_or("OME-XML without an Image's Pixels")?;
    if pixels
        .descendants()
        .any(|n| n.has_tag_name("UUID") && n.attribute("FileName").is_some())
    {
        return Err(
            "an OME-TIFF whose planes are spread over several files (TiffData naming files); \
             slabscope reads one file's planes"
                .into(),
        );
    }
    let size = |key: &str| -> Result<usize, String> {
        let text = pixels
            .attribute(key)
            .ok_or(format!("OME-XML Pixels without {key}"))?;
        text.trim()
            .parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or(format!(
                "OME-XML {key}=\"{text}\" is not a positive whole number"
            ))
    };
    let [a, b, c] = dimension_order(pixels.attribute("DimensionOrder").unwrap_or("XYZCT"))?;
    let physical = |axis: &str| -> Result<Option<f64>, String> {
        let Some(text) = pixels.attribute(format!("PhysicalSize{axis}").as_str()) else {
            return Ok(None);
        };
        let unit = pixels
            .attribute(format!("PhysicalSize{axis}Unit").as_str())
            .unwrap_or("µm");
        let per = mm_per(unit).ok_or(format!(
            "OME-XML PhysicalSize{axis}Unit=\"{unit}\" is not a length unit slabscope knows"
        ))?;
        text.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v > 0.0)
            .map(|v| Some(v * per))
            .ok_or(format!(
                "OME-XML PhysicalSize{axis}=\"{text}\" is not a positive number"
            ))
    };
    Ok(Some(OmePixels {
        size_xy: [size("SizeX")?, size("SizeY")?],
        size_zct: [size("SizeZ")?, size("SizeC")?, size("SizeT")?],
        order: [a, b, c],
        spacing: [physical("X")?, physical("Y")?, physical("Z")?],
        images: images.len(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn xml(pixels: &str) -> String {
        format!(
            "<?xml version=\"1.0\"?><OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\">\
             <Image ID=\"Image:0\"><Pixels {pixels}><TiffData/></Pixels></Image></OME>"
        )
    }

    #[test]
    fn pages_follow_the_dimension_order() {
        let p = parse(&xml(
            "DimensionOrder=\"XYZTC\" SizeX=\"5\" SizeY=\"4\" SizeZ=\"3\" SizeC=\"2\" SizeT=\"2\"",
        ))
        .unwrap()
        .unwrap();
        assert_eq!(p.order, [0, 2, 1]);
        assert_eq!(p.pages(), 12);
        // z fastest, then t, then c.
        assert_eq!(p.page([0, 0, 0]), 0);
        assert_eq!(p.page([2, 0, 0]), 2);
        assert_eq!(p.page([0, 0, 1]), 3);
        assert_eq!(p.page([0, 1, 0]), 6);
        assert_eq!(p.page([1, 1, 1]), 10);
        assert_eq!(p.spacing, [None; 3]);
    }

    #[test]
    fn sizes_are_millimetres_whatever_the_unit_and_micrometres_by_default() {
        let p = parse(&xml(
            "SizeX=\"2\" SizeY=\"2\" SizeZ=\"2\" SizeC=\"1\" SizeT=\"1\" PhysicalSizeX=\"0.5\" \
             PhysicalSizeY=\"250\" PhysicalSizeYUnit=\"nm\" PhysicalSizeZ=\"2\" PhysicalSizeZUnit=\"mm\"",
        ))
        .unwrap()
        .unwrap();
        assert_eq!(p.order, [0, 1, 2], "XYZCT by default");
        let [x, y, z] = p.spacing.map(Option::unwrap);
        assert!((x - 5e-4).abs() < 1e-15 && (y - 2.5e-4).abs() < 1e-15 && z == 2.0);
    }

    #[test]
    fn what_cannot_be_used_is_named() {
        assert_eq!(parse("ImageJ=1.53\nslices=3"), Ok(None));
        assert_eq!(parse("a plain description"), Ok(None));
        let bad = |pixels: &str| parse(&xml(pixels)).unwrap_err();
        let sizes = "SizeX=\"2\" SizeY=\"2\" SizeZ=\"2\" SizeC=\"1\" SizeT=\"1\"";
        assert!(bad("SizeX=\"2\"").contains("without SizeY"));
        assert!(bad(&format!("{sizes} DimensionOrder=\"XYZZT\"")).contains("DimensionOrder"));
        assert!(
            bad(&format!(
                "{sizes} PhysicalSizeX=\"1\" PhysicalSizeXUnit=\"parsec\""
            ))
            .contains("parsec")
        );
        assert!(bad(&format!("{sizes} PhysicalSizeX=\"-1\"")).contains("positive number"));
        assert!(
            bad("SizeX=\"0\" SizeY=\"2\" SizeZ=\"2\" SizeC=\"1\" SizeT=\"1\"").contains("SizeX")
        );
        assert!(
            parse("<?xml version=\"1.0\"?><OME><Image")
                .unwrap_err()
                .starts_with("OME-XML")
        );
    }
}
