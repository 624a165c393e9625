// prepend: conv_fast.wgsl, conv_tex.wgsl
// The texture family's weight-gradient tiles (see conv_tex.wgsl for the family): x and dy
// read through textures, dy shared across lanes by subgroup shuffles, partial sums per chunk of
// output rows that conv_fast_weight_sum adds. Compiled appended to conv_fast.wgsl (Params,
// chunk_rows, tap_axes, walk_from, walk_next) and conv_tex.wgsl (LaneIds, lane_tile);
// conv_direct_weight.wgsl's weight gradients use this file's bdy, bpart, dy_quads and dy_texel.

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

// dy texels per voxel as src/ops/conv_fast_weight.rs (dy_tex_channels) packs dy for the weight
// gradients: one or two quads for at most 4 or 8 output channels, else co16 * 4.
fn dy_quads() -> u32 {
    return select(p.co16 * 4u, (p.co + 3u) / 4u, p.co <= 8u);
}

struct Acc16 { a: array<vec4<f32>, 16> }

// acc[o] += dy[o] * x for the 16 output channels of the position held by lane `j` of the
// group (g0..g3: its dy texels).
fn bw_step(acc: Acc16, x: vec4<f32>, g0: vec4<f32>, g1: vec4<f32>, g2: vec4<f32>, g3: vec4<f32>, j: u32) -> Acc16 {
    return bw_mac16(acc, x, subgroupShuffle(g0, j), subgroupShuffle(g1, j), subgroupShuffle(g2, j), subgroupShuffle(g3, j));
}

// acc[o] += d[o] * x for the 16 output channels d0..d3 hold.
fn bw_mac16(acc: Acc16, x: vec4<f32>, d0: vec4<f32>, d1: vec4<f32>, d2: vec4<f32>, d3: vec4<f32>) -> Acc16 {
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

// What every weight-gradient lane needs: its pair, whether that pair is real, the tap's axes,
// the chunk's rows, and the lane's place in the tile (tl as lane_tile returns it).
struct BwLane { bp: BwPair, live: bool, k: vec3<u32>, span: vec2<u32>, lane: u32, base: u32 }

fn bw_lane(tl: vec3<u32>) -> BwLane {
    let bp = bw_pair(tl.x, tl.y);
    return BwLane(bp, bp.pair < p.kd * p.kh * p.kw * (p.cpad / 4u), tap_axes(bp.tap), chunk_rows(bp.chunk), tl.y, tl.z);
}

// The first part row of the lane's pair: part[chunk][tap][4q] (rows of copad columns).
fn bw_part_row(b: BwLane) -> u32 {
    return (b.bp.chunk * p.kd * p.kh * p.kw + b.bp.tap) * p.cpad + 4u * b.bp.q;
}

// The x texels of a step: the lane's channel quad at the 8 columns ow0..ow0+7 reach through
// its tap (one per lane of the tile, handed around with its dy by the step functions).
fn bw_xs(w: Walk, b: BwLane) -> Rows {
    let z = walk_z(w, b.k);
    let zw = i32(w.ow0 * p.sw + b.k.z) - i32(p.pw);
    let s = i32(p.sw);
    let n = w.n; let q = b.bp.q;
    return Rows(bw_x(n, q, z.x, z.y, zw), bw_x(n, q, z.x, z.y, zw + s), bw_x(n, q, z.x, z.y, zw + 2 * s),
                bw_x(n, q, z.x, z.y, zw + 3 * s), bw_x(n, q, z.x, z.y, zw + 4 * s), bw_x(n, q, z.x, z.y, zw + 5 * s),
                bw_x(n, q, z.x, z.y, zw + 6 * s), bw_x(n, q, z.x, z.y, zw + 7 * s));
}

// The lane's dy texel of quad `quad` at column ow0 + lane of the step's row (zero past its end).
fn dy_texel(w: Walk, lane: u32, quad: u32) -> vec4<f32> {
    let mine = w.ow0 + lane;
    let dc = vec3<i32>(i32(min(mine, p.ow - 1u)), i32(w.oh), i32((w.n * dy_quads() + quad) * p.od + w.od));
    return select(vec4<f32>(0.0), textureLoad(bdy, dc), mine < p.ow);
}

// dw of output channels o.. (column c of part row o) for input channels 4q..4q+3 (v), rows
// `stride` apart.
fn put_dw(o: u32, c: u32, stride: u32, v: vec4<f32>) {
    bpart[o + c] = v.x;
    bpart[o + stride + c] = v.y;
    bpart[o + 2u * stride + c] = v.z;
    bpart[o + 3u * stride + c] = v.w;
}

@compute @workgroup_size(64)
fn conv_fast_backward_weight_tex(ids: LaneIds) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    let b = bw_lane(tl);
    let cg = b.bp.cg; let base = b.base;
    var acc: Acc16;
    var w = walk_from(b.span.x);
    let steps = walk_steps(b.span);
    for (var i = 0u; i < steps; i++) {
        // Lane l fetches the 16 dy values at ow0 + l.
        let g0 = dy_texel(w, b.lane, cg * 4u);
        let g1 = dy_texel(w, b.lane, cg * 4u + 1u);
        let g2 = dy_texel(w, b.lane, cg * 4u + 2u);
        let g3 = dy_texel(w, b.lane, cg * 4u + 3u);
        let x = bw_xs(w, b);
        // Written out: llvmpipe does not unroll loops.
        acc = bw_step(acc, x.r0, g0, g1, g2, g3, base);
        acc = bw_step(acc, x.r1, g0, g1, g2, g3, base + 1u);
        acc = bw_step(acc, x.r2, g0, g1, g2, g3, base + 2u);
        acc = bw_step(acc, x.r3, g0, g1, g2, g3, base + 3u);
        acc = bw_step(acc, x.r4, g0, g1, g2, g3, base + 4u);
        acc = bw_step(acc, x.r5, g0, g1, g2, g3, base + 5u);
        acc = bw_step(acc, x.r6, g0, g1, g2, g3, base + 6u);
        acc = bw_step(acc, x.r7, g0, g1, g2, g3, base + 7u);
        w = walk_next(w);
    }
    if (!b.live) { return; }
    let copad = p.co16 * 16u;
    let o = bw_part_row(b) * copad + cg * 16u;
    for (var k = 0u; k < 16u; k++) {
        put_dw(o, k, copad, acc.a[k]);
    }
}

// ---- backward weight, narrow (co <= 4): as above with one dy texel per position ----------
// dy packed with 4 channels (one quad per voxel); each lane accumulates dw[4 channels][4
// channels] of its (tap, quad) pair; part keeps the 16-column layout (columns 0..3 written).
struct Acc4 { a0: vec4<f32>, a1: vec4<f32>, a2: vec4<f32>, a3: vec4<f32> }

fn bw_step4(acc: Acc4, x: vec4<f32>, g: vec4<f32>, j: u32) -> Acc4 {
    return bw_mac4(acc, x, subgroupShuffle(g, j));
}

fn bw_mac4(acc: Acc4, x: vec4<f32>, d: vec4<f32>) -> Acc4 {
    return Acc4(acc.a0 + d.x * x, acc.a1 + d.y * x, acc.a2 + d.z * x, acc.a3 + d.w * x);
}

@compute @workgroup_size(64)
fn conv_fast_backward_weight_tex4(ids: LaneIds) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    // co16 = 1: channel group 0.
    let b = bw_lane(tl);
    let base = b.base;
    var acc = Acc4(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    var w = walk_from(b.span.x);
    let steps = walk_steps(b.span);
    for (var i = 0u; i < steps; i++) {
        let g = dy_texel(w, b.lane, 0u);
        let x = bw_xs(w, b);
        acc = bw_step4(acc, x.r0, g, base);
        acc = bw_step4(acc, x.r1, g, base + 1u);
        acc = bw_step4(acc, x.r2, g, base + 2u);
        acc = bw_step4(acc, x.r3, g, base + 3u);
        acc = bw_step4(acc, x.r4, g, base + 4u);
        acc = bw_step4(acc, x.r5, g, base + 5u);
        acc = bw_step4(acc, x.r6, g, base + 6u);
        acc = bw_step4(acc, x.r7, g, base + 7u);
        w = walk_next(w);
    }
    if (!b.live) { return; }
    put_dw4(bw_part_row(b) * 16u, acc);
}

// ---- backward weight, half width (5-8 output channels): two dy texels per position --------
// dy packed with 8 channels (two quads per voxel: the packing backward_input reads, so one
// packing serves both gradients), where the 16-channel kernel above would multiply 8-11 zero
// channels of 16; each lane accumulates dw[8 channels][4 channels] of its (tap, quad) pair;
// part keeps the 16-column layout (columns 0..7 written).
struct BwAcc8 { a: array<vec4<f32>, 8> }

fn bw_step8(acc: BwAcc8, x: vec4<f32>, g0: vec4<f32>, g1: vec4<f32>, j: u32) -> BwAcc8 {
    return bw_mac8(acc, x, subgroupShuffle(g0, j), subgroupShuffle(g1, j));
}

fn bw_mac8(acc: BwAcc8, x: vec4<f32>, d0: vec4<f32>, d1: vec4<f32>) -> BwAcc8 {
    var r = acc;
    r.a[0] += d0.x * x; r.a[1] += d0.y * x; r.a[2] += d0.z * x; r.a[3] += d0.w * x;
    r.a[4] += d1.x * x; r.a[5] += d1.y * x; r.a[6] += d1.z * x; r.a[7] += d1.w * x;
    return r;
}

@compute @workgroup_size(64)
fn conv_fast_backward_weight_tex8(ids: LaneIds) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    // co16 = 1: channel group 0.
    let b = bw_lane(tl);
    let base = b.base;
    var acc: BwAcc8;
    var w = walk_from(b.span.x);
    let steps = walk_steps(b.span);
    for (var i = 0u; i < steps; i++) {
        // Lane l fetches the two dy texels at ow0 + l.
        let g0 = dy_texel(w, b.lane, 0u);
        let g1 = dy_texel(w, b.lane, 1u);
        let x = bw_xs(w, b);
        acc = bw_step8(acc, x.r0, g0, g1, base);
        acc = bw_step8(acc, x.r1, g0, g1, base + 1u);
        acc = bw_step8(acc, x.r2, g0, g1, base + 2u);
        acc = bw_step8(acc, x.r3, g0, g1, base + 3u);
        acc = bw_step8(acc, x.r4, g0, g1, base + 4u);
        acc = bw_step8(acc, x.r5, g0, g1, base + 5u);
        acc = bw_step8(acc, x.r6, g0, g1, base + 6u);
        acc = bw_step8(acc, x.r7, g0, g1, base + 7u);
        w = walk_next(w);
    }
    if (!b.live) { return; }
    let o = bw_part_row(b) * 16u;
    for (var c = 0u; c < 8u; c++) {
        put_dw(o, c, 16u, acc.a[c]);
    }
}

// ---- backward weight, three W taps a lane (kw = 3, sw = 1, not folded) ----------------------
// As the tiles above, but a lane owns a tap row r = (kd, kh) and channel quad q (pair r * cq +
// q) with all three of its taps along W, for at most 4 output channels (`_tex4_w3`) or a group
// of 8 (`_tex8_w3`; src/ops/conv_fast_weight.rs says when). At column stride 1 those taps read overlapping x:
// 10 texels serve a step's 8 positions x 3 taps, where the tiles above fetch a texel for every
// (position, tap), and a texel fetch costs lavapipe tens of FMAs (`rendernet bench
// --operands`). The part layout is unchanged (the three taps are consecutive rows).
fn bw_lane3(tl: vec3<u32>) -> BwLane {
    let rows = p.kd * p.kh;
    let cq = p.cpad / 4u;
    let groups = (rows * cq + 7u) / 8u;
    let r = tl.x / groups;
    let pair = (tl.x % groups) * 8u + tl.y;
    // Output channel groups of 8 (one for the narrow tiles): cg is the group.
    let per = (p.co + 7u) / 8u;
    let bp = BwPair(r / per, r % per, pair, min(pair / cq, rows - 1u) * 3u, pair % cq);
    return BwLane(bp, pair < rows * cq, tap_axes(bp.tap), chunk_rows(bp.chunk), tl.y, tl.z);
}

// The 10 x texels of a step for a lane of bw_lane3: columns ow0 - pw .. ow0 - pw + 9.
struct Xs10 { r: Rows, x8: vec4<f32>, x9: vec4<f32> }

fn bw_xs10(w: Walk, b: BwLane) -> Xs10 {
    let z = walk_z(w, b.k);
    let zw = i32(w.ow0) - i32(p.pw);
    return Xs10(bw_xs(w, b), bw_x(w.n, b.bp.q, z.x, z.y, zw + 8), bw_x(w.n, b.bp.q, z.x, z.y, zw + 9));
}

struct Acc4x3 { t0: Acc4, t1: Acc4, t2: Acc4 }

fn bw_step4x3(acc: Acc4x3, x0: vec4<f32>, x1: vec4<f32>, x2: vec4<f32>, g: vec4<f32>, j: u32) -> Acc4x3 {
    let d = subgroupShuffle(g, j);
    return Acc4x3(bw_mac4(acc.t0, x0, d), bw_mac4(acc.t1, x1, d), bw_mac4(acc.t2, x2, d));
}

fn put_dw4(o: u32, a: Acc4) {
    put_dw(o, 0u, 16u, a.a0); put_dw(o, 1u, 16u, a.a1);
    put_dw(o, 2u, 16u, a.a2); put_dw(o, 3u, 16u, a.a3);
}

@compute @workgroup_size(64)
fn conv_fast_backward_weight_tex4_w3(ids: LaneIds) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    // co16 = 1: channel group 0.
    let b = bw_lane3(tl);
    let base = b.base;
    var acc: Acc4x3;
    var w = walk_from(b.span.x);
    let steps = walk_steps(b.span);
    for (var i = 0u; i < steps; i++) {
        let g = dy_texel(w, b.lane, 0u);
        let x = bw_xs10(w, b);
        acc = bw_step4x3(acc, x.r.r0, x.r.r1, x.r.r2, g, base);
        acc = bw_step4x3(acc, x.r.r1, x.r.r2, x.r.r3, g, base + 1u);
        acc = bw_step4x3(acc, x.r.r2, x.r.r3, x.r.r4, g, base + 2u);
        acc = bw_step4x3(acc, x.r.r3, x.r.r4, x.r.r5, g, base + 3u);
        acc = bw_step4x3(acc, x.r.r4, x.r.r5, x.r.r6, g, base + 4u);
        acc = bw_step4x3(acc, x.r.r5, x.r.r6, x.r.r7, g, base + 5u);
        acc = bw_step4x3(acc, x.r.r6, x.r.r7, x.x8, g, base + 6u);
        acc = bw_step4x3(acc, x.r.r7, x.x8, x.x9, g, base + 7u);
        w = walk_next(w);
    }
    if (!b.live) { return; }
    let o = bw_part_row(b) * 16u;
    put_dw4(o, acc.t0);
    put_dw4(o + p.cpad * 16u, acc.t1);
    put_dw4(o + 2u * p.cpad * 16u, acc.t2);
}

struct Acc8x3 { t0: BwAcc8, t1: BwAcc8, t2: BwAcc8 }

fn bw_step8x3(acc: Acc8x3, x0: vec4<f32>, x1: vec4<f32>, x2: vec4<f32>, g0: vec4<f32>, g1: vec4<f32>, j: u32) -> Acc8x3 {
    let d0 = subgroupShuffle(g0, j); let d1 = subgroupShuffle(g1, j);
    return Acc8x3(bw_mac8(acc.t0, x0, d0, d1), bw_mac8(acc.t1, x1, d0, d1), bw_mac8(acc.t2, x2, d0, d1));
}

@compute @workgroup_size(64)
fn conv_fast_backward_weight_tex8_w3(ids: LaneIds) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    // Output channels 8 cg .. 8 cg + 7: dy quads 2 cg, 2 cg + 1.
    let b = bw_lane3(tl);
    let base = b.base; let cg = b.bp.cg;
    var acc: Acc8x3;
    var w = walk_from(b.span.x);
    let steps = walk_steps(b.span);
    for (var i = 0u; i < steps; i++) {
        let g0 = dy_texel(w, b.lane, 2u * cg);
        let g1 = dy_texel(w, b.lane, 2u * cg + 1u);
        let x = bw_xs10(w, b);
        acc = bw_step8x3(acc, x.r.r0, x.r.r1, x.r.r2, g0, g1, base);
        acc = bw_step8x3(acc, x.r.r1, x.r.r2, x.r.r3, g0, g1, base + 1u);
        acc = bw_step8x3(acc, x.r.r2, x.r.r3, x.r.r4, g0, g1, base + 2u);
        acc = bw_step8x3(acc, x.r.r3, x.r.r4, x.r.r5, g0, g1, base + 3u);
        acc = bw_step8x3(acc, x.r.r4, x.r.r5, x.r.r6, g0, g1, base + 4u);
        acc = bw_step8x3(acc, x.r.r5, x.r.r6, x.r.r7, g0, g1, base + 5u);
        acc = bw_step8x3(acc, x.r.r6, x.r.r7, x.x8, g0, g1, base + 6u);
        acc = bw_step8x3(acc, x.r.r7, x.x8, x.x9, g0, g1, base + 7u);
        w = walk_next(w);
    }
    if (!b.live) { return; }
    let copad = p.co16 * 16u;
    let o = bw_part_row(b) * copad + 8u * cg;
    let next = p.cpad * copad;
    for (var c = 0u; c < 8u; c++) {
        put_dw(o, c, copad, acc.t0.a[c]);
        put_dw(o + next, c, copad, acc.t1.a[c]);
        put_dw(o + 2u * next, c, copad, acc.t2.a[c]);
    }
}
