//! The second pass over a bag: the paired images, decoded and handed over in frame order
//! while the messages stream by (nothing but the frames not yet complete is held).

use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;

use image::RgbImage;

use super::scan::{COMPRESSED_IMAGE, Msg, for_each_message};
use super::{BagFiles, BagSequence, images, msgs};
use crate::recording::sequence::SequenceError;
use crate::rig::track::FrameSource;

/// The image pairs of a bag, as a [`FrameSource`].
#[derive(Debug, Clone)]
pub struct BagFrames {
    files: BagFiles,
    topics: [String; 2],
    /// Per side: message index → frame.
    wanted: [HashMap<usize, usize>; 2],
    /// Per side: the camera_info's size.
    sizes: [(u32, u32); 2],
}

impl BagFrames {
    /// The frames of `bag`.
    pub fn new(bag: &BagSequence) -> Self {
        let side = |k: usize| -> HashMap<usize, usize> {
            bag.pairs.iter().enumerate().map(|(f, p)| (if k == 0 { p.0.index } else { p.1.index }, f)).collect()
        };
        let size = |c: &evorec_core::camera::Pinhole| (u32::from(c.width()), u32::from(c.height()));
        Self {
            files: bag.files.clone(),
            topics: [bag.rig.topics.left_image.clone(), bag.rig.topics.right_image.clone()],
            wanted: [side(0), side(1)],
            sizes: [size(&bag.seq.rig.left), size(&bag.seq.rig.right)],
        }
    }

    fn error(&self, m: &Msg<'_>, e: &str) -> SequenceError {
        SequenceError::file(PathBuf::from(self.files.display()), format!("{} message {}: {e}", m.topic, m.index))
    }

    /// Decodes one image message of side `k` to RGB of its camera's size.
    fn decode(&self, m: &Msg<'_>, k: usize) -> Result<RgbImage, SequenceError> {
        let rgb = if m.schema == COMPRESSED_IMAGE {
            let img = msgs::compressed_image(m.data).map_err(|e| self.error(m, &e.to_string()))?;
            images::compressed_to_rgb(&img)
        } else {
            let img = msgs::image(m.data).map_err(|e| self.error(m, &e.to_string()))?;
            images::to_rgb(&img)
        }
        .map_err(|e| self.error(m, &e))?;
        let (w, h) = self.sizes[k];
        if rgb.dimensions() != (w, h) {
            let msg = format!("image is {}x{}, its camera_info says {w}x{h}", rgb.width(), rgb.height());
            return Err(self.error(m, &msg));
        }
        Ok(rgb)
    }
}

impl FrameSource for BagFrames {
    fn stream(
        self: Box<Self>,
        end: usize,
        emit: &mut dyn FnMut(usize, RgbImage, RgbImage) -> bool,
    ) -> Result<(), SequenceError> {
        let mut pending: BTreeMap<usize, [Option<RgbImage>; 2]> = BTreeMap::new();
        let mut next = 0;
        let mut failure = None;
        let result = for_each_message(&self.files, |m| {
            if next >= end {
                return Ok(false);
            }
            let Some(k) = self.topics.iter().position(|t| t == m.topic) else { return Ok(true) };
            let Some(&frame) = self.wanted[k].get(&m.index) else { return Ok(true) };
            if frame >= end {
                return Ok(true);
            }
            match self.decode(m, k) {
                Ok(img) => pending.entry(frame).or_default()[k] = Some(img),
                Err(e) => {
                    failure = Some(e);
                    return Ok(false);
                }
            }
            while let Some(entry) = pending.first_entry() {
                if *entry.key() != next || entry.get().iter().any(Option::is_none) {
                    break;
                }
                let [l, r] = entry.remove();
                let (Some(l), Some(r)) = (l, r) else { break };
                if !emit(next, l, r) {
                    next = end;
                    return Ok(false);
                }
                next += 1;
            }
            Ok(true)
        });
        if let Some(e) = failure {
            return Err(e);
        }
        let file = || PathBuf::from(self.files.display());
        let pass = result.map_err(|e| {
            let text = format!("{e:#}");
            let text = text.strip_prefix(&format!("{}: ", self.files.display())).map_or(text.clone(), str::to_owned);
            SequenceError::file(file(), text)
        })?;
        if next < end {
            return Err(match pass.cut {
                // The first pass read up to the same place: it is where the bag ends.
                Some(cut) => SequenceError::file(&cut.file, cut.what()),
                None => SequenceError::file(
                    file(),
                    format!("frame {next}'s images were not found on the second pass (the bag changed while read?)"),
                ),
            });
        }
        Ok(())
    }
}
