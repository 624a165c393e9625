// Gradient guard. `finite_check` sets flags[slot] to 1 if any value of x is NaN or Inf (an
// all-ones exponent, tested on the bits so no fast-math assumption can fold it away), else
// 0; `finite_any` sets flags[0] to 1 if any of flags[1..=count] is set. Adam reads flags[0]
// and leaves every parameter untouched when it is set. This op has no gradient.

struct Params { n: u32, slot: u32 }
@group(0) @binding(0) var<uniform> p: Params;

@group(0) @binding(1) var<storage, read> x: array<f32>;
@group(0) @binding(2) var<storage, read_write> flags: array<f32>;

var<workgroup> bad: array<u32, 64>;

@compute @workgroup_size(64)
fn finite_check(@builtin(local_invocation_index) lid: u32) {
    var b = 0u;
    for (var i = lid; i < p.n; i += 64u) {
        b |= u32((bitcast<u32>(x[i]) & 0x7f800000u) == 0x7f800000u);
    }
    flag_any(lid, b, p.slot);
}

// Writes flags[slot] = 1 if any invocation's `b` is set (a fixed-order tree).
fn flag_any(lid: u32, b: u32, slot: u32) {
    bad[lid] = b;
    workgroupBarrier();
    for (var w = 32u; w > 0u; w >>= 1u) {
        if (lid < w) { bad[lid] |= bad[lid + w]; }
        workgroupBarrier();
    }
    if (lid == 0u) { flags[slot] = f32(bad[0]); }
}

// The same for n a multiple of 4, four values a load: llvmpipe runs each storage load as a
// loop over the 8 SIMD lanes, a vec4 at less than four floats' cost (~3.6 on a Zen 3).
@group(0) @binding(1) var<storage, read> x4: array<vec4<f32>>;

@compute @workgroup_size(64)
fn finite_check_vec4(@builtin(local_invocation_index) lid: u32) {
    var b = 0u;
    for (var i = lid; 4u * i < p.n; i += 64u) {
        b |= bad_quad(x4[i]);
    }
    flag_any(lid, b, p.slot);
}

fn bad_quad(v: vec4<f32>) -> u32 {
    return u32(any((bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u)) == vec4<u32>(0x7f800000u)));
}

// A whole buffer of many tensors at once (the executor's flat gradients; n a multiple of 4):
// workgroup g checks quads [g * p.slot, (g + 1) * p.slot) and sets flags[1 + g], so the work
// spreads over the CPU threads in one dispatch; finite_any then ORs the workgroups' flags.
@compute @workgroup_size(64)
fn finite_check_chunks_vec4(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let end = min((wid.x + 1u) * p.slot, p.n / 4u);
    var b = 0u;
    for (var i = wid.x * p.slot + lid; i < end; i += 64u) {
        b |= bad_quad(x4[i]);
    }
    flag_any(lid, b, 1u + wid.x);
}

@group(0) @binding(1) var<storage, read_write> aflags: array<f32>;

@compute @workgroup_size(1)
fn finite_any() {
    var any = 0.0;
    for (var k = 1u; k <= p.n; k++) {
        any = max(any, aflags[k]);
    }
    aflags[0] = any;
}
