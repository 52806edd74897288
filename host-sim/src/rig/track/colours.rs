//! `evorec colours`: the block's face colours as a rig's cameras see them, measured by tracking
//! a stretch of a recording in which the block is shown, and written as the `[target]` table
//! that a sequence or a rig file takes (`face_hues_deg`).
//!
//! Tracking does not need it: the tracker learns the colours itself from the configured ones
//! (`evorec_core::colour`). Measured colours as the configured ones make the search band start
//! where the faces are, which helps a camera whose colours are far off, and they document the
//! rig.

use std::fmt::Write as _;

use anyhow::{Result, bail};
use evorec_core::colour::ColourModel;
use evorec_core::model::{Block, FACES};
use evorec_core::status::Status;

use super::TrackOutput;

/// Names of the faces, in the model's order.
const FACE_NAMES: [&str; FACES] = ["+x", "+y", "+z", "-x", "-y", "-z"];

/// The measured colour of one face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceColour {
    /// The configured hue (degrees).
    pub configured_deg: f32,
    /// The learnt hue (degrees), `None` for a face never seen.
    pub measured_deg: Option<f32>,
    /// Half-width of the learnt band (degrees).
    pub band_deg: f32,
    /// Frames the face was learnt from.
    pub frames: u16,
}

/// What `evorec colours` measured.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourReport {
    /// Per face.
    pub faces: [FaceColour; FACES],
    /// What the true pose is expected to score under this light (1 on a flat image).
    pub expected_fitness: f32,
    /// Frames tracked, and the first of them.
    pub tracked_frames: usize,
    /// The shift of the silhouette rows learnt (pixel widths outwards, `evorec_core::edge`).
    pub edge_shift_px: f32,
}

impl ColourReport {
    /// The report of a tracked stretch of `block`'s recording.
    ///
    /// # Errors
    /// No frame was tracked, so nothing was measured.
    pub fn of(block: &Block, out: &TrackOutput) -> Result<Self> {
        let tracked = out.tracked.iter().filter(|t| t.status == Status::Tracking).count();
        let model: &ColourModel = &out.colours;
        if tracked == 0 || (0..FACES).all(|k| model.frames_seen(k) == 0) {
            bail!("the block was not found in the {} frames tracked: nothing measured", out.tracked.len());
        }
        let bands = model.bands();
        let faces = core::array::from_fn(|k| FaceColour {
            configured_deg: block.face_hues_deg[k],
            measured_deg: (model.frames_seen(k) > 0).then(|| model.hue_deg(k)),
            band_deg: 2.0 * f32::from(bands[k].half),
            frames: model.frames_seen(k),
        });
        Ok(Self {
            faces,
            expected_fitness: model.expected_fitness(),
            tracked_frames: tracked,
            edge_shift_px: out.edge_shift_px,
        })
    }

    /// A table for a terminal.
    pub fn describe(&self) -> String {
        let mut s = String::from("face  configured  measured  band     frames\n");
        for (name, f) in FACE_NAMES.iter().zip(&self.faces) {
            let measured = f.measured_deg.map_or("not seen".to_owned(), |m| format!("{m:.1}°"));
            let (configured, band) = (format!("{:.1}°", f.configured_deg), format!("±{:.0}°", f.band_deg));
            let _ = writeln!(s, "{name:<4}  {configured:>10}  {measured:>8}  {band:<7}  {}", f.frames);
        }
        let _ = write!(
            s,
            "expected score of the true pose under this light: {:.3} ({} frames tracked)\n\
             silhouette rows learnt {:+.2} px outwards (learnt while tracking, never configured)",
            self.expected_fitness, self.tracked_frames, self.edge_shift_px
        );
        s
    }

    /// The `[target]` table with the measured hues (the configured one for a face not seen),
    /// with a header naming where they were measured.
    pub fn to_toml(&self, source: &str) -> String {
        let hues: Vec<String> =
            self.faces.iter().map(|f| format!("{:.1}", f.measured_deg.unwrap_or(f.configured_deg))).collect();
        let unseen: Vec<&str> =
            FACE_NAMES.iter().zip(&self.faces).filter(|(_, f)| f.measured_deg.is_none()).map(|(n, _)| *n).collect();
        let mut s = format!(
            "# The block's face colours as measured by `evorec colours` on {source}\n\
             # (faces +x +y +z -x -y -z). Copy face_hues_deg into the [target] table of\n\
             # sequence.toml, or of the rig file of a bag.\n"
        );
        if !unseen.is_empty() {
            let _ = writeln!(s, "# Not seen, so as configured: {}.", unseen.join(" "));
        }
        let _ = write!(s, "[target]\nface_hues_deg = [{}]\n", hues.join(", "));
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_names_every_face_and_keeps_the_unseen_ones() {
        let configured = [0.0, 120.0, 240.0, 0.0, 120.0, 240.0];
        let faces = core::array::from_fn(|k| FaceColour {
            configured_deg: configured[k],
            measured_deg: (k < 3).then(|| configured[k] - 10.0),
            band_deg: 20.0,
            frames: if k < 3 { 40 } else { 0 },
        });
        let report = ColourReport { faces, expected_fitness: 0.9, tracked_frames: 40, edge_shift_px: -0.25 };
        let toml_text = report.to_toml("SEQ");
        assert!(toml_text.contains("face_hues_deg = [-10.0, 110.0, 230.0, 0.0, 120.0, 240.0]"), "{toml_text}");
        assert!(toml_text.contains("Not seen, so as configured: -x -y -z."));
        let parsed: toml::Table = toml::from_str(&toml_text).unwrap();
        assert_eq!(parsed["target"]["face_hues_deg"].as_array().unwrap().len(), 6);
        let text = report.describe();
        assert!(text.contains("not seen") && text.contains("0.900") && text.contains("-0.25 px"), "{text}");
    }
}
