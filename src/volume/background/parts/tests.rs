//! The background found in parts against [`Background::find`]: volumes cut into random grids of
//! chunks, each chunk given only its own voxels, the chunks taken in a shuffled order and every
//! summary and answer sent through bytes.

use proptest::prelude::*;

use super::super::{Background, BackgroundRule, MaskWords, border_threshold, threshold_of_border};
use super::*;
use crate::progress::Monitor;
use crate::volume::{Volume, VoxelType, Voxels};

/// A xorshift generator: the tests' randomness from a seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            v.swap(i, self.below(i + 1));
        }
    }
}

/// Up to three random cuts inside `0..d`, sorted, with 0 and `d`: chunks of irregular sizes.
fn cuts(rng: &mut Rng, d: usize) -> Vec<usize> {
    let mut c = vec![0, d];
    for _ in 0..rng.below(4) {
        if d > 1 {
            c.push(1 + rng.below(d - 1));
        }
    }
    c.sort_unstable();
    c.dedup();
    c
}

/// The chunks of the grid `cuts` cuts a volume of `dims` into, each with a copy of its own
/// voxels alone (all a task is given).
fn chunks_of<T: Voxel>(v: &[T], dims: [usize; 3], cuts: &[Vec<usize>; 3]) -> Vec<(Chunk, Vec<T>)> {
    let mut out = Vec::new();
    for z in cuts[2].windows(2) {
        for y in cuts[1].windows(2) {
            for x in cuts[0].windows(2) {
                let origin = [x[0], y[0], z[0]];
                let size = [x[1] - x[0], y[1] - y[0], z[1] - z[0]];
                let chunk = Chunk::new(dims, origin, size).unwrap();
                let mut own = Vec::with_capacity(chunk.len());
                for k in 0..size[2] {
                    for j in 0..size[1] {
                        let row = origin[0] + dims[0] * (origin[1] + j + dims[1] * (origin[2] + k));
                        own.extend_from_slice(&v[row..row + size[0]]);
                    }
                }
                out.push((chunk, own));
            }
        }
    }
    out
}

/// The threshold from the chunks' border values, taken in a shuffled order.
fn threshold_in_parts<T: Voxel>(
    chunks: &[(Chunk, Vec<T>)],
    volume: &Volume,
    rng: &mut Rng,
) -> Option<f32> {
    let mut order: Vec<usize> = (0..chunks.len()).collect();
    rng.shuffle(&mut order);
    let mut border = Vec::new();
    for i in order {
        border.extend(border_values_in(&chunks[i].1, &chunks[i].0).unwrap());
    }
    let s = volume.stats();
    threshold_of_border(border, (s.min, s.max), volume.dims())
}

/// What the join found: the background, and how many face labels the join alone made
/// background (none of their chunk's voxels on the volume's border).
fn mask_in_parts<T: Voxel>(
    chunks: &[(Chunk, Vec<T>)],
    dims: [usize; 3],
    t: f32,
    rng: &mut Rng,
) -> (Background, usize, Vec<ChunkMask>) {
    let labels: Vec<ChunkLabels> = chunks
        .iter()
        .map(|(c, v)| ChunkLabels::find(v, c, t).unwrap())
        .collect();
    for l in &labels {
        assert!(l.memory_bytes() <= ChunkLabels::most_bytes(l.chunk()));
    }
    let mut order: Vec<usize> = (0..chunks.len()).collect();
    rng.shuffle(&mut order);
    let mut join = BackgroundJoin::new(dims);
    let mut local = std::collections::HashMap::new();
    for &i in &order {
        let s = labels[i].summary();
        let bytes = s.to_bytes();
        assert_eq!(bytes.len() % 8, 0);
        let back = ChunkSummary::from_bytes(&bytes).unwrap();
        assert_eq!(back, s);
        local.insert(s.chunk.origin, s.border.clone());
        join.add(back).unwrap();
    }
    let mut answers = join.finish().unwrap();
    rng.shuffle(&mut answers);
    let len: usize = dims.iter().product();
    let mut words = MaskWords::Memory(vec![!0; len.div_ceil(64)]);
    let (mut count, mut joined, mut masks) = (0, 0, Vec::new());
    for a in answers {
        let back = ChunkAnswer::from_bytes(&a.to_bytes()).unwrap();
        assert_eq!(back, a);
        for (w, l) in a.background.iter().zip(&local[&a.chunk.origin]) {
            joined += (w & !l).count_ones() as usize;
        }
        // A task labels its chunk again (it keeps nothing between rounds): the same labels.
        let (c, v) = chunks.iter().find(|(c, _)| c == a.chunk()).unwrap();
        let again = ChunkLabels::find(v, c, t).unwrap();
        let m = again.mask(&back).unwrap();
        let m = ChunkMask::from_bytes(&m.to_bytes()).unwrap();
        m.write_into(words.words_mut()).unwrap();
        count += m.count();
        masks.push(m);
    }
    // Bits past the volume's last voxel were never a chunk's.
    if let MaskWords::Memory(w) = &mut words
        && !len.is_multiple_of(64)
    {
        *w.last_mut().unwrap() &= (1 << (len % 64)) - 1;
    }
    (
        Background::of_parts(dims, Some(t), words, count).unwrap(),
        joined,
        masks,
    )
}

/// The volumes of the tests: 0 noise, 1 a dark surround of a bright block holding cavities,
/// 2 a bright block holding winding tunnels (some from the border) inside a dark surround;
/// some voxels missing.
fn volume_of(kind: usize, dims: [usize; 3], rng: &mut Rng) -> Vec<f32> {
    let [nx, ny, nz] = dims;
    let len = nx * ny * nz;
    let at = |i: usize| [i % nx, (i / nx) % ny, i / (nx * ny)];
    let shell = |c: [usize; 3]| (0..3).any(|a| c[a] == 0 || c[a] + 1 == dims[a]);
    let mut v: Vec<f32> = (0..len)
        .map(|i| match kind {
            0 => (rng.below(10) * 10) as f32,
            _ if shell(at(i)) || (kind == 1 && rng.below(8) == 0) => rng.below(4) as f32,
            _ => 100.0 + rng.below(3) as f32,
        })
        .collect();
    if kind == 2 {
        for walk in 0..4 {
            let mut c = at(rng.below(len));
            if walk == 0 {
                c[rng.below(3)] = 0;
            }
            for _ in 0..3 * (nx + ny + nz) {
                v[c[0] + nx * (c[1] + ny * c[2])] = rng.below(4) as f32;
                let a = rng.below(3);
                c[a] = if rng.below(2) == 0 {
                    c[a].saturating_sub(1)
                } else {
                    (c[a] + 1).min(dims[a] - 1)
                };
            }
        }
    }
    if rng.below(3) == 0 {
        v[rng.below(len)] = f32::NAN;
    }
    v
}

/// Checks the parts' threshold and background against `find`'s for one volume and grid, and
/// the mask at a threshold of its own against the fill's; the face labels the join alone made
/// background.
fn check<T: Voxel>(v: Vec<T>, dims: [usize; 3], ty: VoxelType, seed: u64) -> usize {
    let mut rng = Rng(seed | 1);
    let grid = [
        cuts(&mut rng, dims[0]),
        cuts(&mut rng, dims[1]),
        cuts(&mut rng, dims[2]),
    ];
    let chunks = chunks_of(&v, dims, &grid);
    let volume = Volume::from_voxels(dims, [1.0; 3], ty, Voxels::owned(v)).unwrap();
    let t = threshold_in_parts(&chunks, &volume, &mut rng);
    let expected = border_threshold(&volume);
    assert_eq!(
        t.map(f32::to_bits),
        expected.map(f32::to_bits),
        "{dims:?} {grid:?}"
    );
    let found = Background::find(&volume, BackgroundRule::Auto, &Monitor::none()).unwrap();
    let mut joined = 0;
    let parts = match t {
        None => Background::of_parts(dims, None, MaskWords::memory(0), 0).unwrap(),
        Some(t) => {
            let (b, j, _) = mask_in_parts(&chunks, dims, t, &mut rng);
            joined += j;
            b
        }
    };
    assert_eq!(parts, found, "{dims:?} {grid:?}");
    // Any threshold, found or not (dims below 3 too): the fill's mask.
    let t = volume.stats().mean as f32;
    let fill = Background::at(
        &volume,
        (BackgroundRule::Auto, Some(t)),
        &Monitor::none(),
        |w| Ok(MaskWords::memory(w)),
    )
    .unwrap();
    let (b, j, _) = mask_in_parts(&chunks, dims, t, &mut rng);
    assert_eq!(b, fill, "{dims:?} {grid:?} at {t}");
    joined + j
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn parts_in_any_grid_and_order_find_what_find_finds(
        nx in 1usize..13, ny in 1usize..13, nz in 1usize..13, kind in 0usize..3, seed: u64,
    ) {
        let dims = [nx, ny, nz];
        let v = volume_of(kind, dims, &mut Rng(seed | 1));
        check(v, dims, VoxelType::F32, seed.rotate_left(7));
    }
}

#[test]
fn tunnels_that_cross_chunks_are_joined_in_voxels_of_their_own_type() {
    let mut joined = 0;
    for seed in 1..40u64 {
        let mut rng = Rng(seed * 0x9e37_79b9);
        let dims = [6 + rng.below(10), 6 + rng.below(10), 6 + rng.below(10)];
        let v = volume_of(2, dims, &mut rng);
        let bytes: Vec<u8> = v
            .iter()
            .map(|&x| if x.is_nan() { 7 } else { x as u8 })
            .collect();
        joined += check(bytes, dims, VoxelType::U8, seed);
        let wide: Vec<u16> = v
            .iter()
            .map(|&x| if x.is_nan() { 9 } else { x as u16 * 300 })
            .collect();
        joined += check(wide, dims, VoxelType::U16, seed + 99);
    }
    // Many labels were background only through another chunk.
    assert!(joined > 100, "{joined}");
}

/// A 12 × 9 × 8 volume in 3 × 3 × 2 chunks: a dark shell (1) around a bright block (100)
/// holding two dark pockets (0): one reaching the shell only through a tunnel across two other
/// chunks, one on its own.
fn pockets() -> (Vec<f32>, [usize; 3], [Vec<usize>; 3]) {
    let dims = [12, 9, 8];
    let idx = |x: usize, y: usize, z: usize| x + 12 * (y + 9 * z);
    let mut v: Vec<f32> = (0..12 * 9 * 8)
        .map(|i| {
            let c = [i % 12, (i / 12) % 9, i / 108];
            if (0..3).any(|a| c[a] == 0 || c[a] + 1 == dims[a]) {
                1.0
            } else {
                100.0
            }
        })
        .collect();
    for z in 2..=5 {
        for x in 5..=6 {
            v[idx(x, 4, z)] = 0.0;
        }
    }
    for y in 1..=3 {
        v[idx(5, y, 2)] = 0.0;
    }
    for x in 1..=4 {
        v[idx(x, 1, 2)] = 0.0;
    }
    v[idx(8, 6, 5)] = 0.0;
    v[idx(9, 6, 5)] = 0.0;
    (
        v,
        dims,
        [vec![0, 4, 8, 12], vec![0, 3, 6, 9], vec![0, 4, 8]],
    )
}

#[test]
fn a_pocket_reaching_the_border_through_other_chunks_is_background() {
    let (v, dims, grid) = pockets();
    let chunks = chunks_of(&v, dims, &grid);
    let volume = Volume::new(dims, [1.0; 3], VoxelType::F32, v.clone()).unwrap();
    let mut rng = Rng(5);
    let t = threshold_in_parts(&chunks, &volume, &mut rng);
    assert_eq!(t, Some(1.0));
    let (b, joined, masks) = mask_in_parts(&chunks, dims, 1.0, &mut rng);
    let idx = |x: usize, y: usize, z: usize| x + 12 * (y + 9 * z);
    assert!(
        b.contains(idx(6, 4, 5), 0.0),
        "the pocket, beyond its tunnel's chunks"
    );
    assert!(!b.contains(idx(9, 6, 5), 0.0), "the pocket on its own");
    assert!(!b.contains(idx(6, 6, 4), 100.0), "the bright block");
    // The shell (12·9·8 − 10·7·6 = 444), the pocket (8) and its tunnel (7).
    assert_eq!(b.fraction, 459.0 / 864.0);
    // The pocket's labels in its two chunks (z below and above 4, the first holding the
    // tunnel's first voxel too): background through the join alone; the tunnel's other
    // chunks reach the shell themselves.
    assert_eq!(joined, 2);
    let found = Background::find(&volume, BackgroundRule::Auto, &Monitor::none()).unwrap();
    assert_eq!(b, found);
    // A task holding the chunks of one layer along z (as a strip of the partition's does the
    // chunks around its box): the background there, nothing elsewhere.
    let layer: Vec<ChunkMask> = masks
        .into_iter()
        .filter(|m| m.chunk().origin()[2] == 4)
        .collect();
    assert_eq!(layer.len(), 9);
    let part = Background::in_part(dims, BackgroundRule::Auto, Some(1.0), &layer).unwrap();
    let mut inside = 0;
    for (i, &x) in v.iter().enumerate() {
        let held = i / (12 * 9) >= 4;
        assert_eq!(part.contains(i, x), held && b.contains(i, x), "voxel {i}");
        inside += usize::from(held && b.contains(i, x));
    }
    assert!(inside > 200 && part.fraction == inside as f64 / (12.0 * 9.0 * 4.0));
    let other = Background::in_part([12, 9, 9], BackgroundRule::Auto, Some(1.0), &layer);
    assert!(other.unwrap_err().to_string().contains("[12, 9, 9] grid"));
    // A threshold's rule and none need no mask; a found one without a threshold is none.
    let below = Background::in_part(dims, BackgroundRule::Below(50.0), None, &[]).unwrap();
    assert!(below.contains(0, 50.0) && !below.contains(0, 50.5));
    let none = Background::in_part(dims, BackgroundRule::None, Some(1.0), &layer).unwrap();
    assert_eq!(none, Background::none());
    let auto = Background::in_part(dims, BackgroundRule::Auto, None, &layer).unwrap();
    assert!(auto.value.is_none() && !auto.contains(0, 0.0));
    // The client's: find's rule, threshold and fraction from the chunks' counts, no mask.
    let client = Background::summarized(BackgroundRule::Auto, Some(1.0), 459, 864);
    assert_eq!(
        (client.rule, client.value, client.fraction),
        (found.rule, found.value, found.fraction)
    );
    assert!(client.memory_bytes() == 0 && !client.contains(0, 0.0));
}

/// The summary of the middle chunk of [`pockets`] and the join's answer to it.
fn middle() -> (ChunkLabels, ChunkAnswer) {
    let (v, dims, grid) = pockets();
    let chunks = chunks_of(&v, dims, &grid);
    let labels: Vec<ChunkLabels> = chunks
        .iter()
        .map(|(c, v)| ChunkLabels::find(v, c, 1.0).unwrap())
        .collect();
    let mut join = BackgroundJoin::new(dims);
    for l in &labels {
        join.add(l.summary()).unwrap();
    }
    let answers = join.finish().unwrap();
    let i = chunks
        .iter()
        .position(|(c, _)| c.origin() == [4, 3, 0])
        .unwrap();
    (labels[i].clone(), answers[i].clone())
}

#[test]
fn bytes_cut_short_or_foreign_are_refused() {
    let (labels, answer) = middle();
    let mask = labels.mask(&answer).unwrap().to_bytes();
    let summary = labels.summary().to_bytes();
    let answer = answer.to_bytes();
    for (bytes, read) in [
        (
            &summary,
            (|b| ChunkSummary::from_bytes(b).map(|_| ())) as fn(&[u8]) -> Result<()>,
        ),
        (&answer, |b| ChunkAnswer::from_bytes(b).map(|_| ())),
        (&mask, |b| ChunkMask::from_bytes(b).map(|_| ())),
    ] {
        read(bytes).unwrap();
        for cut in 0..bytes.len() {
            assert!(read(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        let mut longer = bytes.clone();
        longer.extend([0; 8]);
        assert!(read(&longer).is_err());
        let mut other = bytes.clone();
        other[7] = 2;
        let e = read(&other).unwrap_err().to_string();
        assert!(
            e.contains("of version 2 where this slabscope reads version 1"),
            "{e}"
        );
        other[0] = b'X';
        let e = read(&other).unwrap_err().to_string();
        assert!(
            e.ends_with("that does not read back: not one of slabscope's"),
            "{e}"
        );
        // Every single byte changed: refused, or read back as something else that checks.
        for at in 8..bytes.len() {
            let mut changed = bytes.clone();
            changed[at] ^= 0xff;
            let _ = read(&changed);
        }
    }
    // A mask whose count (the word after magic, dims, origin and size) is not its bits'.
    let mut miscounted = mask.clone();
    miscounted[80] += 1;
    let e = ChunkMask::from_bytes(&miscounted).unwrap_err().to_string();
    assert!(e.ends_with("a count of 18 for 17 bits"), "{e}");
    // A face label past the count, in the middle chunk's first inner face (x low).
    let mut s = labels.summary();
    s.faces[0] = super::bytes::runs([1, s.ids + 1].into_iter().chain([0; 10]));
    let e = ChunkSummary::from_bytes(&s.to_bytes())
        .unwrap_err()
        .to_string();
    assert!(e.contains("face 0: a label"), "{e}");
}

#[test]
fn a_summary_of_one_component_is_a_few_bytes() {
    let dims = [48, 48, 48];
    let chunk = Chunk::new(dims, [16; 3], [16; 3]).unwrap();
    let labels = ChunkLabels::find(&vec![0u8; 16 * 16 * 16], &chunk, 1.0).unwrap();
    assert_eq!(labels.count(), 1);
    // 17 words, a word of border bits, six faces of one run (label 1, 256 voxels: 1 + 2
    // bytes), padded to 24 bytes.
    let s = labels.summary();
    assert_eq!(s.faces.iter().map(Vec::len).collect::<Vec<_>>(), [3; 6]);
    assert_eq!(s.to_bytes().len(), 17 * 8 + 8 + 24);
}

#[test]
fn chunks_that_do_not_make_the_volume_are_refused() {
    let (v, dims, grid) = pockets();
    let chunks = chunks_of(&v, dims, &grid);
    let summaries: Vec<ChunkSummary> = chunks
        .iter()
        .map(|(c, v)| ChunkLabels::find(v, c, 1.0).unwrap().summary())
        .collect();
    let join_of = |s: &[ChunkSummary]| {
        let mut j = BackgroundJoin::new(dims);
        for s in s {
            j.add(s.clone())?;
        }
        j.finish()
    };
    assert!(join_of(&summaries).is_ok());
    let e = join_of(&summaries[1..]).unwrap_err().to_string();
    assert!(e.contains("no chunk beyond a face"), "{e}");
    let mut twice = summaries.clone();
    twice.push(summaries[3].clone());
    let e = join_of(&twice).unwrap_err().to_string();
    assert!(e.contains("two chunks at [0, 3, 0]"), "{e}");
    let mut other = BackgroundJoin::new([12, 9, 9]);
    assert!(other.add(summaries[0].clone()).is_err());
    // Bricks laid as a wall: rows of chunks whose ends do not line up.
    let dims = [4, 2, 1];
    let wall = [
        ([0, 0, 0], [2, 1, 1]),
        ([2, 0, 0], [2, 1, 1]),
        ([0, 1, 0], [1, 1, 1]),
    ];
    let mut join = BackgroundJoin::new(dims);
    let mut result = Ok(());
    for (origin, size) in wall
        .into_iter()
        .chain([([1, 1, 0], [2, 1, 1]), ([3, 1, 0], [1, 1, 1])])
    {
        let c = Chunk::new(dims, origin, size).unwrap();
        let l = ChunkLabels::find(&vec![0.0f32; c.len()], &c, 1.0).unwrap();
        result = result.and(join.add(l.summary()));
    }
    assert!(result.and(join.finish().map(|_| ())).is_err());
}

#[test]
fn wrong_voxels_answers_and_counts_are_refused() {
    let (labels, answer) = middle();
    let c = *labels.chunk();
    assert_eq!((c.origin(), c.size(), c.len()), ([4, 3, 0], [4, 3, 4], 48));
    assert!(ChunkLabels::find(&[0.0f32; 47], &c, 1.0).is_err());
    assert!(border_values_in(&[0.0f32; 49], &c).is_err());
    assert!(Chunk::new([12, 9, 8], [10, 0, 0], [3, 1, 1]).is_err());
    assert!(Chunk::new([12, 9, 8], [0, 0, 0], [0, 1, 1]).is_err());
    assert!(Chunk::new([12, 9, 8], [usize::MAX, 0, 0], [2, 1, 1]).is_err());
    let other = Chunk::new([12, 9, 8], [0, 0, 0], [4, 3, 4]).unwrap();
    let elsewhere = ChunkLabels::find(&[0.0f32; 48], &other, 1.0).unwrap();
    let e = elsewhere.mask(&answer).unwrap_err().to_string();
    assert!(
        e.contains("given to the chunk of [4, 3, 4] at [0, 0, 0]"),
        "{e}"
    );
    let mask = labels.mask(&answer).unwrap();
    // The shell's 12 voxels at z = 0, the pocket's 4 and the tunnel's (5, 3, 2) in this chunk.
    assert_eq!(mask.count(), 17);
    let mut words = vec![0u64; 864usize.div_ceil(64)];
    assert!(mask.write_into(&mut words[1..]).is_err());
    mask.write_into(&mut words).unwrap();
    let count = mask.count();
    assert!(
        Background::of_parts(
            [12, 9, 8],
            Some(1.0),
            MaskWords::Memory(words.clone()),
            count + 1
        )
        .is_err()
    );
    assert!(
        Background::of_parts(
            [12, 9, 8],
            Some(1.0),
            MaskWords::Memory(words[1..].to_vec()),
            count
        )
        .is_err()
    );
    let b = Background::of_parts([12, 9, 8], Some(1.0), MaskWords::Memory(words), count).unwrap();
    assert_eq!(b.fraction, 17.0 / 864.0);
    assert!(b.contains(5 + 12 * (3 + 9 * 2), 0.0));
}
