// Projection of 4x4 transposed-conv kernels onto the resize-convolution subspace (see
// src/graph/resize_conv.rs), in place after an optimiser step: every run of 16 values of
// `w` (one kernel of a [Cin, Cout, 4, 4] weight) becomes P times itself, P the 16x16
// orthogonal projector, row-major. One invocation per kernel; it reads its 16 values
// before writing any, so in place is safe. Not differentiated: it is an optimiser step
// (projected gradient descent), not a graph op.

struct Params { kernels: u32 }
@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> proj: array<f32>;
@group(0) @binding(2) var<storage, read_write> w: array<f32>;

@compute @workgroup_size(64)
fn resize_conv_project(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = gid.x + gid.y * nwg.x * 64u;
    if (k >= p.kernels) { return; }
    var old: array<f32, 16>;
    for (var j = 0u; j < 16u; j++) {
        old[j] = w[k * 16u + j];
    }
    for (var i = 0u; i < 16u; i++) {
        var acc = 0.0;
        for (var j = 0u; j < 16u; j++) {
            acc += proj[i * 16u + j] * old[j];
        }
        w[k * 16u + i] = acc;
    }
}
