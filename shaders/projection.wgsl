// RenderNet's projection unit, the linear part: a camera-aligned feature grid
// x [N, C, D, H, W] is read as [N, K = C*D, H*W] (channel index c*D + d, a free view of
// NCDHW memory) and mixed by a 1x1 convolution, i.e. a matmul per batch item:
//   y[n, o, s] = Σ_k w[o, k] x[n, k, s] + b[o]         (w is [O, K] = PyTorch's [O, K, 1, 1])
// The PReLU that follows is its own op. Backward: dx = wᵀ dy, dw = Σ_n dy xᵀ; the bias
// gradient is a reduce over [N, O, S].

struct Params { n: u32, k: u32, o: u32, s: u32 }
@group(0) @binding(0) var<uniform> p: Params;

@group(0) @binding(1) var<storage, read> fx: array<f32>;
@group(0) @binding(2) var<storage, read> fw: array<f32>;
@group(0) @binding(3) var<storage, read> fb: array<f32>;
@group(0) @binding(4) var<storage, read_write> fy: array<f32>;

@compute @workgroup_size(64)
fn projection_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n * p.o * p.s) { return; }
    let s = i % p.s;
    let o = (i / p.s) % p.o;
    let n = i / (p.s * p.o);
    var acc = fb[o];
    for (var k = 0u; k < p.k; k++) {
        acc += fw[o * p.k + k] * fx[(n * p.k + k) * p.s + s];
    }
    fy[i] = acc;
}

@group(0) @binding(1) var<storage, read> idy: array<f32>;
@group(0) @binding(2) var<storage, read> iw: array<f32>;
@group(0) @binding(3) var<storage, read_write> idx: array<f32>;

@compute @workgroup_size(64)
fn projection_backward_input(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n * p.k * p.s) { return; }
    let s = i % p.s;
    let k = (i / p.s) % p.k;
    let n = i / (p.s * p.k);
    var acc = 0.0;
    for (var o = 0u; o < p.o; o++) {
        acc += iw[o * p.k + k] * idy[(n * p.o + o) * p.s + s];
    }
    idx[i] = acc;
}

@group(0) @binding(1) var<storage, read> wx: array<f32>;
@group(0) @binding(2) var<storage, read> wdy: array<f32>;
@group(0) @binding(3) var<storage, read_write> wdw: array<f32>;

@compute @workgroup_size(64)
fn projection_backward_weight(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.o * p.k) { return; }
    let k = i % p.k;
    let o = i / p.k;
    var acc = 0.0;
    for (var n = 0u; n < p.n; n++) {
        for (var s = 0u; s < p.s; s++) {
            acc += wdy[(n * p.o + o) * p.s + s] * wx[(n * p.k + k) * p.s + s];
        }
    }
    wdw[i] = acc;
}
