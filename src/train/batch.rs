//! Turning dataset samples into the network's inputs and targets, with patch crops.

use crate::data::Sample;
use crate::error::{Error, Result};
use crate::nn::camera;
use crate::nn::rendernet::Preset;
use crate::reference::Image;

/// Inputs and targets of one batch, flattened in the graph's layouts.
#[derive(Default)]
pub struct Batch {
    /// `[N, 1, R, R, R]`.
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
    Ok(camera::input_values(&g))
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

impl Batch {
    /// Appends one sample seen through the camera-grid window `[h0, w0, h, w]` (the full
    /// grid when it covers it), with the targets named in `names` cropped to match.
    pub fn push(&mut self, p: &Preset, s: &Sample, window: [usize; 4], names: &[String]) -> Result<()> {
        let [h0, w0, h, w] = window;
        self.grid.extend(grid_values(p, s)?);
        let crop_arg = (h != p.cam || w != p.cam).then_some(window);
        self.pose.extend(camera::pose_for_view(&s.view, p.input, p.cam, crop_arg));
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
