//! Where a chart's ticks stand and how their numbers read.

/// At most about `most` ticks over `lo..=hi` at a round step (1, 2 or 5 times a power of ten;
/// whole numbers only when `whole`), every one within the range.
pub fn ticks(lo: f64, hi: f64, most: usize, whole: bool) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi < lo {
        return Vec::new();
    }
    if hi == lo {
        return vec![lo];
    }
    let step = step(hi - lo, most.max(2), whole);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last).map(|k| clean(k as f64 * step)).collect()
}

/// The round step that cuts `range` into at most about `most` parts.
pub fn step(range: f64, most: usize, whole: bool) -> f64 {
    let raw = range / most as f64;
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|&s| s >= raw * (1.0 - 1e-12))
        .unwrap_or(10.0 * power);
    if whole { step.max(1.0).round() } else { step }
}

/// `v` without the binary noise of `k · step` (`0.30000000000000004` → `0.3`).
fn clean(v: f64) -> f64 {
    format!("{v:.12e}").parse().unwrap_or(v)
}

/// `v` as a tick reads at ticks `step` apart: as many decimals as the step needs, thousands as
/// `K` and millions as `M` (`120K`, `3.4M`).
pub fn label(v: f64, step: f64) -> String {
    let (scaled, suffix, step) = if v.abs() >= 1e6 && step >= 1e5 {
        (v / 1e6, "M", step / 1e6)
    } else if v.abs() >= 1e4 && step >= 1e3 {
        (v / 1e3, "K", step / 1e3)
    } else {
        (v, "", step)
    };
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10() - 1e-9).ceil() as usize
    };
    let text = format!("{scaled:.decimals$}");
    // "-0" reads as 0.
    let text = if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        text.trim_start_matches('-').to_string()
    } else {
        text
    };
    format!("{text}{suffix}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_fall_on_round_steps_within_the_range() {
        assert_eq!(ticks(0.0, 1.0, 5, false), [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]);
        assert_eq!(ticks(0.0, 0.37, 5, false), [0.0, 0.1, 0.2, 0.3]);
        assert_eq!(ticks(0.0, 207.0, 6, true), [0.0, 50.0, 100.0, 150.0, 200.0]);
        assert_eq!(ticks(0.0, 3.0, 8, true), [0.0, 1.0, 2.0, 3.0]);
        assert_eq!(ticks(-1.0, 1.0, 4, false), [-1.0, -0.5, 0.0, 0.5, 1.0]);
        assert_eq!(ticks(2.0, 2.0, 5, false), [2.0]);
        assert!(ticks(1.0, 0.0, 5, false).is_empty());
        assert!(ticks(0.0, f64::NAN, 5, false).is_empty());
    }

    #[test]
    fn labels_have_the_decimals_their_step_needs() {
        assert_eq!(label(0.2, 0.2), "0.2");
        assert_eq!(label(0.05, 0.05), "0.05");
        assert_eq!(label(150.0, 50.0), "150");
        assert_eq!(label(120_000.0, 20_000.0), "120K");
        assert_eq!(label(3_400_000.0, 200_000.0), "3.4M");
        assert_eq!(label(-0.0, 0.1), "0.0");
    }
}
