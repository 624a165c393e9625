// Rigid-body resampling of a voxel grid into a camera-aligned grid (RenderNet's first layer).
//
// Points are (d, h, w) in voxel-index units, voxel centres at integer indices; c = (size-1)/2
// is a grid's centre. Pose per batch item: (s, az, el, t_d, t_h, t_w). The forward map from
// input to output is p = c_out + t + s * R_el * R_az * (q - c_in), where R_az turns the +W axis
// towards +D (about H) and R_el turns +H towards +D (about W). Each output voxel p samples x
// trilinearly at the inverse image q = c_in + R_az^T R_el^T (p - c_out - t) / s.
// Samples outside the input read ZERO (an occupancy grid is empty outside; unlike the original
// code's edge clamp this keeps the backward gather bounded and the map continuous).
//
// Entry points: resample_forward (one thread per (n, output voxel), all channels),
// resample_backward_input (deterministic gather, one thread per (n, c, input voxel)),
// resample_backward_pose (one thread per (n, output voxel), six partials to a scratch tensor
// [N*6, Do*Ho*Wo] that the host sums with reduce.wgsl).

struct Params {
    n: u32, c: u32,
    id: u32, ih: u32, iw: u32,
    od: u32, oh: u32, ow: u32,
}
@group(0) @binding(0) var<uniform> p: Params;

// Shared by all entry points: the poses, [N, 6].
@group(0) @binding(1) var<storage, read> pose: array<f32>;

// The rigid transform of one batch item, with the pieces the pose gradient needs.
struct Xform {
    s: f32,
    raz: mat3x3<f32>,
    rel: mat3x3<f32>,
    daz: mat3x3<f32>,  // d R_az / d az
    del: mat3x3<f32>,  // d R_el / d el
    origin: vec3<f32>, // c_out + t
    c_in: vec3<f32>,
}

// Matrices are built from columns. R_az rows: [c 0 s; 0 1 0; -s 0 c] (mixes D and W).
// R_el rows: [c s 0; -s c 0; 0 0 1] (mixes D and H).
fn xform(n: u32) -> Xform {
    let b = n * 6u;
    let s = pose[b];
    let ca = cos(pose[b + 1u]);
    let sa = sin(pose[b + 1u]);
    let ce = cos(pose[b + 2u]);
    let se = sin(pose[b + 2u]);
    let t = vec3<f32>(pose[b + 3u], pose[b + 4u], pose[b + 5u]);
    let z = vec3<f32>(0.0);
    var x: Xform;
    x.s = s;
    x.raz = mat3x3<f32>(vec3(ca, 0.0, -sa), vec3(0.0, 1.0, 0.0), vec3(sa, 0.0, ca));
    x.rel = mat3x3<f32>(vec3(ce, -se, 0.0), vec3(se, ce, 0.0), vec3(0.0, 0.0, 1.0));
    x.daz = mat3x3<f32>(vec3(-sa, 0.0, -ca), z, vec3(ca, 0.0, -sa));
    x.del = mat3x3<f32>(vec3(-se, -ce, 0.0), vec3(ce, -se, 0.0), z);
    let osz = vec3<f32>(f32(p.od), f32(p.oh), f32(p.ow));
    let isz = vec3<f32>(f32(p.id), f32(p.ih), f32(p.iw));
    x.origin = (osz - 1.0) * 0.5 + t;
    x.c_in = (isz - 1.0) * 0.5;
    return x;
}

// The output-frame offset u = (p - c_out - t) / s of output voxel `o`.
fn out_offset(x: Xform, o: vec3<f32>) -> vec3<f32> {
    return (o - x.origin) / x.s;
}

// Where output voxel `o` samples the input: q = c_in + R_az^T R_el^T u. The forward and both
// backward kernels call this one function so their sample points agree bit for bit.
fn sample_point(x: Xform, o: vec3<f32>) -> vec3<f32> {
    return x.c_in + transpose(x.raz) * (transpose(x.rel) * out_offset(x, o));
}

// Output voxel coordinates (d, h, w) of linear index `v` within one output volume.
fn out_coords(v: u32) -> vec3<f32> {
    let w = v % p.ow;
    let r = v / p.ow;
    return vec3<f32>(f32(r / p.oh), f32(r % p.oh), f32(w));
}

// ---- forward and pose backward: trilinear sampling of x -------------------------------

@group(0) @binding(2) var<storage, read> src: array<f32>;

// Value (.x) and gradient w.r.t. q (.yzw) of the trilinear interpolation of the input volume
// starting at `base`, at q; corners outside the grid count as zero.
fn trilinear(base: u32, q: vec3<f32>) -> vec4<f32> {
    let q0 = floor(q);
    let f = q - q0;
    // Clamped so the i32 cast stays in range; a clamped corner is outside the grid anyway.
    let i0 = vec3<i32>(clamp(q0, vec3(-2.0), vec3(1e9)));
    let lim = vec3<i32>(i32(p.id), i32(p.ih), i32(p.iw));
    var acc = vec4<f32>(0.0);
    for (var k = 0u; k < 8u; k++) {
        let bit = vec3<u32>(k >> 2u, (k >> 1u) & 1u, k & 1u);
        let i = i0 + vec3<i32>(bit);
        if (any(i < vec3<i32>(0)) || any(i >= lim)) { continue; }
        let up = bit == vec3<u32>(1u);
        let w = select(1.0 - f, f, up);              // per-axis weights
        let dw = select(vec3(-1.0), vec3(1.0), up);  // their derivatives w.r.t. q
        let v = src[base + (u32(i.x) * p.ih + u32(i.y)) * p.iw + u32(i.z)];
        acc += v * vec4(w.x * w.y * w.z, dw.x * w.y * w.z, w.x * dw.y * w.z, w.x * w.y * dw.z);
    }
    return acc;
}

@group(0) @binding(3) var<storage, read_write> f_y: array<f32>;

@compute @workgroup_size(64)
fn resample_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    let vo = p.od * p.oh * p.ow;
    if (i >= p.n * vo) { return; }
    let n = i / vo;
    let v = i - n * vo;
    let q = sample_point(xform(n), out_coords(v));
    let vi = p.id * p.ih * p.iw;
    for (var c = 0u; c < p.c; c++) {
        let nc = n * p.c + c;
        f_y[nc * vo + v] = trilinear(nc * vi, q).x;
    }
}

// ---- backward to the input grid: gather ------------------------------------------------

@group(0) @binding(2) var<storage, read> bi_dy: array<f32>;
@group(0) @binding(3) var<storage, read_write> bi_dx: array<f32>;

// dx[n,c,i] = sum_o dy[n,c,o] * prod_k max(0, 1 - |q(o)_k - i_k|). Only outputs whose sample
// lies in the open box (i-1, i+1)^3 contribute; that box maps forward to a parallelepiped
// centred at the image of i with half-extent s * sum_j |M_kj| per output axis (M = R_el R_az),
// whose bounding box is scanned. The weight test below, not the box, decides membership.
@compute @workgroup_size(64)
fn resample_backward_input(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let idx = gid.x + gid.y * nwg.x * 64u;
    let vi = p.id * p.ih * p.iw;
    if (idx >= p.n * p.c * vi) { return; }
    let nc = idx / vi;
    let v = idx - nc * vi;
    let n = nc / p.c;
    let iw = v % p.iw;
    let r = v / p.iw;
    let ipos = vec3<f32>(f32(r / p.ih), f32(r % p.ih), f32(iw));

    let x = xform(n);
    let m = x.rel * x.raz;
    let centre = x.origin + x.s * (m * (ipos - x.c_in));
    // Columns of |M| summed (component k = sum_j |M_kj|): the half-extent of M applied to
    // [-1, 1]^3, plus slack for rounding.
    let half = x.s * (abs(m[0]) + abs(m[1]) + abs(m[2])) + 1e-3;
    let omax = vec3<f32>(f32(p.od), f32(p.oh), f32(p.ow)) - 1.0;
    let lo = vec3<u32>(clamp(ceil(centre - half), vec3(0.0), omax));
    let hi = vec3<u32>(clamp(floor(centre + half), vec3(0.0), omax));

    let vo = p.od * p.oh * p.ow;
    let base = nc * vo;
    var acc = 0.0;
    for (var od = lo.x; od <= hi.x; od++) {
        for (var oh = lo.y; oh <= hi.y; oh++) {
            for (var ow = lo.z; ow <= hi.z; ow++) {
                let q = sample_point(x, vec3<f32>(f32(od), f32(oh), f32(ow)));
                let d = abs(q - ipos);
                if (all(d < vec3(1.0))) {
                    let w = (1.0 - d.x) * (1.0 - d.y) * (1.0 - d.z);
                    acc += bi_dy[base + (od * p.oh + oh) * p.ow + ow] * w;
                }
            }
        }
    }
    bi_dx[idx] = acc;
}

// ---- backward to the pose: per-voxel partials ------------------------------------------

@group(0) @binding(3) var<storage, read> bp_dy: array<f32>;
@group(0) @binding(4) var<storage, read_write> bp_scratch: array<f32>;

// With g = sum_c dy[n,c,o] * grad_q sample_c(q) and u = (o - c_out - t) / s:
//   dq/ds = -(q - c_in) / s,  dq/daz = dR_az^T R_el^T u,  dq/del = R_az^T dR_el^T u,
//   dq/dt_j = -(R_az^T R_el^T)[:, j] / s, so g . dq/dt = -(R_el R_az g) / s.
// Partial k of voxel o goes to scratch[(n*6 + k) * Vo + o].
@compute @workgroup_size(64)
fn resample_backward_pose(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    let vo = p.od * p.oh * p.ow;
    if (i >= p.n * vo) { return; }
    let n = i / vo;
    let v = i - n * vo;
    let x = xform(n);
    let u = out_offset(x, out_coords(v));
    let q = sample_point(x, out_coords(v));
    let vi = p.id * p.ih * p.iw;
    var g = vec3<f32>(0.0);
    for (var c = 0u; c < p.c; c++) {
        let nc = n * p.c + c;
        let dy = bp_dy[nc * vo + v];
        if (dy != 0.0) { g += dy * trilinear(nc * vi, q).yzw; }
    }
    let raz_t = transpose(x.raz);
    let rel_t = transpose(x.rel);
    let dt = -(x.rel * (x.raz * g)) / x.s;
    let out = n * 6u * vo + v;
    bp_scratch[out] = -dot(g, q - x.c_in) / x.s;
    bp_scratch[out + vo] = dot(g, transpose(x.daz) * (rel_t * u));
    bp_scratch[out + 2u * vo] = dot(g, raz_t * (transpose(x.del) * u));
    bp_scratch[out + 3u * vo] = dt.x;
    bp_scratch[out + 4u * vo] = dt.y;
    bp_scratch[out + 5u * vo] = dt.z;
}
