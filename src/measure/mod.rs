//! Information measures on histograms: Shannon entropy, Jensen-Shannon divergence, mutual
//! information and its normalized form (paper eq. 1, 5, 7 and 8). Pure maths, in bits; nothing
//! here knows about volumes.

mod blocks;
mod fragments;

pub use blocks::{BlockCounts, Counter, DenseCounts, ReadResult, Run, RunEnds, block_entropies};
pub(crate) use blocks::{Bytes, Words, corrupt, put_varint};
pub use fragments::{Fragment, PartialCounts, Sample, key_ray, ray_key};

/// `Σ c·log2 c` over the non-zero counts, the part of an entropy that depends on the shape.
#[inline]
fn sum_c_log_c(counts: impl IntoIterator<Item = u64>) -> f64 {
    counts
        .into_iter()
        .filter(|&c| c > 0)
        .map(|c| {
            let c = c as f64;
            c * c.log2()
        })
        .sum()
}

/// Shannon entropy in bits of the distribution given by `counts` (eq. 1); 0 for no counts.
///
/// Computed as `log2 N - Σ c·log2 c / N`, which is exact for counts and never negative beyond
/// rounding.
pub fn entropy(counts: impl IntoIterator<Item = u64> + Clone) -> f64 {
    let n: u64 = counts.clone().into_iter().sum();
    if n == 0 {
        return 0.0;
    }
    let n = n as f64;
    (n.log2() - sum_c_log_c(counts) / n).max(0.0)
}

/// `N·H` of a count histogram in bits: `N log2 N - Σ c log2 c`. Additive forms of information
/// (the gain of a split, the information kept by a partition) are differences of these.
pub fn scaled_entropy(counts: impl IntoIterator<Item = u64> + Clone) -> f64 {
    let n: u64 = counts.clone().into_iter().sum();
    if n == 0 {
        return 0.0;
    }
    let n = n as f64;
    (n * n.log2() - sum_c_log_c(counts)).max(0.0)
}

/// Jensen-Shannon divergence of two count histograms weighted by their totals (eq. 5 with
/// `π_i = N_i / (N_1 + N_2)`), in bits: `H(p_1 + p_2) - Σ π_i H(p_i)`.
pub fn jensen_shannon(a: &[u64], b: &[u64]) -> f64 {
    let (na, nb) = (a.iter().sum::<u64>() as f64, b.iter().sum::<u64>() as f64);
    if na == 0.0 || nb == 0.0 {
        return 0.0;
    }
    let merged = entropy(a.iter().zip(b).map(|(x, y)| x + y));
    let parts = (na * entropy(a.iter().copied()) + nb * entropy(b.iter().copied())) / (na + nb);
    (merged - parts).max(0.0)
}

/// Mutual information and joint entropy of a joint histogram stored row-major (`bins_x` rows of
/// `bins_y`), in bits: `(MI, H(X,Y))` (eq. 7).
pub fn mutual_information(joint: &[u64], bins_x: usize, bins_y: usize) -> (f64, f64) {
    assert_eq!(joint.len(), bins_x * bins_y, "joint histogram shape");
    let rows = (0..bins_x).map(|x| joint[x * bins_y..(x + 1) * bins_y].iter().sum::<u64>());
    let cols = (0..bins_y).map(|y| (0..bins_x).map(|x| joint[x * bins_y + y]).sum::<u64>());
    let h_xy = entropy(joint.iter().copied());
    let h_x = entropy(rows.collect::<Vec<_>>());
    let h_y = entropy(cols.collect::<Vec<_>>());
    ((h_x + h_y - h_xy).max(0.0), h_xy)
}

/// Normalized mutual information `MI(X,Y) / H(X,Y)` (eq. 8), in [0, 1]; 1 when `H(X,Y) = 0`.
pub fn normalized_mutual_information(joint: &[u64], bins_x: usize, bins_y: usize) -> f64 {
    let (mi, h_xy) = mutual_information(joint, bins_x, bins_y);
    if h_xy <= 0.0 {
        1.0
    } else {
        (mi / h_xy).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn entropy_of_uniform_is_log2_n() {
        for n in [1usize, 2, 3, 32, 1000] {
            assert!(close(entropy(vec![7u64; n]), (n as f64).log2()), "n = {n}");
        }
        assert_eq!(entropy(vec![0u64, 0]), 0.0);
        assert_eq!(entropy(vec![5u64, 0, 0]), 0.0);
        // p = (1/2, 1/4, 1/4): 1.5 bits.
        assert!(close(entropy([2u64, 1, 1]), 1.5));
    }

    #[test]
    fn js_is_zero_for_identical_and_one_bit_for_disjoint_halves() {
        assert!(close(jensen_shannon(&[3, 5, 0], &[6, 10, 0]), 0.0));
        assert!(close(jensen_shannon(&[4, 0], &[0, 4]), 1.0));
        // Disjoint but unequal weights: JS = H(π) = H(1/4, 3/4).
        let h = -(0.25f64 * 0.25f64.log2() + 0.75 * 0.75f64.log2());
        assert!(close(jensen_shannon(&[1, 0], &[0, 3]), h));
        assert_eq!(jensen_shannon(&[0, 0], &[1, 1]), 0.0);
    }

    #[test]
    fn mutual_information_of_identity_and_independence() {
        // X = Y uniform over 4 values: MI = H = 2 bits, NMI = 1.
        let mut joint = vec![0u64; 16];
        for i in 0..4 {
            joint[i * 4 + i] = 5;
        }
        let (mi, h) = mutual_information(&joint, 4, 4);
        assert!(close(mi, 2.0) && close(h, 2.0));
        assert!(close(normalized_mutual_information(&joint, 4, 4), 1.0));
        // Independent: a product table has MI = 0.
        let joint: Vec<u64> = (0..4)
            .flat_map(|x| (0..3).map(move |y| (x + 1) * (y + 1)))
            .collect();
        assert!(mutual_information(&joint, 4, 3).0.abs() < 1e-12);
        // A single cell: H(X,Y) = 0, NMI defined as 1.
        assert_eq!(normalized_mutual_information(&[0, 9, 0, 0], 2, 2), 1.0);
    }
}
