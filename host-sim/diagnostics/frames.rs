//! What the probes share: a simulated world's frame pair as the tracker sees it.
use evorec_core::image::{Image, Rgb565};
use evorec_core::tracker::StereoFrame;
use evorec_sim::sim::board::World;
use evorec_sim::sim::render;

/// Renders `world` at its current time into `left` and `right` (RGB565, `w × h` each) and
/// returns them as a stereo frame.
pub fn rgb565_frame<'a>(
    world: &mut World,
    left: &'a mut [u8],
    right: &'a mut [u8],
    w: u16,
    h: u16,
) -> anyhow::Result<StereoFrame<'a, Rgb565>> {
    let images = world.render();
    render::rgb565_into(&images.left, left);
    render::rgb565_into(&images.right, right);
    Ok(StereoFrame {
        left: Image::<&[u8], Rgb565>::new_checked(&left[..], w, h)?,
        right: Image::<&[u8], Rgb565>::new_checked(&right[..], w, h)?,
    })
}
