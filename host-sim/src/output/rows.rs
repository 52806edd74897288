//! Row sizes of the surface-strips sampling that the host can run.
//!
//! The number of sample points per row is a const generic of the core's tracker (`G`), so a
//! size chosen at run time is dispatched onto one of a few compiled sizes. [`with_rows!`](crate::with_rows)
//! does the dispatch; [`check`] names the accepted sizes in its error.

use anyhow::{Error, Result, anyhow};

/// The points per sample row that the host binary is compiled for.
pub const SUPPORTED: [usize; 4] = [5, 6, 7, 8];

/// Checks a run-time row size; `what` names the option in the error (e.g. `--points-per-row`).
///
/// # Errors
/// A size that is not in [`SUPPORTED`].
pub fn check(what: &str, g: usize) -> Result<()> {
    if SUPPORTED.contains(&g) { Ok(()) } else { Err(refused(what, g)) }
}

/// The error for a row size `g` outside [`SUPPORTED`], naming the option `what`.
pub fn refused(what: &str, g: usize) -> Error {
    anyhow!("{what} {g}: the host is compiled for {SUPPORTED:?} points per row")
}

/// Evaluates `$body` with the const `$G` bound to the run-time row size `$g`, or evaluates to
/// an `Err` naming `$what` when `$g` is not one of [`SUPPORTED`].
///
/// ```
/// use evorec_sim::with_rows;
/// fn points<const G: usize>() -> usize { G * G }
/// let n: anyhow::Result<usize> = with_rows!("--points", 7, G => Ok(points::<G>()));
/// assert_eq!(n.unwrap(), 49);
/// assert!(with_rows!("--points", 9, G => Ok(points::<G>())).is_err());
/// ```
#[macro_export]
macro_rules! with_rows {
    ($what:expr, $g:expr, $G:ident => $body:expr) => {
        match $g {
            5 => {
                const $G: usize = 5;
                $body
            }
            6 => {
                const $G: usize = 6;
                $body
            }
            7 => {
                const $G: usize = 7;
                $body
            }
            8 => {
                const $G: usize = 8;
                $body
            }
            g => Err($crate::output::rows::refused($what, g)),
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    fn size<const G: usize>() -> Result<usize> {
        Ok(G)
    }

    #[test]
    fn every_supported_size_reaches_its_own_instance() {
        for g in SUPPORTED {
            assert_eq!(with_rows!("--points", g, G => size::<G>()).unwrap(), g);
        }
    }

    #[test]
    fn other_sizes_are_refused_with_the_option_named() {
        for g in [0, 4, 9, 64] {
            let e = with_rows!("--points-per-row", g, G => size::<G>()).unwrap_err().to_string();
            assert!(e.starts_with(&format!("--points-per-row {g}:")), "{e}");
            assert!(e.contains("[5, 6, 7, 8]"), "{e}");
        }
    }
}
