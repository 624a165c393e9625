// Losses and metrics against a target (targets get no gradient). The forward entry points
// write per-element terms; the caller sums them with the deterministic reduction (a mean
// for the losses, a per-image mean for PSNR's MSE). The backward entry points read the
// upstream scalar gradient from a one-element tensor, so losses chain inside a graph.
//   MSE: term (p - t)^2,                          dp = g * 2 (p - t) / n
//   BCE: term -(t ln q + (1 - t) ln(1 - q)),      dp = g * (q - t) / (q (1 - q)) / n
//        with q = clamp(p, eps, 1 - eps); dp = 0 where p lies outside [eps, 1 - eps].

struct Params { n: u32, inv_n: f32, eps: f32 }
@group(0) @binding(0) var<uniform> p: Params;

@group(0) @binding(1) var<storage, read> pred: array<f32>;
@group(0) @binding(2) var<storage, read> tgt: array<f32>;

@group(0) @binding(3) var<storage, read_write> terms: array<f32>;

@compute @workgroup_size(64)
fn sq_diff(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    let e = pred[i] - tgt[i];
    terms[i] = e * e;
}

@compute @workgroup_size(64)
fn bce_terms(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    let q = clamp(pred[i], p.eps, 1.0 - p.eps);
    let t = tgt[i];
    terms[i] = -(t * log(q) + (1.0 - t) * log(1.0 - q));
}

@group(0) @binding(3) var<storage, read> dloss: array<f32>;
@group(0) @binding(4) var<storage, read_write> dpred: array<f32>;

@compute @workgroup_size(64)
fn mse_backward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    dpred[i] = dloss[0] * 2.0 * (pred[i] - tgt[i]) * p.inv_n;
}

@compute @workgroup_size(64)
fn bce_backward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    let x = pred[i];
    let q = clamp(x, p.eps, 1.0 - p.eps);
    let inside = x >= p.eps && x <= 1.0 - p.eps;
    dpred[i] = select(0.0, dloss[0] * (q - tgt[i]) / (q * (1.0 - q)) * p.inv_n, inside);
}

// ---- four values per invocation, for n a multiple of 4 (ops::elementwise picks these) ----
// llvmpipe runs every storage load and store as a loop over the 8 SIMD lanes: a quarter of
// the loops, though each vec4 costs more than a float (Zen 3, Mesa 22.3: a vec4 load ~3.6
// floats' loads, a vec4 store ~2 floats' stores; `rendernet bench --operands`).
@group(0) @binding(1) var<storage, read> pred4: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> tgt4: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> terms4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn sq_diff_vec4(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (4u * i >= p.n) { return; }
    let e = pred4[i] - tgt4[i];
    terms4[i] = e * e;
}

@group(0) @binding(4) var<storage, read_write> dpred4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn mse_backward_vec4(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (4u * i >= p.n) { return; }
    dpred4[i] = dloss[0] * 2.0 * (pred4[i] - tgt4[i]) * p.inv_n;
}
