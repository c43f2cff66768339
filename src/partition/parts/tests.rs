use super::testing::{in_parts, layered};
use super::*;
use crate::partition::{Stop, partition};
use crate::testing::Lcg;
use crate::volume::VoxelType;
use crate::volume::background::BackgroundRule;

#[test]
fn strips_counted_apart_from_their_boxes_and_added_shuffled_give_the_whole_partition() {
    let mut rng = Lcg::new(7);
    let volumes = [
        layered(VoxelType::U8, 0.0, 1.0),
        layered(VoxelType::F32, 3.0, 0.371),
    ];
    for v in &volumes {
        for axis in [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.3, 0.5, 0.8],
        ] {
            for background in [BackgroundRule::Auto, BackgroundRule::None] {
                for (method, stop) in [
                    (Method::TopDown, Stop::Slabs(3)),
                    (Method::Optimal, Stop::Slabs(4)),
                    (Method::TopDown, Stop::Slabs(1)),
                ] {
                    let mut p = PartitionParams {
                        method,
                        stop,
                        ..PartitionParams::default()
                    };
                    p.stack.background = background;
                    let case = format!(
                        "{:?} {axis:?} {background:?} {method:?} {stop:?}",
                        v.voxel_type()
                    );
                    let expected = partition(v, axis, &p, &Monitor::none()).unwrap();
                    let none = Monitor::none();
                    let background = Background::find(v, background, &none).unwrap();
                    let got = in_parts(v, axis, &p, &background, &mut rng);
                    let json = |p: &Partition| serde_json::to_string(p).unwrap();
                    assert_eq!(json(&got), json(&expected), "{case}");
                }
            }
        }
    }
}

#[test]
fn parts_read_back_from_their_bytes_and_nothing_else_does() {
    let v = layered(VoxelType::F32, 3.0, 0.371);
    let p = PartitionParams {
        stop: Stop::Slabs(3),
        ..PartitionParams::default()
    };
    let none = Monitor::none();
    let split = StackSplit::new(&v, [0.3, 0.5, 0.8], &p).unwrap();
    let background = Background::none();
    let count = |rows: Range<usize>| split.count(&v, &background, rows, &none).unwrap();
    // A part holding folded rows and a row kept apart, and one holding kept rows alone.
    let mut first = count(0..3);
    first.add(count(6..7)).unwrap();
    let later = count(8..12);
    for part in [&first, &later] {
        let bytes = part.to_bytes();
        assert_eq!(&SliceCounts::from_bytes(&bytes).unwrap(), part);
        // Cut short anywhere, longer, or another version: refused.
        for cut in [0, 8, bytes.len() / 2, bytes.len() - 8] {
            assert!(SliceCounts::from_bytes(&bytes[..cut]).is_err(), "{cut}");
        }
        let mut other = bytes.clone();
        other[7] = 9;
        let e = SliceCounts::from_bytes(&other).unwrap_err();
        assert!(e.contains("version 9"), "{e}");
        let mut longer = bytes.clone();
        longer.extend([0; 8]);
        assert!(SliceCounts::from_bytes(&longer).is_err());
        let e = SlabJoints::from_bytes(&bytes).unwrap_err();
        assert!(e.contains("not slabscope's slab joints"), "{e}");
        // Fewer bytes than a word: foreign, or the start of a part cut short.
        let e = SliceCounts::from_bytes(b"junk").unwrap_err();
        assert!(e.contains("not slabscope's slice counts"), "{e}");
        let e = SliceCounts::from_bytes(&bytes[..4]).unwrap_err();
        assert!(e.contains("cut short"), "{e}");
    }
    let slabs = [(0, 10), (10, split.slices())];
    let joints = split
        .count_boundaries(&v, &background, 2..8, &slabs, &none)
        .unwrap();
    let bytes = joints.to_bytes();
    assert_eq!(SlabJoints::from_bytes(&bytes).unwrap(), joints);
    assert!(SlabJoints::from_bytes(&bytes[..bytes.len() - 8]).is_err());
    assert!(SliceCounts::from_bytes(&bytes).is_err());
    // A stack claiming tables beyond what any partition holds is refused before they are made.
    let mut huge = bytes.clone();
    huge[8..16].copy_from_slice(&(1u64 << 40).to_le_bytes());
    assert!(SlabJoints::from_bytes(&huge).is_err());
}

#[test]
fn rows_counted_twice_or_left_out_are_errors() {
    let v = layered(VoxelType::U8, 0.0, 1.0);
    let p = PartitionParams::default();
    let none = Monitor::none();
    let split = StackSplit::new(&v, [0.0, 0.0, 1.0], &p).unwrap();
    let background = Background::none();
    let mut a = split.count(&v, &background, 0..5, &none).unwrap();
    let b = split.count(&v, &background, 4..8, &none).unwrap();
    let e = a.add(b).unwrap_err().to_string();
    assert!(e.contains("rows 4–7"), "{e}");
    let e = split
        .slabs(&v, &background, a, &none)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains(&format!("5 of {} rows", split.rows())), "{e}");
    let other = StackSplit::new(&v, [1.0, 0.0, 0.0], &p).unwrap();
    let mut a = split.count(&v, &background, 0..5, &none).unwrap();
    let b = other.count(&v, &background, 5..6, &none).unwrap();
    assert!(a.add(b).is_err());
}

#[test]
fn an_oblique_strip_holds_far_less_in_a_box_a_layer_than_in_one_box() {
    let v = layered(VoxelType::U8, 0.0, 1.0);
    let split = StackSplit::new(&v, [0.3, 0.5, 0.8], &PartitionParams::default()).unwrap();
    let layers: Vec<Range<usize>> = (0..28).step_by(4).map(|z| z..z + 4).collect();
    let (mut one, mut layered) = (0, 0);
    for rows in split.strips(4) {
        let whole = split.voxel_box(&v, &rows).unwrap().unwrap();
        let boxes = split.voxel_boxes(&v, &rows, &layers).unwrap();
        for (b, planes) in boxes.iter().zip(&layers) {
            let Some(b) = b else { continue };
            // Within the one box and the layer's planes.
            for m in 0..3 {
                assert!(whole.origin[m] <= b.origin[m]);
                assert!(b.origin[m] + b.size[m] <= whole.origin[m] + whole.size[m]);
            }
            assert!(planes.start <= b.origin[2] && b.origin[2] + b.size[2] <= planes.end);
        }
        one += whole.len();
        layered += boxes.iter().flatten().map(VoxelBox::len).sum::<usize>();
    }
    assert!(layered * 3 < one * 2, "{layered} of {one}");
}

#[test]
fn a_strips_kept_runs_give_its_second_pass_bit_for_bit_and_read_back_from_their_bytes_alone() {
    let v = layered(VoxelType::F32, 3.0, 0.371);
    let none = Monitor::none();
    let p = PartitionParams::default();
    for (axis, background) in [
        ([0.3, 0.5, 0.8], Background::none()),
        (
            [0.0, 0.0, 1.0],
            Background::find(&v, BackgroundRule::Auto, &none).unwrap(),
        ),
    ] {
        let split = StackSplit::new(&v, axis, &p).unwrap();
        let n = split.slices();
        for rows in split.strips(3) {
            let (counts, runs) = split
                .count_keeping(&v, &background, rows.clone(), &none)
                .unwrap();
            assert_eq!(
                counts,
                split.count(&v, &background, rows.clone(), &none).unwrap()
            );
            assert_eq!(runs.rows(), rows);
            let bytes = runs.to_bytes();
            let read = StripRuns::from_bytes(&bytes).unwrap();
            // Slabs of a slice each (read from the runs, where the first pass reads the stack),
            // uneven ones, and one slab (no pair).
            let singles: Vec<Slab> = (0..n).map(|s| (s, s + 1)).collect();
            for slabs in [
                singles,
                vec![(0, 3), (3, 4), (4, 17), (17, n)],
                vec![(0, n)],
            ] {
                let expected = split
                    .count_boundaries(&v, &background, rows.clone(), &slabs, &none)
                    .unwrap();
                assert_eq!(
                    runs.joints(&slabs, &none).unwrap(),
                    expected,
                    "{axis:?} {rows:?}"
                );
                assert_eq!(read.joints(&slabs, &none).unwrap(), expected);
            }
            // Slabs that do not tile the stack are refused.
            for slabs in [vec![(0, 3), (4, n)], vec![(0, n - 1)], vec![(1, n)], vec![]] {
                let e = runs.joints(&slabs, &none).unwrap_err().to_string();
                assert!(e.contains("tile the stack"), "{e}");
            }
            assert!(runs.held_bytes() > 0);
            // Cut short anywhere, longer, another version or a byte changed: refused or read as
            // some runs, never a panic.
            for cut in 0..bytes.len() {
                assert!(StripRuns::from_bytes(&bytes[..cut]).is_err(), "{cut}");
            }
            let mut longer = bytes.clone();
            longer.push(0);
            assert!(StripRuns::from_bytes(&longer).is_err());
            let mut other = bytes.clone();
            other[7] = 9;
            assert!(
                StripRuns::from_bytes(&other)
                    .unwrap_err()
                    .contains("version 9")
            );
            let mut rng = Lcg::new(rows.start as u64);
            for _ in 0..2000 {
                let mut changed = bytes.clone();
                let at = 48 + (rng.next_u64() as usize) % (bytes.len() - 48);
                changed[at] = rng.next_u64() as u8;
                if let Ok(runs) = StripRuns::from_bytes(&changed) {
                    let _ = runs.joints(&[(0, 5), (5, n)], &none);
                }
            }
        }
    }
}
