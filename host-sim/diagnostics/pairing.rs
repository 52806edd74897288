//! The stereo pairing check's evidence on a recorded sequence: the image motion of each camera
//! (`MotionMeter`), and the correlation of the two series at offsets −3..=3 frames, with the
//! right images as recorded and moved SHIFT frames later (each left image paired with the right
//! one SHIFT frames before it). Prints the whole series' correlations, then for each window of
//! `out_of_step::WINDOW` frames (every `out_of_step::EVERY` frames) the offset of the best correlation.
//!
//! `cargo run --release -p evorec-sim --example pairing -- SEQ_DIR [SHIFT ...]`

use std::path::Path;

use anyhow::{Context, Result, ensure};
use evorec_sim::recording::sequence::Sequence;
use evorec_sim::rig::track::out_of_step::{EVERY, MotionMeter, WINDOW, correlation};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = args.first().context("usage: pairing SEQ_DIR [SHIFT ...]")?;
    let shifts: Vec<usize> = args.iter().skip(1).map(|s| s.parse()).collect::<Result<_, _>>()?;
    let seq = Sequence::load(Path::new(dir))?;
    let (mut ml, mut mr) = (MotionMeter::default(), MotionMeter::default());
    let (mut left, mut right) = (Vec::new(), Vec::new());
    for row in &seq.frames {
        let l = image::open(&row.left).with_context(|| row.left.display().to_string())?.to_rgb8();
        let r = image::open(&row.right).with_context(|| row.right.display().to_string())?.to_rgb8();
        left.push(ml.measure(&l));
        right.push(mr.measure(&r));
    }
    for shift in std::iter::once(0).chain(shifts) {
        ensure!(shift < left.len(), "SHIFT {shift}: the sequence has {} frames", left.len());
        let n = left.len() - shift;
        // Right late by `shift`: the pair i holds left i + shift and right i.
        let (l, r) = (&left[shift..shift + n], &right[..n]);
        let row: Vec<String> =
            (-3..=3).map(|k| correlation(l, r, k).map_or("-".into(), |c| format!("{c:.4}"))).collect();
        println!("shift {shift}: r(-3..=3) = {}", row.join(" "));
        let mut peaks = [0usize; 7];
        let mut start = 0;
        while start + WINDOW <= n {
            let (wl, wr) = (&l[start..start + WINDOW], &r[start..start + WINDOW]);
            let best =
                (-3..=3i32).filter_map(|k| correlation(wl, wr, k).map(|c| (k, c))).max_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((k, _)) = best {
                peaks[(k + 3) as usize] += 1;
            }
            start += EVERY;
        }
        println!("  windows peaking at offset -3..=3: {peaks:?}");
    }
    Ok(())
}
