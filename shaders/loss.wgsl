// prepend: workgroup_sum.wgsl
// Losses and metrics against a target (targets get no gradient). The losses' forward entry
// points (`*_mean`) write the mean in one dispatch; `sq_diff` writes per-element terms that
// the caller sums with the deterministic reduction (PSNR's per-image MSE). The backward entry points read the
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

// ---- a loss's mean in one dispatch (Loss::forward): one workgroup of 64 invocations, each
// summing the terms of a strided run (four a load where n is a multiple of 4), then
// workgroup_sum's fixed-order tree. The terms never go through memory, and the elementwise
// dispatch that wrote them is gone: on lavapipe each dispatch costs tens of microseconds
// whatever it computes (README "What a dispatch costs"), four losses a training step.
@group(0) @binding(3) var<storage, read_write> mean: array<f32>;

// Four elements' terms, MSE's or BCE's (`bce`, a constant lavapipe folds).
fn terms_of(x: vec4<f32>, t: vec4<f32>, bce: bool) -> vec4<f32> {
    if (bce) {
        let q = clamp(x, vec4<f32>(p.eps), vec4<f32>(1.0 - p.eps));
        return -(t * log(q) + (1.0 - t) * log(1.0 - q));
    }
    let e = x - t;
    return e * e;
}

// Writes the mean of the invocations' sums `s`. Each entry point reads its operands one way
// only (pred or pred4: one binding, two types), so the two loops below are separate functions.
fn write_mean(lid: u32, s: f32) {
    let total = workgroup_sum(lid, s);
    if (lid == 0u) { mean[0] = total * p.inv_n; }
}

fn terms_from(lid: u32, bce: bool) -> f32 {
    var s = 0.0;
    for (var k = lid; k < p.n; k += 64u) {
        s += terms_of(vec4<f32>(pred[k]), vec4<f32>(tgt[k]), bce).x;
    }
    return s;
}

fn terms_from4(lid: u32, bce: bool) -> f32 {
    var s4 = vec4<f32>(0.0);
    for (var k = lid; k < p.n / 4u; k += 64u) {
        s4 += terms_of(pred4[k], tgt4[k], bce);
    }
    return (s4.x + s4.y) + (s4.z + s4.w);
}

@compute @workgroup_size(64)
fn mse_mean(@builtin(local_invocation_index) lid: u32) { write_mean(lid, terms_from(lid, false)); }

@compute @workgroup_size(64)
fn mse_mean_vec4(@builtin(local_invocation_index) lid: u32) { write_mean(lid, terms_from4(lid, false)); }

@compute @workgroup_size(64)
fn bce_mean(@builtin(local_invocation_index) lid: u32) { write_mean(lid, terms_from(lid, true)); }

@compute @workgroup_size(64)
fn bce_mean_vec4(@builtin(local_invocation_index) lid: u32) { write_mean(lid, terms_from4(lid, true)); }
