//! Order statistics of the benchmark figures.

/// Value at quantile `p` (0..=1) of `v` (sorted in place), interpolated linearly
/// between the two nearest ranks (the usual definition: the median of an even
/// count is the mean of the middle two); NaN if `v` is empty. Units are `v`'s.
pub fn quantile(v: &mut [f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let rank = (v.len() as f64 - 1.0) * p.clamp(0.0, 1.0);
    let (lo, hi) = (rank.floor() as usize, rank.ceil() as usize);
    v[lo] + (rank - lo as f64) * (v[hi] - v[lo])
}

#[cfg(test)]
mod tests {
    use super::quantile;

    #[test]
    fn median_and_p95_interpolate_between_ranks() {
        assert_eq!(quantile(&mut [4.0, 1.0, 3.0, 2.0], 0.5), 2.5);
        assert_eq!(quantile(&mut [3.0, 1.0, 2.0], 0.5), 2.0);
        // 1..=21: rank 19 is the 20th value
        let mut v: Vec<f64> = (1..=21).rev().map(f64::from).collect();
        assert_eq!(quantile(&mut v, 0.95), 20.0);
        assert!((quantile(&mut [0.0, 10.0], 0.95) - 9.5).abs() < 1e-12);
        assert_eq!(quantile(&mut [7.0], 0.5), 7.0);
        assert!(quantile(&mut [], 0.5).is_nan());
    }
}
