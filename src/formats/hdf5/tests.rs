use super::*;

#[test]
fn sniffs_the_signature_at_the_start_or_after_a_user_block() {
    assert_eq!(Hdf5.sniff(b"\x89HDF\r\n\x1a\n\0\0"), Sniff::Mine);
    let mut head = vec![0u8; 512];
    head.extend_from_slice(SIGNATURE);
    assert_eq!(Hdf5.sniff(&head), Sniff::Mine);
    head[512] = 0;
    assert_eq!(Hdf5.sniff(&head), Sniff::No);
    assert_eq!(Hdf5.sniff(b"\x89HDF"), Sniff::No);
    assert_eq!(Hdf5.sniff(b"\x89PNG\r\n\x1a\n"), Sniff::No);
}

#[test]
fn element_types_map_to_voxel_types() {
    let path = Path::new("x.h5");
    let int = |size, signed, byte_order| DatatypeMessage::FixedPoint {
        size,
        byte_order,
        signed,
        bit_offset: 0,
        bit_precision: (size * 8) as u16,
    };
    let le = ByteOrder::LittleEndian;
    assert_eq!(
        voxel_type(path, "/a", &int(2, true, ByteOrder::BigEndian)).unwrap(),
        (VoxelType::I16, Endian::Big, None)
    );
    assert_eq!(
        voxel_type(path, "/a", &int(4, false, le)).unwrap(),
        (VoxelType::U32, Endian::Little, None)
    );
    // 64-bit integers are held as f32.
    assert_eq!(
        voxel_type(path, "/a", &int(8, true, le)).unwrap(),
        (VoxelType::F32, Endian::Little, Some(Wide::I64))
    );
    assert_eq!(
        voxel_type(path, "/a", &int(8, false, ByteOrder::BigEndian)).unwrap(),
        (VoxelType::F32, Endian::Big, Some(Wide::U64))
    );
    let e = voxel_type(path, "/a", &int(16, true, le))
        .unwrap_err()
        .to_string();
    assert!(e.contains("dataset /a holds"), "{e}");
    assert!(!e.contains('\n'), "{e}");
}

#[test]
fn the_budget_counts_the_stored_bytes_and_the_volume() {
    let path = Path::new("x.h5");
    // 4x5x6 u16: 240 bytes stored, 240 held.
    assert!(check_budget(path, "/a", &[4, 5, 6], (VoxelType::U16, 2), 480).is_ok());
    assert!(check_budget(path, "/a", &[4, 5, 6], (VoxelType::U16, 2), 479).is_err());
    // Two volumes of f64: 1920 stored, one volume of f32 held (480).
    assert!(check_budget(path, "/a", &[2, 4, 5, 6], (VoxelType::F64, 8), 2400).is_ok());
    assert!(check_budget(path, "/a", &[2, 4, 5, 6], (VoxelType::F64, 8), 2399).is_err());
    // Claimed sizes past u64 are too large, not an overflow.
    // Two volumes of i64: 1920 stored, one volume of f32 held (480).
    assert!(check_budget(path, "/a", &[2, 4, 5, 6], (VoxelType::F32, 8), 2400).is_ok());
    assert!(check_budget(path, "/a", &[2, 4, 5, 6], (VoxelType::F32, 8), 2399).is_err());
    let huge = [usize::MAX, usize::MAX, 2];
    assert!(check_budget(path, "/a", &huge, (VoxelType::U8, 1), u64::MAX).is_err());
}

#[test]
fn info_names_the_read_dataset_first_and_counts_the_rest() {
    let found: Vec<pick::Found> = (0..20)
        .map(|i| pick::Found {
            path: format!("d{i:02}"),
            shape: vec![2, 3, 4],
            ty: "u8".into(),
        })
        .collect();
    let details = pick::details(&found, "d07");
    assert_eq!(details.count, 20);
    assert_eq!(details.datasets[0].path, "/d07");
    assert_eq!(details.datasets[1].path, "/d00");
    let line = &crate::formats::Details::lines(&details)[0].1;
    assert!(
        line.starts_with("/d07 (2x3x4 u8), /d00 (2x3x4 u8)"),
        "{line}"
    );
    assert!(line.ends_with(", and 4 more"), "{line}");
}
