// PReLU with one learned slope per channel (the paper's activation; alpha initialised to 0).
// x is [N, C, S...] flattened to [N, C, S]. Forward y = x for x > 0, alpha[c] * x otherwise.
// Backward dx = dy * (x > 0 ? 1 : alpha[c]); the alpha gradient is Σ_{n,s} dy * x over x <= 0,
// written per element to `contrib` here and summed deterministically by reduce.wgsl.

struct Params { n: u32, c: u32, s: u32 }
@group(0) @binding(0) var<uniform> p: Params;

@group(0) @binding(1) var<storage, read> fx: array<f32>;
@group(0) @binding(2) var<storage, read> falpha: array<f32>;
@group(0) @binding(3) var<storage, read_write> fy: array<f32>;

@compute @workgroup_size(64)
fn prelu_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    let x = fx[i];
    let ch = (i / p.s) % p.c;
    fy[i] = select(falpha[ch] * x, x, x > 0.0);
}

@group(0) @binding(1) var<storage, read> bx: array<f32>;
@group(0) @binding(2) var<storage, read> balpha: array<f32>;
@group(0) @binding(3) var<storage, read> bdy: array<f32>;
@group(0) @binding(4) var<storage, read_write> bdx: array<f32>;
@group(0) @binding(5) var<storage, read_write> contrib: array<f32>;

@compute @workgroup_size(64)
fn prelu_backward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    let x = bx[i];
    let dy = bdy[i];
    let ch = (i / p.s) % p.c;
    let pos = x > 0.0;
    bdx[i] = select(balpha[ch] * dy, dy, pos);
    contrib[i] = select(dy * x, 0.0, pos);
}

// ---- four elements per invocation, for S a multiple of 4 ----
// One vec4 load per operand instead of four scalar loads, and one slope load per four
// elements: llvmpipe turns each storage load into a loop over the 8 SIMD lanes, so the
// load count, not the arithmetic, sets these kernels' speed. The four share a channel
// because S % 4 == 0. p.n still counts scalars.
@group(0) @binding(1) var<storage, read> fx4: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> fy4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn prelu_forward_vec4(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (4u * i >= p.n) { return; }
    let x = fx4[i];
    let a = falpha[(4u * i / p.s) % p.c];
    fy4[i] = select(a * x, x, x > vec4<f32>(0.0));
}

@group(0) @binding(1) var<storage, read> bx4: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> bdy4: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> bdx4: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> contrib4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn prelu_backward_vec4(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (4u * i >= p.n) { return; }
    let x = bx4[i];
    let dy = bdy4[i];
    let a = balpha[(4u * i / p.s) % p.c];
    let pos = x > vec4<f32>(0.0);
    bdx4[i] = select(a * dy, dy, pos);
    contrib4[i] = select(dy * x, vec4<f32>(0.0), pos);
}
