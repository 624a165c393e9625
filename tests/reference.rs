//! The reference renderer against closed-form images: a smooth sphere grid must render as the
//! analytic Phong sphere and the analytic disk, renders are deterministic, the azimuth turns
//! an asymmetric shape (with a 360-degree period), and `rendernet truth` writes a PNG.

use rendernet::reference::{GBUF_CHANNELS, GpuGrid, Image, Light, Options, Part, RayMarcher, Shader, View};
use rendernet::{Gpu, Tensor};
use rendernet::voxel::{VoxelGrid, shapes};
use std::sync::OnceLock;

/// Grid side of the sphere test and the sphere's radius in voxels.
const N: usize = 48;
const R_VOX: f64 = 20.0;
/// Image side; small for lavapipe.
const S: u32 = 64;
/// Radius 1.65 makes the image 1 object unit wide (fov = 2 * 1.65 / 3.3), so the sphere
/// (radius 20/48 of the unit grid) spans 5/6 of the image.
const VIEW_RADIUS: f64 = 1.65;

fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new().expect("a GPU or lavapipe adapter"))
}

/// Occupancy `clamp(0.5 + (R - dist), 0, 1)` (voxel units) about the grid centre: a one-voxel
/// linear ramp whose 0.5 level set is the sphere of radius R.
fn sphere_grid() -> VoxelGrid {
    let c = N as f64 / 2.0 - 0.5;
    let occ = (0..N * N * N)
        .map(|i| {
            let (d, h, w) = (i / (N * N), (i / N) % N, i % N);
            let dist = ((d as f64 - c).powi(2) + (h as f64 - c).powi(2) + (w as f64 - c).powi(2)).sqrt();
            (0.5 + (R_VOX - dist)).clamp(0.0, 1.0) as f32
        })
        .collect();
    VoxelGrid::new([N; 3], occ).unwrap()
}

/// The sphere's radius in pixels and a pixel centre's offset from the image centre, in pixels
/// (x right, y up).
fn disk_coords(i: u32, j: u32) -> (f64, f64, f64) {
    let fov = 2.0 * VIEW_RADIUS / 3.3;
    let r_px = R_VOX / N as f64 / fov * S as f64;
    let x = j as f64 + 0.5 - S as f64 / 2.0;
    let y = S as f64 / 2.0 - (i as f64 + 0.5);
    (x, y, r_px)
}

/// The closed-form Phong image: orthographic sphere with normal (x, y, sqrt(1 - x^2 - y^2)),
/// the same light, background 0, clamped like the renderer.
fn analytic_phong(light: &Light) -> Vec<f64> {
    let l = light.direction().as_dvec3();
    let mut img = vec![0.0; 3 * (S * S) as usize];
    for i in 0..S {
        for j in 0..S {
            let (x, y, r) = disk_coords(i, j);
            let (x, y) = (x / r, y / r);
            if x * x + y * y >= 1.0 {
                continue;
            }
            let n = glam::DVec3::new(x, y, (1.0 - x * x - y * y).sqrt());
            let ndl = n.dot(l);
            let rz = 2.0 * ndl * n.z - l.z;
            let spec = if ndl > 0.0 { light.ks as f64 * rz.max(0.0).powf(light.shininess as f64) } else { 0.0 };
            for c in 0..3 {
                let v = light.colour[c] as f64 * (light.ambient as f64 + light.kd as f64 * ndl.max(0.0) + spec);
                img[(c as u32 * S * S + i * S + j) as usize] = v.clamp(0.0, 1.0);
            }
        }
    }
    img
}

fn renderer() -> RayMarcher {
    // One ray per pixel centre, as the analytic images are point-sampled.
    RayMarcher::new(gpu()).with_options(Options { supersample: 1, ..Options::default() })
}

fn render(grid: &VoxelGrid, view: &View, shader: Shader) -> Image {
    renderer().render(gpu(), grid, view, &Light::default(), shader, S).unwrap()
}

fn sphere_view() -> View {
    // An oblique pose, so the test also covers the rotation (a sphere must not care).
    View { azimuth: 37.0, elevation: 61.0, radius: VIEW_RADIUS }
}

#[test]
fn sphere_phong_matches_the_analytic_image() {
    let img = render(&sphere_grid(), &sphere_view(), Shader::Phong);
    assert_eq!(img.shape(), [3, S as usize, S as usize]);
    let want = analytic_phong(&Light::default());
    // Every pixel counts, silhouette and background included (no band needs excluding: the
    // marched boundary lands within a pixel of the analytic one).
    let se: f64 = img.data.iter().zip(&want).map(|(&g, &w)| (g as f64 - w).powi(2)).sum();
    let psnr = 10.0 * (1.0 / (se / want.len() as f64)).log10();
    eprintln!("sphere Phong PSNR {psnr:.2} dB over all {S}x{S} pixels");
    assert!(psnr > 35.0, "PSNR {psnr:.2} dB");
    // The same restricted to the disk's pixels, so the black background cannot carry it.
    let (mut se, mut count) = (0.0, 0usize);
    for i in 0..S {
        for j in 0..S {
            let (x, y, r) = disk_coords(i, j);
            if x * x + y * y < r * r {
                for c in 0..3 {
                    let k = (c * S * S + i * S + j) as usize;
                    se += (img.data[k] as f64 - want[k]).powi(2);
                    count += 1;
                }
            }
        }
    }
    let psnr_disk = 10.0 * (count as f64 / se).log10();
    eprintln!("sphere Phong PSNR inside the disk {psnr_disk:.2} dB over {} pixels", count / 3);
    assert!(psnr_disk > 33.0, "PSNR inside the disk {psnr_disk:.2} dB");
}

#[test]
fn sphere_mask_matches_the_analytic_disk() {
    let img = render(&sphere_grid(), &sphere_view(), Shader::Mask);
    assert_eq!(img.shape(), [1, S as usize, S as usize]);
    let (mut inter, mut union) = (0usize, 0usize);
    for i in 0..S {
        for j in 0..S {
            let (x, y, r) = disk_coords(i, j);
            let want = x * x + y * y < r * r;
            let got = img.get(0, i as usize, j as usize) >= 0.5;
            inter += (want && got) as usize;
            union += (want || got) as usize;
        }
    }
    let iou = inter as f64 / union as f64;
    eprintln!("sphere mask IoU {iou:.4}");
    assert!(iou > 0.98, "IoU {iou}");
    // Supersampled 3x3, the mask is the pixel's coverage: in [0, 1], and summed over the
    // image it is the disk's area in pixels.
    let ss = RayMarcher::new(gpu()).with_options(Options { supersample: 3, ..Options::default() });
    let img = ss.render(gpu(), &sphere_grid(), &sphere_view(), &Light::default(), Shader::Mask, S).unwrap();
    assert!(img.data.iter().all(|v| (0.0..=1.0).contains(v)), "coverage outside [0, 1]");
    let r = disk_coords(0, 0).2;
    let (area, want) = (img.data.iter().map(|&v| v as f64).sum::<f64>(), std::f64::consts::PI * r * r);
    eprintln!("supersampled coverage {area:.1} px, disk area {want:.1} px");
    assert!((area - want).abs() < 0.01 * want, "coverage {area} px against the disk's {want} px");
}

#[test]
fn sphere_depth_matches_the_analytic_depth() {
    let img = render(&sphere_grid(), &sphere_view(), Shader::Depth);
    let fov = 2.0 * VIEW_RADIUS / 3.3;
    let (mut sum, mut count, mut worst) = (0.0, 0usize, 0.0f64);
    for i in 0..S {
        for j in 0..S {
            let (x, y, r) = disk_coords(i, j);
            // Inside the disk, away from the rim, where depth is steep in the image and a
            // pixel's worth of boundary placement dominates.
            if x * x + y * y >= (r - 2.0) * (r - 2.0) {
                continue;
            }
            let z = (r * r - x * x - y * y).sqrt() * fov / S as f64; // object units
            let err = (img.get(0, i as usize, j as usize) as f64 - (1.0 + z) / 2.0).abs();
            sum += err;
            worst = worst.max(err);
            count += 1;
        }
    }
    // Depth error in voxels = 2 * err * N. The bisection places the crossing to ~1e-3 of a
    // step; what remains is the trilinear field's bias on a curved ramp (~0.05 voxel). Without
    // the bisection the error would be up to half a step (0.25 voxel on average).
    let (mean_vox, worst_vox) = (2.0 * sum / count as f64 * N as f64, 2.0 * worst * N as f64);
    eprintln!("sphere depth error: mean {mean_vox:.3} voxel, worst {worst_vox:.3} voxel over {count} pixels");
    assert!(mean_vox < 0.1 && worst_vox < 0.4, "mean {mean_vox} worst {worst_vox} voxels");
}

#[test]
fn ambient_occlusion_is_open_on_a_sphere_and_dark_in_corners() {
    // A convex sphere occludes nothing of itself.
    let img = render(&sphere_grid(), &sphere_view(), Shader::AmbientOcclusion);
    let mask = render(&sphere_grid(), &sphere_view(), Shader::Mask);
    let inside: Vec<f32> =
        img.data.iter().zip(&mask.data).filter(|(_, m)| **m == 1.0).map(|(a, _)| *a).collect();
    let min = inside.iter().cloned().fold(1.0f32, f32::min);
    assert!(min > 0.9, "sphere AO min {min}");
    // A chair has inner corners (seat against back, legs under the seat).
    let chair = shapes::chair(0).to_grid(32).unwrap();
    let img = render(&chair, &View { azimuth: 20.0, elevation: 70.0, radius: 3.0 }, Shader::AmbientOcclusion);
    let dark = img.data.iter().filter(|&&v| v > 0.0 && v < 0.8).count();
    eprintln!("chair AO: {dark} pixels below 0.8, min {}", img.data.iter().filter(|&&v| v > 0.0).cloned().fold(1.0f32, f32::min));
    assert!(dark > 10, "only {dark} occluded pixels on a chair");
}

#[test]
fn rendering_is_deterministic() {
    let grid = shapes::chair(3).to_grid(32).unwrap();
    let view = View { azimuth: 123.0, elevation: 50.0, radius: 3.0 };
    for shader in [Shader::Phong, Shader::AmbientOcclusion, Shader::Contour] {
        let a = render(&grid, &view, shader);
        let b = render(&grid, &view, shader);
        assert!(a.data.iter().zip(&b.data).all(|(x, y)| x.to_bits() == y.to_bits()), "{shader:?} differs");
    }
}

#[test]
fn azimuth_turns_the_shape_with_period_360() {
    let grid = shapes::chair(1).to_grid(40).unwrap();
    let at = |az: f64| render(&grid, &View { azimuth: az, elevation: 70.0, radius: 3.3 }, Shader::Phong);
    let (a0, a90, a360) = (at(0.0), at(90.0), at(360.0));
    assert_eq!(a0.data, a360.data, "azimuth 0 and 360 must give identical images");
    let diff = a0.data.iter().zip(&a90.data).filter(|(x, y)| (*x - *y).abs() > 0.1).count();
    assert!(diff > 100, "azimuth 0 and 90 differ in only {diff} values");
    // Both see something.
    assert!(a0.data.iter().any(|&v| v > 0.2) && a90.data.iter().any(|&v| v > 0.2));
}

#[test]
fn every_shader_renders_within_range() {
    let grid = shapes::chair(2).to_grid(32).unwrap();
    let view = View::default();
    for shader in Shader::ALL {
        let img = render(&grid, &view, shader);
        assert_eq!(img.channels, shader.channels());
        assert!(img.data.iter().all(|v| (0.0..=1.0).contains(v)), "{shader:?} outside [0, 1]");
        let mask = render(&grid, &view, Shader::Mask);
        let bg = img.get(0, 0, 0);
        assert_eq!(mask.get(0, 0, 0), 0.0);
        assert_eq!(bg, if shader == Shader::Contour { 1.0 } else { 0.0 }, "{shader:?} background");
        assert!(img.data.iter().any(|&v| v != bg), "{shader:?} is blank");
    }
}

/// A [`Part`] draws the whole image's pixels: three parts of a chair's supersampled image
/// (inside; at the frame's left edge; running 9 pixels past its right and bottom edges) match
/// the whole image's pixels (contours away from the part's edge), and the rows and
/// columns past the frame are marched, not left blank. Tolerance: the ray origins are
/// computed from the part's centre, so they differ from the whole image's by f32 rounding
/// (~1e-7 object units); a grazing ray can flip a sub-pixel, so 1 value plus 2 in 1000 may
/// differ by up to one sub-pixel's share, every other by 1e-4 (measured on lavapipe: none
/// differ). Contours are compared 5 pixels from the part's and the frame's edges, where
/// neither image clamps its neighbours.
#[test]
fn a_part_draws_the_whole_images_pixels() {
    let grid = shapes::chair(4).to_grid(24).unwrap();
    let view = View { azimuth: 213.0, elevation: 58.0, radius: 1.6 };
    let r = RayMarcher::new(gpu()).with_options(Options { supersample: 2, ..Options::default() });
    let g = GpuGrid::upload(gpu(), &grid).unwrap();
    let shaders = [Shader::Phong, Shader::Normal, Shader::Mask, Shader::Depth, Shader::Contour];
    let draw = |side: usize, part: Option<Part>| -> Vec<Image> {
        let outs: Vec<Tensor> = shaders.iter().map(|s| Tensor::zeros(gpu(), &[s.channels(), side, side]).unwrap()).collect();
        let pairs: Vec<(Shader, &Tensor)> = shaders.iter().copied().zip(&outs).collect();
        gpu().run(|pass| r.record_part(gpu(), pass, &g, &view, &Light::default(), &pairs, part)).unwrap();
        shaders.iter().zip(&outs).map(|(s, t)| Image { channels: s.channels(), size: side, data: t.to_vec(gpu()).unwrap() }).collect()
    };
    let frame = 37;
    let whole = draw(frame, None);
    for (x0, y0, side) in [(7, 5, 19), (0, 11, 13), (28, 29, 17)] {
        let part = draw(side, Some(Part { frame: frame as u32, x0: x0 as u32, y0: y0 as u32 }));
        for (k, s) in shaders.iter().enumerate() {
            let (mut n, mut off) = (0, 0);
            for c in 0..s.channels() {
                // Contour lines read neighbours up to two voxels (here 4 pixels) away, which
                // the part clamps at its edge: compared inside, 5 pixels from its edge.
                let m = if *s == Shader::Contour { 5 } else { 0 };
                let clear = |v: usize, len: usize| v >= m && v + m < len;
                let inside = |y: usize, x: usize| clear(y0 + y, frame) && clear(x0 + x, frame) && clear(y, side) && clear(x, side);
                for (y, x) in (0..side).flat_map(|y| (0..side).map(move |x| (y, x))).filter(|&(y, x)| inside(y, x)) {
                    let d = (part[k].get(c, y, x) - whole[k].get(c, y0 + y, x0 + x)).abs();
                    assert!(d <= 0.26, "{s:?} part at ({x0}, {y0}) differs by {d} at ({x}, {y})");
                    n += 1;
                    off += (d > 1e-4) as usize;
                }
            }
            assert!(off <= 1 + n / 500, "{s:?} part at ({x0}, {y0}): {off} of {n} values differ");
        }
    }
    // Past the frame's edge the chair is still drawn: at radius 1 the frame (0.6 object units
    // wide) cuts through the chair.
    let view = View { radius: 1.0, ..view };
    let outs = [Tensor::zeros(gpu(), &[1, 24, 24]).unwrap()];
    gpu().run(|pass| r.record_part(gpu(), pass, &g, &view, &Light::default(), &[(Shader::Mask, &outs[0])], Some(Part { frame: 16, x0: 4, y0: 4 }))).unwrap();
    let beyond = Image { channels: 1, size: 24, data: outs[0].to_vec(gpu()).unwrap() };
    let outside = (0..24).flat_map(|y| (0..24).map(move |x| (y, x))).filter(|&(y, x)| y >= 12 || x >= 12);
    assert!(outside.map(|(y, x)| beyond.get(0, y, x)).any(|m| m > 0.5), "nothing drawn past the frame's edge");
}

/// The G-buffer alone, at one sample per pixel, holds what the shading pass draws for
/// Normal (encoded `(n + 1) / 2`), Albedo and Mask, within f32 rounding (1e-6), and a wrong
/// G-buffer shape is an error.
#[test]
fn the_g_buffer_holds_the_normal_albedo_and_mask_images() {
    let grid = shapes::chair(2).to_grid(20).unwrap();
    let view = View { azimuth: 41.0, elevation: 66.0, radius: 2.2 };
    let r = renderer();
    let g = GpuGrid::upload(gpu(), &grid).unwrap();
    let side = 29;
    let gbuf = Tensor::zeros(gpu(), &[GBUF_CHANNELS, side, side]).unwrap();
    gpu().run(|pass| r.record_gbuffer(gpu(), pass, &g, &view, None, false, &gbuf)).unwrap();
    let gb = gbuf.to_vec(gpu()).unwrap();
    let plane = side * side;
    let (normal, albedo, mask) = (render_sized(&grid, &view, Shader::Normal, side), render_sized(&grid, &view, Shader::Albedo, side), render_sized(&grid, &view, Shader::Mask, side));
    assert!(gb[..plane].iter().any(|&m| m == 1.0) && gb[..plane].contains(&0.0), "the chair should cover part of the image");
    for k in 0..plane {
        let hit = gb[k] != 0.0;
        assert_eq!(mask.data[k], if hit { 1.0 } else { 0.0 }, "mask at {k}");
        for c in 0..3 {
            let n = if hit { (gb[(2 + c) * plane + k] + 1.0) * 0.5 } else { 0.0 };
            let a = if hit { gb[(5 + c) * plane + k] } else { 0.0 };
            assert!((normal.data[c * plane + k] - n).abs() < 1e-6 && (albedo.data[c * plane + k] - a).abs() < 1e-6, "channel {c} at {k}");
        }
    }
    let bad = Tensor::zeros(gpu(), &[GBUF_CHANNELS - 1, side, side]).unwrap();
    assert!(gpu().run(|pass| r.record_gbuffer(gpu(), pass, &g, &view, None, false, &bad)).is_err());
}

fn render_sized(grid: &VoxelGrid, view: &View, shader: Shader, side: usize) -> Image {
    renderer().render(gpu(), grid, view, &Light::default(), shader, side as u32).unwrap()
}

#[test]
fn a_part_outside_its_frame_is_an_error() {
    let grid = shapes::chair(0).to_grid(16).unwrap();
    let g = GpuGrid::upload(gpu(), &grid).unwrap();
    let out = Tensor::zeros(gpu(), &[1, 8, 8]).unwrap();
    for part in [Part { frame: 0, x0: 0, y0: 0 }, Part { frame: 8, x0: 8, y0: 0 }, Part { frame: 8, x0: 0, y0: 9 }] {
        let r = gpu().run(|pass| renderer().record_part(gpu(), pass, &g, &View::default(), &Light::default(), &[(Shader::Mask, &out)], Some(part)));
        assert!(r.is_err(), "{part:?} accepted");
    }
}

#[test]
fn bad_arguments_are_errors_not_panics() {
    let grid = shapes::chair(0).to_grid(16).unwrap();
    let r = renderer();
    let l = Light::default();
    assert!(r.render(gpu(), &grid, &View::default(), &l, Shader::Phong, 0).is_err());
    let bad_view = View { radius: 0.0, ..View::default() };
    assert!(r.render(gpu(), &grid, &bad_view, &l, Shader::Phong, 8).is_err());
    let bad_view = View { elevation: 200.0, ..View::default() };
    assert!(r.render(gpu(), &grid, &bad_view, &l, Shader::Phong, 8).is_err());
    let bad_light = Light { ks: f32::NAN, ..l };
    assert!(r.render(gpu(), &grid, &View::default(), &bad_light, Shader::Phong, 8).is_err());
    let bad = RayMarcher::new(gpu()).with_options(Options { supersample: 0, ..Options::default() });
    assert!(bad.render(gpu(), &grid, &View::default(), &l, Shader::Phong, 8).is_err());
}

#[test]
fn truth_cli_writes_a_png() {
    let dir = std::env::temp_dir().join(format!("rendernet-truth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("x.png");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rendernet"))
        .args(["truth", "--size", "48", "--resolution", "32", "--shader", "toon", "--out"])
        .arg(&png)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("rendered the embedded Stanford bunny"), "{stdout}");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_rendernet"))
        .args(["truth", "--shader", "nope"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    std::fs::remove_dir_all(&dir).ok();
}

/// The analytic sphere normal `(x, y, sqrt(1 - x^2 - y^2))` at pixel `(i, j)` when the pixel
/// lies at least `rim` pixels inside the disk.
fn sphere_normal(i: u32, j: u32, rim: f64) -> Option<glam::DVec3> {
    let (x, y, r) = disk_coords(i, j);
    (x * x + y * y < (r - rim) * (r - rim)).then(|| {
        let (x, y) = (x / r, y / r);
        glam::DVec3::new(x, y, (1.0 - x * x - y * y).sqrt())
    })
}

/// Normal, albedo and toon against closed forms on the sphere: the encoded normal is the
/// analytic one, an uncoloured grid has albedo 1 everywhere, and toon is the diffuse term
/// quantised up to the next of four bands (0, 1/3, 2/3, 1), pixel by pixel.
#[test]
fn sphere_normal_albedo_and_toon_match_closed_forms() {
    let (grid, view) = (sphere_grid(), sphere_view());
    let (normal, albedo, toon) = (render(&grid, &view, Shader::Normal), render(&grid, &view, Shader::Albedo), render(&grid, &view, Shader::Toon));
    let l = Light::default();
    let ld = l.direction().as_dvec3();
    let (mut n_err, mut count, mut toon_ok, mut toon_count) = (0.0f64, 0usize, 0usize, 0usize);
    let mut bands = std::collections::BTreeSet::new();
    for i in 0..S {
        for j in 0..S {
            // Two pixels in from the rim: the march's silhouette is within a pixel.
            let Some(n) = sphere_normal(i, j, 2.0) else { continue };
            let got = glam::DVec3::from_array(std::array::from_fn(|c| 2.0 * normal.get(c, i as usize, j as usize) as f64 - 1.0));
            n_err += (got - n).length();
            count += 1;
            for c in 0..3 {
                assert_eq!(albedo.get(c, i as usize, j as usize), 1.0, "albedo at ({i}, {j})");
            }
            // Toon, away from band edges (where the marched normal may fall either side) and
            // from the outline pixels (0).
            let ndl = n.dot(ld).clamp(0.0, 1.0);
            let got = toon.get(0, i as usize, j as usize) as f64;
            if (3.0 * ndl - (3.0 * ndl).round()).abs() < 0.05 || got == 0.0 {
                continue;
            }
            let q = (3.0 * ndl).ceil() / 3.0;
            let want = (l.colour[0] as f64 * (l.ambient as f64 + l.kd as f64 * q)).clamp(0.0, 1.0);
            toon_count += 1;
            toon_ok += usize::from((got - want).abs() < 1e-3);
            bands.insert((q * 3.0).round() as u32);
        }
    }
    let mean = n_err / count as f64;
    eprintln!("sphere normal error {mean:.4} over {count} pixels; toon {toon_ok}/{toon_count} pixels exact, bands {bands:?}");
    // Measured 0.033: the normal is the gradient of a 48^3 grid's smoothed field. A swapped
    // axis or a flipped sign errs by ~1.
    assert!(mean < 0.05, "mean normal error {mean}");
    assert!(toon_ok as f64 >= 0.97 * toon_count as f64, "toon: {toon_ok} of {toon_count} pixels on the analytic band");
    assert!(bands.len() >= 3, "bands seen: {bands:?}");
}

/// A slab's open face against the same slab with a wall standing on it: the face is open
/// (AO near 1) alone, and darkens along the inner corner once the wall is there, while the
/// pixels away from the wall keep their value.
#[test]
fn ambient_occlusion_darkens_an_inner_corner() {
    let n = 32;
    let grid = |wall: bool| {
        let occ = (0..n * n * n)
            .map(|i| {
                let (d, h, w) = (i / (n * n), (i / n) % n, i % n);
                let inner = |v: usize| (4..28).contains(&v);
                let slab = inner(d) && inner(w) && (4..8).contains(&h);
                let upright = wall && inner(d) && inner(h) && (4..8).contains(&w);
                f32::from(u8::from(slab || upright))
            })
            .collect();
        VoxelGrid::new([n; 3], occ).unwrap()
    };
    let view = View { azimuth: 60.0, elevation: 50.0, radius: 3.0 };
    let (open, corner) = (render(&grid(false), &view, Shader::AmbientOcclusion), render(&grid(true), &view, Shader::AmbientOcclusion));
    let mask = render(&grid(false), &view, Shader::Mask);
    let on_slab: Vec<usize> = (0..mask.data.len()).filter(|&k| mask.data[k] == 1.0 && corner.data[k] > 0.0).collect();
    let open_px = on_slab.iter().filter(|&&k| open.data[k] > 0.9).count();
    let darkened = on_slab.iter().filter(|&&k| open.data[k] > 0.9 && corner.data[k] < 0.8).count();
    let kept = on_slab.iter().filter(|&&k| (open.data[k] - corner.data[k]).abs() < 0.02).count();
    eprintln!("slab: {} pixels, {open_px} open alone, {darkened} darkened by the wall, {kept} unchanged", on_slab.len());
    assert!(on_slab.len() > 200, "the slab covers only {} pixels", on_slab.len());
    assert!(open_px as f64 > 0.9 * on_slab.len() as f64, "a lone slab's face is open: {open_px} of {}", on_slab.len());
    assert!(darkened as f64 > 0.05 * on_slab.len() as f64, "the wall darkens {darkened} of {} pixels", on_slab.len());
    assert!(kept as f64 > 0.3 * on_slab.len() as f64, "only {kept} pixels kept their value");
}

/// Contour images with and without suggestive contours (`suggestive_bend` infinite), two
/// sub-pixels per axis as the datasets render them.
fn contours_with_and_without_suggestive(grid: &VoxelGrid, view: &View) -> (Image, Image) {
    let at = |bend: f32| {
        let o = Options { supersample: 2, suggestive_bend: bend, ..Options::default() };
        RayMarcher::new(gpu()).with_options(o).render(gpu(), grid, view, &Light::default(), Shader::Contour, S).unwrap()
    };
    (at(Options::default().suggestive_bend), at(f32::INFINITY))
}

/// A sphere's `n.v` only grows from the rim inwards, so it has no suggestive contour: the
/// contour image is its silhouette alone, the same with suggestive contours on or off.
#[test]
fn a_sphere_has_no_suggestive_contours() {
    let (on, off) = contours_with_and_without_suggestive(&sphere_grid(), &sphere_view());
    let lines = off.data.iter().filter(|&&v| v < 0.5).count();
    assert!(lines > 50, "the silhouette drew only {lines} pixels");
    assert_eq!(on.data, off.data, "suggestive contours drawn on a sphere");
}

/// A Gaussian bump on a flat slab, seen obliquely: `n.v` dips on the bump's flanks, so
/// suggestive contours appear there (and nowhere on the flat, where `n.v` is constant),
/// inside the object, where neither the silhouette nor a depth jump draws a line.
#[test]
fn a_bump_seen_obliquely_has_suggestive_contours_on_it() {
    // The steepest flank (31 degrees) stays below the line of sight (35 degrees), so no part
    // of the bump hides another: every line on it is a suggestive contour.
    let (base, amp, sigma) = (14.0, 6.0, 6.0);
    let c = N as f64 / 2.0 - 0.5;
    let surface = |d: f64, w: f64| base + amp * (-((d - c).powi(2) + (w - c).powi(2)) / (2.0 * sigma * sigma)).exp();
    // A one-voxel ramp to 0 on every side, a few voxels inside the grid's faces, so the slab
    // has clean edges rather than the grid's boundary.
    let occ = (0..N * N * N)
        .map(|i| {
            let (d, h, w) = (i / (N * N), (i / N) % N, i % N);
            let (d, h, w) = (d as f64, h as f64, w as f64);
            let inside = (surface(d, w) - h).min(h - 3.0).min(d - 3.0).min(N as f64 - 4.0 - d).min(w - 3.0).min(N as f64 - 4.0 - w);
            (0.5 + inside).clamp(0.0, 1.0) as f32
        })
        .collect();
    let grid = VoxelGrid::new([N; 3], occ).unwrap();
    let view = View { azimuth: 20.0, elevation: 55.0, radius: 2.4 };
    let (on, off) = contours_with_and_without_suggestive(&grid, &view);
    // The bump's axis (object x = z = 0, up the y axis) in the image: pixels within 3 sigma
    // of it, at any height, count as on the bump.
    let r = view.rotation().as_dmat3();
    let fov = view.fov();
    let to_px = |p: glam::DVec3| {
        let q = r * p;
        (q.x / fov + 0.5) * S as f64 - 0.5
    };
    let unit = N as f64;
    let (x_lo, x_hi) = (to_px(glam::DVec3::new(0.0, 0.0, 0.0)), to_px(glam::DVec3::new(0.0, 1.0, 0.0)));
    let reach = 3.0 * sigma / unit / fov * S as f64;
    let mut extra = 0;
    for i in 0..S as usize {
        for j in 0..S as usize {
            let (a, b) = (on.get(0, i, j), off.get(0, i, j));
            assert!(a <= b, "suggestive contours only add ink, at ({i}, {j})");
            if a < b - 0.2 {
                extra += 1;
                let j = j as f64;
                assert!(j > x_lo.min(x_hi) - reach && j < x_lo.max(x_hi) + reach, "a suggestive line off the bump, at ({i}, {j})");
            }
        }
    }
    eprintln!("bump: {extra} pixels of suggestive contour");
    assert!(extra >= 5, "only {extra} pixels of suggestive contour on the bump");
}
