// Broadcast over space: y[r, s] = x[r] for x [N, C] (any trailing size-1 axes) and
// y [N, C, S...], r = n * C + c. The backward, dx[r] = Σ_s dy[r, s], is the deterministic
// sum of reduce.wgsl viewed as [1, N*C, S] (the same sum a bias gradient takes).

struct Params { rows: u32, s: u32 }
@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> x: array<f32>;
@group(0) @binding(2) var<storage, read_write> y: array<f32>;

@compute @workgroup_size(64)
fn expand_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.rows * p.s) { return; }
    y[i] = x[i / p.s];
}
