// Phong shading of image-space maps (paper Section 3.3, plus a specular term the original
// code lacked). Per pixel, with the normal map stored as an image (u = 2v - 1,
// n = u / max(|u|, 1e-6)), light direction l and colour col, view v = (0, 0, 1):
//   d = n.l,  s = r.v = 2 d n_z - l_z  (r = 2 d n - l),
//   I_c = m col_c (A_c (ambient + kd max(0, d)) + ks P),  P = max(0, s)^shininess.
// One invocation per pixel. Forward writes I; backward is split in two entry points (maps,
// light) so that neither binds more than 8 storage buffers, WebGPU's portable default.
// Both recompute the pixel's forward values through shared helpers instead of saving them.

struct Params {
    n_pix: u32,     // N * H * W
    hw: u32,        // H * W
    c: u32,         // albedo channels, 1 (grey, broadcast) or 3
    ambient: f32,
    kd: f32,
    ks: f32,
    shininess: f32,
    _pad: u32,
}
@group(0) @binding(0) var<uniform> p: Params;

// Inputs shared by every entry point, so the helpers below can read them.
@group(0) @binding(1) var<storage, read> nmap: array<f32>;
@group(0) @binding(2) var<storage, read> albedo: array<f32>;
@group(0) @binding(3) var<storage, read> mask: array<f32>;
@group(0) @binding(4) var<storage, read> light: array<f32>;

// The smallest base given to pow: log2 of 0 is -inf, and 0 * -inf (shininess 1 in the
// derivative) would be NaN. Only bases s > 0 reach pow; s <= 0 gives exactly 0.
const TINY: f32 = 1e-30;

struct Pixel {
    raw_len: f32,     // |u| before the clamp
    len: f32,         // max(|u|, 1e-6)
    n: vec3<f32>,
    l: vec3<f32>,
    col: vec3<f32>,
    a: vec3<f32>,     // albedo, broadcast to 3 channels when grey
    m: f32,
    d: f32,           // n.l
    diffuse: f32,     // ambient + kd max(0, d)
    spec: f32,        // max(0, s)^shininess
    dspec: f32,       // d spec / d s, 0 where s <= 0
}

fn pixel(b: u32, pix: u32) -> Pixel {
    var q: Pixel;
    let nb = b * 3u * p.hw + pix;
    let u = 2.0 * vec3<f32>(nmap[nb], nmap[nb + p.hw], nmap[nb + 2u * p.hw]) - 1.0;
    q.raw_len = length(u);
    q.len = max(q.raw_len, 1e-6);
    q.n = u / q.len;
    let lb = b * 6u;
    q.l = vec3<f32>(light[lb], light[lb + 1u], light[lb + 2u]);
    q.col = vec3<f32>(light[lb + 3u], light[lb + 4u], light[lb + 5u]);
    if (p.c == 3u) {
        let ab = b * 3u * p.hw + pix;
        q.a = vec3<f32>(albedo[ab], albedo[ab + p.hw], albedo[ab + 2u * p.hw]);
    } else {
        q.a = vec3<f32>(albedo[b * p.hw + pix]);
    }
    q.m = mask[b * p.hw + pix];
    q.d = dot(q.n, q.l);
    q.diffuse = p.ambient + p.kd * max(q.d, 0.0);
    let s = 2.0 * q.d * q.n.z - q.l.z;
    let sb = max(s, TINY);
    q.spec = select(0.0, pow(sb, p.shininess), s > 0.0);
    q.dspec = select(0.0, p.shininess * pow(sb, p.shininess - 1.0), s > 0.0);
    return q;
}

@group(0) @binding(5) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(64)
fn phong_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n_pix) { return; }
    let b = i / p.hw;
    let pix = i - b * p.hw;
    let q = pixel(b, pix);
    let rgb = q.m * q.col * (q.a * q.diffuse + p.ks * q.spec);
    let ob = b * 3u * p.hw + pix;
    out[ob] = rgb.x;
    out[ob + p.hw] = rgb.y;
    out[ob + 2u * p.hw] = rgb.z;
}

// Gradients of one pixel with respect to everything it reads.
struct Grads {
    dv: vec3<f32>,    // normal map as stored (through decode and normalisation)
    da: vec3<f32>,    // albedo per channel (summed into .x by the caller when grey)
    dm: f32,
    dl: vec3<f32>,    // this pixel's share of the light direction gradient
    dcol: vec3<f32>,  // and of the light colour gradient
}

@group(0) @binding(5) var<storage, read> dy: array<f32>;

fn grads(b: u32, pix: u32) -> Grads {
    let q = pixel(b, pix);
    let yb = b * 3u * p.hw + pix;
    let g = vec3<f32>(dy[yb], dy[yb + p.hw], dy[yb + 2u * p.hw]);
    let gc = g * q.col;                       // upstream times light colour, per channel
    let shade = q.a * q.diffuse + p.ks * q.spec;  // I / (m col), per channel
    var r: Grads;
    r.dm = dot(gc, shade);
    r.dcol = g * q.m * shade;
    r.da = gc * q.m * q.diffuse;
    // dL/dd through the diffuse clamp, dL/ds through the specular clamp and power.
    let gd = select(0.0, p.kd * q.m * dot(gc, q.a), q.d > 0.0);
    let gs = p.ks * q.m * (gc.x + gc.y + gc.z) * q.dspec;
    // s = 2 d n_z - l_z: d feeds s too, n_z and l_z feed s directly.
    let gdd = gd + 2.0 * q.n.z * gs;
    let gn = gdd * q.l + vec3<f32>(0.0, 0.0, 2.0 * q.d * gs);
    r.dl = gdd * q.n - vec3<f32>(0.0, 0.0, gs);
    // n = u / |u| projects out the radial part; below the clamp n = u / 1e-6 is linear.
    let gu = select((gn - q.n * dot(q.n, gn)) / q.len, gn / q.len, q.raw_len <= 1e-6);
    r.dv = 2.0 * gu;
    return r;
}

@group(0) @binding(6) var<storage, read_write> dnmap: array<f32>;
@group(0) @binding(7) var<storage, read_write> dalbedo: array<f32>;
@group(0) @binding(8) var<storage, read_write> dmask: array<f32>;

@compute @workgroup_size(64)
fn phong_backward_maps(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n_pix) { return; }
    let b = i / p.hw;
    let pix = i - b * p.hw;
    let r = grads(b, pix);
    let nb = b * 3u * p.hw + pix;
    dnmap[nb] = r.dv.x;
    dnmap[nb + p.hw] = r.dv.y;
    dnmap[nb + 2u * p.hw] = r.dv.z;
    if (p.c == 3u) {
        dalbedo[nb] = r.da.x;
        dalbedo[nb + p.hw] = r.da.y;
        dalbedo[nb + 2u * p.hw] = r.da.z;
    } else {
        dalbedo[b * p.hw + pix] = r.da.x + r.da.y + r.da.z;
    }
    dmask[b * p.hw + pix] = r.dm;
}

// Per-pixel light partials laid out [N * 6, H * W], summed over pixels afterwards by the
// deterministic reduction (no float atomics, so reruns are bit-identical).
@group(0) @binding(6) var<storage, read_write> dlight_parts: array<f32>;

@compute @workgroup_size(64)
fn phong_backward_light(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n_pix) { return; }
    let b = i / p.hw;
    let pix = i - b * p.hw;
    let r = grads(b, pix);
    let base = b * 6u * p.hw + pix;
    dlight_parts[base] = r.dl.x;
    dlight_parts[base + p.hw] = r.dl.y;
    dlight_parts[base + 2u * p.hw] = r.dl.z;
    dlight_parts[base + 3u * p.hw] = r.dcol.x;
    dlight_parts[base + 4u * p.hw] = r.dcol.y;
    dlight_parts[base + 5u * p.hw] = r.dcol.z;
}
