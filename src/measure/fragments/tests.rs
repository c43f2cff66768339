//! The tests of counts that add: pieces of sequences counted apart and added in any order,
//! in place or through bytes, count the whole.

use super::*;
use crate::testing::Lcg;

/// Sequences of symbols below `bins` with missing samples, of lengths 0 to `max`.
fn sequences(lcg: &mut Lcg, n: usize, max: u64, bins: u64) -> Vec<Vec<Sample>> {
    let mut next = |k: u64| (lcg.next_u64() >> 33) % k;
    (0..n)
        .map(|_| {
            let len = next(max + 1);
            (0..len)
                .map(|_| (next(9) != 0).then(|| next(bins) as u8))
                .collect()
        })
        .collect()
}

fn whole(seqs: &[Vec<Sample>], bins: usize, block: usize) -> BlockCounts {
    let mut c = BlockCounts::new(bins, block);
    for seq in seqs.iter().filter(|s| !s.is_empty()) {
        for s in seq {
            match s {
                Some(s) => c.push(*s),
                None => c.end_sequence(),
            }
        }
        c.end_sequence();
    }
    c
}

fn same(a: &BlockCounts, b: &BlockCounts, at: &str) {
    for k in [1, a.block() - 1, a.block()] {
        assert_eq!(a.table(k), b.table(k), "{k}-blocks, {at}");
    }
    assert_eq!(a.entropies(), b.entropies(), "{at}");
}

#[test]
fn pieces_counted_apart_and_added_in_any_order_count_the_whole() {
    let mut lcg = Lcg::new(42);
    for trial in 0..300 {
        let block = 2 + trial % 3;
        let bins = [2, 3, 5, 32][trial % 4];
        let seqs = sequences(&mut lcg, 12, 14, bins as u64);
        let mut next = |k: u64| (lcg.next_u64() >> 33) % k;
        // Each sequence cut at random places, each piece counted apart.
        let mut pieces = Vec::new();
        for (key, seq) in seqs.iter().enumerate().filter(|(_, s)| !s.is_empty()) {
            let n = seq.len() as u64;
            let mut cuts: Vec<u64> = (1..n).filter(|_| next(3) == 0).collect();
            cuts.insert(0, 0);
            cuts.push(n);
            for w in cuts.windows(2) {
                let mut c = BlockCounts::new(bins, block);
                let mut f = Fragment::new(key as u64, w[0]);
                for &s in &seq[w[0] as usize..w[1] as usize] {
                    f.push(&mut c, s);
                }
                let rays = u64::from(f.first());
                let open = f.close(&mut c, w[1] == n).into_iter().collect();
                pieces.push(PartialCounts::of(c, rays, open));
            }
        }
        // Shuffled, added in random groups, the groups added.
        for i in (1..pieces.len()).rev() {
            pieces.swap(i, next(i as u64 + 1) as usize);
        }
        let mut groups: Vec<PartialCounts> = Vec::new();
        for p in pieces {
            let g = next(groups.len() as u64 + 1) as usize;
            match groups.get_mut(g) {
                Some(group) => group.add(p),
                None => groups.push(p),
            }
        }
        let mut total = PartialCounts::new(bins, block);
        while let Some(g) = groups.pop() {
            total.add(g);
        }
        let at = format!("trial {trial}, L {block}, {bins} bins");
        assert!(total.is_complete(), "{at}: {:?}", total.fragments());
        let met = seqs.iter().filter(|s| !s.is_empty()).count() as u64;
        assert_eq!(total.rays, met, "{at}");
        same(&total.counts, &whole(&seqs, bins, block), &at);
    }
}

#[test]
fn adding_in_place_and_through_bytes_is_adding() {
    let mut lcg = Lcg::new(4411);
    for trial in 0..200 {
        let (block, bins) = (2 + trial % 3, [3, 32, 256][trial % 3]);
        let seqs = sequences(&mut lcg, 10, 16, bins as u64);
        let mut next = |k: u64| (lcg.next_u64() >> 33) % k;
        // Each sequence cut at random places, the pieces dealt to random parts.
        let mut parts = vec![PartialCounts::new(bins, block); 1 + next(5) as usize];
        for (key, seq) in seqs.iter().enumerate().filter(|(_, s)| !s.is_empty()) {
            let mut start = 0;
            while start < seq.len() {
                let end = (start + 1 + next(6) as usize).min(seq.len());
                let p = next(parts.len() as u64) as usize;
                let mut f = Fragment::new(key as u64 * 7919 % 97, start as u64);
                for &x in &seq[start..end] {
                    f.push(&mut parts[p].counts, x);
                }
                parts[p].rays += u64::from(f.first());
                let left = f.close(&mut parts[p].counts, end == seq.len());
                parts[p].add(PartialCounts::of(
                    BlockCounts::new(bins, block),
                    0,
                    Vec::from_iter(left),
                ));
                start = end;
            }
        }
        let (mut by_value, mut in_place) = (
            PartialCounts::new(bins, block),
            PartialCounts::new(bins, block),
        );
        for p in &parts {
            by_value.add(p.clone());
            in_place.add_ref(&PartialCounts::from_bytes(&p.to_bytes()).unwrap());
            assert_eq!(in_place.fragments(), by_value.fragments(), "trial {trial}");
        }
        assert!(in_place.is_complete(), "trial {trial}");
        same(
            &in_place.counts,
            &whole(&seqs, bins, block),
            &format!("trial {trial}"),
        );
    }
}

#[test]
fn a_piece_is_32_bytes_and_keeps_its_head_and_run() {
    // Half of the 56 bytes before: a cluster's part holds one a ray crossing its faces.
    assert_eq!(std::mem::size_of::<Fragment>(), 32);
    let mut c = BlockCounts::new(256, 4);
    let mut f = Fragment::new(3, 10);
    for s in [Some(255), None, Some(7), Some(254), Some(253)] {
        f.push(&mut c, s);
    }
    let head: Vec<Sample> = (0..f.head_len(4)).map(|k| f.head_sample(k)).collect();
    assert_eq!(head, [Some(255), None, Some(7)]);
    assert!(f.broken() && !f.first() && !f.last() && f.len() == 5);
    // The run after the missing sample: 7, 254 (0xfe), 253 (0xfd), three symbols of 8 bits.
    assert_eq!(f.run().parts(), ((7 << 16) | (0xfe << 8) | 0xfd, 3));
    let mut run = f.run();
    for s in [1, 2, 3, 4, 5, 6] {
        c.push_to(&mut run, s);
    }
    // A long run's length is kept capped: only whether it reaches L - 1 and L counts.
    f.walked(6, run);
    assert_eq!(f.run().parts(), ((3 << 24) | (4 << 16) | (5 << 8) | 6, 7));
    assert_eq!(f.end, 21);
}

#[test]
fn ray_keys_are_in_the_order_of_row_then_ray() {
    let rays = [
        (-3, -2),
        (5, -2),
        (-7, -1),
        (-1, 0),
        (0, 0),
        (2, 0),
        (-9, 4),
        (1, 4),
    ];
    let keys: Vec<u64> = rays.iter().map(|&(i, j)| ray_key(i, j)).collect();
    assert!(keys.windows(2).all(|w| w[0] < w[1]), "{keys:x?}");
    assert_eq!(ray_key(0, 0), 0x8000_0000_8000_0000);
    assert_eq!(ray_key(-1, 1), 0x8000_0001_7fff_ffff);
}

#[test]
fn a_piece_alone_counts_only_what_it_holds() {
    // a b a b c as a b | a b c: the first piece holds no 3-block, the second only abc;
    // aba and bab cross the seam and are counted when the pieces meet.
    let seq = [0u8, 1, 0, 1, 2];
    let mut parts = Vec::new();
    for (start, end) in [(0, 2), (2, 5)] {
        let mut c = BlockCounts::new(4, 3);
        let mut f = Fragment::new(7, start);
        for &s in &seq[start as usize..end as usize] {
            f.push(&mut c, Some(s));
        }
        let f = f.close(&mut c, end == 5).unwrap();
        parts.push((c, f));
    }
    assert_eq!(parts[0].0.blocks(), 0);
    assert_eq!(parts[1].0.table(3).unwrap(), vec![(vec![0, 1, 2], 1)]);
    let (c0, f0) = parts.remove(0);
    let (c1, f1) = parts.remove(0);
    let mut total = PartialCounts::of(c0, 1, vec![f0]);
    total.add(PartialCounts::of(c1, 0, vec![f1]));
    assert!(total.is_complete());
    let mut expect = BlockCounts::new(4, 3);
    for s in seq {
        expect.push(s);
    }
    expect.end_sequence();
    same(&total.counts, &expect, "a b | a b c");
}

#[test]
fn a_rays_key_gives_back_its_indices_and_orders_rows_first() {
    let rays = [
        (0, 0),
        (-1, 0),
        (0, -1),
        (7, -3),
        (-2_000_000, 5),
        (i32::MAX as i64, i32::MIN as i64),
    ];
    for &(i, j) in &rays {
        assert_eq!(key_ray(ray_key(i, j)), (i, j));
    }
    let mut by_key = rays.to_vec();
    by_key.sort_by_key(|&(i, j)| ray_key(i, j));
    let mut by_row = rays.to_vec();
    by_row.sort_by_key(|&(i, j)| (j, i));
    assert_eq!(by_key, by_row);
}
