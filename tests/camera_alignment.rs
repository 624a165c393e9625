//! The network's camera grid must line up with the reference renderer's image, or no
//! amount of training can fix it (convolutions only see local neighbourhoods). Resample a
//! chair with `pose_for_view`, take its silhouette (max over depth), and compare it with the
//! renderer's mask at the camera grid's resolution, over several views and a crop.

use rendernet::nn::camera::{input_dims, input_values, pose_for_view};
use rendernet::ops::resample;
use rendernet::reference::{Light, RayMarcher, Shader, View};
use rendernet::voxel::shapes;
use rendernet::{Gpu, Tensor};

fn silhouette_iou(gpu: &Gpu, view: View, crop: Option<[usize; 4]>) -> f64 {
    let r = 32;
    let cam = 48;
    let grid = shapes::chair(5).to_grid(r).unwrap();
    let x = Tensor::from_slice(gpu, &[1, 1, r, r, r], &input_values(&grid)).unwrap();
    let [h0, w0, hh, ww] = crop.unwrap_or([0, 0, cam, cam]);
    let pose = Tensor::from_slice(gpu, &[1, 6], &pose_for_view(&view, r, cam, crop)).unwrap();
    let y = Tensor::zeros(gpu, &[1, 1, cam, hh, ww]).unwrap();
    gpu.run(|p| resample::forward(gpu, p, &x, &pose, &y)).unwrap();
    let y = y.to_vec(gpu).unwrap();
    let mask = RayMarcher::new(gpu).render(gpu, &grid, &view, &Light::default(), Shader::Mask, cam as u32).unwrap();
    let (mut inter, mut union) = (0.0, 0.0);
    for i in 0..hh {
        for j in 0..ww {
            let sil = (0..cam).map(|d| y[(d * hh + i) * ww + j]).fold(0.0f32, f32::max) > 0.5;
            let m = mask.get(0, h0 + i, w0 + j) > 0.5;
            inter += (sil && m) as u32 as f64;
            union += (sil || m) as u32 as f64;
        }
    }
    assert!(union > 20.0, "the chair should cover some pixels ({union})");
    inter / union
}

#[test]
fn resampled_silhouette_matches_the_rendered_mask() {
    let gpu = Gpu::new().unwrap();
    assert_eq!(input_dims([4, 5, 6]), [6, 5, 4]);
    let mut ious = Vec::new();
    for (az, el, radius) in [(30.0, 70.0, 3.3), (200.0, 120.0, 4.5), (95.0, 20.0, 3.0), (310.0, 160.0, 6.0), (140.0, 60.0, 3.5)] {
        let view = View { azimuth: az, elevation: el, radius };
        let iou = silhouette_iou(&gpu, view, None);
        // Trilinear occupancy at 0.5 vs a smooth iso-surface ray-marched at pixel centres:
        // they differ by about a voxel along edges; a mirrored or rotated mapping gives < 0.5.
        eprintln!("view {view:?}: IoU {iou:.3}");
        ious.push(iou);
    }
    // Trilinear occupancy at 0.5 vs a smooth iso-surface ray-marched at pixel centres differ
    // by about a voxel along edges, which costs most on small, thin views (0.75 measured at
    // radius 6); a flipped azimuth gives a mean of 0.58 and a crop mismatch 0.47.
    let mean = ious.iter().sum::<f64>() / ious.len() as f64;
    assert!(ious.iter().all(|&i| i > 0.7) && mean > 0.88, "silhouette IoUs {ious:?}");
    let iou = silhouette_iou(&gpu, View { azimuth: 30.0, elevation: 70.0, radius: 3.3 }, Some([8, 16, 24, 20]));
    assert!(iou > 0.8, "crop: silhouette IoU {iou}");
}
