//! Tick positions and labels.

/// Ticks at multiples of a "nice" step (1, 2 or 5 times a power of ten) inside `[lo, hi]`,
/// aiming at about `target` ticks, with their labels (as many decimals as the step needs).
pub fn nice_ticks(lo: f64, hi: f64, target: usize) -> Vec<(f64, String)> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Vec::new();
    }
    let target = target.max(2) as f64;
    let magnitude = 10f64.powf(((hi - lo) / target).log10().floor());
    // The step of 1, 2 or 5 times a power of ten giving the tick count closest to `target`
    // without exceeding it by more than one (ties: the larger step).
    let count = |step: f64| ((hi / step + 1e-9).floor() - (lo / step - 1e-9).ceil() + 1.0).max(0.0);
    let step = [0.5, 1.0, 2.0, 5.0, 10.0, 20.0]
        .iter()
        .map(|m| m * magnitude)
        .filter(|&s| count(s) <= target + 1.0)
        .min_by(|a, b| {
            (count(*a) - target)
                .abs()
                .total_cmp(&(count(*b) - target).abs())
                .then(b.total_cmp(a))
        })
        .unwrap_or(20.0 * magnitude);
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            let label = format!("{v:.decimals$}");
            let label = if label
                .trim_start_matches('-')
                .chars()
                .all(|c| c == '0' || c == '.')
            {
                label.trim_start_matches('-').to_string()
            } else {
                label
            };
            (v, label)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_nice() {
        let t = nice_ticks(-50.0, 50.0, 5);
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["-40", "-20", "0", "20", "40"]);
        let t = nice_ticks(-1.3, 0.2, 5);
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["-1.0", "-0.5", "0.0"]);
        let t = nice_ticks(0.13, 1.2, 5);
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0.2", "0.4", "0.6", "0.8", "1.0", "1.2"]);
        assert!(nice_ticks(1.0, 1.0, 5).is_empty());
    }
}
