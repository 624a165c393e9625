// prepend: workgroup_sum.wgsl
// Deterministic sums. `x` is viewed as [A, B, C]; out[b] = scale * sum over a and c of
// x[a, b, c]. One 64-invocation workgroup per output element: strided partial sums then a
// fixed-order tree, so results do not depend on scheduling (bit-identical reruns).
// Serves bias and PReLU-alpha gradients (A = N, B = channels, C = spatial), per-image MSE
// (A = 1, B = images) and per-parameter gradient partials (pose, light); the losses' means
// sum their terms as they make them (loss.wgsl), with the same tree (workgroup_sum.wgsl).

struct Params { a: u32, b: u32, c: u32, scale: f32 }
@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> x: array<f32>;
@group(0) @binding(2) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(64)
fn sum_outer_inner(@builtin(local_invocation_index) lid: u32,
                   @builtin(workgroup_id) wid: vec3<u32>,
                   @builtin(num_workgroups) nwg: vec3<u32>) {
    // Uniform control flow: every invocation reaches the barriers, even past the end.
    let b = wid.x + wid.y * nwg.x;
    let valid = b < p.b;
    var s = 0.0;
    if (valid) {
        let total = p.a * p.c;
        for (var k = lid; k < total; k += 64u) {
            let ai = k / p.c;
            let ci = k - ai * p.c;
            s += x[(ai * p.b + b) * p.c + ci];
        }
    }
    tree_sum(lid, s, valid, b);
}

// out[b] = scale * the sum of every invocation's `s`, in a fixed-order tree.
fn tree_sum(lid: u32, s: f32, valid: bool, b: u32) {
    let total = workgroup_sum(lid, s);
    if (valid && lid == 0u) { out[b] = total * p.scale; }
}

// The same for C a multiple of 4: four values a load, and a loop over A around a loop over C
// in place of the flat index's division. llvmpipe runs every storage load as a loop over the
// 8 SIMD lanes (a vec4 at ~3.6 floats' cost) and divides lane by lane (measured on an AMD
// Zen 3: a load ~180 FMAs at the ceiling, a division ~40; `rendernet bench --operands`).
@group(0) @binding(1) var<storage, read> x4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn sum_outer_inner_vec4(@builtin(local_invocation_index) lid: u32,
                        @builtin(workgroup_id) wid: vec3<u32>,
                        @builtin(num_workgroups) nwg: vec3<u32>) {
    let b = wid.x + wid.y * nwg.x;
    let valid = b < p.b;
    var s4 = vec4<f32>(0.0);
    if (valid) {
        let c4 = p.c / 4u;
        for (var ai = 0u; ai < p.a; ai++) {
            let row = (ai * p.b + b) * c4;
            for (var k = lid; k < c4; k += 64u) {
                s4 += x4[row + k];
            }
        }
    }
    tree_sum(lid, (s4.x + s4.y) + (s4.z + s4.w), valid, b);
}
