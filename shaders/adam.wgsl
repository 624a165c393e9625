// One Adam step in place (Kingma & Ba, Algorithm 1), elementwise over a parameter tensor:
//   m = b1 m + (1 - b1) g,  v = b2 v + (1 - b2) g^2,
//   param -= lr * (m / bc1) / (sqrt(v / bc2) + eps),  bc1 = 1 - b1^t, bc2 = 1 - b2^t.
// The bias corrections are computed on the host in f64 (b2^t for large t loses digits in f32).
// `guard[0] != 0` (set by finite.wgsl when a gradient holds NaN/Inf) skips the update, so a
// poisoned step never reaches the weights; the unguarded step binds a zero buffer there.

struct Params { n: u32, lr: f32, beta1: f32, beta2: f32, eps: f32, bc1: f32, bc2: f32 }
@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> grad: array<f32>;
@group(0) @binding(2) var<storage, read_write> param: array<f32>;
@group(0) @binding(3) var<storage, read_write> m: array<f32>;
@group(0) @binding(4) var<storage, read_write> v: array<f32>;
@group(0) @binding(5) var<storage, read> guard: array<f32>;

@compute @workgroup_size(64)
fn adam_step(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n || guard[0] != 0.0) { return; }
    let u = update(vec4<f32>(grad[i]), vec4<f32>(m[i]), vec4<f32>(v[i]));
    m[i] = u.m.x;
    v[i] = u.v.x;
    param[i] -= u.step.x;
}

// The new moments and the step to subtract from the parameters, four at a time (the scalar
// entry uses one lane).
struct Update { m: vec4<f32>, v: vec4<f32>, step: vec4<f32> }

fn update(g: vec4<f32>, m0: vec4<f32>, v0: vec4<f32>) -> Update {
    let mi = p.beta1 * m0 + (1.0 - p.beta1) * g;
    let vi = p.beta2 * v0 + (1.0 - p.beta2) * g * g;
    return Update(mi, vi, p.lr * (mi / p.bc1) / (sqrt(vi / p.bc2) + p.eps));
}

// ---- four parameters per invocation, for n a multiple of 4 ----
// llvmpipe turns every storage load or store into a loop over the 8 SIMD lanes and a vec4
// costs about what a float does, so this takes a quarter of the scalar entry's load loops
// (8 of them a parameter there: grad, m, v, param, guard; m, v, param written).
@group(0) @binding(1) var<storage, read> grad4: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> param4: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> m4: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> v4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn adam_step_vec4(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (4u * i >= p.n || guard[0] != 0.0) { return; }
    let u = update(grad4[i], m4[i], v4[i]);
    m4[i] = u.m;
    v4[i] = u.v;
    param4[i] -= u.step;
}
