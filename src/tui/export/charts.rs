//! The export's charts, drawn by the library's chart renderer from the numbers the lessons show:
//! the curves along the axis with the slab boundaries, the first split's two histograms and the
//! ΔI of every cut it weighed, a merge's joint histogram as a heat map with its colour scale, and
//! the worked examples' histograms and 2×2 table. Every chart has its axes, ticks and labels.

use anyhow::Result;
use slabscope::Partition;
use slabscope::explain::{JsExample, MergeLesson, NmiExample, SplitLesson};
use slabscope::render::chart::{
    Chart, HeatMap, Mark, Scale, Series, Style, draw_charts, draw_heat_map,
};
use tiny_skia::Pixmap;

/// The pictures' files.
pub const CURVES: &str = "curves.png";
pub const SPLIT: &str = "first-split.png";
pub const MERGE: &str = "merge-joint-histogram.png";
pub const MERGE_BEST: &str = "merge-highest-nmi.png";
pub const WORKED_JS: &str = "worked-js-histograms.png";
pub const WORKED_NMI: &str = "worked-nmi-joint-table.png";

const FIRST: [u8; 3] = [40, 100, 190];
const SECOND: [u8; 3] = [230, 120, 30];
const GAIN: [u8; 3] = [30, 130, 70];
const NMI: [u8; 3] = [120, 60, 160];
const MARK: [u8; 3] = [200, 40, 40];

/// Slices `[a, b)` as read: `slices a–(b-1)`, or `slice a` alone.
pub fn slices((a, b): (usize, usize)) -> String {
    if b <= a + 1 {
        format!("slice {a}")
    } else {
        format!("slices {a}–{}", b - 1)
    }
}

fn scale(label: &str, lo: f64, hi: f64, whole: bool) -> Scale {
    Scale {
        label: label.into(),
        lo,
        hi,
        whole,
    }
}

/// `0 .. most` with room above the highest value (1 when all are 0).
fn headroom(values: impl Iterator<Item = f64>) -> f64 {
    let most = values.fold(0.0f64, f64::max);
    if most > 0.0 { most * 1.1 } else { 1.0 }
}

fn series(name: &str, style: Style, colour: [u8; 3], points: Vec<[f64; 2]>) -> Series {
    Series {
        name: name.into(),
        style,
        colour,
        points,
    }
}

/// The NMI of neighbouring slices and the ΔI of one cut of the whole stack at each slice, the
/// boundaries of `p`'s slabs marked.
pub fn curves(p: &Partition, width: u32, height: u32) -> Result<Pixmap> {
    let cut = |values: &[f64]| -> Vec<[f64; 2]> {
        values
            .iter()
            .enumerate()
            .map(|(i, &v)| [(i + 1) as f64, v])
            .collect()
    };
    let marks: Vec<Mark> = p
        .slabs
        .iter()
        .skip(1)
        .map(|&(a, _)| Mark {
            x: a as f64,
            colour: MARK,
            name: format!("{} boundary", p.method.name()),
        })
        .collect();
    let x = || scale("cut before slice c", 0.0, p.slices as f64, true);
    let nmi = Chart {
        title: "NMI of slices c-1 and c".into(),
        x: x(),
        y: scale("NMI", 0.0, 1.0, false),
        series: vec![series("NMI", Style::Line, NMI, cut(&p.nmi_curve))],
        marks: marks.clone(),
    };
    let gain = Chart {
        title: "ΔI of one cut of the whole stack at c".into(),
        x: x(),
        y: scale(
            "ΔI (bits)",
            0.0,
            headroom(p.gain_curve.iter().copied()),
            false,
        ),
        series: vec![series("ΔI", Style::Line, GAIN, cut(&p.gain_curve))],
        marks,
    };
    Ok(draw_charts(&[nmi, gain], width, height)?)
}

/// Each bin's share of `counts`.
fn shares(counts: &[u64]) -> Vec<[f64; 2]> {
    let total = counts.iter().sum::<u64>().max(1) as f64;
    counts
        .iter()
        .enumerate()
        .map(|(b, &c)| [b as f64, c as f64 / total])
        .collect()
}

/// Two histograms side by side over their bins, each as shares of its own samples.
fn histograms(title: String, names: [String; 2], counts: [&[u64]; 2]) -> Chart {
    let bins = counts[0].len().max(counts[1].len()).max(1);
    let first = shares(counts[0]);
    let second = shares(counts[1]);
    // Room above the bars for the legend.
    let hi = 1.25 * headroom(first.iter().chain(&second).map(|p| p[1]));
    let [a, b] = names;
    Chart {
        title,
        x: scale("bin", -0.5, bins as f64 - 0.5, true),
        y: scale("share of the part's samples", 0.0, hi, false),
        series: vec![
            series(&a, Style::Bars, FIRST, first),
            series(&b, Style::Bars, SECOND, second),
        ],
        marks: Vec::new(),
    }
}

/// The first split: its parts' histograms, and ΔI of every cut inside the slab, the one taken
/// marked.
pub fn split(s: &SplitLesson, width: u32, height: u32) -> Result<Pixmap> {
    let (a, b) = ((s.split.0, s.at), (s.at, s.split.1));
    let parts = histograms(
        format!(
            "Split {}: the two parts' histograms, JS = {:.4} bits",
            s.step, s.js
        ),
        [slices(a), slices(b)],
        [&s.first, &s.second],
    );
    let points: Vec<[f64; 2]> = s
        .gains
        .iter()
        .enumerate()
        .map(|(i, &g)| [(s.split.0 + 1 + i) as f64, g])
        .collect();
    let gains = Chart {
        title: format!(
            "ΔI of each cut of {}, the best {:.4} bits",
            slices(s.split),
            s.gain
        ),
        x: scale(
            "cut before slice c",
            s.split.0 as f64,
            s.split.1 as f64,
            true,
        ),
        y: scale("ΔI (bits)", 0.0, headroom(s.gains.iter().copied()), false),
        series: vec![series("ΔI", Style::Line, GAIN, points)],
        marks: vec![Mark {
            x: s.at as f64,
            colour: MARK,
            name: format!("cut taken at {}", s.at),
        }],
    };
    Ok(draw_charts(&[parts, gains], width, height)?)
}

/// A merge's joint histogram.
pub fn merge(m: &MergeLesson, width: u32, height: u32) -> Result<Pixmap> {
    let map = HeatMap {
        title: format!(
            "Merge {}: {} and {}, NMI = {:.4}",
            m.step,
            slices(m.merge.0),
            slices(m.merge.1),
            m.nmi
        ),
        x_label: format!("bin in {}", slices(m.merge.0)),
        y_label: format!("bin in {}", slices(m.merge.1)),
        bins: m.bins,
        cells: m.joint.clone(),
    };
    Ok(draw_heat_map(&map, width, height)?)
}

/// The worked example's two 4-bin histograms.
pub fn worked_js(js: &JsExample, width: u32, height: u32) -> Result<Pixmap> {
    let chart = histograms(
        format!("Two histograms of 8 voxels, JS = {:.4} bits", js.js),
        ["p1".into(), "p2".into()],
        [&js.first, &js.second],
    );
    Ok(draw_charts(&[chart], width, height)?)
}

/// The worked example's 2×2 joint table.
pub fn worked_nmi(nmi: &NmiExample, width: u32, height: u32) -> Result<Pixmap> {
    let cells = nmi
        .joint
        .iter()
        .enumerate()
        .map(|(i, &c)| [(i / 2) as u64, (i % 2) as u64, c])
        .collect();
    let map = HeatMap {
        title: format!(
            "A 2×2 joint table, MI = {:.4}, NMI = {:.4}",
            nmi.mi, nmi.nmi
        ),
        x_label: "bin in slice X".into(),
        y_label: "bin in slice Y".into(),
        bins: 2,
        cells,
    };
    Ok(draw_heat_map(&map, width, height)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_slice_reads_as_one_and_shares_sum_to_one() {
        assert_eq!(slices((7, 8)), "slice 7");
        assert_eq!(slices((0, 94)), "slices 0–93");
        let s = shares(&[1, 3, 0, 4]);
        assert_eq!(s, [[0.0, 0.125], [1.0, 0.375], [2.0, 0.0], [3.0, 0.5]]);
        assert_eq!(shares(&[0, 0]), [[0.0, 0.0], [1.0, 0.0]]);
        assert!((headroom([0.5, 0.2].into_iter()) - 0.55).abs() < 1e-12);
        assert!((headroom(std::iter::empty()) - 1.0).abs() < 1e-12);
    }
}
