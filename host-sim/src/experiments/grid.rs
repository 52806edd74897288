//! The parallel runner of the experiment grids (`evorec paper`, `evorec servo`): every cell
//! runs on rayon's pool, one progress bar counts the frames of all cells, and the results come
//! back in the cells' order.

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

/// Runs `run` on every cell in parallel and returns the results in the order of `cells`.
///
/// `frames` gives the number of frames of a cell (the progress bar's total, shown unless
/// `show_progress` is false); `run` receives a callback to call once per frame.
///
/// # Errors
/// The first error of a cell (the other cells may have run).
pub fn run_cells<C, R>(
    cells: &[C],
    frames: impl Fn(&C) -> u64,
    show_progress: bool,
    run: impl Fn(&C, &(dyn Fn() + Sync)) -> Result<R> + Sync,
) -> Result<Vec<R>>
where
    C: Sync,
    R: Send,
{
    let bar = if show_progress {
        crate::output::logging::progress_bar(cells.iter().map(frames).sum())
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {percent:>3}% {pos}/{len} frames, eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let tick = || bar.inc(1);
    // An indexed parallel iterator collects in input order: no re-sorting needed.
    let results = cells.par_iter().map(|cell| run(cell, &tick)).collect::<Result<Vec<R>>>();
    bar.finish();
    results
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_come_back_in_cell_order_and_every_frame_ticks() {
        let cells: Vec<u64> = (0..37).collect();
        let ticks = std::sync::atomic::AtomicU64::new(0);
        let out = run_cells(
            &cells,
            |c| *c,
            false,
            |c, tick| {
                for _ in 0..*c {
                    tick();
                    ticks.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                }
                Ok(c * 10)
            },
        )
        .unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(out, cells.iter().map(|c| c * 10).collect::<Vec<_>>());
        assert_eq!(ticks.into_inner(), cells.iter().sum::<u64>());
    }

    #[test]
    fn an_error_of_one_cell_is_returned() {
        let cells = [1, 2, 3];
        let err =
            run_cells(&cells, |_| 1, false, |c, _| if *c == 2 { anyhow::bail!("cell {c} failed") } else { Ok(*c) });
        assert_eq!(err.map_err(|e| e.to_string()), Err("cell 2 failed".to_owned()));
    }
}
