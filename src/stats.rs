//! Order statistics shared by the reports (the paper's metrics, ensembles).

/// The `q` quantile of sorted values (linear interpolation); NaN when there are none.
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        1 => sorted[0],
        n => {
            let pos = q.clamp(0.0, 1.0) * (n - 1) as f64;
            let i = pos.floor() as usize;
            let j = (i + 1).min(n - 1);
            sorted[i] + (sorted[j] - sorted[i]) * (pos - i as f64)
        }
    }
}
