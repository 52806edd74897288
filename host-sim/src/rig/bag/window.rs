//! `--start` / `--end`: the part of a bag to use, as seconds from the bag's first stereo frame
//! (`12.5`) or as a `header.stamp` in nanoseconds (`1700000012500000000ns`).

use std::str::FromStr;

/// One end of the time window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeArg {
    /// Seconds from the first stereo frame's stamp.
    FromStart(f64),
    /// A `header.stamp` (ns since the epoch).
    Stamp(i64),
}

impl FromStr for TimeArg {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || {
            format!(
                "'{s}': expected seconds from the first frame (e.g. 12.5) or a stamp in ns (e.g. 1700000012500000000ns)"
            )
        };
        match s.strip_suffix("ns") {
            Some(ns) => ns.trim().parse::<i64>().map(Self::Stamp).map_err(|_| bad()),
            None => match s.trim().parse::<f64>() {
                Ok(v) if v.is_finite() && v >= 0.0 => Ok(Self::FromStart(v)),
                _ => Err(bad()),
            },
        }
    }
}

impl TimeArg {
    /// The stamp (ns) this stands for, the first frame being at `first_ns`.
    pub fn stamp_ns(self, first_ns: i64) -> i64 {
        match self {
            Self::FromStart(s) => first_ns.saturating_add((s * 1e9).round() as i64),
            Self::Stamp(ns) => ns,
        }
    }
}

/// The range of `stamps` (sorted, ns) within `[start, end]` (either open), as positions.
///
/// # Errors
/// No stamp in the window, naming it and the stamps' span.
pub fn select(stamps: &[i64], start: Option<TimeArg>, end: Option<TimeArg>) -> Result<std::ops::Range<usize>, String> {
    let (Some(&first), Some(&last)) = (stamps.first(), stamps.last()) else { return Ok(0..0) };
    let lo = start.map_or(i64::MIN, |t| t.stamp_ns(first));
    let hi = end.map_or(i64::MAX, |t| t.stamp_ns(first));
    let range = stamps.partition_point(|&s| s < lo)..stamps.partition_point(|&s| s <= hi);
    if range.is_empty() {
        let s = |ns: i64| format!("{:.3} s", (ns - first) as f64 / 1e9);
        let bound = |t: Option<TimeArg>, ns: i64| t.map_or_else(|| "-".to_owned(), |_| s(ns));
        return Err(format!(
            "--start/--end: no stereo frame between {} and {} (the frames span 0 to {} from the first one, stamp {first} ns)",
            bound(start, lo),
            bound(end, hi),
            s(last)
        ));
    }
    Ok(range)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn seconds_from_the_start_and_stamps_select_frames() {
        let stamps: Vec<i64> = (0..10).map(|k| 1_000_000_000 + k * 100_000_000).collect();
        let t = |s: &str| Some(s.parse::<TimeArg>().unwrap());
        assert_eq!(select(&stamps, t("0.25"), t("0.5")).unwrap(), 3..6);
        assert_eq!(select(&stamps, t("1200000000ns"), None).unwrap(), 2..10);
        assert_eq!(select(&stamps, None, None).unwrap(), 0..10);
        assert!(select(&stamps, t("5"), None).unwrap_err().contains("no stereo frame between 5.000 s and -"));
        assert!("-1".parse::<TimeArg>().is_err() && "12xns".parse::<TimeArg>().is_err());
    }
}
