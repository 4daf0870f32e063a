//! One transparent fragment of a sample, the order that sorts a sample's fragments, and how
//! many of them the exact pass composites exactly: what the fragment lists (`blend.rs`) and the
//! k-buffer past the cap (`kbuffer.rs`) share.
use super::shade::Shaded;
use std::cmp::Ordering;

/// Transparent fragments of one sample composited exactly (`Blend::Exact`); the farther ones
/// of a sample with more are merged into one approximate layer.
pub const FRAGMENT_CAP: u32 = 32;

/// One transparent fragment in a tile: the tile-local sample, 1/w, and its shading.
#[derive(Clone, Copy, Debug, Default)]
pub struct Frag {
    pub sample: u32,
    pub invw: f32,
    pub shaded: Shaded,
}

/// Total order on fragments of one sample, far to near, independent of submission order.
#[inline(always)]
pub(super) fn far_to_near(a: &Frag, b: &Frag) -> Ordering {
    a.invw
        .total_cmp(&b.invw)
        .then_with(|| {
            let ka = a.shaded.rgba.map(f32::to_bits);
            let kb = b.shaded.rgba.map(f32::to_bits);
            ka.cmp(&kb)
        })
        .then(a.shaded.id.cmp(&b.shaded.id))
        .then_with(|| {
            let ka = a.shaded.velocity.map(f32::to_bits);
            let kb = b.shaded.velocity.map(f32::to_bits);
            ka.cmp(&kb)
        })
}
