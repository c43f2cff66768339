//! Worked examples on tiny data, computed by the library's own measures before the tour shows
//! the volume's: the paper's ray of five samples with its three 3-blocks and four 2-blocks and
//! the entropy rate they give (§4), two 4-bin histograms and their Jensen-Shannon divergence
//! (eq. 5, 6), and a 2×2 joint histogram with its MI and NMI (eq. 7, 8).

use serde::Serialize;

use super::BlockCount;
use crate::measure::{
    BlockCounts, entropy, jensen_shannon, mutual_information, normalized_mutual_information,
};

/// The paper's example ray (§4): five samples `x0 … x4`, their blocks and `h`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RayExample {
    /// The samples' bins, `x0` first.
    pub samples: Vec<u8>,
    /// Block length L.
    pub block: usize,
    /// The L-blocks in ray order (`x0x1x2`, `x1x2x3`, `x2x3x4`).
    pub blocks: Vec<Vec<u8>>,
    /// The (L-1)-blocks in ray order (`x0x1` … `x3x4`).
    pub short_blocks: Vec<Vec<u8>>,
    /// The L-blocks counted, most frequent first.
    pub table: Vec<BlockCount>,
    /// The (L-1)-blocks counted, most frequent first.
    pub short_table: Vec<BlockCount>,
    /// `H(X^L)`, bits.
    pub h_long: f64,
    /// `H(X^(L-1))`, bits.
    pub h_short: f64,
    /// `h = H(X^L) - H(X^(L-1))`, bits per sample.
    pub entropy_rate: f64,
}

/// Two slabs' histograms and what a cut between them gains.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JsExample {
    /// The first part's voxels per bin.
    pub first: Vec<u64>,
    /// The second part's.
    pub second: Vec<u64>,
    /// `π1, π2`: each part's share of the voxels.
    pub weights: [f64; 2],
    /// `H(p1)`, `H(p2)` and `H(p1 + p2)`, bits.
    pub entropies: [f64; 3],
    /// `JS = H(p1 + p2) - π1 H(p1) - π2 H(p2)`, bits: with the two parts the whole volume, the
    /// cut's `ΔI` too.
    pub js: f64,
}

/// Two slices' joint histogram over corresponding pixels, and how alike it says they are.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NmiExample {
    /// Pixels by (bin in X, bin in Y), row-major, 2 × 2.
    pub joint: Vec<u64>,
    /// `H(X)`, `H(Y)` and `H(X,Y)`, bits.
    pub entropies: [f64; 3],
    /// `MI = H(X) + H(Y) - H(X,Y)`, bits.
    pub mi: f64,
    /// `NMI = MI / H(X,Y)`.
    pub nmi: f64,
}

/// The three worked examples.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Worked {
    /// The ray of five samples.
    pub ray: RayExample,
    /// The two histograms.
    pub js: JsExample,
    /// The joint table.
    pub nmi: NmiExample,
}

/// The worked examples, every number from the library's measures.
pub fn worked() -> Worked {
    Worked {
        ray: ray_example(&[0, 1, 0, 1, 1], 2, 3),
        js: js_example(&[4, 2, 1, 1], &[1, 1, 2, 4]),
        nmi: nmi_example(&[3, 1, 1, 3]),
    }
}

/// The blocks of `samples` (bins below `bins`) of length `block` and the entropy rate they give.
pub fn ray_example(samples: &[u8], bins: usize, block: usize) -> RayExample {
    let mut counts = BlockCounts::new(bins, block);
    for &s in samples {
        counts.push(s);
    }
    counts.end_sequence();
    let (_, h_short, h_long) = counts.entropies();
    let table = |k: usize| BlockCount::table_of(&counts, k);
    let windows = |k: usize| samples.windows(k).map(<[u8]>::to_vec).collect();
    RayExample {
        samples: samples.to_vec(),
        block,
        blocks: windows(block),
        short_blocks: windows(block - 1),
        table: table(block),
        short_table: table(block - 1),
        h_long,
        h_short,
        entropy_rate: h_long - h_short,
    }
}

/// The Jensen-Shannon divergence of `first` and `second`, weighted by their voxels.
pub fn js_example(first: &[u64], second: &[u64]) -> JsExample {
    let (n1, n2) = (
        first.iter().sum::<u64>() as f64,
        second.iter().sum::<u64>() as f64,
    );
    let mixed: Vec<u64> = first.iter().zip(second).map(|(a, b)| a + b).collect();
    JsExample {
        first: first.to_vec(),
        second: second.to_vec(),
        weights: [n1 / (n1 + n2), n2 / (n1 + n2)],
        entropies: [
            entropy(first.iter().copied()),
            entropy(second.iter().copied()),
            entropy(mixed),
        ],
        js: jensen_shannon(first, second),
    }
}

/// The MI and NMI of a 2 × 2 joint histogram, row-major.
pub fn nmi_example(joint: &[u64; 4]) -> NmiExample {
    let (mi, h_xy) = mutual_information(joint, 2, 2);
    NmiExample {
        joint: joint.to_vec(),
        entropies: [
            entropy([joint[0] + joint[1], joint[2] + joint[3]]),
            entropy([joint[0] + joint[2], joint[1] + joint[3]]),
            h_xy,
        ],
        mi,
        nmi: normalized_mutual_information(joint, 2, 2),
    }
}

/// `0 1 1` as the tour writes a block.
fn block_text(b: &[u8]) -> String {
    b.iter().map(u8::to_string).collect()
}

impl RayExample {
    /// The example in sentences.
    pub fn lines(&self) -> Vec<String> {
        let list = |blocks: &[Vec<u8>]| {
            blocks
                .iter()
                .map(|b| block_text(b))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let table = |t: &[BlockCount], n: usize| {
            t.iter()
                .map(|b| format!("{} {}/{n}", block_text(&b.symbols), b.count))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (l, s) = (self.block, self.block - 1);
        vec![
            format!(
                "Samples x0…x{} along one ray: {}",
                self.samples.len() - 1,
                list(&self.samples.iter().map(|&x| vec![x]).collect::<Vec<_>>()).replace(", ", " ")
            ),
            format!(
                "{} blocks of {l}: {}",
                self.blocks.len(),
                list(&self.blocks)
            ),
            format!(
                "{} blocks of {s}: {}",
                self.short_blocks.len(),
                list(&self.short_blocks)
            ),
            format!(
                "p(x^{l}): {}  H(X^{l}) = {:.4} bits",
                table(&self.table, self.blocks.len()),
                self.h_long
            ),
            format!(
                "p(x^{s}): {}  H(X^{s}) = {:.4} bits",
                table(&self.short_table, self.short_blocks.len()),
                self.h_short
            ),
            format!(
                "h = H(X^{l}) - H(X^{s}) = {:.4} - {:.4} = {:.4} bits per sample",
                self.h_long, self.h_short, self.entropy_rate
            ),
        ]
    }
}

impl JsExample {
    /// The example in sentences.
    pub fn lines(&self) -> Vec<String> {
        let counts = |c: &[u64]| c.iter().map(u64::to_string).collect::<Vec<_>>().join(" ");
        let [h1, h2, h] = self.entropies;
        let [p1, p2] = self.weights;
        vec![
            format!(
                "Slab 1's voxels per bin: {}   slab 2's: {}",
                counts(&self.first),
                counts(&self.second)
            ),
            format!("π1 = {p1:.4}, π2 = {p2:.4} (their shares of the voxels)"),
            format!("H(p1) = {h1:.4}, H(p2) = {h2:.4}, H(p1 + p2) = {h:.4} bits"),
            format!(
                "JS = {h:.4} - {p1:.4}·{h1:.4} - {p2:.4}·{h2:.4} = {:.4} bits",
                self.js
            ),
            format!(
                "With the two slabs the whole volume, (v1 + v2) / vT = 1: ΔI = {:.4} bits",
                self.js
            ),
        ]
    }
}

impl NmiExample {
    /// The example in sentences.
    pub fn lines(&self) -> Vec<String> {
        let [hx, hy, hxy] = self.entropies;
        let j = &self.joint;
        vec![
            "Two slices X and Y, pixels counted by their bins in both:".to_string(),
            format!("           Y bin 0  Y bin 1"),
            format!("  X bin 0  {:>7}  {:>7}", j[0], j[1]),
            format!("  X bin 1  {:>7}  {:>7}", j[2], j[3]),
            format!("H(X) = {hx:.4}, H(Y) = {hy:.4}, H(X,Y) = {hxy:.4} bits"),
            format!(
                "MI = {hx:.4} + {hy:.4} - {hxy:.4} = {:.4} bits   NMI = MI / H(X,Y) = {:.4}",
                self.mi, self.nmi
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) {
        assert!((a - b).abs() < 1e-12, "{a} against {b}");
    }

    #[test]
    fn the_papers_ray_has_three_3_blocks_and_four_2_blocks() {
        let r = worked().ray;
        assert_eq!(r.samples, [0, 1, 0, 1, 1]);
        assert_eq!(r.blocks, [vec![0, 1, 0], vec![1, 0, 1], vec![0, 1, 1]]);
        assert_eq!(r.short_blocks.len(), 4);
        // Three 3-blocks, each once: H = log2 3. Four 2-blocks: 01 twice, 10 and 11 once:
        // H = 1/2 + 2·(1/4 · 2) = 1.5.
        assert_eq!(
            r.table.iter().map(|b| b.count).collect::<Vec<_>>(),
            [1, 1, 1]
        );
        let short: Vec<_> = r
            .short_table
            .iter()
            .map(|b| (b.symbols.clone(), b.count))
            .collect();
        assert_eq!(short, [(vec![0, 1], 2), (vec![1, 0], 1), (vec![1, 1], 1)]);
        close(r.h_long, 3f64.log2());
        close(r.h_short, 1.5);
        close(r.entropy_rate, 3f64.log2() - 1.5);
        let lines = r.lines().join("\n");
        assert!(lines.contains("3 blocks of 3: 010, 101, 011"), "{lines}");
        assert!(lines.contains("4 blocks of 2: 01, 10, 01, 11"), "{lines}");
        assert!(
            lines.contains("= 1.5850 - 1.5000 = 0.0850 bits per sample"),
            "{lines}"
        );
    }

    #[test]
    fn two_histograms_js_by_hand() {
        let j = worked().js;
        // p1 = (1/2, 1/4, 1/8, 1/8), p2 its mirror: H = 1.75 each; the mixture (5, 3, 3, 5)/16.
        close(j.entropies[0], 1.75);
        close(j.entropies[1], 1.75);
        let m = -2.0 * (5.0 / 16.0 * (5.0f64 / 16.0).log2() + 3.0 / 16.0 * (3.0f64 / 16.0).log2());
        close(j.entropies[2], m);
        assert_eq!(j.weights, [0.5, 0.5]);
        close(j.js, m - 1.75);
        assert!(j.lines()[3].ends_with(&format!("= {:.4} bits", m - 1.75)));
    }

    #[test]
    fn a_2x2_table_mi_and_nmi_by_hand() {
        let n = worked().nmi;
        // p(x,y) = 3/8 on the diagonal, 1/8 off it; both marginals uniform.
        let hxy = -2.0 * (3.0 / 8.0 * (3.0f64 / 8.0).log2() + 1.0 / 8.0 * (1.0f64 / 8.0).log2());
        close(n.entropies[0], 1.0);
        close(n.entropies[1], 1.0);
        close(n.entropies[2], hxy);
        close(n.mi, 2.0 - hxy);
        close(n.nmi, (2.0 - hxy) / hxy);
        assert!(n.lines()[5].contains(&format!("NMI = MI / H(X,Y) = {:.4}", (2.0 - hxy) / hxy)));
    }
}
