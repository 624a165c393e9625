// prepend: conv_fast.wgsl, conv_tex.wgsl
// The texture family's weight-gradient tiles (see conv_tex.wgsl for the family): x and dy
// read through textures, dy shared across lanes by subgroup shuffles, partial sums per chunk of
// output rows that conv_fast_weight_sum adds. Compiled appended to conv_fast.wgsl (Params,
// chunk_rows, tap_axes, walk_from, walk_next) and conv_tex.wgsl (LaneIds, lane_tile);
// conv_direct.wgsl's weight gradient uses this file's bdy, bpart and dy_quads.

// ---- backward weight: lanes = 8 (tap, input channel quad) pairs; dy shared by shuffles ----
// One subgroup of 8 lanes per (group of 8 pairs, output channel group of 16, chunk of output
// rows). Lane L owns pair L = tap * cq + q and accumulates dw[16 channels][4 channels] of it
// over the chunk's positions: per output position it fetches its x texel at the position its
// tap reaches, while the 16 dy values of that position (the same for every lane) come from
// texels the 8 lanes fetched for 8 positions at once, handed around with subgroupShuffle.
// Writes part[chunk][tap][cpad][copad] like conv_fast_backward_weight; conv_fast_weight_sum
// adds the chunks. Params: the dispatch geometry (never folded); cpad of x, co16 of dy; nchunks,
// chunk (rows per chunk), total = tiles.
@group(0) @binding(1) var bx: texture_storage_3d<rgba32float, read>;    // packed x (as tx)
@group(0) @binding(2) var bdy: texture_storage_3d<rgba32float, read>;   // packed dy: dy_quads() quads per item
@group(0) @binding(3) var<storage, read_write> bpart: array<f32>;

// dy texels per voxel as src/ops/conv_fast.rs (dy_tex_channels) packs dy for the weight
// gradients: one or two quads for at most 4 or 8 output channels, else co16 * 4.
fn dy_quads() -> u32 {
    return select(p.co16 * 4u, (p.co + 3u) / 4u, p.co <= 8u);
}

struct Acc16 { a: array<vec4<f32>, 16> }

// acc[o] += dy[o] * x for the 16 output channels of the position held by lane `j` of the
// group (g0..g3: its dy texels).
fn bw_step(acc: Acc16, x: vec4<f32>, g0: vec4<f32>, g1: vec4<f32>, g2: vec4<f32>, g3: vec4<f32>, j: u32) -> Acc16 {
    let d0 = subgroupShuffle(g0, j); let d1 = subgroupShuffle(g1, j);
    let d2 = subgroupShuffle(g2, j); let d3 = subgroupShuffle(g3, j);
    var r = acc;
    r.a[0] += d0.x * x; r.a[1] += d0.y * x; r.a[2] += d0.z * x; r.a[3] += d0.w * x;
    r.a[4] += d1.x * x; r.a[5] += d1.y * x; r.a[6] += d1.z * x; r.a[7] += d1.w * x;
    r.a[8] += d2.x * x; r.a[9] += d2.y * x; r.a[10] += d2.z * x; r.a[11] += d2.w * x;
    r.a[12] += d3.x * x; r.a[13] += d3.y * x; r.a[14] += d3.z * x; r.a[15] += d3.w * x;
    return r;
}

fn bw_x(n: u32, q: u32, zd: i32, zh: i32, zw: i32) -> vec4<f32> {
    let inside = zd >= 0 && zd < i32(p.id) && zh >= 0 && zh < i32(p.ih) && zw >= 0 && zw < i32(p.iw);
    let c = vec3<i32>(clamp(zw, 0, i32(p.iw) - 1), clamp(zh, 0, i32(p.ih) - 1),
                      i32((n * (p.cpad / 4u) + q) * p.id) + clamp(zd, 0, i32(p.id) - 1));
    return select(vec4<f32>(0.0), textureLoad(bx, c), inside);
}

// Weight-gradient tile `t` (groups of 8 (tap, channel quad) pairs, per output channel group
// and chunk of rows): lane `lane`'s pair (tap clamped for lanes past the last pair).
struct BwPair { chunk: u32, cg: u32, pair: u32, tap: u32, q: u32 }

fn bw_pair(t: u32, lane: u32) -> BwPair {
    let taps = p.kd * p.kh * p.kw;
    let cq = p.cpad / 4u;
    let groups = (taps * cq + 7u) / 8u;
    let r = t / groups;
    let pair = (t % groups) * 8u + lane;
    return BwPair(r / p.co16, r % p.co16, pair, min(pair / cq, taps - 1u), pair % cq);
}

@compute @workgroup_size(64)
fn conv_fast_backward_weight_tex(ids: LaneIds) {
    let tl = lane_tile(ids);
    let t = tl.x;
    if (t >= p.total) { return; }
    let lane = tl.y;
    let base = tl.z;
    let taps = p.kd * p.kh * p.kw;
    let cq = p.cpad / 4u;
    let bp = bw_pair(t, lane);
    let cg = bp.cg; let chunk = bp.chunk; let tap = bp.tap; let q = bp.q;
    let live = bp.pair < taps * cq;
    let k = tap_axes(tap);
    let kw = k.z;
    let span = chunk_rows(chunk);
    let dq = dy_quads();
    var acc: Acc16;
    var w = walk_from(span.x);
    let steps = walk_steps(span);
    for (var i = 0u; i < steps; i++) {
        let z = walk_z(w, k);
        let n = w.n;
        let oh = w.oh;
        let zd = z.x;
        let zh = z.y;
        let ow0 = w.ow0;
        let dz = i32((n * dq + cg * 4u) * p.od + w.od);
        // Lane l fetches the 16 dy values at ow0 + l (zero past the row's end).
        let mine = ow0 + lane;
        let ok = mine < p.ow;
        let dc = vec3<i32>(i32(min(mine, p.ow - 1u)), i32(oh), dz);
        let od_ = i32(p.od);
        let g0 = select(vec4<f32>(0.0), textureLoad(bdy, dc), ok);
        let g1 = select(vec4<f32>(0.0), textureLoad(bdy, dc + vec3<i32>(0, 0, od_)), ok);
        let g2 = select(vec4<f32>(0.0), textureLoad(bdy, dc + vec3<i32>(0, 0, 2 * od_)), ok);
        let g3 = select(vec4<f32>(0.0), textureLoad(bdy, dc + vec3<i32>(0, 0, 3 * od_)), ok);
        let zw = i32(ow0 * p.sw + kw) - i32(p.pw);
        let s = i32(p.sw);
        // Written out: llvmpipe does not unroll loops.
        acc = bw_step(acc, bw_x(n, q, zd, zh, zw), g0, g1, g2, g3, base);
        acc = bw_step(acc, bw_x(n, q, zd, zh, zw + s), g0, g1, g2, g3, base + 1u);
        acc = bw_step(acc, bw_x(n, q, zd, zh, zw + 2 * s), g0, g1, g2, g3, base + 2u);
        acc = bw_step(acc, bw_x(n, q, zd, zh, zw + 3 * s), g0, g1, g2, g3, base + 3u);
        acc = bw_step(acc, bw_x(n, q, zd, zh, zw + 4 * s), g0, g1, g2, g3, base + 4u);
        acc = bw_step(acc, bw_x(n, q, zd, zh, zw + 5 * s), g0, g1, g2, g3, base + 5u);
        acc = bw_step(acc, bw_x(n, q, zd, zh, zw + 6 * s), g0, g1, g2, g3, base + 6u);
        acc = bw_step(acc, bw_x(n, q, zd, zh, zw + 7 * s), g0, g1, g2, g3, base + 7u);
        w = walk_next(w);
    }
    if (!live) { return; }
    let copad = p.co16 * 16u;
    let o = ((chunk * taps + tap) * p.cpad + 4u * q) * copad + cg * 16u;
    for (var k = 0u; k < 16u; k++) {
        let v = acc.a[k];
        bpart[o + k] = v.x;
        bpart[o + copad + k] = v.y;
        bpart[o + 2u * copad + k] = v.z;
        bpart[o + 3u * copad + k] = v.w;
    }
}

// ---- backward weight, narrow (co <= 4): as above with one dy texel per position ----------
// dy packed with 4 channels (one quad per voxel); each lane accumulates dw[4 channels][4
// channels] of its (tap, quad) pair; part keeps the 16-column layout (columns 0..3 written).
struct Acc4 { a0: vec4<f32>, a1: vec4<f32>, a2: vec4<f32>, a3: vec4<f32> }

fn bw_step4(acc: Acc4, x: vec4<f32>, g: vec4<f32>, j: u32) -> Acc4 {
    let d = subgroupShuffle(g, j);
    return Acc4(acc.a0 + d.x * x, acc.a1 + d.y * x, acc.a2 + d.z * x, acc.a3 + d.w * x);
}

@compute @workgroup_size(64)
fn conv_fast_backward_weight_tex4(ids: LaneIds) {
    let tl = lane_tile(ids);
    let t = tl.x;
    if (t >= p.total) { return; }
    let lane = tl.y;
    let base = tl.z;
    let taps = p.kd * p.kh * p.kw;
    let cq = p.cpad / 4u;
    // co16 = 1: channel group 0.
    let bp = bw_pair(t, lane);
    let chunk = bp.chunk; let pair = bp.pair; let tap = bp.tap; let q = bp.q;
    let k = tap_axes(tap);
    let span = chunk_rows(chunk);
    var acc = Acc4(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    var w = walk_from(span.x);
    let steps = walk_steps(span);
    for (var i = 0u; i < steps; i++) {
        let z = walk_z(w, k);
        let n = w.n;
        let zd = z.x;
        let zh = z.y;
        let ow0 = w.ow0;
        // Lane l fetches the dy texel at ow0 + l (zero past the row's end).
        let mine = ow0 + lane;
        let dc = vec3<i32>(i32(min(mine, p.ow - 1u)), i32(w.oh), i32(n * p.od + w.od));
        let g = select(vec4<f32>(0.0), textureLoad(bdy, dc), mine < p.ow);
        let zw = i32(ow0 * p.sw + k.z) - i32(p.pw);
        let s = i32(p.sw);
        acc = bw_step4(acc, bw_x(n, q, zd, zh, zw), g, base);
        acc = bw_step4(acc, bw_x(n, q, zd, zh, zw + s), g, base + 1u);
        acc = bw_step4(acc, bw_x(n, q, zd, zh, zw + 2 * s), g, base + 2u);
        acc = bw_step4(acc, bw_x(n, q, zd, zh, zw + 3 * s), g, base + 3u);
        acc = bw_step4(acc, bw_x(n, q, zd, zh, zw + 4 * s), g, base + 4u);
        acc = bw_step4(acc, bw_x(n, q, zd, zh, zw + 5 * s), g, base + 5u);
        acc = bw_step4(acc, bw_x(n, q, zd, zh, zw + 6 * s), g, base + 6u);
        acc = bw_step4(acc, bw_x(n, q, zd, zh, zw + 7 * s), g, base + 7u);
        w = walk_next(w);
    }
    if (pair >= taps * cq) { return; }
    let o = ((chunk * taps + tap) * p.cpad + 4u * q) * 16u;
    let a = array<vec4<f32>, 4>(acc.a0, acc.a1, acc.a2, acc.a3);
    for (var c = 0u; c < 4u; c++) {
        let v = a[c];
        bpart[o + c] = v.x;
        bpart[o + 16u + c] = v.y;
        bpart[o + 32u + c] = v.z;
        bpart[o + 48u + c] = v.w;
    }
}

// ---- backward weight, half width (5-8 output channels): two dy texels per position --------
// dy packed with 8 channels (two quads per voxel: the packing backward_input reads, so one
// packing serves both gradients), where the 16-channel kernel above would multiply 8-11 zero
// channels of 16; each lane accumulates dw[8 channels][4 channels] of its (tap, quad) pair;
// part keeps the 16-column layout (columns 0..7 written).
struct BwAcc8 { a: array<vec4<f32>, 8> }

fn bw_step8(acc: BwAcc8, x: vec4<f32>, g0: vec4<f32>, g1: vec4<f32>, j: u32) -> BwAcc8 {
    let d0 = subgroupShuffle(g0, j); let d1 = subgroupShuffle(g1, j);
    var r = acc;
    r.a[0] += d0.x * x; r.a[1] += d0.y * x; r.a[2] += d0.z * x; r.a[3] += d0.w * x;
    r.a[4] += d1.x * x; r.a[5] += d1.y * x; r.a[6] += d1.z * x; r.a[7] += d1.w * x;
    return r;
}

@compute @workgroup_size(64)
fn conv_fast_backward_weight_tex8(ids: LaneIds) {
    let tl = lane_tile(ids);
    let t = tl.x;
    if (t >= p.total) { return; }
    let lane = tl.y;
    let base = tl.z;
    let taps = p.kd * p.kh * p.kw;
    // co16 = 1: channel group 0.
    let bp = bw_pair(t, lane);
    let chunk = bp.chunk; let tap = bp.tap; let q = bp.q;
    let k = tap_axes(tap);
    let span = chunk_rows(chunk);
    var acc: BwAcc8;
    var w = walk_from(span.x);
    let steps = walk_steps(span);
    for (var i = 0u; i < steps; i++) {
        let z = walk_z(w, k);
        let n = w.n;
        let zd = z.x;
        let zh = z.y;
        let ow0 = w.ow0;
        // Lane l fetches the two dy texels at ow0 + l (zero past the row's end).
        let mine = ow0 + lane;
        let ok = mine < p.ow;
        let dc = vec3<i32>(i32(min(mine, p.ow - 1u)), i32(w.oh), i32(2u * n * p.od + w.od));
        let g0 = select(vec4<f32>(0.0), textureLoad(bdy, dc), ok);
        let g1 = select(vec4<f32>(0.0), textureLoad(bdy, dc + vec3<i32>(0, 0, i32(p.od))), ok);
        let zw = i32(ow0 * p.sw + k.z) - i32(p.pw);
        let s = i32(p.sw);
        acc = bw_step8(acc, bw_x(n, q, zd, zh, zw), g0, g1, base);
        acc = bw_step8(acc, bw_x(n, q, zd, zh, zw + s), g0, g1, base + 1u);
        acc = bw_step8(acc, bw_x(n, q, zd, zh, zw + 2 * s), g0, g1, base + 2u);
        acc = bw_step8(acc, bw_x(n, q, zd, zh, zw + 3 * s), g0, g1, base + 3u);
        acc = bw_step8(acc, bw_x(n, q, zd, zh, zw + 4 * s), g0, g1, base + 4u);
        acc = bw_step8(acc, bw_x(n, q, zd, zh, zw + 5 * s), g0, g1, base + 5u);
        acc = bw_step8(acc, bw_x(n, q, zd, zh, zw + 6 * s), g0, g1, base + 6u);
        acc = bw_step8(acc, bw_x(n, q, zd, zh, zw + 7 * s), g0, g1, base + 7u);
        w = walk_next(w);
    }
    if (bp.pair >= taps * (p.cpad / 4u)) { return; }
    let o = ((chunk * taps + tap) * p.cpad + 4u * q) * 16u;
    for (var c = 0u; c < 8u; c++) {
        let v = acc.a[c];
        bpart[o + c] = v.x;
        bpart[o + 16u + c] = v.y;
        bpart[o + 32u + c] = v.z;
        bpart[o + 48u + c] = v.w;
    }
}
