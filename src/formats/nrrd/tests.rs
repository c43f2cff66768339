//! Tests of the NRRD header parser: a full header, where it ends, bad headers and their
//! reasons, and space directions.

use super::*;

fn parse(text: &str) -> Result<Header> {
    parse_header(Path::new("t.nrrd"), text.as_bytes())
}

#[test]
fn parses_a_full_header() {
    let h = parse(
        "NRRD0005\n# comment\ntype: unsigned short\ndimension: 3\nsizes: 4 5 6\n\
         endian: big\nencoding: gz\nspace directions: (2,0,0) (0,0.5,0) (0,0,3)\n\
         byte skip: -1\nkey:=value\n\nDATA",
    )
    .unwrap();
    assert_eq!(h.voxel_type, VoxelType::U16);
    assert_eq!(h.sizes, vec![4, 5, 6]);
    assert_eq!(h.encoding, Encoding::Gzip);
    assert_eq!(h.endian, Some(Endian::Big));
    assert_eq!(
        h.directions,
        Some(vec![
            Some(vec![2.0, 0.0, 0.0]),
            Some(vec![0.0, 0.5, 0.0]),
            Some(vec![0.0, 0.0, 3.0])
        ])
    );
    assert_eq!(h.byte_skip, Skip::FromEnd);
}

#[test]
fn header_length_stops_at_the_blank_line() {
    let text = "NRRD0004\ntype: uchar\ndimension: 1\nsizes: 3\nencoding: raw\n\nabc";
    assert_eq!(parse(text).unwrap().len, text.len() - 3);
}

#[test]
fn rejects_bad_headers_with_reasons() {
    let err = |t: &str| parse(t).unwrap_err().to_string();
    assert!(
        err("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 2\nencoding: raw\n\n")
            .contains("dimension is 3")
    );
    assert!(err("NRRD0004\ntype: int64\n").contains("unsupported"));
    assert!(err("NRRD0004\ntype: uchar\ndimension: 1\nsizes: 2\n\n").contains("\"encoding\""));
    assert!(err("NRRD0004\ntype: uchar\nencoding: bzip2\n").contains("bzip2"));
    assert!(err("NRRD0004\ntype: uchar\nsizes: 2 x\n").contains("whole numbers"));
    assert!(err("NRRD0004\nno colon here\n").contains("not \"field: value\""));
    assert!(err("PNG").contains("magic"));
}

#[test]
fn directions_accept_none_and_spaces() {
    assert_eq!(
        parse_directions("none (3,4,0) ( 0, 0, 2 )"),
        Some(vec![
            None,
            Some(vec![3.0, 4.0, 0.0]),
            Some(vec![0.0, 0.0, 2.0])
        ])
    );
    assert_eq!(parse_directions("(1,0"), None);
}
