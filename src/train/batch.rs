//! Turning dataset samples into the network's inputs and targets, with patch crops.

use crate::data::Sample;
use crate::error::{Error, Result};
use crate::nn::camera;
use crate::nn::rendernet::Preset;
use crate::reference::Image;

/// Inputs and targets of one batch, flattened in the graph's layouts.
#[derive(Default)]
pub struct Batch {
    /// `[N, C, R, R, R]` (C: [`Preset::in_channels`]).
    pub grid: Vec<f32>,
    /// `[N, 6]`.
    pub pose: Vec<f32>,
    /// `[N, 6]`.
    pub light: Vec<f32>,
    /// Target name -> `[N, C, h, w]`.
    pub targets: Vec<(String, Vec<f32>)>,
}

/// The input grid of a sample at the preset's resolution, in network axis order.
pub fn grid_values(p: &Preset, s: &Sample) -> Result<Vec<f32>> {
    let g = if s.grid.dims() == [p.input; 3] {
        s.grid.clone()
    } else {
        s.grid.resample_to(p.input).map_err(|e| Error::Invalid(e.to_string()))?
    };
    Ok(camera::input_values_with(&g, p.in_channels()))
}

/// Rows `[y0, y0+h)` and columns `[x0, x0+w)` of every channel of `img`.
pub fn crop(img: &Image, y0: usize, x0: usize, h: usize, w: usize) -> Vec<f32> {
    let mut out = Vec::with_capacity(img.channels * h * w);
    for c in 0..img.channels {
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                out.push(img.get(c, y, x));
            }
        }
    }
    out
}

/// Top-left corner `(h0, w0)` of a `w`-voxel training window, from three random numbers.
/// Uniform windows of a quarter of the grid mostly show background (objects cover 6-25% of
/// the image), so three times in four the window is centred on a random object pixel (of
/// the `mask` image, else of the first image's non-zero pixels) and clamped into the grid.
pub fn window_origin(p: &Preset, s: &Sample, w: usize, r: [u64; 3]) -> (usize, usize) {
    let span = (p.cam - w + 1) as u64;
    let uniform = ((r[1] % span) as usize, (r[2] % span) as usize);
    if r[0] % 4 == 3 {
        return uniform;
    }
    let Some(img) = s.images.get("mask").or_else(|| s.images.values().next()) else { return uniform };
    let hw = img.size * img.size;
    let fg: Vec<usize> = (0..hw).filter(|&i| img.data[i] > 0.5).collect();
    if fg.is_empty() {
        return uniform;
    }
    let pix = fg[(r[1] % fg.len() as u64) as usize];
    let f = img.size / p.cam; // image pixels per camera voxel
    let centre = |v: usize| (v / f).saturating_sub(w / 2).min(p.cam - w);
    (centre(pix / img.size), centre(pix % img.size))
}

impl Batch {
    /// Appends one sample seen through the camera-grid window `[h0, w0, h, w]` (the full
    /// grid when it covers it), with the targets named in `names` cropped to match.
    pub fn push(&mut self, p: &Preset, s: &Sample, window: [usize; 4], names: &[String]) -> Result<()> {
        let [h0, w0, h, w] = window;
        self.grid.extend(grid_values(p, s)?);
        let crop_arg = (h != p.cam || w != p.cam).then_some(window);
        self.pose.extend(p.pose_values(&s.view, p.cam, crop_arg));
        self.light.extend(camera::light_values(&s.light));
        let f = p.image_for(p.cam) / p.cam; // image pixels per camera voxel
        for name in names {
            let img = s.images.get(name).ok_or_else(|| Error::Invalid(format!("dataset sample lacks the '{name}' image")))?;
            if img.size != p.image_for(p.cam) {
                return Err(Error::Invalid(format!(
                    "dataset images are {}px but preset '{}' renders {}px",
                    img.size,
                    p.name,
                    p.image_for(p.cam)
                )));
            }
            let vals = crop(img, h0 * f, w0 * f, h * f, w * f);
            match self.targets.iter_mut().find(|(n, _)| n == name) {
                Some((_, v)) => v.extend(vals),
                None => self.targets.push((name.clone(), vals)),
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::{Light, View};
    use crate::voxel::VoxelGrid;

    /// A 64^2 mask with one 4x4 object at pixels (rows 48..52, columns 8..12) of a tiny-preset
    /// sample (64^3 camera grid, 128 px images: 2 px per camera voxel).
    fn sample_with_object() -> Sample {
        let s = 128;
        let mut mask = vec![0.0; s * s];
        for y in 96..104 {
            for x in 16..24 {
                mask[y * s + x] = 1.0;
            }
        }
        let mut images = std::collections::BTreeMap::new();
        images.insert("mask".to_string(), Image { channels: 1, size: s, data: mask });
        let grid = VoxelGrid::new([2, 2, 2], vec![0.0; 8]).expect("valid grid");
        Sample { grid, view: View::default(), light: Light::default(), shape_id: 0, images }
    }

    /// Three windows in four contain the object; uniform windows of 16 out of 64 voxels
    /// would contain it about one time in sixteen, so the count separates the two.
    #[test]
    fn windows_mostly_show_the_object() {
        let (p, s, w) = (Preset::tiny(), sample_with_object(), 16);
        let mut state = 1u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            state >> 11
        };
        let mut hits = 0;
        for _ in 0..400 {
            let (h0, w0) = window_origin(&p, &s, w, [next(), next(), next()]);
            assert!(h0 + w <= p.cam && w0 + w <= p.cam, "window ({h0}, {w0}) leaves the grid");
            // The object spans camera voxels rows 48..52, columns 8..12.
            hits += usize::from((h0..h0 + w).contains(&49) && (w0..w0 + w).contains(&9));
        }
        assert!((270..=330).contains(&hits), "{hits} of 400 windows show the object; expected ~300");
    }
}
