//! Shared by every kernel test: one GPU per test binary, a seeded RNG, tolerance checks and
//! central finite differences of plain-Rust f64 reference functions.
//!
//! Tolerance policy: GPU results are f32 and compared with `|got - want| <= atol + rtol*|want|`.
//! f32 has a unit roundoff of 6e-8; a sum of K terms of size ~1 accumulates ~sqrt(K)*6e-8
//! relative error, so for the K <= ~10^4 of our test shapes rtol = 1e-4 with atol scaled to
//! the output's magnitude leaves > 10x headroom while any real bug (a dropped term, a
//! flipped sign, an off-by-one tap) shows up at 1e-2 or more. Finite differences run on the
//! f64 reference with step h = 1e-6 (truncation ~h^2, roundoff ~1e-16/h, both far below
//! the f32 error of the GPU gradient they are compared with).
#![allow(dead_code)]

use rendernet::{Gpu, Tensor};
use std::sync::OnceLock;

/// The test GPU, opened once per test binary (tests in it run on threads).
pub fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| {
        // SAFETY-free: set before any wgpu use so Mesa does not warn on a missing runtime dir.
        let gpu = Gpu::new().unwrap_or_else(|e| panic!("kernel tests need a GPU or lavapipe: {e}"));
        // Every packing copies its texels in, whatever its size and this machine's calibration,
        // so the copies are what every texture test checks (`run_unsplit` checks the stores).
        gpu.settle_pack_copies(0);
        gpu
    })
}

/// The crate's SplitMix64: `Rng(seed)`, small and reproducible.
pub use rendernet::rng::SplitMix64 as Rng;

/// Test draws on top of [`Rng`].
pub trait Draws {
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64;
    /// `n` values uniform in [lo, hi).
    fn vec(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64>;
}

impl Draws for Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
    fn vec(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(lo, hi)).collect()
    }
}

/// Uploads f64 values as an f32 tensor.
pub fn upload(shape: &[usize], data: &[f64]) -> Tensor {
    let v: Vec<f32> = data.iter().map(|&x| x as f32).collect();
    Tensor::from_slice(gpu(), shape, &v).expect("upload")
}

/// A zero tensor.
pub fn zeros(shape: &[usize]) -> Tensor {
    Tensor::zeros(gpu(), shape).expect("alloc")
}

/// Downloads a tensor as f64.
pub fn download(t: &Tensor) -> Vec<f64> {
    t.to_vec(gpu()).expect("download").iter().map(|&x| x as f64).collect()
}

/// Rounds through f32, so references see exactly the inputs the GPU sees.
pub fn f32_round(v: &[f64]) -> Vec<f64> {
    v.iter().map(|&x| x as f32 as f64).collect()
}

/// Panics with the worst offender if any `|got - want| > atol + rtol * |want|`.
pub fn assert_close(what: &str, got: &[f64], want: &[f64], atol: f64, rtol: f64) {
    assert_eq!(got.len(), want.len(), "{what}: length {} vs reference {}", got.len(), want.len());
    let mut worst = (0.0f64, 0usize);
    for (i, (&g, &w)) in got.iter().zip(want).enumerate() {
        let excess = (g - w).abs() - (atol + rtol * w.abs());
        if !(excess <= worst.0) || g.is_nan() {
            worst = (if g.is_nan() { f64::INFINITY } else { excess }, i);
        }
    }
    if worst.0 > 0.0 {
        let i = worst.1;
        panic!(
            "{what}: element {i} is {} but the reference says {} (atol {atol}, rtol {rtol}); \
             max |reference| {}",
            got[i],
            want[i],
            want.iter().fold(0.0f64, |m, x| m.max(x.abs()))
        );
    }
    // A check against an all-zero reference proves little: make tests use real signal.
    assert!(want.iter().any(|&w| w.abs() > atol), "{what}: reference is all ~zero, test is vacuous");
}

/// Central finite differences of `f` at `x`: d f / d x_i for every i.
pub fn fd_grad(x: &[f64], f: impl Fn(&[f64]) -> f64) -> Vec<f64> {
    fd_grad_at(x, 0..x.len(), f)
}

/// Central finite differences of `f` at `x`, only for the indices `at` (in their order): for
/// tensors too large to difference every value.
pub fn fd_grad_at(x: &[f64], at: impl IntoIterator<Item = usize>, f: impl Fn(&[f64]) -> f64) -> Vec<f64> {
    let h = 1e-6;
    let mut xp = x.to_vec();
    at.into_iter()
        .map(|i| {
            let x0 = xp[i];
            xp[i] = x0 + h;
            let fp = f(&xp);
            xp[i] = x0 - h;
            let fm = f(&xp);
            xp[i] = x0;
            (fp - fm) / (2.0 * h)
        })
        .collect()
}

/// The indices to difference in a tensor of `len` values: all of them up to `max`, else
/// `max` distinct ones drawn from `rng` (sorted). A kernel bug shows on a border face, a phase
/// or a channel: a share of at least ~1/20 of the values, which `max` = 500 random indices
/// miss with odds under 1e-11; differencing every value of the largest conv cases took
/// minutes of CI per test.
pub fn fd_sample(len: usize, max: usize, rng: &mut Rng) -> Vec<usize> {
    if len <= max {
        return (0..len).collect();
    }
    // A partial Fisher-Yates shuffle: the first `max` of a random permutation.
    let mut all: Vec<usize> = (0..len).collect();
    for i in 0..max {
        let j = i + rng.below(len - i);
        all.swap(i, j);
    }
    let mut at = all[..max].to_vec();
    at.sort_unstable();
    at
}

/// `Σ r_i y_i`: the scalar whose gradient w.r.t. y is `r`, used to test backward passes
/// with a random upstream gradient `r`.
pub fn dot(r: &[f64], y: &[f64]) -> f64 {
    r.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// Runs `f` in one compute pass and waits.
pub fn run(f: impl FnOnce(&mut wgpu::ComputePass<'_>) -> rendernet::Result<()>) {
    gpu().run(f).expect("dispatch");
}

/// Whether texture packings copy their texels in on the test adapter: a CPU adapter that
/// runs the texture family (`gpu()` settles the choice to copy there).
#[allow(dead_code)]
pub fn copies_on_this_adapter() -> bool {
    let g = gpu();
    g.info.device_type == wgpu::DeviceType::Cpu && g.has_subgroups_of_8() && g.reads_rgba32f_storage()
}

/// Records `f` into a pass begun on an encoder of its own, which ops cannot split (on a CPU
/// adapter their texture packings then store their texels instead of copying them in:
/// src/gpu/passes.rs), and runs it.
#[allow(dead_code)]
pub fn run_unsplit(f: impl FnOnce(&mut wgpu::ComputePass<'_>) -> rendernet::Result<()>) {
    let mut enc = gpu().device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        f(&mut pass).expect("dispatch");
    }
    gpu().submit_and_wait(enc).expect("submit");
}
