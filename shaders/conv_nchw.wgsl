// The narrow 3x3 heads' forward (2D, stride 1, padding 1, at most 8 output channels, W a
// multiple of 4) on the input as it lies, NCHW, with no packing (or copied into a texture as it
// lies: `_stage` below). src/ops/conv_nchw.rs binds it,
// one dispatch per group of 4 output channels (og, og + 1, ...: the group's first is og).
//
// Why: the texture family first packs x into an rgba32f texture, and on lavapipe a
// storage-texture store costs ~470 FMAs per 8-lane vector (Intel Xeon family 6 model 167,
// `rendernet bench --operands`): packing the 16->3 head's 128x128x16 input took ~1.0 of its
// 1.45 ms forward. Here each lane reads 4 consecutive outputs' input (one vec4 along W of a
// channel row, and its two neighbours' vec4s for the W taps) straight from the storage buffer.
// The backward passes keep the texture family.
//
// Lane: 4 outputs along W (vec4 column t) x 8 rows x the group's 4 output channels, 32 vec4
// accumulators carried over the loop on input channels. Weights: packed once per weight tensor
// (conv_nchw_pack_weights) as wk[c * 9 + tap] = output channels og..og+3 of input channel c at tap
// (kh * 3 + kw), read through a uniform binding (lane-uniform, ~10 FMAs a load).

struct NchwParams { n: u32, ci: u32, co: u32, h: u32, w4: u32, hb: u32, has_bias: u32, total: u32, og: u32, pad0: u32, pad1: u32, pad2: u32 }
@group(0) @binding(0) var<uniform> q: NchwParams;

// ---- weights: [co, ci, 3, 3] (OIHW), the group's 4 output channels -> wk, zero past co ----
@group(0) @binding(1) var<storage, read> wsrc: array<f32>;
@group(0) @binding(2) var<storage, read_write> wdst: array<vec4<f32>>;

fn weight_or_zero(k: u32, i: u32) -> f32 {
    let o = q.og + k;
    return select(0.0, wsrc[min(o, q.co - 1u) * q.ci * 9u + i], o < q.co);
}

@compute @workgroup_size(64)
fn conv_nchw_pack_weights(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= q.ci * 9u) { return; }
    wdst[i] = vec4<f32>(weight_or_zero(0u, i), weight_or_zero(1u, i), weight_or_zero(2u, i), weight_or_zero(3u, i));
}

// ---- forward ----
@group(0) @binding(1) var<storage, read> x4: array<vec4<f32>>;
// 576 vec4s: input channels up to 64 (src/ops/conv_nchw.rs checks).
@group(0) @binding(2) var<uniform> wk: array<vec4<f32>, 576>;
@group(0) @binding(3) var<storage, read> bias: array<f32>;
@group(0) @binding(4) var<storage, read_write> y4: array<vec4<f32>>;

// Or, where src/ops/conv_nchw.rs says so (`_stage`), the same values as the direct kernels'
// stage texture (conv_direct.wgsl): texel (t, row, n * ci + c) = x4[plane + row * w4 + t], x's
// own memory copied in with no dispatch. A storage-buffer load costs lavapipe 22.3 a loop over
// the lanes, a storage-texture load a gather: 157 against 18 ceiling FMAs per vec4 on an AMD
// Zen 4 (`rendernet bench --operands`), and each lane loads 30 a channel.
@group(0) @binding(5) var xs: texture_storage_3d<rgba32float, read>;

// One input row's values under the lane's 4 outputs at W taps -1, 0 and +1.
struct Taps { a: vec4<f32>, b: vec4<f32>, c: vec4<f32> }

// One row's taps from its vec4 column m and the neighbours l, r (already zero off the image).
fn taps_of(l: vec4<f32>, m: vec4<f32>, r: vec4<f32>) -> Taps {
    return Taps(vec4<f32>(l.w, m.x, m.y, m.z), m, vec4<f32>(m.y, m.z, m.w, r.x));
}

// Input row `row` (zero outside the image) of the channel plane at vec4 `plane`, column t.
fn taps(plane: u32, row: i32, t: u32) -> Taps {
    let inside = row >= 0 && row < i32(q.h);
    let at = plane + u32(clamp(row, 0, i32(q.h) - 1)) * q.w4;
    let m = select(vec4<f32>(0.0), x4[at + t], inside);
    let l = select(vec4<f32>(0.0), x4[at + max(t, 1u) - 1u], inside && t > 0u);
    let r = select(vec4<f32>(0.0), x4[at + min(t + 1u, q.w4 - 1u)], inside && t + 1u < q.w4);
    return taps_of(l, m, r);
}

// The same from the stage texture, the plane at layer `layer`.
fn taps_stage(layer: u32, row: i32, t: u32) -> Taps {
    let inside = row >= 0 && row < i32(q.h);
    let y = u32(clamp(row, 0, i32(q.h) - 1));
    let m = select(vec4<f32>(0.0), textureLoad(xs, vec3<u32>(t, y, layer)), inside);
    let l = select(vec4<f32>(0.0), textureLoad(xs, vec3<u32>(max(t, 1u) - 1u, y, layer)), inside && t > 0u);
    let r = select(vec4<f32>(0.0), textureLoad(xs, vec3<u32>(min(t + 1u, q.w4 - 1u), y, layer)), inside && t + 1u < q.w4);
    return taps_of(l, m, r);
}

// The 10 input rows r0 - 1 .. r0 + 8 a lane's 8 output rows read.
struct Rows10 { x0: Taps, x1: Taps, x2: Taps, x3: Taps, x4: Taps, x5: Taps, x6: Taps, x7: Taps, x8: Taps, x9: Taps }

fn rows10(plane: u32, r0: i32, t: u32) -> Rows10 {
    return Rows10(taps(plane, r0 - 1, t), taps(plane, r0, t), taps(plane, r0 + 1, t), taps(plane, r0 + 2, t), taps(plane, r0 + 3, t),
                  taps(plane, r0 + 4, t), taps(plane, r0 + 5, t), taps(plane, r0 + 6, t), taps(plane, r0 + 7, t), taps(plane, r0 + 8, t));
}

fn rows10_stage(layer: u32, r0: i32, t: u32) -> Rows10 {
    return Rows10(taps_stage(layer, r0 - 1, t), taps_stage(layer, r0, t), taps_stage(layer, r0 + 1, t), taps_stage(layer, r0 + 2, t),
                  taps_stage(layer, r0 + 3, t), taps_stage(layer, r0 + 4, t), taps_stage(layer, r0 + 5, t), taps_stage(layer, r0 + 6, t),
                  taps_stage(layer, r0 + 7, t), taps_stage(layer, r0 + 8, t));
}

// One output row's 4 W positions, per output channel.
struct Out { o0: vec4<f32>, o1: vec4<f32>, o2: vec4<f32>, o3: vec4<f32> }

// One kernel row's weights at W taps 0, 1, 2, each over the 4 output channels.
struct Krow { a: vec4<f32>, b: vec4<f32>, c: vec4<f32> }

fn krow(c: u32, kh: u32) -> Krow {
    let i = c * 9u + kh * 3u;
    return Krow(wk[i], wk[i + 1u], wk[i + 2u]);
}

// One input row's 3 taps of one output channel (weights a, b, c).
fn row3(x: Taps, a: f32, b: f32, c: f32) -> vec4<f32> {
    return (a * x.a + b * x.b) + c * x.c;
}

// Output row r from input rows r - 1, r, r + 1: each output channel's 9 products summed as a
// tree, the accumulator added last, one channel finished before the next (as conv_tex.wgsl's
// `mac_w3`): 1.05x on the 16->3 and 16->5 heads against a chain through the accumulator per row.
fn mac3(o: Out, x0: Taps, x1: Taps, x2: Taps, k0: Krow, k1: Krow, k2: Krow) -> Out {
    return Out(o.o0 + ((row3(x0, k0.a.x, k0.b.x, k0.c.x) + row3(x1, k1.a.x, k1.b.x, k1.c.x)) + row3(x2, k2.a.x, k2.b.x, k2.c.x)),
               o.o1 + ((row3(x0, k0.a.y, k0.b.y, k0.c.y) + row3(x1, k1.a.y, k1.b.y, k1.c.y)) + row3(x2, k2.a.y, k2.b.y, k2.c.y)),
               o.o2 + ((row3(x0, k0.a.z, k0.b.z, k0.c.z) + row3(x1, k1.a.z, k1.b.z, k1.c.z)) + row3(x2, k2.a.z, k2.b.z, k2.c.z)),
               o.o3 + ((row3(x0, k0.a.w, k0.b.w, k0.c.w) + row3(x1, k1.a.w, k1.b.w, k1.c.w)) + row3(x2, k2.a.w, k2.b.w, k2.c.w)));
}

fn bias_or_zero(k: u32) -> f32 {
    let o = k + q.og;
    return select(0.0, bias[min(o, q.co - 1u)], q.has_bias != 0u && o < q.co);
}

fn put(n: u32, row: u32, t: u32, o: Out) {
    if (row >= q.h) { return; }
    let plane = q.h * q.w4;
    let at = ((n * q.co + q.og) * q.h + row) * q.w4 + t;
    y4[at] = o.o0;
    if (q.og + 1u < q.co) { y4[at + plane] = o.o1; }
    if (q.og + 2u < q.co) { y4[at + 2u * plane] = o.o2; }
    if (q.og + 3u < q.co) { y4[at + 3u * plane] = o.o3; }
}

// A lane: vec4 column t, first row r0 of its block of 8, item n (live: within the grid).
struct Lane { t: u32, r0: i32, n: u32, live: bool }

// One invocation per vec4 column, block of 8 rows and item, over a grid_1d grid (2D past
// 65535 workgroups).
fn lane_of(gid: vec3<u32>, nwg: vec3<u32>) -> Lane {
    let i = gid.x + gid.y * nwg.x * 64u;
    let rest = i / q.w4;
    return Lane(i % q.w4, i32((rest % q.hb) * 8u), rest / q.hb, i < q.total);
}

// The lane's 8 output rows.
struct Acc8r { a0: Out, a1: Out, a2: Out, a3: Out, a4: Out, a5: Out, a6: Out, a7: Out }

fn acc_init() -> Acc8r {
    let b = vec4<f32>(0.0);
    let i = Out(b + bias_or_zero(0u), b + bias_or_zero(1u), b + bias_or_zero(2u), b + bias_or_zero(3u));
    return Acc8r(i, i, i, i, i, i, i, i);
}

// Input channel c's contribution from its 10 rows x.
fn mac_channel(a: Acc8r, c: u32, x: Rows10) -> Acc8r {
    let k0 = krow(c, 0u);
    let k1 = krow(c, 1u);
    let k2 = krow(c, 2u);
    return Acc8r(mac3(a.a0, x.x0, x.x1, x.x2, k0, k1, k2), mac3(a.a1, x.x1, x.x2, x.x3, k0, k1, k2),
                 mac3(a.a2, x.x2, x.x3, x.x4, k0, k1, k2), mac3(a.a3, x.x3, x.x4, x.x5, k0, k1, k2),
                 mac3(a.a4, x.x4, x.x5, x.x6, k0, k1, k2), mac3(a.a5, x.x5, x.x6, x.x7, k0, k1, k2),
                 mac3(a.a6, x.x6, x.x7, x.x8, k0, k1, k2), mac3(a.a7, x.x7, x.x8, x.x9, k0, k1, k2));
}

fn put_acc(l: Lane, a: Acc8r) {
    let r = u32(l.r0);
    put(l.n, r, l.t, a.a0);
    put(l.n, r + 1u, l.t, a.a1);
    put(l.n, r + 2u, l.t, a.a2);
    put(l.n, r + 3u, l.t, a.a3);
    put(l.n, r + 4u, l.t, a.a4);
    put(l.n, r + 5u, l.t, a.a5);
    put(l.n, r + 6u, l.t, a.a6);
    put(l.n, r + 7u, l.t, a.a7);
}

@compute @workgroup_size(64)
fn conv_nchw_forward3x3(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let l = lane_of(gid, nwg);
    if (!l.live) { return; }
    var a = acc_init();
    for (var c = 0u; c < q.ci; c++) {
        a = mac_channel(a, c, rows10((l.n * q.ci + c) * q.h * q.w4, l.r0, l.t));
    }
    put_acc(l, a);
}

// The same on x in its stage texture.
@compute @workgroup_size(64)
fn conv_nchw_forward3x3_stage(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let l = lane_of(gid, nwg);
    if (!l.live) { return; }
    var a = acc_init();
    for (var c = 0u; c < q.ci; c++) {
        a = mac_channel(a, c, rows10_stage(l.n * q.ci + c, l.r0, l.t));
    }
    put_acc(l, a);
}
