//! The core's one frame type and one layer view, shared by every stage that writes or reads
//! an image of surfaces (as tiny-skia's `Pixmap` and `PixmapRef`).
//!
//! - [`Frame`] owns its buffers: what the rasterizer and the analytic renderer return, what
//!   the accumulation buffer sums and keeps. Channels every frame has are plain vectors;
//!   channels only some renders write (velocity) are options, so a new channel is added here
//!   once and not to every stage's own struct.
//! - [`Layer`] borrows the same three buffers of colour, depth and ids: the static layer a
//!   render starts from or composites with (the rasterizer's background, the analytic
//!   backdrop, the accumulation buffer's static objects) and the sharp renders the scatter
//!   kernel splats.
//!
//! All buffers are row-major, `height` rows of `width` entries (pixels or samples, as the
//! stage says), `rgba` 4 floats an entry.
//!
//! This module depends on no stage, so every stage may use it.
use crate::budget::{advise_huge_pages, try_reserve, try_vec, Need};
use crate::error::{Error, Result};

/// An owned image of surfaces: row-major buffers of `height` x `width` entries.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Width in entries (pixels or samples).
    pub width: u32,
    /// Height in entries.
    pub height: u32,
    /// (H,W,4) premultiplied linear RGBA.
    pub rgba: Vec<f32>,
    /// (H,W) view-axis distance of the nearest surface, inf where there is none.
    pub depth: Vec<f32>,
    /// (H,W) object id of the nearest surface, -1 where there is none.
    pub ids: Vec<i32>,
    /// (H,W,2) screen motion in pixels of the nearest surface, or None when the render does not
    /// write it (the rasterizer without previous positions: the motion is zero everywhere).
    pub velocity: Option<Vec<f32>>,
    /// Per pixel and object id, how long each object is visible there over the shutter, or
    /// None when the render does not write it (only the analytic renderer can, on request).
    pub exposure: Option<Exposure>,
}

/// Per pixel and object id, the time each object is the visible one over the shutter:
/// `height` x `width` x `planes` row-major (one plane per object id `0..planes-1`, the last
/// plane for id -1: no surface). Which object is visible is the renderer's to define (the
/// analytic renderer: the frontmost surface at the sample, whatever its alpha).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Exposure {
    /// Planes per pixel: the object ids `0..planes-1` and, last, id -1.
    pub planes: u32,
    /// (H,W,P) the shutter-weighted fraction of the shutter the object is visible, in [0, 1]
    /// (the mean over the pixel's samples).
    pub fraction: Vec<f32>,
    /// (H,W,P) the first shutter time it is visible at any of the pixel's samples, NaN where it
    /// never is.
    pub first: Vec<f32>,
    /// (H,W,P) the last shutter time it is visible at any of the pixel's samples, NaN where it
    /// never is.
    pub last: Vec<f32>,
}

impl Exposure {
    /// An empty exposure of `width` x `height` pixels and `planes` planes (fractions 0, times
    /// NaN), after checking its 12 bytes per pixel and plane against the memory budget (the
    /// error names `name`, the argument that asked for it).
    pub fn new(width: u32, height: u32, planes: u32, name: &'static str) -> Result<Self> {
        let sizes = [
            (name, u64::from(planes)),
            ("height", u64::from(height)),
            ("width", u64::from(width)),
        ];
        Need::new("exposure").add(&sizes, 12)?.check()?;
        let n = planes as usize * width as usize * height as usize;
        Ok(Exposure {
            planes,
            fraction: try_vec(n, 0.0, name)?,
            first: try_vec(n, f32::NAN, name)?,
            last: try_vec(n, f32::NAN, name)?,
        })
    }

    /// The plane of object id `id` (-1 is the last), or None when it has none.
    #[inline]
    pub fn plane(&self, id: i32) -> Option<usize> {
        match id {
            -1 => Some(self.planes as usize - 1),
            i if i >= 0 && (i as u32) + 1 < self.planes => Some(i as usize),
            _ => None,
        }
    }
}

impl Frame {
    /// A frame of the given size, every entry empty (transparent black, depth inf, id -1),
    /// with a zero velocity channel when `velocity`.
    pub fn new(width: u32, height: u32, velocity: bool) -> Self {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            rgba: vec![0.0; 4 * n],
            depth: vec![f32::INFINITY; n],
            ids: vec![-1; n],
            velocity: velocity.then(|| vec![0.0; 2 * n]),
            exposure: None,
        }
    }

    /// A frame of the given size whose buffers have room for every entry but length 0, to be
    /// written in place (through their spare capacity) and then given their length: a render
    /// that writes every entry need not fill them first. Buffers of 4 MiB and more are backed
    /// by huge pages where Linux allows (`budget::advise_huge_pages`). An allocation the system
    /// refuses is an error naming `width`.
    pub fn with_capacity(width: u32, height: u32, velocity: bool) -> Result<Self> {
        let n = width as usize * height as usize;
        let mut frame = Frame {
            width,
            height,
            velocity: velocity.then(Vec::new),
            ..Default::default()
        };
        try_reserve(&mut frame.rgba, 4 * n, "width")?;
        try_reserve(&mut frame.depth, n, "width")?;
        try_reserve(&mut frame.ids, n, "width")?;
        if let Some(v) = &mut frame.velocity {
            try_reserve(v, 2 * n, "width")?;
        }
        advise_huge_pages(&frame.rgba);
        advise_huge_pages(&frame.depth);
        advise_huge_pages(&frame.ids);
        if let Some(v) = &frame.velocity {
            advise_huge_pages(v);
        }
        Ok(frame)
    }

    /// Entries (pixels or samples) of the frame.
    pub fn len(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Whether the frame has no entry.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The frame's colour, depth and ids as a borrowed layer.
    pub fn as_layer(&self) -> Layer<'_> {
        Layer {
            width: self.width as usize,
            height: self.height as usize,
            rgba: &self.rgba,
            depth: &self.depth,
            ids: &self.ids,
        }
    }
}

/// A borrowed image of surfaces: colour, depth and ids of `height` x `width` entries,
/// row-major (a static layer kept by the caller, a sharp render, a [`Frame`]'s buffers).
#[derive(Clone, Copy, Debug)]
pub struct Layer<'a> {
    /// Entries per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// (H,W,4) premultiplied linear RGBA.
    pub rgba: &'a [f32],
    /// (H,W) view-axis distance of the surface, inf where there is none.
    pub depth: &'a [f32],
    /// (H,W) object id of the surface, -1 where there is none.
    pub ids: &'a [i32],
}

impl Layer<'_> {
    /// Entries of the layer.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// Whether the layer has no entry.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Checks that the buffers hold `height` x `width` entries (4 floats each for `rgba`);
    /// the error names `name`.
    pub fn check_lengths(&self, name: &'static str) -> Result<()> {
        let n = self.len();
        if self.rgba.len() != 4 * n || self.depth.len() != n || self.ids.len() != n {
            return Err(Error::shape(
                name,
                format!(
                    "rgba ({h},{w},4), depth and ids ({h},{w}) expected, got {} / {} / {} values",
                    self.rgba.len(),
                    self.depth.len(),
                    self.ids.len(),
                    h = self.height,
                    w = self.width
                ),
            ));
        }
        Ok(())
    }

    /// The colour of entry `i` (row-major index).
    #[inline]
    pub fn rgba_at(&self, i: usize) -> [f32; 4] {
        let c = &self.rgba[4 * i..4 * i + 4];
        [c[0], c[1], c[2], c[3]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_frame_is_empty_and_its_layer_sees_its_buffers() {
        let f = Frame::new(3, 2, false);
        assert_eq!((f.len(), f.velocity.is_none()), (6, true));
        assert!(f.depth.iter().all(|d| d.is_infinite()) && f.ids.iter().all(|i| *i == -1));
        let l = f.as_layer();
        assert!(l.check_lengths("frame").is_ok());
        assert_eq!((l.width, l.height, l.rgba_at(5)), (3, 2, [0.0; 4]));
        assert_eq!(Frame::new(3, 2, true).velocity.map(|v| v.len()), Some(12));
        let room = Frame::with_capacity(3, 2, true).unwrap();
        assert!(room.rgba.is_empty() && room.rgba.capacity() >= 24);
        assert!(room.velocity.unwrap().capacity() >= 12);
    }

    #[test]
    fn lengths_that_do_not_match_the_size_are_an_error_naming_the_argument() {
        let (rgba, depth, ids) = ([0.0f32; 24], [1.0f32; 6], [0i32; 6]);
        let l = Layer {
            width: 3,
            height: 2,
            rgba: &rgba,
            depth: &depth,
            ids: &ids,
        };
        assert!(l.check_lengths("layer").is_ok());
        let short = Layer {
            ids: &ids[..5],
            ..l
        };
        let e = short.check_lengths("backdrop").unwrap_err().to_string();
        assert!(e.contains("backdrop"), "{e}");
        let wide = Layer { width: 4, ..l };
        assert!(wide.check_lengths("layer").is_err());
    }

    /// The VmFlags of the mapping holding `addr` in /proc/self/smaps.
    #[cfg(target_os = "linux")]
    fn vm_flags(addr: usize) -> Option<String> {
        let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
        let mut inside = false;
        for line in smaps.lines() {
            let range = line
                .split_whitespace()
                .next()
                .and_then(|r| r.split_once('-'));
            if let Some((a, b)) = range.filter(|(a, _)| !a.ends_with(':')) {
                let hex = |x: &str| usize::from_str_radix(x, 16).ok();
                if let (Some(a), Some(b)) = (hex(a), hex(b)) {
                    inside = a <= addr && addr < b;
                    continue;
                }
            }
            if inside {
                if let Some(flags) = line.strip_prefix("VmFlags:") {
                    return Some(flags.to_string());
                }
            }
        }
        None
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_large_frame_is_advised_huge_pages() {
        // Without transparent huge pages in the kernel (or set to never) the advice is declined.
        let thp = std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled");
        if thp.map_or(true, |s| s.contains("[never]")) {
            eprintln!("a_large_frame_is_advised_huge_pages: not checked, this kernel has no transparent huge pages");
            return;
        }
        // 3840x2160: colour 127 MiB (above glibc's largest mmap threshold: a mapping of its
        // own), depth and ids 31.6 MiB each (a mapping or the heap, split where advised).
        let f = Frame::with_capacity(3840, 2160, true).unwrap();
        let middle = |p: *const u8, bytes: usize| p as usize + bytes / 2;
        let n = f.len();
        let buffers = [
            ("rgba", middle(f.rgba.as_ptr().cast(), 16 * n)),
            ("depth", middle(f.depth.as_ptr().cast(), 4 * n)),
            ("ids", middle(f.ids.as_ptr().cast(), 4 * n)),
            (
                "velocity",
                middle(f.velocity.as_ref().unwrap().as_ptr().cast(), 8 * n),
            ),
        ];
        for (name, addr) in buffers {
            let flags = vm_flags(addr).expect("the buffer is mapped");
            assert!(
                flags.split_whitespace().any(|f| f == "hg"),
                "{name}: {flags}"
            );
        }
    }
}
