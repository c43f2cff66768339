//! The optimal partition (beyond the paper): the contiguous partition into K slabs that keeps the
//! most information `I(slab; intensity)`, by dynamic programming, for every K up to a limit.
//! `I = (F(all) - Σ F(slab)) / v_T` with `F = N·H`, so the best partition minimizes `Σ F(slab)`.

use serde::Serialize;

use super::Slab;
use super::top_down::Gains;
use crate::error::{Error, Result};

/// The most slices the dynamic programme takes (its table is slices² values).
pub const MAX_SLICES: usize = 8192;

/// The longest stack whose optimum is computed only to compare with greedy (a 32 MiB table).
pub const COMPARE_MAX_SLICES: usize = 2048;

/// The best partition with a given number of slabs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Optimum {
    /// The slabs, in slice order.
    pub slabs: Vec<Slab>,
    /// `I(slab; intensity)` it keeps, bits.
    pub information: f64,
}

/// The optimal partitions into 1 ..= K slabs.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimalPartitions {
    /// Number of slices.
    pub slices: usize,
    /// `by_count[k - 1]` is the best partition into `k` slabs.
    pub by_count: Vec<Optimum>,
}

impl OptimalPartitions {
    /// The best partitions of the stack with per-slice `histograms` into 1 ..= `max_slabs` slabs.
    pub fn new(histograms: &[u64], bins: usize, max_slabs: usize) -> Result<Self> {
        let n = histograms.len() / bins;
        if n > MAX_SLICES {
            return Err(Error::invalid(
                "slices",
                n,
                format!("at most {MAX_SLICES} for the optimal partition"),
            ));
        }
        let kmax = max_slabs.clamp(1, n.max(1));
        let gains = Gains::new(histograms, bins);
        // cost[a * (n + 1) + b] = F([a, b)).
        let width = n + 1;
        let mut cost = vec![0.0f64; width * width];
        for a in 0..n {
            for b in a + 1..=n {
                cost[a * width + b] = gains.scaled(a, b);
            }
        }
        let whole = cost[n];
        // best[k][b]: least Σ F over k slabs covering [0, b); from[k][b]: where the last starts.
        let mut best = vec![vec![f64::INFINITY; width]; kmax + 1];
        let mut from = vec![vec![0usize; width]; kmax + 1];
        best[1][1..=n].copy_from_slice(&cost[1..=n]);
        for k in 2..=kmax {
            for b in k..=n {
                for a in k - 1..b {
                    let c = best[k - 1][a] + cost[a * width + b];
                    if c < best[k][b] {
                        best[k][b] = c;
                        from[k][b] = a;
                    }
                }
            }
        }
        let by_count = (1..=kmax)
            .map(|k| {
                let mut slabs = Vec::with_capacity(k);
                let mut end = n;
                for j in (1..=k).rev() {
                    let start = if j == 1 { 0 } else { from[j][end] };
                    slabs.push((start, end));
                    end = start;
                }
                slabs.reverse();
                let information = gains.bits(whole - best[k][n]);
                Optimum { slabs, information }
            })
            .collect();
        Ok(Self {
            slices: n,
            by_count,
        })
    }

    /// The best partition into `k` slabs, if it was computed.
    pub fn get(&self, k: usize) -> Option<&Optimum> {
        k.checked_sub(1).and_then(|i| self.by_count.get(i))
    }
}
