// prepend: conv_fast.wgsl, conv_tex.wgsl
// The texture family's weight-gradient tiles (see conv_tex.wgsl for the family): x and dy
// read through textures, dy shared across lanes by subgroup shuffles, partial sums per chunk of
// output rows that conv_fast_weight_sum adds. Compiled appended to conv_fast.wgsl (Params,
// chunk_rows, tap_axes, walk_from, walk_next) and conv_tex.wgsl (LaneIds, lane_tile1: every tile here is a workgroup of its own);
// conv_direct_weight.wgsl's weight gradients use this file's bdy, bpart, dy_quads and dy_texel.

// ---- backward weight: lanes = 8 (tap, input channel quad) pairs; dy shared by shuffles ----
// One subgroup of 8 lanes per (group of 8 pairs, output channel group of 16, chunk of output
// rows). Lane L owns pair L = tap * cq + q and accumulates dw[16 channels][4 channels] of it
// over the chunk's positions, 8 columns a step: it fetches its x texels at the positions its
// tap reaches, while the 16 dy values of each position (the same for every lane) come from
// texels the 8 lanes fetched for the step's 8 positions, handed around with subgroupShuffle
// (dy_t), and each accumulator takes the step's 8 multiply-adds in a row (chain8).
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

// a + sum_j c_j x_j over a step's 8 positions (c: one output channel's dy, positions 0..3 in
// lo, 4..7 in hi): one accumulator through 8 multiply-adds in a row, so that it is loaded and
// stored once for them. lavapipe keeps a tile's accumulators in memory; with one
// multiply-add per accumulator a position (as the tiles did), a store per multiply-add bounds
// the tile on AMD Zen (README "Weight gradients an accumulator at a time").
fn chain8(a: vec4<f32>, lo: vec4<f32>, hi: vec4<f32>, x0: vec4<f32>, x1: vec4<f32>, x2: vec4<f32>, x3: vec4<f32>,
          x4: vec4<f32>, x5: vec4<f32>, x6: vec4<f32>, x7: vec4<f32>) -> vec4<f32> {
    return a + lo.x * x0 + lo.y * x1 + lo.z * x2 + lo.w * x3 + hi.x * x4 + hi.y * x5 + hi.z * x6 + hi.w * x7;
}

// A step's dy of 4 output channels (quad texel g: lane j's is position j's) by channel:
// lo[c] holds channel c at positions 0..3, hi[c] at 4..7.
struct DyT { lo: array<vec4<f32>, 4>, hi: array<vec4<f32>, 4> }

fn dy_t(g: vec4<f32>, base: u32) -> DyT {
    let d0 = subgroupShuffle(g, base); let d1 = subgroupShuffle(g, base + 1u);
    let d2 = subgroupShuffle(g, base + 2u); let d3 = subgroupShuffle(g, base + 3u);
    let d4 = subgroupShuffle(g, base + 4u); let d5 = subgroupShuffle(g, base + 5u);
    let d6 = subgroupShuffle(g, base + 6u); let d7 = subgroupShuffle(g, base + 7u);
    return DyT(array<vec4<f32>, 4>(vec4<f32>(d0.x, d1.x, d2.x, d3.x), vec4<f32>(d0.y, d1.y, d2.y, d3.y),
                                   vec4<f32>(d0.z, d1.z, d2.z, d3.z), vec4<f32>(d0.w, d1.w, d2.w, d3.w)),
               array<vec4<f32>, 4>(vec4<f32>(d4.x, d5.x, d6.x, d7.x), vec4<f32>(d4.y, d5.y, d6.y, d7.y),
                                   vec4<f32>(d4.z, d5.z, d6.z, d7.z), vec4<f32>(d4.w, d5.w, d6.w, d7.w)));
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
// the chunk's rows, and the lane's place in the tile (tl as lane_tile1 returns it).
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

// 4 output channels' dw over a step (d: their dy by channel, dy_t; x: the 8 positions' x).
struct Acc4 { a0: vec4<f32>, a1: vec4<f32>, a2: vec4<f32>, a3: vec4<f32> }

fn rows8(a: vec4<f32>, lo: vec4<f32>, hi: vec4<f32>, x: Rows) -> vec4<f32> {
    return chain8(a, lo, hi, x.r0, x.r1, x.r2, x.r3, x.r4, x.r5, x.r6, x.r7);
}

fn quad8(a: Acc4, d: DyT, x: Rows) -> Acc4 {
    return Acc4(rows8(a.a0, d.lo[0], d.hi[0], x), rows8(a.a1, d.lo[1], d.hi[1], x),
                rows8(a.a2, d.lo[2], d.hi[2], x), rows8(a.a3, d.lo[3], d.hi[3], x));
}

// dw of output channels c.. (columns c..c + 3 of part rows `stride` apart from o).
fn put_dw4(o: u32, c: u32, stride: u32, a: Acc4) {
    put_dw(o, c, stride, a.a0); put_dw(o, c + 1u, stride, a.a1);
    put_dw(o, c + 2u, stride, a.a2); put_dw(o, c + 3u, stride, a.a3);
}

// The lane's dy of quad `quad` over the step by channel (dy_texel, then dy_t).
fn dy_step(w: Walk, b: BwLane, quad: u32) -> DyT {
    return dy_t(dy_texel(w, b.lane, quad), b.base);
}

@compute @workgroup_size(8)
fn conv_fast_backward_weight_tex(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    let b = bw_lane(tl);
    let q0 = b.bp.cg * 4u;
    var a0: Acc4; var a1: Acc4; var a2: Acc4; var a3: Acc4;
    var w = walk_from(b.span.x);
    let steps = walk_steps(b.span);
    for (var i = 0u; i < steps; i++) {
        // Lane l fetches the 16 dy values at ow0 + l.
        let x = bw_xs(w, b);
        a0 = quad8(a0, dy_step(w, b, q0), x);
        a1 = quad8(a1, dy_step(w, b, q0 + 1u), x);
        a2 = quad8(a2, dy_step(w, b, q0 + 2u), x);
        a3 = quad8(a3, dy_step(w, b, q0 + 3u), x);
        w = walk_next(w);
    }
    if (!b.live) { return; }
    let copad = p.co16 * 16u;
    let o = bw_part_row(b) * copad + q0 * 4u;
    put_dw4(o, 0u, copad, a0); put_dw4(o, 4u, copad, a1);
    put_dw4(o, 8u, copad, a2); put_dw4(o, 12u, copad, a3);
}

// ---- backward weight, narrow (co <= 4): as above with one dy texel per position ----------
// dy packed with 4 channels (one quad per voxel); each lane accumulates dw[4 channels][4
// channels] of its (tap, quad) pair; part keeps the 16-column layout (columns 0..3 written).
@compute @workgroup_size(8)
fn conv_fast_backward_weight_tex4(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    // co16 = 1: channel group 0.
    let b = bw_lane(tl);
    var acc: Acc4;
    var w = walk_from(b.span.x);
    let steps = walk_steps(b.span);
    for (var i = 0u; i < steps; i++) {
        acc = quad8(acc, dy_step(w, b, 0u), bw_xs(w, b));
        w = walk_next(w);
    }
    if (!b.live) { return; }
    put_dw4(bw_part_row(b) * 16u, 0u, 16u, acc);
}

// ---- backward weight, half width (5-8 output channels): two dy texels per position --------
// dy packed with 8 channels (two quads per voxel: the packing backward_input reads, so one
// packing serves both gradients), where the 16-channel kernel above would multiply 8-11 zero
// channels of 16; each lane accumulates dw[8 channels][4 channels] of its (tap, quad) pair;
// part keeps the 16-column layout (columns 0..7 written).
@compute @workgroup_size(8)
fn conv_fast_backward_weight_tex8(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    // co16 = 1: channel group 0.
    let b = bw_lane(tl);
    var lo: Acc4; var hi: Acc4;
    var w = walk_from(b.span.x);
    let steps = walk_steps(b.span);
    for (var i = 0u; i < steps; i++) {
        let x = bw_xs(w, b);
        lo = quad8(lo, dy_step(w, b, 0u), x);
        hi = quad8(hi, dy_step(w, b, 1u), x);
        w = walk_next(w);
    }
    if (!b.live) { return; }
    let o = bw_part_row(b) * 16u;
    put_dw4(o, 0u, 16u, lo); put_dw4(o, 4u, 16u, hi);
}

// ---- backward weight, three W taps a lane (kw = 3, sw = 1, not folded) ----------------------
// As the tiles above, but a lane owns a tap row r = (kd, kh) and channel quad q (pair r * cq +
// q) with all three of its taps along W, for at most 4 output channels (`_tex4_w3`) or a group
// of 8 or 16 (`_tex8_w3`, `_tex16_w3`; src/ops/conv_fast_weight.rs, tex_tiling, says when). At
// column stride 1 those taps read overlapping x:
// 10 texels serve a step's 8 positions x 3 taps, where the tiles above fetch a texel for every
// (position, tap), and a texel fetch costs lavapipe tens of FMAs (`rendernet bench
// --operands`). The part layout is unchanged (the three taps are consecutive rows).
fn bw_lane3(tl: vec3<u32>) -> BwLane {
    return bw_lane3_of(tl, 8u);
}

// bw_lane3 over groups of `width` output channels.
fn bw_lane3_of(tl: vec3<u32>, width: u32) -> BwLane {
    let rows = p.kd * p.kh;
    let cq = p.cpad / 4u;
    // Output channel groups of `width` (one for the narrow tiles): cg is the group.
    let per = (p.co + width - 1u) / width;
    // Groups of 8 pairs a chunk and channel group: all of them, or (`_tex16_w3` beside
    // `_tex16_w3_halves`) the whole ones only.
    let groups = p.total / (p.nchunks * per);
    let r = tl.x / groups;
    let pair = (tl.x % groups) * 8u + tl.y;
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

// bw_xs10 at the next 8 columns (walk v), after x: its first 2 texels are x's last 2.
fn bw_xs10_after(x: Xs10, v: Walk, b: BwLane) -> Xs10 {
    let z = walk_z(v, b.k);
    let zw = i32(v.ow0) - i32(p.pw);
    let n = v.n; let q = b.bp.q;
    return Xs10(Rows(x.x8, x.x9, bw_x(n, q, z.x, z.y, zw + 2), bw_x(n, q, z.x, z.y, zw + 3), bw_x(n, q, z.x, z.y, zw + 4),
                     bw_x(n, q, z.x, z.y, zw + 5), bw_x(n, q, z.x, z.y, zw + 6), bw_x(n, q, z.x, z.y, zw + 7)),
                bw_x(n, q, z.x, z.y, zw + 8), bw_x(n, q, z.x, z.y, zw + 9));
}

// A lane's dw of one output channel at the three W taps (vec4: its 4 input channels).
struct Taps3 { k0: vec4<f32>, k1: vec4<f32>, k2: vec4<f32> }

// One output channel's dw at the 3 taps over a step (tap k reaches x texels k .. k + 7).
fn taps3(a: Taps3, lo: vec4<f32>, hi: vec4<f32>, x: Xs10) -> Taps3 {
    let r = x.r;
    return Taps3(chain8(a.k0, lo, hi, r.r0, r.r1, r.r2, r.r3, r.r4, r.r5, r.r6, r.r7),
                 chain8(a.k1, lo, hi, r.r1, r.r2, r.r3, r.r4, r.r5, r.r6, r.r7, x.x8),
                 chain8(a.k2, lo, hi, r.r2, r.r3, r.r4, r.r5, r.r6, r.r7, x.x8, x.x9));
}

// 4 output channels' dw at the 3 taps (d: their dy by channel).
struct Quad3 { c0: Taps3, c1: Taps3, c2: Taps3, c3: Taps3 }

fn quad3(a: Quad3, d: DyT, x: Xs10) -> Quad3 {
    return Quad3(taps3(a.c0, d.lo[0], d.hi[0], x), taps3(a.c1, d.lo[1], d.hi[1], x),
                 taps3(a.c2, d.lo[2], d.hi[2], x), taps3(a.c3, d.lo[3], d.hi[3], x));
}

// Writes a Quad3 (output channels c..c + 3) to the three taps' part rows from o.
fn put_quad3(o: u32, c: u32, stride: u32, a: Quad3) {
    let next = p.cpad * stride;
    put_dw4(o, c, stride, Acc4(a.c0.k0, a.c1.k0, a.c2.k0, a.c3.k0));
    put_dw4(o + next, c, stride, Acc4(a.c0.k1, a.c1.k1, a.c2.k1, a.c3.k1));
    put_dw4(o + 2u * next, c, stride, Acc4(a.c0.k2, a.c1.k2, a.c2.k2, a.c3.k2));
}

@compute @workgroup_size(8)
fn conv_fast_backward_weight_tex4_w3(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    // co16 = 1: channel group 0.
    let b = bw_lane3(tl);
    var acc: Quad3;
    var w = walk_from(b.span.x);
    let steps = walk_steps(b.span);
    for (var i = 0u; i < steps; i++) {
        acc = quad3(acc, dy_step(w, b, 0u), bw_xs10(w, b));
        w = walk_next(w);
    }
    if (!b.live) { return; }
    put_quad3(bw_part_row(b) * 16u, 0u, 16u, acc);
}

@compute @workgroup_size(8)
fn conv_fast_backward_weight_tex8_w3(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    // Output channels 8 cg .. 8 cg + 7: dy quads 2 cg, 2 cg + 1.
    let b = bw_lane3(tl);
    let cg = b.bp.cg;
    var lo: Quad3; var hi: Quad3;
    var w = walk_from(b.span.x);
    let steps = walk_steps(b.span);
    for (var i = 0u; i < steps; i++) {
        let x = bw_xs10(w, b);
        lo = quad3(lo, dy_step(w, b, 2u * cg), x);
        hi = quad3(hi, dy_step(w, b, 2u * cg + 1u), x);
        w = walk_next(w);
    }
    if (!b.live) { return; }
    let copad = p.co16 * 16u;
    let o = bw_part_row(b) * copad + 8u * cg;
    put_quad3(o, 0u, copad, lo); put_quad3(o, 4u, copad, hi);
}

// 16 output channels a lane (groups of 16: dy quads 4 cg .. 4 cg + 3): an x fetch feeds twice
// the multiply-adds of `_tex8_w3`, in half as many tiles. Steps of 16 columns (two of 8 in a
// row: ow0 and ow0 + 8; a row of an odd count of 8-column steps gets the tiles above, see
// conv_fast_weight::tex_tiling): lavapipe blends every accumulator with the loop's lane mask
// and stores it back once an iteration, so twice the multiply-adds an iteration halve that
// cost (1.04-1.10x on conv3d 16->16, README "Steps of 16 columns").
fn quad3_16(a: Quad3, w: Walk, v: Walk, b: BwLane, quad: u32, x: Xs10, y: Xs10) -> Quad3 {
    return quad3(quad3(a, dy_step(w, b, quad), x), dy_step(v, b, quad), y);
}

@compute @workgroup_size(8)
fn conv_fast_backward_weight_tex16_w3(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    let b = bw_lane3_of(tl, 16u);
    let q0 = 4u * b.bp.cg;
    var a0: Quad3; var a1: Quad3; var a2: Quad3; var a3: Quad3;
    var w = walk_from(b.span.x);
    let steps = walk_steps_by(b.span, 16u);
    for (var i = 0u; i < steps; i++) {
        let v = Walk(w.n, w.od, w.oh, w.ow0 + 8u);
        let x = bw_xs10(w, b);
        let y = bw_xs10_after(x, v, b);
        a0 = quad3_16(a0, w, v, b, q0, x, y);
        a1 = quad3_16(a1, w, v, b, q0 + 1u, x, y);
        a2 = quad3_16(a2, w, v, b, q0 + 2u, x, y);
        a3 = quad3_16(a3, w, v, b, q0 + 3u, x, y);
        w = walk_next_by(w, 16u);
    }
    if (!b.live) { return; }
    let copad = p.co16 * 16u;
    let o = bw_part_row(b) * copad + 4u * q0;
    put_quad3(o, 0u, copad, a0); put_quad3(o, 4u, copad, a1);
    put_quad3(o, 8u, copad, a2); put_quad3(o, 12u, copad, a3);
}

// ---- the same past the whole groups: two lanes a pair, a column half each -------------------
// Where a chunk's (tap row, quad) pairs leave 1-4 past their last whole group of 8 (3^3 taps on
// 16 channels: 36 pairs, 4 past 32), a tile of `_tex16_w3` over them would leave half its lanes
// or more idle. Here lane L takes pair 8 g + L % 4 (g whole groups) and, of each step of 16
// columns, the 8 of half L / 4: its x at those columns, and the dy of those positions (every
// lane fetches both halves' dy texels, as `_tex16_w3` does, and takes its half's after the
// shuffles). Lanes L and L ^ 4 then add their sums. One tile a chunk and output channel group;
// `_tex16_w3` takes the whole groups in a dispatch of its own (src/ops/conv_fast_weight.rs).
fn bw_lane3_halves(tl: vec3<u32>) -> BwLane {
    let rows = p.kd * p.kh;
    let cq = p.cpad / 4u;
    let per = (p.co + 15u) / 16u;
    let pair = (rows * cq / 8u) * 8u + tl.y % 4u;
    let bp = BwPair(tl.x / per, tl.x % per, pair, min(pair / cq, rows - 1u) * 3u, pair % cq);
    return BwLane(bp, pair < rows * cq, tap_axes(bp.tap), chunk_rows(bp.chunk), tl.y, tl.z);
}

// a where `first`, else b.
fn dyt_select(b: DyT, a: DyT, first: bool) -> DyT {
    return DyT(array<vec4<f32>, 4>(select(b.lo[0], a.lo[0], first), select(b.lo[1], a.lo[1], first),
                                   select(b.lo[2], a.lo[2], first), select(b.lo[3], a.lo[3], first)),
               array<vec4<f32>, 4>(select(b.hi[0], a.hi[0], first), select(b.hi[1], a.hi[1], first),
                                   select(b.hi[2], a.hi[2], first), select(b.hi[3], a.hi[3], first)));
}

// The lane's sums plus those of lane ^ 4 (the pair's other half).
fn taps3_halves(a: Taps3) -> Taps3 {
    return Taps3(a.k0 + subgroupShuffleXor(a.k0, 4u), a.k1 + subgroupShuffleXor(a.k1, 4u), a.k2 + subgroupShuffleXor(a.k2, 4u));
}

fn quad3_halves(a: Quad3) -> Quad3 {
    return Quad3(taps3_halves(a.c0), taps3_halves(a.c1), taps3_halves(a.c2), taps3_halves(a.c3));
}

@compute @workgroup_size(8)
fn conv_fast_backward_weight_tex16_w3_halves(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    let b = bw_lane3_halves(tl);
    let first = tl.y < 4u;
    let q0 = 4u * b.bp.cg;
    var a0: Quad3; var a1: Quad3; var a2: Quad3; var a3: Quad3;
    var w = walk_from(b.span.x);
    let steps = walk_steps_by(b.span, 16u);
    for (var i = 0u; i < steps; i++) {
        let v = Walk(w.n, w.od, w.oh, w.ow0 + 8u);
        let x = bw_xs10(Walk(w.n, w.od, w.oh, select(w.ow0 + 8u, w.ow0, first)), b);
        a0 = quad3(a0, dyt_select(dy_step(v, b, q0), dy_step(w, b, q0), first), x);
        a1 = quad3(a1, dyt_select(dy_step(v, b, q0 + 1u), dy_step(w, b, q0 + 1u), first), x);
        a2 = quad3(a2, dyt_select(dy_step(v, b, q0 + 2u), dy_step(w, b, q0 + 2u), first), x);
        a3 = quad3(a3, dyt_select(dy_step(v, b, q0 + 3u), dy_step(w, b, q0 + 3u), first), x);
        w = walk_next_by(w, 16u);
    }
    a0 = quad3_halves(a0); a1 = quad3_halves(a1); a2 = quad3_halves(a2); a3 = quad3_halves(a3);
    if (!b.live || !first) { return; }
    let copad = p.co16 * 16u;
    let o = bw_part_row(b) * copad + 4u * q0;
    put_quad3(o, 0u, copad, a0); put_quad3(o, 4u, copad, a1);
    put_quad3(o, 8u, copad, a2); put_quad3(o, 12u, copad, a3);
}
