//! Many lights scored from one forward pass. The Phong head's light enters only the analytic
//! shading of the network's normal, albedo and mask maps (`ops::phong`), so once a start's
//! maps are read back, every light direction costs a few flops per pixel on the CPU instead
//! of a network forward: the light searches rank thousands of directions for the price of
//! one render per view.

use crate::ops::phong::Phong;

/// One start's light-independent maps over the search window.
pub(super) struct Maps {
    /// Unit normals (decoded from the map's [0, 1] encoding as the shader decodes them).
    normal: Vec<[f32; 3]>,
    /// Albedo, grey broadcast to three channels.
    albedo: Vec<[f32; 3]>,
    mask: Vec<f32>,
}

impl Maps {
    /// Batch entry `b` of maps read back from the network: `normal [N, 3, H, W]`, `albedo [N,
    /// C, H, W]` (C 1 or 3), `mask [N, 1, H, W]`, `hw = H * W`.
    pub(super) fn of(normal: &[f32], albedo: &[f32], mask: &[f32], hw: usize, b: usize) -> Maps {
        let c = albedo.len() / (mask.len() / hw) / hw;
        let (nb, ab) = (&normal[b * 3 * hw..(b + 1) * 3 * hw], &albedo[b * c * hw..(b + 1) * c * hw]);
        let normal = (0..hw)
            .map(|px| {
                let u = [2.0 * nb[px] - 1.0, 2.0 * nb[hw + px] - 1.0, 2.0 * nb[2 * hw + px] - 1.0];
                let len = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt().max(1e-6);
                u.map(|x| x / len)
            })
            .collect();
        let albedo = (0..hw).map(|px| if c == 3 { [ab[px], ab[hw + px], ab[2 * hw + px]] } else { [ab[px]; 3] }).collect();
        Maps { normal, albedo, mask: mask[b * hw..(b + 1) * hw].to_vec() }
    }

    /// The image `[3, H, W]` these maps give under `light` (`nn::camera::light_values`:
    /// direction then colour), as the Phong op draws it (view along +z).
    #[cfg(test)]
    pub(super) fn shade(&self, ph: &Phong, light: &[f32; 6]) -> Vec<f32> {
        let hw = self.mask.len();
        let mut out = vec![0.0; 3 * hw];
        for px in 0..hw {
            let v = self.pixel(ph, light, px);
            for c in 0..3 {
                out[c * hw + px] = v[c];
            }
        }
        out
    }

    /// Summed squared error against `target` (`[3, H, W]`) of the image under `light`,
    /// clamped to [0, 1] as a user sees it.
    pub(super) fn sse(&self, ph: &Phong, light: &[f32; 6], target: &[f32]) -> f64 {
        let hw = self.mask.len();
        let mut sum = 0.0;
        for px in 0..hw {
            let v = self.pixel(ph, light, px);
            for c in 0..3 {
                sum += ((v[c].clamp(0.0, 1.0) - target[c * hw + px]) as f64).powi(2);
            }
        }
        sum
    }

    fn pixel(&self, ph: &Phong, light: &[f32; 6], px: usize) -> [f32; 3] {
        let (n, a, m) = (self.normal[px], self.albedo[px], self.mask[px]);
        let d = n[0] * light[0] + n[1] * light[1] + n[2] * light[2];
        let s = 2.0 * d * n[2] - light[2];
        let spec = if s > 0.0 { s.powf(ph.shininess) } else { 0.0 };
        let diffuse = ph.ambient + ph.kd * d.max(0.0);
        [0, 1, 2].map(|c| m * light[3 + c] * (a[c] * diffuse + ph.ks * spec))
    }
}
