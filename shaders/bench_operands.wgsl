// append: fn operand(i: u32, it: u32, k: u32, sid: u32, x: f32) -> f32 { return x; }
// The loop `rendernet bench --operands` times (src/bench/operands.rs): bench_fma's 8
// independent accumulators, each FMA's addend read through `operand(i, it, k, sid, x)`, which
// src/bench/operands.rs appends to this file once per kind of operand (a storage-buffer load, a
// uniform-buffer load, a texel fetch, ...), each compiled as its own module: nothing but the
// operand differs between the timings, so their differences are what one operand costs.
struct Params { iters: u32, total: u32, div: u32, mask: u32, table: array<vec4<f32>, 8> }
@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read_write> out: array<f32>;
@group(0) @binding(2) var<storage, read> buf: array<f32>;
@group(0) @binding(3) var tex: texture_2d<f32>;
@group(0) @binding(4) var stex: texture_storage_2d<rgba32float, read>;
// `buf` again, four floats an element; and where the store rows write.
@group(0) @binding(5) var<storage, read> buf4: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> sink: array<f32>;
@group(0) @binding(7) var<storage, read_write> sink4: array<vec4<f32>>;
@group(0) @binding(8) var wtex: texture_storage_2d<rgba32float, write>;
// A 64 KiB tensor bound as a uniform buffer (the most lavapipe allows in one binding).
@group(0) @binding(9) var<uniform> win: array<vec4<f32>, 4096>;
var<workgroup> wg: array<f32, 128>;

// Dispatched with exactly p.total invocations (a multiple of 64): no early return, so the
// workgroup barrier stays in uniform control flow.
@compute @workgroup_size(64)
fn bench_operand(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32, @builtin(subgroup_invocation_id) sid: u32) {
    let i = gid.x + gid.y * nwg.x * 64u;
    wg[li] = f32(li) * 1e-3;
    wg[li + 64u] = 0.5;
    workgroupBarrier();
    // Values stay bounded (|a| < 1) so no lane goes denormal or infinite.
    let x = f32(i % 1024u) * 1e-7;
    let y = 0.9999 - x;
    var a0 = x; var a1 = x; var a2 = x; var a3 = x; var a4 = x; var a5 = x; var a6 = x; var a7 = x;
    for (var it = 0u; it < p.iters; it++) {
        a0 = fma(a0, y, operand(i, it, 0u, sid, x)); a1 = fma(a1, y, operand(i, it, 1u, sid, x));
        a2 = fma(a2, y, operand(i, it, 2u, sid, x)); a3 = fma(a3, y, operand(i, it, 3u, sid, x));
        a4 = fma(a4, y, operand(i, it, 4u, sid, x)); a5 = fma(a5, y, operand(i, it, 5u, sid, x));
        a6 = fma(a6, y, operand(i, it, 6u, sid, x)); a7 = fma(a7, y, operand(i, it, 7u, sid, x));
    }
    out[i] = a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7;
}
