//! Stride-2 4x4 transposed convs that are exactly "nearest-neighbour upsample, then a 3x3
//! conv" (resize-convolution, Odena et al. 2016, "Deconvolution and checkerboard
//! artifacts"), at the transposed conv's cost of 4 taps per output instead of 9.
//!
//! Upsampling by repetition and convolving with `k` (3x3) equals a stride-2 transposed conv
//! whose 4x4 kernel is `k` convolved with a 2x2 box: each output phase then sums the same
//! nine weights, so a flat input gives a flat output and the two phases of each axis cannot
//! drift apart into a 2-pixel checkerboard. These kernels form a 9-dimensional subspace of
//! the 16-dimensional 4x4 kernels; [`expand`] maps into it (initialisation) and [`project`]
//! is the orthogonal projection onto it, applied after each optimiser step so training stays
//! inside it (projected gradient descent).
//! [`Executor::keep_resize_conv`] marks a graph's weight to be kept so.

use super::{Executor, Kind, Value};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::ops;

impl Executor {
    /// Keeps the 4x4 transposed-conv weight `v` (`[Cin, Cout, 4, 4]`) a resize-convolution:
    /// every training step projects it back onto that subspace right after Adam, on the GPU
    /// and in the step's own submit (see [`crate::graph::resize_conv`]). The weight is taken
    /// to be one already (`Init::XavierUpsample`, or a checkpoint of such a run).
    pub fn keep_resize_conv(&mut self, gpu: &Gpu, v: Value) -> Result<()> {
        let info = self.graph.info(v);
        if !matches!(info.kind, Kind::Param(_)) || info.shape.len() != 4 || info.shape[2..] != [4, 4] {
            return Err(Error::Invalid(format!("'{}' {:?} is not a [Cin, Cout, 4, 4] parameter", info.name, info.shape)));
        }
        // The projection binds the weight itself: a joint's part may start unaligned (flat.rs).
        if self.flat.joint_of(v).is_some() {
            return Err(Error::Invalid(format!("'{}' is a part of a concatenation laid out as one view; a resize-convolution's weight cannot be", info.name)));
        }
        if self.projector.is_none() {
            self.projector = Some(ops::resize_conv::projector(gpu)?);
        }
        if !self.resize_convs.contains(&v) {
            self.resize_convs.push(v);
        }
        Ok(())
    }
}

/// The 4x4 kernel `k ⊛ box2x2` of a 3x3 kernel `k` (row-major).
pub fn expand(k: &[f32]) -> [f32; 16] {
    let mut w = [0.0; 16];
    for (i, row) in matrix().iter().enumerate() {
        w[i] = row.iter().zip(k).map(|(a, b)| (*a as f32) * b).sum();
    }
    w
}

/// Projects every 4x4 kernel of `w` (a `[Cin, Cout, 4, 4]` weight, or any length that is a
/// multiple of 16) orthogonally onto the resize-conv subspace, in place.
pub fn project(w: &mut [f32]) {
    let p = projector();
    for kernel in w.chunks_mut(16) {
        let old: Vec<f64> = kernel.iter().map(|&v| v as f64).collect();
        for (i, out) in kernel.iter_mut().enumerate() {
            *out = (0..16).map(|j| p[i][j] * old[j]).sum::<f64>() as f32;
        }
    }
}

/// The projector of [`project`] in f32, row-major (for the GPU kernel `ops::resize_conv`).
pub fn projector_f32() -> Vec<f32> {
    projector().iter().flatten().map(|&v| v as f32).collect()
}

/// The 16x9 matrix `A` with `expand(k) = A k`: output tap `(y, x)` sums the 3x3 taps
/// `(ky, kx)` with `ky` in `{y-1, y}` and `kx` in `{x-1, x}` (inside 0..3).
fn matrix() -> [[f64; 9]; 16] {
    let mut a = [[0.0; 9]; 16];
    for y in 0..4usize {
        for x in 0..4usize {
            for ky in y.saturating_sub(1)..=y.min(2) {
                for kx in x.saturating_sub(1)..=x.min(2) {
                    a[y * 4 + x][ky * 3 + kx] = 1.0;
                }
            }
        }
    }
    a
}

/// `P = A (AᵀA)⁻¹ Aᵀ`, the orthogonal projector onto the span of `A`'s columns.
fn projector() -> [[f64; 16]; 16] {
    let a = matrix();
    // AᵀA (9x9, symmetric positive definite: A has full column rank), inverted by
    // Gauss-Jordan elimination with partial pivoting.
    let mut m = [[0.0; 18]; 9];
    for i in 0..9 {
        for j in 0..9 {
            m[i][j] = (0..16).map(|r| a[r][i] * a[r][j]).sum();
        }
        m[i][9 + i] = 1.0;
    }
    for c in 0..9 {
        let piv = (c..9).max_by(|&x, &y| m[x][c].abs().total_cmp(&m[y][c].abs())).expect("rows left");
        m.swap(c, piv);
        let d = m[c][c];
        for v in m[c].iter_mut() {
            *v /= d;
        }
        for r in 0..9 {
            if r != c {
                let f = m[r][c];
                let row = m[c];
                for (v, pv) in m[r].iter_mut().zip(row) {
                    *v -= f * pv;
                }
            }
        }
    }
    let mut p = [[0.0; 16]; 16];
    for (i, pi) in p.iter_mut().enumerate() {
        for (j, pij) in pi.iter_mut().enumerate() {
            *pij = (0..9).map(|s| (0..9).map(|t| a[i][s] * m[s][9 + t] * a[j][t]).sum::<f64>()).sum();
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Expanded kernels are fixed points of the projection; a generic kernel is not, and its
    /// projection is (idempotence), with the removed part orthogonal to the subspace.
    #[test]
    fn projection_keeps_resize_kernels_and_is_idempotent() {
        let k = [0.3, -0.2, 0.5, 0.1, 0.9, -0.4, 0.2, 0.05, -0.7];
        let w = expand(&k);
        let mut pw = w;
        project(&mut pw);
        assert!(w.iter().zip(&pw).all(|(a, b)| (a - b).abs() < 1e-5), "{w:?} vs {pw:?}");
        let generic: Vec<f32> = (0..16).map(|i| ((i * 7 % 5) as f32 - 2.0) * 0.3 + (i == 5) as u8 as f32).collect();
        let mut once = generic.clone();
        project(&mut once);
        assert!(generic.iter().zip(&once).any(|(a, b)| (a - b).abs() > 1e-2), "a generic kernel is not a resize kernel");
        let mut twice = once.clone();
        project(&mut twice);
        assert!(once.iter().zip(&twice).all(|(a, b)| (a - b).abs() < 1e-5));
        let removed: Vec<f32> = generic.iter().zip(&once).map(|(a, b)| a - b).collect();
        assert!(removed.iter().zip(&w).map(|(a, b)| a * b).sum::<f32>().abs() < 1e-4, "residual not orthogonal");
    }

    /// Projected kernels have equal weight sums in all four phases (each phase takes every
    /// other tap along each axis), the property that rules out a checkerboard on flat input.
    #[test]
    fn projected_kernels_have_equal_phase_sums() {
        let mut w: Vec<f32> = (0..16).map(|i| ((i * 11 % 7) as f32 - 3.0) * 0.2).collect();
        let phase = |w: &[f32], py: usize, px: usize| -> f32 { [0, 2].iter().flat_map(|&y| [0, 2].map(|x| w[(y + py) * 4 + x + px])).sum() };
        let before: Vec<f32> = (0..4).map(|q| phase(&w, q / 2, q % 2)).collect();
        assert!(before.iter().any(|s| (s - before[0]).abs() > 1e-2), "test kernel already balanced: {before:?}");
        project(&mut w);
        let after: Vec<f32> = (0..4).map(|q| phase(&w, q / 2, q % 2)).collect();
        assert!(after.iter().all(|s| (s - after[0]).abs() < 1e-5), "{after:?}");
    }
}
