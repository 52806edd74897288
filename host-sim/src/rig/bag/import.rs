//! `evorec import`: a bag written as an `evorec-seq/1` directory. The directory is written
//! into `OUT.partial` and renamed when complete ([`crate::output::io::write_dir`]), so a bad image
//! found late leaves nothing at `OUT`. Files go through [`crate::output::io`]; PNGs are written with
//! fast compression, the two of a pair in parallel, while a reader thread decodes the next.

use std::path::Path;
use std::sync::mpsc::sync_channel;

use anyhow::{Result, anyhow};
use image::RgbImage;
use indicatif::ProgressBar;

use super::BagSequence;
use super::source::BagFrames;
use crate::output::io;
use crate::recording::sequence::write::{frames_csv, image_path, joints_csv};
use crate::rig::track::FrameSource;

/// Writes `bag` as the sequence directory `out` (which must not exist or be empty).
///
/// # Errors
/// A non-empty `out`, an undecodable image (naming topic and message), I/O errors.
pub fn import(bag: &BagSequence, out: &Path, progress: Option<&ProgressBar>) -> Result<()> {
    io::write_dir(out, |dir| {
        let seq = &bag.seq;
        io::write_file_in(dir, "sequence.toml", bag.manifest.as_bytes())?;
        io::write_file_in(dir, "robot.urdf", bag.urdf.as_bytes())?;
        io::write_file_in(dir, "calib/left.yaml", bag.left_yaml.as_bytes())?;
        io::write_file_in(dir, "calib/right.yaml", bag.right_yaml.as_bytes())?;
        io::write_file_in(dir, "joints.csv", joints_csv(&seq.joints).as_bytes())?;
        let rows: Vec<(u64, f64)> = seq.frames.iter().map(|f| (f.index, f.t_s)).collect();
        io::write_file_in(dir, "frames.csv", frames_csv(&rows).as_bytes())?;
        std::fs::create_dir_all(dir.join("left"))?;
        std::fs::create_dir_all(dir.join("right"))?;
        write_images(bag, dir, progress)
    })
}

fn write_images(bag: &BagSequence, dir: &Path, progress: Option<&ProgressBar>) -> Result<()> {
    let (tx, rx) = sync_channel::<(usize, RgbImage, RgbImage)>(4);
    let source = Box::new(BagFrames::new(bag));
    let end = bag.pairs.len();
    let reader = std::thread::spawn(move || source.stream(end, &mut |i, l, r| tx.send((i, l, r)).is_ok()));
    let mut written = Ok(());
    for (i, l, r) in rx.iter() {
        let index = bag.seq.frames[i].index;
        let (a, b) = rayon::join(
            || io::write_png_fast(&dir.join(image_path("left", index)), &l),
            || io::write_png_fast(&dir.join(image_path("right", index)), &r),
        );
        if let Err(e) = a.and(b) {
            written = Err(e);
            break;
        }
        if let Some(p) = progress {
            p.inc(1);
        }
    }
    drop(rx);
    let read = reader.join().map_err(|_| anyhow!("the bag reader thread panicked"))?;
    written?;
    read?;
    Ok(())
}
