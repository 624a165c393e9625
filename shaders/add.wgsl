// Residual add. Forward y = a + b. Its backward is the identity (da = db = dy) and needs no
// kernel of its own: the executor copies dy into each input's gradient (`add_copy`) or, where
// one tensor feeds several nodes, sums into it (`add_accumulate`, acc += x).

struct Params { n: u32 }
@group(0) @binding(0) var<uniform> p: Params;

@group(0) @binding(1) var<storage, read> fa: array<f32>;
@group(0) @binding(2) var<storage, read> fb: array<f32>;
@group(0) @binding(3) var<storage, read_write> fy: array<f32>;

@compute @workgroup_size(64)
fn add_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    fy[i] = fa[i] + fb[i];
}

@group(0) @binding(1) var<storage, read> ax: array<f32>;
@group(0) @binding(2) var<storage, read_write> acc: array<f32>;

@compute @workgroup_size(64)
fn add_accumulate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    acc[i] = acc[i] + ax[i];
}

@compute @workgroup_size(64)
fn add_copy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    acc[i] = ax[i];
}

// ---- four values per invocation, for n a multiple of 4 (ops::elementwise picks these) ----
// llvmpipe runs every storage load and store as a loop over the 8 SIMD lanes: a quarter of
// the loops, though each vec4 costs more than a float (Zen 3, Mesa 22.3: a vec4 load ~3.6
// floats' loads, a vec4 store ~2 floats' stores; `rendernet bench --operands`).
@group(0) @binding(1) var<storage, read> fa4: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> fb4: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> fy4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn add_forward_vec4(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (4u * i >= p.n) { return; }
    fy4[i] = fa4[i] + fb4[i];
}

@group(0) @binding(1) var<storage, read> ax4: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> acc4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn add_accumulate_vec4(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (4u * i >= p.n) { return; }
    acc4[i] = acc4[i] + ax4[i];
}

@compute @workgroup_size(64)
fn add_copy_vec4(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (4u * i >= p.n) { return; }
    acc4[i] = ax4[i];
}
