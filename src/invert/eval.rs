//! Inverse rendering measured on held-out samples of a dataset (`rendernet eval-invert`):
//! camera, light and radius errors against the known scene, and whose failure a wrong camera
//! is, the search's or the network's.

use super::{InvertOptions, Inverter, polar_unit};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::reference::{Image, Light, View};

/// A unit vector for `view`'s azimuth and elevation, for measuring pose errors as angles
/// (the angle between two views' vectors is the angle between their camera directions).
pub fn view_direction(view: &View) -> [f64; 3] {
    polar_unit(view.azimuth, view.elevation)
}

/// Unit vector towards the light in the camera frame ([`Light::direction`] in f64).
pub fn light_direction(light: &Light) -> [f64; 3] {
    polar_unit(light.azimuth, light.elevation)
}

/// Angle in degrees between two unit vectors.
pub fn angle_between(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d: f64 = (0..3).map(|i| a[i] * b[i]).sum();
    d.clamp(-1.0, 1.0).acos().to_degrees()
}

/// How far one inversion landed from the known scene.
#[derive(Clone, Copy, Debug)]
pub struct InvertError {
    /// Shape the sample shows.
    pub shape_id: u32,
    /// Angle between the true and recovered camera directions, degrees.
    pub pose_degrees: f64,
    /// The same for the camera the network's own image MSE picked (`Estimate::network_view`):
    /// equal to `pose_degrees` with [`super::Pick::Network`].
    pub network_pose_degrees: f64,
    /// Angle between the true and recovered light directions, degrees.
    pub light_degrees: f64,
    /// The same for the search's own light (`Estimate::search_light`: the exact light at the
    /// polished camera with `Pick::Exact`): equal to `light_degrees` without a light network.
    pub search_light_degrees: f64,
    /// Angle between the true light and the best light at the true camera
    /// ([`Inverter::light_optimum`]) of the network that picks the light (the light network
    /// when there is one, else the searching network), degrees: what no light search
    /// through it could improve on.
    pub light_optimum_degrees: f64,
    /// Whether the true light is on the camera's side of the object (its direction has a
    /// component towards the camera). A light behind lights only rims the camera sees, so
    /// its direction is far less determined by the image.
    pub light_in_front: bool,
    /// Angle between the true light and the best light for the exact renderer's own maps of
    /// the grid at the recovered camera ([`Inverter::light_exact`]), degrees: the light the
    /// shape-known inversion gets when it lets the ray marcher, not the network, draw the
    /// maps the light is fitted to.
    pub light_exact_degrees: f64,
    /// The same at the true camera: what the image and grid allow, with no network and no
    /// camera error in the way.
    pub light_exact_truth_degrees: f64,
    /// Image MSE over the search window after the search's refinement started at the true
    /// camera and the searching network's best grid light there ([`Inverter::refined_mse`]).
    pub truth_mse: f64,
    /// Image MSE over the search window at the estimate (`Estimate::curve`'s last value,
    /// scored the same way). A pose far off with `truth_mse < search_mse` is the search's
    /// failure (a better-scoring camera existed); with `truth_mse >= search_mse` the network's
    /// (its render from the wrong view explains the image better).
    pub search_mse: f64,
    /// Recovered radius over the true one.
    pub radius_ratio: f64,
    /// Image MSE of the re-render against the input.
    pub mse: f64,
    /// Wall time of the inversion.
    pub seconds: f64,
}

/// The reference Phong image of a sample of `ds`, or an error naming the dataset.
pub(super) fn phong_target<'a>(ds: &crate::data::Dataset, s: &'a crate::data::Sample) -> Result<&'a Image> {
    s.images.get("phong").ok_or_else(|| Error::Invalid(format!("{}: not a Phong dataset (no 'phong' images)", ds.dir().display())))
}

/// Inverts `samples` held-out samples of `ds` (spread over the split; 0 = all) from their
/// target images, with the grid known, and measures the errors. `progress(done, total)`.
pub fn evaluate(
    gpu: &Gpu,
    inv: &Inverter,
    ds: &crate::data::Dataset,
    samples: usize,
    o: &InvertOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<InvertError>> {
    let test = ds.split(crate::data::Split::Test);
    let n = test.spread(samples).count();
    let mut out = Vec::with_capacity(n);
    for (k, i) in test.spread(samples).enumerate() {
        let s = test.get(i)?;
        let target = phong_target(ds, &s)?;
        let t = std::time::Instant::now();
        let est = inv.invert(gpu, &s.grid, target, o, |_, _| {})?;
        let seconds = t.elapsed().as_secs_f64();
        // The searching network's best light at the truth starts its refinement from there
        // (truth_mse, compared with its own search_mse); the light network's, when there is
        // one, is the optimum its light pick could reach.
        let (own, _) = inv.light_optimum(gpu, &s.grid, target, &s.view)?;
        let optimum = match &inv.light_by {
            None => own,
            Some(by) => by.light_optimum(gpu, &s.grid, target, &s.view)?.0,
        };
        let exact = inv.light_exact(gpu, &s.grid, target, &est.view)?;
        let exact_truth = inv.light_exact(gpu, &s.grid, target, &s.view)?;
        let truth_mse = inv.refined_mse(gpu, &s.grid, target, &s.view, &own, o)?;
        let true_light = light_direction(&s.light);
        let light_off = |l: &Light| angle_between(true_light, light_direction(l));
        out.push(InvertError {
            shape_id: s.shape_id,
            pose_degrees: angle_between(view_direction(&s.view), view_direction(&est.view)),
            network_pose_degrees: angle_between(view_direction(&s.view), view_direction(&est.network_view)),
            light_degrees: light_off(&est.light),
            search_light_degrees: light_off(&est.search_light),
            light_optimum_degrees: light_off(&optimum),
            light_in_front: true_light[2] > 0.0,
            light_exact_degrees: light_off(&exact),
            light_exact_truth_degrees: light_off(&exact_truth),
            truth_mse,
            search_mse: *est.curve.last().expect("at least one step"),
            radius_ratio: est.view.radius / s.view.radius,
            mse: est.mse,
            seconds,
        });
        progress(k + 1, n);
    }
    Ok(out)
}
