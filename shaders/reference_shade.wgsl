// Reference renderer, pass 2: one invocation per output pixel shades the G-buffer written by
// reference_march.wgsl ([9, N, N], N = size * ss) and averages its ss x ss sub-pixels into
// the image [channels, size, size]. Modes (src/reference/mod.rs, `Shader`):
// 0 Phong, 1 albedo, 2 normal, 3 depth, 4 mask, 5 toon, 6 contour, 7 ambient occlusion.
// The background is 0 except for contour (black lines on white).

struct Params {
    size: u32, ss: u32, mode: u32, channels: u32,
    lx: f32, ly: f32, lz: f32, ambient: f32, // light direction (towards the light, camera frame)
    cr: f32, cg: f32, cb: f32, kd: f32,       // light colour, diffuse weight
    ks: f32, shininess: f32,
    depth_jump: f32, // depth difference (object units) that marks an occluding contour
    crease_cos: f32, // neighbouring normals with a smaller cosine mark a crease
    crease_step: i32, // sub-pixels between the normals compared: half a voxel or one pixel,
                      // as the smoothed normals turn over a voxel or two, not over one pixel
    sc_step: f32,     // sub-pixels over which the slope of n.v is measured (two voxels)
    sc_half: f32,     // half an output pixel in sub-pixels: where the slope is measured
    sc_min_bend: f32, // how much n.v must rise on both sides (second difference) to count
    sc_max_cos: f32,  // n.v above this (facing the camera) never holds a suggestive contour
}
@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> gbuf: array<f32>;
@group(0) @binding(2) var<storage, read_write> img: array<f32>;

fn g(c: u32, x: i32, y: i32) -> f32 {
    let n = p.size * p.ss;
    let xc = u32(clamp(x, 0, i32(n) - 1));
    let yc = u32(clamp(y, 0, i32(n) - 1));
    return gbuf[c * n * n + yc * n + xc];
}

fn normal(x: i32, y: i32) -> vec3<f32> {
    return vec3<f32>(g(2u, x, y), g(3u, x, y), g(4u, x, y));
}

// Whether a hit sub-pixel lies on a line: a neighbour one output pixel away (ss sub-pixels)
// is background (silhouette) or lies behind by more than depth_jump (occluding contour), or
// one crease_step away faces a clearly different way (crease).
fn on_line(x: i32, y: i32) -> bool {
    let s = i32(p.ss);
    let z = g(1u, x, y);
    let n = normal(x, y);
    for (var k = 0; k < 4; k++) {
        let dx = select(select(0, s, k == 0), -s, k == 1);
        let dy = select(select(0, s, k == 2), -s, k == 3);
        let qx = x + dx;
        let qy = y + dy;
        let nn = i32(p.size * p.ss);
        if (qx < 0 || qy < 0 || qx >= nn || qy >= nn) { continue; }
        if (g(0u, qx, qy) == 0.0) { return true; }
        if (z - g(1u, qx, qy) > p.depth_jump) { return true; }
        let cx = clamp(x + dx / s * p.crease_step, 0, nn - 1);
        let cy = clamp(y + dy / s * p.crease_step, 0, nn - 1);
        if (g(0u, cx, cy) != 0.0 && dot(n, normal(cx, cy)) < p.crease_cos) { return true; }
    }
    return false;
}

// n.v (v = +z, the camera is orthographic) at a sub-pixel, or -2 where the ray missed or the
// surface lies more than depth_jump from depth z (the far side of an occluding contour).
fn ndv_near(x: i32, y: i32, z: f32) -> f32 {
    if (g(0u, x, y) == 0.0 || abs(g(1u, x, y) - z) > p.depth_jump) { return -2.0; }
    return g(4u, x, y);
}

// n.v a distance t (sub-pixels) along image direction d from (x, y), nearest sub-pixel.
fn ndv_along(x: i32, y: i32, d: vec2<f32>, t: f32, z: f32) -> f32 {
    return ndv_near(x + i32(round(d.x * t)), y + i32(round(d.y * t)), z);
}

// Suggestive contours (DeCarlo et al. 2003): where the radial curvature crosses zero with a
// positive derivative along w, the view vector projected on the tangent plane; equivalently,
// where n.v has a positive local minimum along w. With an orthographic camera w projects onto
// the image along the normal's image-plane part (n.x, -n.y in rows, which grow downwards).
// The slope of n.v is measured over sc_step (a couple of voxels, wider than the grid's
// ripples) at half a pixel (sc_half) either side of the sub-pixel: the line is drawn where it
// turns from falling to rising, so it is about a pixel wide whatever sc_step is. sc_min_bend
// keeps faint bends out: n.v must rise by half that much on each side, so a ripple at a
// convex edge (n.v rising on one side only) draws nothing.
fn on_suggestive(x: i32, y: i32) -> bool {
    let n = normal(x, y);
    let t = length(n.xy);
    if (n.z > p.sc_max_cos || t < 1e-4) { return false; }
    let d = vec2<f32>(n.x, -n.y) / t;
    let z = g(1u, x, y);
    let h = p.sc_step;
    let e = p.sc_half;
    let far_pos = ndv_along(x, y, d, h, z);
    let far_neg = ndv_along(x, y, d, -h, z);
    let a1 = ndv_along(x, y, d, e + 0.5 * h, z);
    let a0 = ndv_along(x, y, d, e - 0.5 * h, z);
    let b1 = ndv_along(x, y, d, 0.5 * h - e, z);
    let b0 = ndv_along(x, y, d, -0.5 * h - e, z);
    if (min(min(far_pos, far_neg), min(min(a1, a0), min(b1, b0))) < -1.5) { return false; }
    let after = a1 - a0;
    let before = b1 - b0;
    return before < 0.0 && after >= 0.0 && min(far_pos, far_neg) - n.z > 0.5 * p.sc_min_bend;
}

fn shade(x: i32, y: i32) -> vec3<f32> {
    if (g(0u, x, y) == 0.0) {
        return select(vec3<f32>(0.0), vec3<f32>(1.0), p.mode == 6u);
    }
    let n = normal(x, y);
    let l = vec3<f32>(p.lx, p.ly, p.lz);
    let colour = vec3<f32>(p.cr, p.cg, p.cb);
    let albedo = vec3<f32>(g(5u, x, y), g(6u, x, y), g(7u, x, y));
    let ndl = dot(n, l);
    switch p.mode {
        case 0u: {
            // Phong; the specular lobe is cut where the light is behind the surface.
            let r = 2.0 * ndl * n - l;
            var spec = 0.0;
            if (ndl > 0.0) { spec = p.ks * pow(max(0.0, r.z), p.shininess); }
            return clamp(colour * (albedo * (p.ambient + p.kd * max(0.0, ndl)) + spec), vec3<f32>(0.0), vec3<f32>(1.0));
        }
        case 1u: { return albedo; }
        case 2u: { return (n + 1.0) * 0.5; }
        case 3u: { return vec3<f32>((1.0 + g(1u, x, y)) * 0.5); }
        case 4u: { return vec3<f32>(1.0); }
        case 5u: {
            if (on_line(x, y) || on_suggestive(x, y)) { return vec3<f32>(0.0); }
            // Four bands: 0, 1/3, 2/3, 1 of the diffuse term.
            let q = ceil(clamp(ndl, 0.0, 1.0) * 3.0) / 3.0;
            return clamp(colour * albedo * (p.ambient + p.kd * q), vec3<f32>(0.0), vec3<f32>(1.0));
        }
        case 6u: { return select(vec3<f32>(1.0), vec3<f32>(0.0), on_line(x, y) || on_suggestive(x, y)); }
        default: { return vec3<f32>(g(8u, x, y)); }
    }
}

@compute @workgroup_size(8, 8)
fn reference_shade(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= p.size || gid.y >= p.size) { return; }
    var acc = vec3<f32>(0.0);
    for (var j = 0u; j < p.ss * p.ss; j++) {
        let x = i32(gid.x * p.ss + j % p.ss);
        let y = i32(gid.y * p.ss + j / p.ss);
        acc += shade(x, y);
    }
    acc /= f32(p.ss * p.ss);
    let plane = p.size * p.size;
    let px = gid.y * p.size + gid.x;
    for (var c = 0u; c < p.channels; c++) { img[c * plane + px] = acc[c]; }
}
