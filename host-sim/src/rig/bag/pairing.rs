//! Stereo pairs by nearest `header.stamp` (the capture time; a bag's receive time is later and
//! jittery). The frame period is the median spacing of the left stamps; a right image pairs
//! with the left image nearest to it when they are at most the tolerance apart (default a
//! quarter of the frame period). Images that find no partner are counted, never dropped
//! silently.

/// The pairs of a bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pairing {
    /// (position in the left list, position in the right list), in stamp order.
    pub pairs: Vec<(usize, usize)>,
    /// Left images without a partner (positions in the left list).
    pub unpaired_left: Vec<usize>,
    /// Right images without a partner.
    pub unpaired_right: Vec<usize>,
    /// The estimated frame period (ns).
    pub period_ns: i64,
    /// The tolerance used (ns).
    pub tolerance_ns: i64,
}

/// The median spacing of the distinct sorted stamps (`None` with fewer than two).
pub fn frame_period_ns(stamps: &[i64]) -> Option<i64> {
    let mut s = stamps.to_vec();
    s.sort_unstable();
    s.dedup();
    let mut d: Vec<i64> = s.windows(2).map(|w| w[1] - w[0]).collect();
    if d.is_empty() {
        return None;
    }
    d.sort_unstable();
    Some(d[d.len() / 2])
}

/// Pairs `left` and `right` stamps (ns, in message order).
///
/// # Errors
/// No tolerance given and fewer than two distinct left stamps to estimate the period from.
pub fn pair(left: &[i64], right: &[i64], tolerance_ns: Option<i64>) -> Result<Pairing, String> {
    let period_ns = frame_period_ns(left).unwrap_or(0);
    let tolerance_ns = match tolerance_ns {
        Some(t) => t,
        None if period_ns > 0 => period_ns / 4,
        None => {
            return Err(
                "fewer than two left images: cannot estimate the frame period; give --pair-tolerance-ms".to_owned()
            );
        }
    };
    let order = |s: &[i64]| {
        let mut o: Vec<usize> = (0..s.len()).collect();
        o.sort_by_key(|&i| (s[i], i));
        o
    };
    let (lo, ro) = (order(left), order(right));
    let mut used = vec![false; right.len()];
    let mut pairs = Vec::new();
    let mut unpaired_left = Vec::new();
    let mut last_left: Option<i64> = None;
    for &l in &lo {
        let t = left[l];
        // The right images nearest to t: just before and just after it.
        let k = ro.partition_point(|&r| right[r] < t);
        let best = [k.checked_sub(1), Some(k)]
            .into_iter()
            .flatten()
            .filter_map(|k| ro.get(k).copied())
            .filter(|&r| !used[r])
            .min_by_key(|&r| (right[r] - t).abs());
        match best {
            Some(r) if (right[r] - t).abs() <= tolerance_ns && last_left != Some(t) => {
                used[r] = true;
                last_left = Some(t);
                pairs.push((l, r));
            }
            _ => unpaired_left.push(l),
        }
    }
    let unpaired_right = ro.into_iter().filter(|r| !used[*r]).collect();
    Ok(Pairing { pairs, unpaired_left, unpaired_right, period_ns, tolerance_ns })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn nearest_stamps_pair_and_strays_are_counted() {
        let left = [0, 33_000_000, 66_000_000, 100_000_000];
        // Right 1 ms late, one missing, one stray far from any left.
        let right = [1_000_000, 67_500_000, 34_000_000, 150_000_000];
        let p = pair(&left, &right, None).unwrap();
        assert_eq!(p.period_ns, 33_000_000);
        assert_eq!(p.tolerance_ns, 8_250_000);
        assert_eq!(p.pairs, vec![(0, 0), (1, 2), (2, 1)]);
        assert_eq!((p.unpaired_left, p.unpaired_right), (vec![3], vec![3]));
        // A tighter tolerance leaves the 1.5 ms pair unpaired.
        let p = pair(&left, &right, Some(1_200_000)).unwrap();
        assert_eq!(p.pairs, vec![(0, 0), (1, 2)]);
        assert!(pair(&[5], &[5], None).is_err());
        assert_eq!(pair(&[5], &[5], Some(0)).unwrap().pairs, vec![(0, 0)]);
    }
}
