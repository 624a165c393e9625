//! The part of the camera grid an inversion renders.

use crate::nn::rendernet::Preset;
use crate::reference::Image;

/// The part of the camera grid a search renders: the target's foreground box grown by
/// [`WINDOW_MARGIN`] camera voxels, sides rounded up to multiples of 4 (what the strides
/// need) and clamped to the grid. Empty space costs nothing: a bunny at radius 3.3 needs
/// about a third of the frame, a chair at radius 6 a tenth. Depth stays whole.
#[derive(Clone, Copy, Debug)]
pub(super) struct Window {
    /// `[h0, w0, h, w]` in camera voxels (as `nn::camera::pose_for_view` takes it).
    pub(super) cam: [usize; 4],
    /// Image pixels per camera voxel.
    pub(super) f: usize,
}

/// Camera voxels of context kept around the foreground: silhouettes of nearby wrong poses
/// still fall inside, and the network's border effects stay off the object.
const WINDOW_MARGIN: usize = 6;

impl Window {
    pub(super) fn full(p: &Preset, size: usize) -> Window {
        Window { cam: [0, 0, p.cam, p.cam], f: size / p.cam }
    }

    pub(super) fn around(p: &Preset, fg: &[bool], size: usize) -> Window {
        let f = size / p.cam;
        let (mut lo, mut hi) = ([usize::MAX; 2], [0usize; 2]);
        for i in (0..fg.len()).filter(|&i| fg[i]) {
            let c = [i / size / f, i % size / f];
            for a in 0..2 {
                lo[a] = lo[a].min(c[a]);
                hi[a] = hi[a].max(c[a]);
            }
        }
        if lo[0] == usize::MAX {
            return Window::full(p, size);
        }
        let mut cam = [0; 4];
        for a in 0..2 {
            let len = (hi[a] - lo[a] + 1 + 2 * WINDOW_MARGIN).next_multiple_of(4).min(p.cam);
            let centre = (lo[a] + hi[a] + 1) / 2;
            cam[a] = centre.saturating_sub(len / 2).min(p.cam - len);
            cam[2 + a] = len;
        }
        Window { cam, f }
    }

    /// The window of the same centre `len` camera voxels across (at most the camera's), so
    /// that windows of several images share one network size.
    pub(super) fn resized(&self, p: &Preset, len: [usize; 2]) -> Window {
        let mut cam = self.cam;
        for a in 0..2 {
            let l = len[a].min(p.cam);
            let centre = self.cam[a] + self.cam[2 + a] / 2;
            cam[a] = centre.saturating_sub(l / 2).min(p.cam - l);
            cam[2 + a] = l;
        }
        Window { cam, f: self.f }
    }

    /// `[rows, columns]` of image pixels inside.
    pub(super) fn pixel_dims(&self) -> [usize; 2] {
        [self.cam[2] * self.f, self.cam[3] * self.f]
    }

    pub(super) fn crop_rgb(&self, img: &Image) -> Vec<f32> {
        let [h, w] = self.pixel_dims();
        crate::train::batch::crop(img, self.cam[0] * self.f, self.cam[1] * self.f, h, w)
    }

    pub(super) fn crop_mask(&self, fg: &[bool], size: usize) -> Vec<bool> {
        let [h, w] = self.pixel_dims();
        let (y0, x0) = (self.cam[0] * self.f, self.cam[1] * self.f);
        (0..h).flat_map(|y| (0..w).map(move |x| fg[(y0 + y) * size + x0 + x])).collect()
    }
}
