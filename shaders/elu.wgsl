// ELU with alpha = 1 (the shape decoder's activation). Forward y = x for x > 0, e^x - 1
// otherwise; backward dx = dy for x > 0, dy * e^x otherwise (from the saved input).

struct Params { n: u32, alpha: f32 }
@group(0) @binding(0) var<uniform> p: Params;

@group(0) @binding(1) var<storage, read> fx: array<f32>;
@group(0) @binding(2) var<storage, read_write> fy: array<f32>;

@compute @workgroup_size(64)
fn elu_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    let x = fx[i];
    fy[i] = select(p.alpha * (exp(x) - 1.0), x, x > 0.0);
}

@group(0) @binding(1) var<storage, read> bx: array<f32>;
@group(0) @binding(2) var<storage, read> bdy: array<f32>;
@group(0) @binding(3) var<storage, read_write> bdx: array<f32>;

@compute @workgroup_size(64)
fn elu_backward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    let x = bx[i];
    bdx[i] = select(bdy[i] * p.alpha * exp(x), bdy[i], x > 0.0);
}
