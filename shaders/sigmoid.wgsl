// Logistic sigmoid. Forward y = 1 / (1 + e^-x); backward dx = dy * y * (1 - y), computed
// from the saved output so the input need not be kept.

struct Params { n: u32 }
@group(0) @binding(0) var<uniform> p: Params;

@group(0) @binding(1) var<storage, read> fx: array<f32>;
@group(0) @binding(2) var<storage, read_write> fy: array<f32>;

@compute @workgroup_size(64)
fn sigmoid_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    fy[i] = 1.0 / (1.0 + exp(-fx[i]));
}

@group(0) @binding(1) var<storage, read> by: array<f32>;
@group(0) @binding(2) var<storage, read> bdy: array<f32>;
@group(0) @binding(3) var<storage, read_write> bdx: array<f32>;

@compute @workgroup_size(64)
fn sigmoid_backward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    let y = by[i];
    bdx[i] = bdy[i] * y * (1.0 - y);
}

// ---- four values per invocation, for n a multiple of 4 (ops::elementwise picks these) ----
// llvmpipe runs every storage load and store as a loop over the 8 SIMD lanes: a quarter of
// the loops, though each vec4 costs more than a float (Zen 3, Mesa 22.3: a vec4 load ~3.6
// floats' loads, a vec4 store ~2 floats' stores; `rendernet bench --operands`).
@group(0) @binding(1) var<storage, read> fx4: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> fy4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn sigmoid_forward_vec4(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (4u * i >= p.n) { return; }
    fy4[i] = 1.0 / (1.0 + exp(-fx4[i]));
}

@group(0) @binding(1) var<storage, read> by4: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> bdy4: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> bdx4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn sigmoid_backward_vec4(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (4u * i >= p.n) { return; }
    let y = by4[i];
    bdx4[i] = bdy4[i] * y * (1.0 - y);
}
