//! The found background's fill: the voxels at or below a threshold connected (6-neighbours) to
//! a border voxel at or below it, as a bit mask. A scanline fill (runs along x, a stack of
//! seeds, no recursion) whose stack is bounded: seeds beyond [`STACK_SEEDS`] are not pushed,
//! their rows marked instead (a bit a row of the volume), and the marked rows are swept for runs
//! that touch the filled voxels of a neighbouring row once the stack is empty, until none is
//! marked. A noisy background (a run or two of air a row between bright voxels) once pushed a
//! seed a run, eight bytes each: gigabytes for a 1024³ volume, beyond any budget. The mask is
//! the connected region whatever the order, so it is the same as the unbounded fill's.

use rayon::prelude::*;

use super::MaskWords;
use crate::error::Result;
use crate::progress::Monitor;
use crate::volume::Voxel;

/// The seeds the stack holds before rows are marked instead: 8 MiB.
const STACK_SEEDS: usize = 1 << 20;

/// [`connected_below_capped`] with the stack bounded by [`STACK_SEEDS`], the mask made in
/// `words` (a word per 64 voxels).
pub(super) fn connected_below_of<T: Voxel>(
    v: &[T],
    dims: [usize; 3],
    t: f32,
    monitor: &Monitor,
    mut words: MaskWords,
) -> Result<(MaskWords, usize)> {
    let (count, _) = connected_below_capped(v, dims, t, monitor, STACK_SEEDS, words.words_mut())?;
    Ok((words, count))
}

/// Bit `j` of the result: whether voxel `64·w + j` is at or below `t` (NaN is not).
fn below_word<T: Voxel>(v: &[T], w: usize, t: f32) -> u64 {
    let start = 64 * w;
    v[start..(start + 64).min(v.len())]
        .iter()
        .enumerate()
        .fold(0, |bits, (j, x)| bits | u64::from(x.to_f32() <= t) << j)
}

/// The voxels of `v` (dimensions `dims`) at or below `t` connected to a border voxel at or
/// below `t`, as a bit mask made in `mask` (a word per 64 voxels), with their count and the
/// marked rows swept; the stack holding about `cap` seeds at most (and a row's more).
///
/// The fill works on one bit mask of the voxels still open (at or below `t`, not filled yet),
/// made in parallel beforehand: extending a run, filling it and finding the runs of the rows
/// beside it are operations on 64 voxels at a time that read no voxel. The filled voxels are
/// then the ones at or below `t` no longer open.
fn connected_below_capped<T: Voxel>(
    v: &[T],
    dims: [usize; 3],
    t: f32,
    monitor: &Monitor,
    cap: usize,
    mask: &mut [u64],
) -> Result<(usize, usize)> {
    let [nx, ny, nz] = dims;
    debug_assert_eq!(mask.len(), v.len().div_ceil(64));
    let open = mask;
    open.par_iter_mut()
        .enumerate()
        .for_each(|(w, bits)| *bits = below_word(v, w, t));
    monitor.check()?;
    let mut fill = Fill {
        v,
        dims,
        t,
        open,
        marked: vec![0; (ny * nz).div_ceil(64)],
        stack: Vec::new(),
        cap,
        count: 0,
        runs: 0,
        swept: 0,
    };
    // Seeds: every border voxel at or below t, a seed a run of them, a row at a time.
    for z in 0..nz {
        for y in 0..ny {
            let row = (z * ny + y) * nx;
            if z == 0 || z + 1 == nz || y == 0 || y + 1 == ny {
                fill.push_starts(row, 0, nx - 1);
            } else {
                for i in [row, row + nx - 1] {
                    if fill.is_open(i) {
                        fill.stack.push(i);
                    }
                }
            }
            if fill.stack.len() >= cap {
                fill.drain(monitor)?;
            }
        }
    }
    fill.drain(monitor)?;
    while fill.sweep(monitor)? {}
    let (count, swept) = (fill.count, fill.swept);
    fill.open
        .par_iter_mut()
        .enumerate()
        .for_each(|(w, bits)| *bits = below_word(v, w, t) & !*bits);
    Ok((count, swept))
}

/// A fill under way.
struct Fill<'a, T> {
    v: &'a [T],
    dims: [usize; 3],
    t: f32,
    /// A bit a voxel: at or below the threshold and not filled yet.
    open: &'a mut [u64],
    /// A bit a row (`z * ny + y`): rows beside filled voxels whose seeds were not pushed.
    marked: Vec<u64>,
    stack: Vec<usize>,
    cap: usize,
    count: usize,
    runs: u32,
    /// Marked rows swept.
    swept: usize,
}

impl<T: Voxel> Fill<'_, T> {
    fn is_open(&self, i: usize) -> bool {
        self.open[i / 64] >> (i % 64) & 1 == 1
    }

    fn filled(&self, i: usize) -> bool {
        self.v[i].to_f32() <= self.t && !self.is_open(i)
    }

    /// The open voxels `a ..= b` as words: `(word, its bits in the range)` in order.
    fn open_words(&self, a: usize, b: usize) -> impl Iterator<Item = (usize, u64)> + '_ {
        (a / 64..=b / 64).map(move |w| {
            let low = if w == a / 64 { !0u64 << (a % 64) } else { !0 };
            let high = if w == b / 64 {
                !0u64 >> (63 - b % 64)
            } else {
                !0
            };
            (w, self.open[w] & low & high)
        })
    }

    /// Pushes a seed at the start of every run of open voxels in `row + a ..= row + b` (a run
    /// cut by `a` starts there).
    fn push_starts(&mut self, row: usize, a: usize, b: usize) {
        let mut carry = 0;
        let mut stack = std::mem::take(&mut self.stack);
        for (w, bits) in self.open_words(row + a, row + b) {
            let mut starts = bits & !(bits << 1 | carry);
            carry = bits >> 63;
            while starts != 0 {
                stack.push(64 * w + starts.trailing_zeros() as usize);
                starts &= starts - 1;
            }
        }
        self.stack = stack;
    }

    /// The run of open voxels around the open voxel `i` within `row ..= last`.
    fn run_around(&self, i: usize, row: usize, last: usize) -> (usize, usize) {
        let mut b = i;
        loop {
            let ones = (!(self.open[b / 64] >> (b % 64))).trailing_zeros() as usize;
            let reach = ones.min(64 - b % 64);
            b += reach;
            if b > last || reach < 64 - (b - reach) % 64 {
                break;
            }
        }
        let mut a = i;
        loop {
            let ones = (!(self.open[a / 64] << (63 - a % 64))).leading_zeros() as usize;
            let reach = ones.min(a % 64 + 1);
            if reach < a % 64 + 1 || a < reach + row {
                a = a + 1 - reach;
                break;
            }
            a -= reach;
        }
        (a.max(row), (b - 1).min(last))
    }

    /// Marks `a ..= b` filled.
    fn close(&mut self, a: usize, b: usize) {
        for w in a / 64..=b / 64 {
            let low = if w == a / 64 { !0u64 << (a % 64) } else { !0 };
            let high = if w == b / 64 {
                !0u64 >> (63 - b % 64)
            } else {
                !0
            };
            self.open[w] &= !(low & high);
        }
    }

    /// The rows beside row `row` (its first voxel's index): along y and along z.
    fn neighbours(&self, row: usize) -> [Option<usize>; 4] {
        let [nx, ny, nz] = self.dims;
        let (y, z) = ((row / nx) % ny, row / (nx * ny));
        [
            (y > 0).then(|| row - nx),
            (y + 1 < ny).then(|| row + nx),
            (z > 0).then(|| row - nx * ny),
            (z + 1 < nz).then(|| row + nx * ny),
        ]
    }

    /// Fills from every seed on the stack until it is empty, marking the rows whose seeds do
    /// not fit on it.
    fn drain(&mut self, monitor: &Monitor) -> Result<()> {
        let nx = self.dims[0];
        while let Some(seed) = self.stack.pop() {
            if !self.is_open(seed) {
                continue;
            }
            // A glance at the cancel flag every few thousand runs: the fill of a large volume
            // takes seconds, and a user who cancels waits no more than milliseconds of it.
            self.runs = self.runs.wrapping_add(1);
            if self.runs.is_multiple_of(4096) {
                monitor.check()?;
            }
            let row = seed - seed % nx;
            let (a, b) = self.run_around(seed, row, row + nx - 1);
            self.close(a, b);
            self.count += b - a + 1;
            for other in self.neighbours(row).into_iter().flatten() {
                if self.stack.len() >= self.cap {
                    let r = other / nx;
                    self.marked[r / 64] |= 1 << (r % 64);
                } else {
                    self.push_starts(other, a - row, b - row);
                }
            }
        }
        Ok(())
    }

    /// Seeds every marked row's runs that touch a filled voxel of a row beside it, filling
    /// whenever the stack is full and at the end; whether any row was marked.
    fn sweep(&mut self, monitor: &Monitor) -> Result<bool> {
        let nx = self.dims[0];
        let mut any = false;
        for w in 0..self.marked.len() {
            while self.marked[w] != 0 {
                let bit = self.marked[w].trailing_zeros() as usize;
                self.marked[w] &= !(1 << bit);
                any = true;
                self.swept += 1;
                let row = (w * 64 + bit) * nx;
                let beside = self.neighbours(row);
                self.push_touching(row, &beside);
                if self.stack.len() >= self.cap {
                    self.drain(monitor)?;
                }
            }
        }
        self.drain(monitor)?;
        Ok(any)
    }

    /// Pushes a seed at the start of every run of open voxels of `row` holding a voxel beside
    /// a filled voxel of one of the rows `beside`.
    fn push_touching(&mut self, row: usize, beside: &[Option<usize>; 4]) {
        let nx = self.dims[0];
        let mut run: Option<(usize, bool)> = None;
        for x in 0..nx {
            if self.is_open(row + x) {
                let (start, touching) = run.unwrap_or((row + x, false));
                let touches = beside.iter().flatten().any(|&o| self.filled(o + x));
                run = Some((start, touching || touches));
            } else if let Some((start, touching)) = run.take()
                && touching
            {
                self.stack.push(start);
            }
        }
        if let Some((start, true)) = run {
            self.stack.push(start);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The region by a breadth-first search over voxels, a queue as long as it likes.
    fn by_search(v: &[f32], [nx, ny, nz]: [usize; 3], t: f32) -> (Vec<bool>, usize) {
        let mut seen = vec![false; v.len()];
        let mut queue = std::collections::VecDeque::new();
        for (i, &value) in v.iter().enumerate() {
            let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
            let border = x == 0 || y == 0 || z == 0 || x + 1 == nx || y + 1 == ny || z + 1 == nz;
            if border && value <= t {
                seen[i] = true;
                queue.push_back(i);
            }
        }
        while let Some(i) = queue.pop_front() {
            let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
            let steps = [
                (x > 0).then(|| i - 1),
                (x + 1 < nx).then(|| i + 1),
                (y > 0).then(|| i - nx),
                (y + 1 < ny).then(|| i + nx),
                (z > 0).then(|| i - nx * ny),
                (z + 1 < nz).then(|| i + nx * ny),
            ];
            for j in steps.into_iter().flatten() {
                if !seen[j] && v[j] <= t {
                    seen[j] = true;
                    queue.push_back(j);
                }
            }
        }
        let n = seen.iter().filter(|&&s| s).count();
        (seen, n)
    }

    #[test]
    fn the_bounded_fill_finds_the_region_a_search_finds() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut random = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut swept = 0;
        for dims in [
            [1, 1, 1],
            [9, 1, 7],
            [1, 11, 6],
            [12, 9, 10],
            [23, 17, 19],
            [150, 4, 3],
            [130, 9, 5],
            [64, 3, 4],
        ] {
            for share in [30, 55, 70, 95] {
                let v: Vec<f32> = (0..dims.iter().product::<usize>())
                    .map(|_| if random() % 100 < share { 0.0 } else { 9.0 })
                    .collect();
                let (seen, n) = by_search(&v, dims, 1.0);
                for cap in [1, 2, 5, usize::MAX] {
                    // Dirty words to start with: the fill owes nothing to a zeroed mask.
                    let mut mask = vec![!0u64; v.len().div_ceil(64)];
                    let (count, rows) =
                        connected_below_capped(&v, dims, 1.0, &Monitor::none(), cap, &mut mask)
                            .unwrap();
                    assert_eq!(count, n, "{dims:?} {share}% {cap}");
                    for (i, &s) in seen.iter().enumerate() {
                        assert_eq!(mask[i / 64] >> (i % 64) & 1 == 1, s, "{dims:?} {i} {cap}");
                    }
                    if cap == usize::MAX {
                        assert_eq!(rows, 0);
                    }
                    swept += rows;
                }
            }
        }
        // The small stacks did mark rows, and their sweeps found what the search finds.
        assert!(swept > 100, "{swept}");
    }
}
