//! Camera pose and light of the reference renderer, with the exact mapping from a grid to
//! the image so the learned model's resampling can match it.
//!
//! # Frames
//! **Object frame.** A grid `[D, H, W]` is centred at the origin and scaled so its longest
//! side is 1 (the object's bounding box normalised to unit size, as the voxelisers make the
//! object fill the grid): the centre of voxel `(d, h, w)` sits at
//! `x = (d + 0.5 - D/2) / L`, `y = (h + 0.5 - H/2) / L`, `z = (w + 0.5 - W/2) / L`,
//! `L = max(D, H, W)`. So `x` ↔ D, `y` ↔ H (up), `z` ↔ W (the procedural shapes' front).
//!
//! **Camera frame.** `x` right, `y` up, `z` towards the camera; rays travel along `-z`.
//! An object point `p` has camera coordinates `c = R p` with
//! `R = Rx(90° - elevation) · Ry(azimuth)`, where `Ry(a) = [[cos a, 0, sin a], [0, 1, 0],
//! [-sin a, 0, cos a]]` turns about the up (H) axis and `Rx(t) = [[1, 0, 0], [0, cos t,
//! -sin t], [0, sin t, cos t]]` tilts about the image-horizontal axis. In words: the object
//! is turned by the azimuth about its up axis, then tilted by `elevation - 90°` so the camera
//! rises above it for elevations below 90°. The camera therefore sits in direction
//! `R^T (0,0,1) = (-sin az · sin el, cos el, cos az · sin el)` of the object frame: azimuth 0,
//! elevation 90 looks at the object's front (+z, +W) with +x (+D) to the right; elevation 10
//! looks almost straight down.
//!
//! **Image.** Orthographic. The image is `fov = 2 / scale` object units wide and high, with
//! `scale = 3.3 / radius` (the original code's convention): at radius 3.3 the unit cube spans
//! half the image, as the original's 64³ grid inside a 128³ resampled grid. Pixel `(row i,
//! col j)` of an `S x S` image (row 0 at the top) shows the ray through camera-plane point
//! `u = ((j + 0.5)/S - 0.5) · fov`, `v = (0.5 - (i + 0.5)/S) · fov`, travelling from `z = +1`
//! to `z = -1` (the unit cube's corners stay within `sqrt(3)/2`).

use glam::{DMat3, DVec3, Mat3, Vec3};

/// Radius at which the object's unit bounding box spans half the image (scale 1).
pub const RADIUS_AT_SCALE_ONE: f64 = 3.3;

/// A camera pose, in the paper's terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Degrees about the up axis; any finite value (the paper samples 0..359). Reduced
    /// modulo 360 before use, so 0 and 360 give identical images.
    pub azimuth: f64,
    /// Polar angle in degrees, 0..=180: 90 is horizontal, below 90 looks down on the object
    /// (the paper samples 10..170).
    pub elevation: f64,
    /// Camera distance; only its scale `3.3 / radius` matters for an orthographic camera
    /// (the paper samples 3..6.3).
    pub radius: f64,
}

impl Default for View {
    /// A three-quarter view from slightly above, at scale 1.
    fn default() -> Self {
        View { azimuth: 30.0, elevation: 70.0, radius: RADIUS_AT_SCALE_ONE }
    }
}

impl View {
    /// `3.3 / radius`: image magnification relative to radius 3.3.
    pub fn scale(&self) -> f64 {
        RADIUS_AT_SCALE_ONE / self.radius
    }

    /// Image width (= height) in object units: `2 / scale`.
    pub fn fov(&self) -> f64 {
        2.0 / self.scale()
    }

    /// `R`, object frame to camera frame (see the module docs).
    pub fn rotation(&self) -> Mat3 {
        let az = self.azimuth.rem_euclid(360.0).to_radians();
        let t = (90.0 - self.elevation).to_radians();
        let ry = DMat3::from_cols(
            DVec3::new(az.cos(), 0.0, -az.sin()),
            DVec3::Y,
            DVec3::new(az.sin(), 0.0, az.cos()),
        );
        let rx = DMat3::from_cols(
            DVec3::X,
            DVec3::new(0.0, t.cos(), t.sin()),
            DVec3::new(0.0, -t.sin(), t.cos()),
        );
        (rx * ry).as_mat3()
    }

    /// Errors unless the angles are finite, elevation lies in 0..=180 and radius is positive.
    pub fn validate(&self) -> Result<(), String> {
        let field = |name: &str, v: f64, check: Result<(), String>| check.map_err(|m| format!("{name} {v}: {m}"));
        field("azimuth", self.azimuth, check_angle(self.azimuth))?;
        field("elevation", self.elevation, check_polar(self.elevation))?;
        field("radius", self.radius, check_radius(self.radius))
    }
}

// One check per kind of value, shared by `View::validate` and the CLI's camera and light
// flags, so a bad value gets the same range whichever way it comes in. Each says what the
// value must be; the caller prefixes its own name for it (a field, a flag).

/// An azimuth: any finite number of degrees.
pub fn check_angle(deg: f64) -> Result<(), String> {
    if deg.is_finite() { Ok(()) } else { Err("must be a finite number of degrees".into()) }
}

/// A polar angle (camera or light elevation): degrees in 0..=180.
pub fn check_polar(deg: f64) -> Result<(), String> {
    if (0.0..=180.0).contains(&deg) { Ok(()) } else { Err("must lie in 0..=180 (degrees)".into()) }
}

/// A camera radius: positive and finite.
pub fn check_radius(r: f64) -> Result<(), String> {
    if r.is_finite() && r > 0.0 { Ok(()) } else { Err("must be positive and finite".into()) }
}

/// A directional light and the Phong material constants.
///
/// Shading: `I = colour * (albedo * (ambient + kd * max(0, n·l)) + ks * max(0, r·v)^shininess)`
/// with `v = (0, 0, 1)` (orthographic), `r = 2 (n·l) n - l`, the specular term dropped where
/// `n·l <= 0` (no highlights on the unlit side), and the result clamped to `[0, 1]` because
/// targets feed a sigmoid-headed network.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Degrees, relative to the camera: positive moves the light to the image's right.
    pub azimuth: f64,
    /// Polar degrees relative to the camera's up axis: 90 is level with the camera, smaller
    /// is higher. With azimuth 0 and elevation 90 the light shines from the camera.
    pub elevation: f64,
    /// RGB colour (intensity) of the light.
    pub colour: [f32; 3],
    /// Ambient term (the original code's 0.1).
    pub ambient: f32,
    /// Diffuse weight (the original code's 0.9).
    pub kd: f32,
    /// Specular weight.
    pub ks: f32,
    /// Specular exponent.
    pub shininess: f32,
}

impl Default for Light {
    /// White light from the upper right front; ambient 0.1, kd 0.9, ks 0.3, shininess 20.
    fn default() -> Self {
        Light {
            azimuth: 30.0,
            elevation: 60.0,
            colour: [1.0; 3],
            ambient: 0.1,
            kd: 0.9,
            ks: 0.3,
            shininess: 20.0,
        }
    }
}

impl Light {
    /// Unit vector towards the light in the camera frame:
    /// `(sin az · sin el, cos el, cos az · sin el)`.
    pub fn direction(&self) -> Vec3 {
        let (az, el) = (self.azimuth.to_radians(), self.elevation.to_radians());
        DVec3::new(az.sin() * el.sin(), el.cos(), az.cos() * el.sin()).as_vec3()
    }

    /// Errors unless every value is finite and the weights are non-negative.
    pub fn validate(&self) -> Result<(), String> {
        let vals = [self.azimuth as f32, self.elevation as f32, self.ambient, self.kd, self.ks, self.shininess];
        if vals.iter().chain(&self.colour).any(|v| !v.is_finite()) {
            return Err("light parameters must be finite".into());
        }
        if self.ambient < 0.0 || self.kd < 0.0 || self.ks < 0.0 || self.shininess < 0.0 {
            return Err("light ambient, kd, ks and shininess must be non-negative".into());
        }
        Ok(())
    }
}
