// prepend: channel_range.wgsl
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

// ---- a channel range of a larger tensor: a Narrow then this Sigmoid run as one (the Phong
// heads' maps, narrowed out of the joint head's output; see `Executor::range_sigmoids`).
// x [N, Cy, S] holds the range at channels c0 .. c0 + Cp; y and dy are the range's [N, Cp, S].
@group(0) @binding(0) var<uniform> rp: ChannelRange;

// Index in x of element i of the range.
fn in_x(i: u32) -> u32 {
    return range_to_whole(i, rp.s, rp.cp, rp.cy, rp.c0);
}

@compute @workgroup_size(64)
fn sigmoid_forward_range(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= rp.n * rp.cp * rp.s) { return; }
    fy[i] = 1.0 / (1.0 + exp(-fx[in_x(i)]));
}

// The gradient of x from the range's: dy * y * (1 - y) on the range's channels, zero on the
// others (the first gradient x gets).
@compute @workgroup_size(64)
fn sigmoid_backward_range(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = gid.x + gid.y * nwg.x * 64u;
    if (j >= rp.n * rp.cy * rp.s) { return; }
    let r = whole_to_range(j, rp.s, rp.cp, rp.cy, rp.c0);
    let y = by[r.i];
    bdx[j] = select(0.0, bdy[r.i] * y * (1.0 - y), r.inside);
}

// The same added into the range's channels of a gradient x already has (another range's).
@compute @workgroup_size(64)
fn sigmoid_backward_range_add(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= rp.n * rp.cp * rp.s) { return; }
    let y = by[i];
    bdx[in_x(i)] += bdy[i] * y * (1.0 - y);
}
