//! Image scores that stay honest when the object is small: full-frame PSNR, PSNR inside the
//! object's box, SSIM inside that box, and IoU of the foreground masks.
//!
//! Rendered objects cover a few percent of a black frame, so full-frame PSNR is mostly a
//! score of the background: an all-black image already gets ~23 dB. Every function here
//! takes a `(prediction, truth)` pair of [`Image`]s of the same shape, clamps both to
//! `[0, 1]` (as images are stored), and computes in f64. [`Scores::black_floor`] gives the
//! scores of an all-black prediction, the floor each score should be read against.

use crate::reference::Image;

/// A pixel is foreground when its brightest channel exceeds this (~10 of 255 grey levels).
///
/// Why 0.04: the reference background is exactly 0, and its darkest surface is the ambient
/// term, 0.1 × albedo (0.1 for the default light and white albedo), so any surface clears it
/// with margin; a sigmoid-headed network never outputs exactly 0, and the faint haze it leaves
/// around objects stays under it, so that haze does not count as predicted object.
pub const FOREGROUND: f32 = 0.04;

/// Pixels added on every side of the foreground's bounding box, so the object's silhouette
/// edge (where a blurry prediction loses most) lies inside the box, not on its border.
pub const BOX_MARGIN: usize = 4;

/// PSNR reported for identical images (whose MSE is 0 and PSNR infinite), as elsewhere in
/// the crate: a finite number keeps means and JSON well defined.
pub const PSNR_CAP: f64 = 99.0;

/// Side of the SSIM Gaussian window and its standard deviation (Wang et al. 2004).
const WINDOW: usize = 11;
const SIGMA: f64 = 1.5;
/// SSIM stabilisers for a dynamic range of 1: `(0.01)^2` and `(0.03)^2`.
const C1: f64 = 0.0001;
const C2: f64 = 0.0009;

/// An inclusive pixel rectangle: columns `x0..=x1`, rows `y0..=y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelBox {
    /// Leftmost column.
    pub x0: usize,
    /// Top row.
    pub y0: usize,
    /// Rightmost column.
    pub x1: usize,
    /// Bottom row.
    pub y1: usize,
}

impl PixelBox {
    /// The whole `size` x `size` frame.
    pub fn full(size: usize) -> Self {
        PixelBox { x0: 0, y0: 0, x1: size - 1, y1: size - 1 }
    }

    /// Pixels inside, as `(y, x)` pairs in row order.
    fn pixels(self) -> impl Iterator<Item = (usize, usize)> {
        (self.y0..=self.y1).flat_map(move |y| (self.x0..=self.x1).map(move |x| (y, x)))
    }
}

/// The four scores of one prediction against its truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scores {
    /// Full-frame PSNR in dB (peak 1, capped at [`PSNR_CAP`]).
    pub psnr: f64,
    /// PSNR in dB inside the object box ([`object_psnr`]).
    pub object_psnr: f64,
    /// SSIM averaged over the object box ([`ssim`]).
    pub ssim: f64,
    /// IoU of the foreground masks ([`mask_iou`]).
    pub iou: f64,
}

impl Scores {
    /// All four scores of `pred` against `truth`.
    ///
    /// # Panics
    /// If the shapes differ.
    pub fn of(pred: &Image, truth: &Image) -> Self {
        Scores { psnr: psnr(pred, truth), object_psnr: object_psnr(pred, truth), ssim: ssim(pred, truth), iou: mask_iou(pred, truth) }
    }

    /// The scores an all-black prediction of `truth`'s shape gets: the floor to read a
    /// network's scores against. Its object box comes from the truth alone.
    pub fn black_floor(truth: &Image) -> Self {
        let black = Image { channels: truth.channels, size: truth.size, data: vec![0.0; truth.data.len()] };
        Scores::of(&black, truth)
    }

    /// [`Scores::of`] for images whose background is `background` (0 for most shaders, 1 for
    /// contour lines on white): both images are scored by their distance from the background
    /// (`|v - background|`), so the object box and the masks find the drawing, not the whole
    /// white frame. PSNR is unchanged by the mapping.
    pub fn on_background(pred: &Image, truth: &Image, background: f32) -> Self {
        if background == 0.0 {
            return Scores::of(pred, truth); // the mapping is the identity (the scores clamp too)
        }
        Scores::of(&from_background(pred, background), &from_background(truth, background))
    }

    /// The floor for [`Scores::on_background`]: an image of the background alone (all-black,
    /// or all-white for contours).
    pub fn background_floor(truth: &Image, background: f32) -> Self {
        Scores::black_floor(&from_background(truth, background))
    }
}

/// `|v - background|` per value (clamped to [0, 1] first): the identity on black backgrounds,
/// the negative on white ones.
pub fn from_background(img: &Image, background: f32) -> Image {
    Image { data: img.data.iter().map(|v| (v.clamp(0.0, 1.0) - background).abs()).collect(), ..img.clone() }
}

/// "all-black" or "all-white": how reports name the [`Scores::background_floor`] image.
pub fn floor_name(background: f32) -> &'static str {
    if background >= 0.5 { "all-white" } else { "all-black" }
}

/// Full-frame PSNR in dB, peak 1, capped at [`PSNR_CAP`].
pub fn psnr(pred: &Image, truth: &Image) -> f64 {
    psnr_in(pred, truth, PixelBox::full(check(pred, truth)))
}

/// PSNR in dB inside [`object_box`]. When neither image has a foreground pixel there is no
/// object to score, and this is the full-frame PSNR.
pub fn object_psnr(pred: &Image, truth: &Image) -> f64 {
    let s = check(pred, truth);
    psnr_in(pred, truth, object_box(pred, truth).unwrap_or(PixelBox::full(s)))
}

/// The bounding box of the pixels that are foreground in either image, grown by
/// [`BOX_MARGIN`] and clamped to the frame; `None` when neither has foreground. Using both
/// images means a prediction is scored on what it drew as well as on what it missed.
pub fn object_box(pred: &Image, truth: &Image) -> Option<PixelBox> {
    let s = check(pred, truth);
    let (fp, ft) = (foreground(pred), foreground(truth));
    let mut b: Option<PixelBox> = None;
    for (y, x) in PixelBox::full(s).pixels().filter(|&(y, x)| fp[y * s + x] || ft[y * s + x]) {
        b = Some(match b {
            None => PixelBox { x0: x, y0: y, x1: x, y1: y },
            Some(b) => PixelBox { x0: b.x0.min(x), y0: b.y0.min(y), x1: b.x1.max(x), y1: b.y1.max(y) },
        });
    }
    b.map(|b| PixelBox {
        x0: b.x0.saturating_sub(BOX_MARGIN),
        y0: b.y0.saturating_sub(BOX_MARGIN),
        x1: (b.x1 + BOX_MARGIN).min(s - 1),
        y1: (b.y1 + BOX_MARGIN).min(s - 1),
    })
}

/// Mean SSIM (Wang et al. 2004) of the luminance (mean of the channels), with an 11x11
/// Gaussian window of sigma 1.5 and `C1 = 0.01^2`, `C2 = 0.03^2`, averaged over the pixels
/// of [`object_box`] (the full frame when neither image has foreground).
///
/// The average is over the object box because full-frame SSIM is inflated by the background
/// as much as PSNR is: black on black scores 1 at every background pixel. At the frame's
/// edge the window is truncated and its weights renormalised to sum to 1, so edge statistics
/// are true weighted means of the pixels that exist rather than means diluted by padding.
pub fn ssim(pred: &Image, truth: &Image) -> f64 {
    let s = check(pred, truth);
    let (x, y) = (luminance(pred), luminance(truth));
    let prod = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).collect::<Vec<_>>();
    let blur = |v: &[f64]| gaussian_blur(v, s);
    let (mx, my) = (blur(&x), blur(&y));
    let (xx, yy, xy) = (blur(&prod(&x, &x)), blur(&prod(&y, &y)), blur(&prod(&x, &y)));
    let area = object_box(pred, truth).unwrap_or(PixelBox::full(s));
    let (mut sum, mut n) = (0.0, 0usize);
    for (r, c) in area.pixels() {
        let i = r * s + c;
        let (ux, uy) = (mx[i], my[i]);
        let (vx, vy, cxy) = (xx[i] - ux * ux, yy[i] - uy * uy, xy[i] - ux * uy);
        sum += (2.0 * ux * uy + C1) * (2.0 * cxy + C2) / ((ux * ux + uy * uy + C1) * (vx + vy + C2));
        n += 1;
    }
    sum / n as f64
}

/// Intersection over union of the two foreground masks ([`FOREGROUND`]); 1 when both are
/// empty (they agree exactly that there is nothing).
pub fn mask_iou(pred: &Image, truth: &Image) -> f64 {
    check(pred, truth);
    let (fp, ft) = (foreground(pred), foreground(truth));
    let inter = fp.iter().zip(&ft).filter(|(a, b)| **a && **b).count();
    let union = fp.iter().zip(&ft).filter(|(a, b)| **a || **b).count();
    if union == 0 { 1.0 } else { inter as f64 / union as f64 }
}

/// The side length, after checking both images have the same shape.
fn check(pred: &Image, truth: &Image) -> usize {
    assert_eq!(pred.shape(), truth.shape(), "metrics compare images of the same shape");
    assert!(truth.size > 0 && truth.data.len() == truth.channels * truth.size * truth.size, "malformed image");
    truth.size
}

/// Clamped value as f64.
fn at(img: &Image, c: usize, y: usize, x: usize) -> f64 {
    img.get(c, y, x).clamp(0.0, 1.0) as f64
}

fn psnr_in(pred: &Image, truth: &Image, b: PixelBox) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for c in 0..truth.channels {
        for (y, x) in b.pixels() {
            sum += (at(pred, c, y, x) - at(truth, c, y, x)).powi(2);
            n += 1;
        }
    }
    if sum == 0.0 { PSNR_CAP } else { (10.0 * (n as f64 / sum).log10()).min(PSNR_CAP) }
}

/// Per pixel (row-major): is the brightest channel above [`FOREGROUND`]?
fn foreground(img: &Image) -> Vec<bool> {
    let s = img.size;
    PixelBox::full(s).pixels().map(|(y, x)| (0..img.channels).any(|c| img.get(c, y, x).clamp(0.0, 1.0) > FOREGROUND)).collect()
}

/// Mean of the clamped channels per pixel (row-major).
fn luminance(img: &Image) -> Vec<f64> {
    let s = img.size;
    PixelBox::full(s).pixels().map(|(y, x)| (0..img.channels).map(|c| at(img, c, y, x)).sum::<f64>() / img.channels as f64).collect()
}

/// Gaussian-weighted local mean, separable: a pass along rows then along columns, each with
/// the window truncated at the edge and divided by the weights it kept. The 2D window's
/// truncated weight sum is the product of the two 1D sums, so this equals the 2D window
/// renormalised.
fn gaussian_blur(v: &[f64], s: usize) -> Vec<f64> {
    let h = (WINDOW / 2) as isize;
    let g: Vec<f64> = (-h..=h).map(|d| (-((d * d) as f64) / (2.0 * SIGMA * SIGMA)).exp()).collect();
    let pass = |src: &[f64], stride: usize, step: usize| {
        // Element (line, k) lives at line * stride + k * step.
        let mut out = vec![0.0; src.len()];
        for line in 0..s {
            for k in 0..s as isize {
                let (mut acc, mut w) = (0.0, 0.0);
                for (j, gj) in g.iter().enumerate() {
                    let t = k + j as isize - h;
                    if (0..s as isize).contains(&t) {
                        acc += gj * src[line * stride + t as usize * step];
                        w += gj;
                    }
                }
                out[line * stride + k as usize * step] = acc / w;
            }
        }
        out
    };
    pass(&pass(v, s, 1), 1, s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(channels: usize, size: usize, f: impl Fn(usize, usize, usize) -> f32) -> Image {
        let mut data = Vec::with_capacity(channels * size * size);
        for c in 0..channels {
            for y in 0..size {
                for x in 0..size {
                    data.push(f(c, y, x));
                }
            }
        }
        Image { channels, size, data }
    }

    /// A 64x64 RGB frame: black, with a shaded 20x20 square at rows 20..40, columns 24..44.
    fn object() -> Image {
        image(3, 64, |c, y, x| if (20..40).contains(&y) && (24..44).contains(&x) { 0.2 + 0.02 * (x + y + c) as f32 } else { 0.0 })
    }

    /// Deterministic uniform noise in `[-amp, amp]` (a small LCG; no RNG crate needed).
    fn noisy(img: &Image, amp: f32) -> Image {
        let mut state = 12345u64;
        let data = img
            .data
            .iter()
            .map(|v| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                v + amp * (2.0 * (state >> 40) as f32 / (1u64 << 24) as f32 - 1.0)
            })
            .collect();
        Image { data, ..img.clone() }
    }

    #[test]
    fn identical_images_score_perfectly() {
        let a = object();
        let s = Scores::of(&a, &a);
        assert_eq!((s.psnr, s.object_psnr, s.iou), (PSNR_CAP, PSNR_CAP, 1.0));
        assert!((s.ssim - 1.0).abs() < 1e-12, "{s:?}");
    }

    #[test]
    fn a_constant_offset_gives_its_psnr() {
        // Every pixel off by 0.1: MSE 0.01, 20 dB, full frame and box alike (all foreground).
        let t = image(3, 32, |c, y, x| 0.3 + 0.005 * (c + y + x) as f32 / 3.0);
        let p = Image { data: t.data.iter().map(|v| v + 0.1).collect(), ..t.clone() };
        assert!((psnr(&p, &t) - 20.0).abs() < 1e-4, "{}", psnr(&p, &t));
        assert!((object_psnr(&p, &t) - 20.0).abs() < 1e-4);
        // Values are clamped: 1.5 scores as 1.0 against 1.0.
        let one = image(1, 8, |_, _, _| 1.0);
        assert_eq!(psnr(&image(1, 8, |_, _, _| 1.5), &one), PSNR_CAP);
    }

    #[test]
    fn object_box_is_the_union_grown_by_the_margin_and_clamped() {
        let dot = |y0: usize, x0: usize, v: f32| image(1, 64, move |_, y, x| if (y, x) == (y0, x0) { v } else { 0.0 });
        let b = object_box(&dot(10, 20, 0.5), &dot(10, 20, 0.0)).unwrap();
        assert_eq!(b, PixelBox { x0: 16, y0: 6, x1: 24, y1: 14 });
        // Near the corners the box stops at the frame.
        assert_eq!(object_box(&dot(1, 62, 0.5), &dot(1, 62, 0.5)).unwrap(), PixelBox { x0: 58, y0: 0, x1: 63, y1: 5 });
        // The union of the prediction's and the truth's foreground.
        assert_eq!(object_box(&dot(50, 50, 0.5), &dot(10, 12, 0.5)).unwrap(), PixelBox { x0: 8, y0: 6, x1: 54, y1: 54 });
        // Below the threshold is background.
        assert_eq!(object_box(&dot(10, 20, 0.03), &dot(10, 20, 0.0)), None);
    }

    #[test]
    fn a_black_prediction_has_iou_zero_and_is_the_floor() {
        let t = object();
        let black = Image { data: vec![0.0; t.data.len()], ..t.clone() };
        assert_eq!(mask_iou(&black, &t), 0.0);
        assert_eq!(Scores::black_floor(&t), Scores::of(&black, &t));
        // Half the square predicted: IoU 1/2.
        let half = image(3, 64, |c, y, x| if x < 34 { t.get(c, y, x) } else { 0.0 });
        assert!((mask_iou(&half, &t) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn ssim_falls_as_noise_grows() {
        let t = object();
        let (a, b) = (ssim(&noisy(&t, 0.02), &t), ssim(&noisy(&t, 0.1), &t));
        assert!(a < 1.0 && b < a, "ssim at noise 0.02: {a}, at 0.1: {b}");
        assert!(b > -1.0);
    }

    #[test]
    fn ssim_of_flat_images_is_exact_up_to_the_edges() {
        // Constant a vs b: means a and b, no variance, so SSIM = (2ab + C1) / (a^2 + b^2 + C1)
        // at every pixel, the edges included only if the truncated window is renormalised.
        let (a, b) = (0.6f32, 0.3f32);
        let want = (2.0 * a as f64 * b as f64 + C1) / ((a as f64).powi(2) + (b as f64).powi(2) + C1);
        let got = ssim(&image(1, 16, |_, _, _| a), &image(1, 16, |_, _, _| b));
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }

    #[test]
    fn separable_ssim_matches_a_direct_2d_window() {
        // The textbook form: at each pixel, a truncated 11x11 window, weights renormalised.
        let t = image(3, 24, |c, y, x| if (3..21).contains(&y) && (2..14).contains(&x) { 0.3 + 0.03 * ((x * y + c) % 7) as f32 } else { 0.0 });
        let p = noisy(&t, 0.08);
        let (lx, ly) = (luminance(&p), luminance(&t));
        let mut sum = 0.0;
        let area = object_box(&p, &t).unwrap();
        for (r, c) in area.pixels() {
            let mut m = [0.0f64; 6]; // weight, x, y, xx, yy, xy
            for i in r.saturating_sub(5)..(r + 6).min(24) {
                for j in c.saturating_sub(5)..(c + 6).min(24) {
                    let d2 = ((i as f64 - r as f64).powi(2) + (j as f64 - c as f64).powi(2)) / (2.0 * SIGMA * SIGMA);
                    let (w, a, b) = ((-d2).exp(), lx[i * 24 + j], ly[i * 24 + j]);
                    for (k, v) in [1.0, a, b, a * a, b * b, a * b].into_iter().enumerate() {
                        m[k] += w * v;
                    }
                }
            }
            let [_, a, b, aa, bb, ab] = m.map(|v| v / m[0]);
            sum += (2.0 * a * b + C1) * (2.0 * (ab - a * b) + C2) / ((a * a + b * b + C1) * (aa - a * a + bb - b * b + C2));
        }
        let n = (area.x1 - area.x0 + 1) * (area.y1 - area.y0 + 1);
        let want = sum / n as f64;
        assert!((ssim(&p, &t) - want).abs() < 1e-10, "{} vs {want}", ssim(&p, &t));
        assert!(want < 0.99, "the noise should show: {want}");
    }

    #[test]
    fn object_psnr_exposes_a_wrong_object_on_a_right_background() {
        // Truth: a 10x10 square at 0.8; prediction: the same square at 0.4, background exact.
        let sq = |v: f32| image(1, 64, move |_, y, x| if (30..40).contains(&y) && (30..40).contains(&x) { v } else { 0.0 });
        let (p, t) = (sq(0.4), sq(0.8));
        // Full frame: 100 errors of 0.4 in 4096 pixels; box: 18x18 = 324 pixels.
        let full = 10.0 * (4096.0 / (100.0 * 0.16f64)).log10();
        let boxed = 10.0 * (324.0 / (100.0 * 0.16f64)).log10();
        assert!((psnr(&p, &t) - full).abs() < 1e-4, "{}", psnr(&p, &t));
        assert!((object_psnr(&p, &t) - boxed).abs() < 1e-4, "{}", object_psnr(&p, &t));
        assert!(object_psnr(&p, &t) < psnr(&p, &t) - 10.0);
    }

    #[test]
    fn without_foreground_object_scores_fall_back_to_the_full_frame() {
        let (p, t) = (image(1, 16, |_, y, _| 0.01 * (y % 3) as f32), image(1, 16, |_, _, _| 0.0));
        assert_eq!(object_psnr(&p, &t), psnr(&p, &t));
        assert!(psnr(&p, &t) < PSNR_CAP);
        assert_eq!(mask_iou(&p, &t), 1.0);
    }

    /// Contours are black lines on white: scored against a white background the object box
    /// is the lines' (not the whole frame), the floor is an all-white image, and PSNR is the
    /// same as without the mapping.
    #[test]
    fn white_backgrounds_score_the_drawing_not_the_frame() {
        let truth = image(1, 64, |_, y, x| if y == 30 && (10..20).contains(&x) { 0.0 } else { 1.0 });
        let pred = image(1, 64, |_, y, x| if y == 31 && (10..20).contains(&x) { 0.2 } else { 1.0 });
        let s = Scores::on_background(&pred, &truth, 1.0);
        let inv = (from_background(&pred, 1.0), from_background(&truth, 1.0));
        assert_eq!(object_box(&inv.0, &inv.1), Some(PixelBox { x0: 6, y0: 26, x1: 23, y1: 35 }));
        assert!((s.psnr - psnr(&pred, &truth)).abs() < 1e-4, "values are mapped in f32");
        assert!(s.object_psnr < s.psnr - 10.0, "the box holds the lines: {s:?}");
        let floor = Scores::background_floor(&truth, 1.0);
        let white = image(1, 64, |_, _, _| 1.0);
        assert!((floor.psnr - psnr(&white, &truth)).abs() < 1e-4 && floor.iou == 0.0);
        assert_eq!((floor_name(1.0), floor_name(0.0)), ("all-white", "all-black"));
        assert_eq!(Scores::on_background(&pred, &truth, 0.0), Scores::of(&pred, &truth));
    }
}
