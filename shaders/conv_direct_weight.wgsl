// prepend: conv_fast.wgsl, conv_tex.wgsl, conv_tex_pack.wgsl, conv_tex_weight.wgsl, conv_direct.wgsl
// The direct kernels' weight gradients: they read the input where it is, in conv_direct.wgsl's
// stage texture (4 voxels along W a texel), and dy packed as conv_tex_weight.wgsl's tiles read
// it (bdy, dy_quads), and write its part layout (bpart) for conv_fast_weight_sum.

// ---- weight gradient: lanes = 8 output columns; each lane 4 W taps x 8 output channels ----
// dw[o, c, kd, kh, kw] = Σ dy[n, o, od, oh, ow] x[n, c, od*sd - pd + kd, oh*sh - ph + kh, ow*sw -
// pw + kw]. A tile is (chunk of output rows, column = (kd, c, kh, chunk of 4 W taps, group of 8
// output channels)); its 8 lanes walk the chunk's rows 8 output columns at a time, each reading
// its own window (taps4, two stage texels) and its own 8 dy values (two texels of the dy texture
// of conv_fast_pack_tex(_w4): dq quads per voxel), then the tile's lanes are summed by a
// shuffle-xor butterfly and written to part[chunk][tap][cpad][co16 * 16] for conv_fast_weight_sum
// (fold 1). No folded packing: the first layer's (1->8 5^3 s2 on 64^3) took about as long as the
// gradient itself. Params: the conv's geometry; cpad = ceil(ci / 4) * 4; nchunks, chunk (rows per
// chunk), total = tiles.
struct Acc32 { lo: array<vec4<f32>, 4>, hi: array<vec4<f32>, 4> }

fn bw_direct_step(acc: Acc32, x: vec4<f32>, dlo: vec4<f32>, dhi: vec4<f32>) -> Acc32 {
    return Acc32(
        array<vec4<f32>, 4>(acc.lo[0] + x.x * dlo, acc.lo[1] + x.y * dlo, acc.lo[2] + x.z * dlo, acc.lo[3] + x.w * dlo),
        array<vec4<f32>, 4>(acc.hi[0] + x.x * dhi, acc.hi[1] + x.y * dhi, acc.hi[2] + x.z * dhi, acc.hi[3] + x.w * dhi));
}

// The sum of v over the 8 lanes of a tile (aligned groups of 8 in the subgroup).
fn tile_sum(v: vec4<f32>) -> vec4<f32> {
    let a = v + subgroupShuffleXor(v, 1u);
    let b = a + subgroupShuffleXor(a, 2u);
    return b + subgroupShuffleXor(b, 4u);
}

// Column of a weight-gradient tile: (kd, c, kh, first W tap, group of 8 output channels), of
// `nkh` tap rows and `nkw` chunks of 4 W taps (p.kh and ceil(p.kw / 4), or 1 where a tile
// takes every tap row or every W tap: kh = 0, kw0 = 0).
struct DirectColumn { kd: u32, c: u32, kh: u32, kw0: u32, g: u32 }

fn direct_column(col: u32, nkh: u32, nkw: u32) -> DirectColumn {
    let groups = (p.co + 7u) / 8u;
    var r = col;
    let g = r % groups; r /= groups;
    let kw0 = (r % nkw) * 4u; r /= nkw;
    let kh = r % nkh; r /= nkh;
    return DirectColumn(r / p.ci, r % p.ci, kh, kw0, g);
}

// dy of output channels g*8..g*8+7 at (n, od, oh, ow) (zero past the row or the channels):
// two texels of the dy texture of conv_fast_pack_tex(_w4), dq quads per voxel.
struct DyPair { lo: vec4<f32>, hi: vec4<f32> }

fn dy_pair(g: u32, n: u32, od: u32, oh: u32, ow: u32) -> DyPair {
    let dq = dy_quads();
    let q1 = min(2u * g + 1u, dq - 1u);
    let ok = ow < p.ow;
    let dc = vec2<i32>(i32(min(ow, p.ow - 1u)), i32(oh));
    let lo = textureLoad(bdy, vec3<i32>(dc, i32((n * dq + 2u * g) * p.od + od)));
    let hi = textureLoad(bdy, vec3<i32>(dc, i32((n * dq + q1) * p.od + od)));
    return DyPair(select(vec4<f32>(0.0), lo, ok), select(vec4<f32>(0.0), hi, ok && 2u * g + 1u < dq));
}

// Sums tap row kh's accumulators over the tile's lanes and writes lane l's share, tap
// kw0 + l / 2 and output channels g * 8 + 4 * (l % 2)..+3, to part[chunk].
fn put_direct_dw(acc: Acc32, k: DirectColumn, kh: u32, chunk: u32, lane: u32) {
    var mine = vec4<f32>(0.0);
    for (var kk = 0u; kk < 4u; kk++) {
        let lo = tile_sum(acc.lo[kk]);
        let hi = tile_sum(acc.hi[kk]);
        mine = select(mine, lo, lane == 2u * kk);
        mine = select(mine, hi, lane == 2u * kk + 1u);
    }
    let kw = k.kw0 + lane / 2u;
    if (kw >= p.kw) { return; }
    let taps = p.kd * p.kh * p.kw;
    let tap = (k.kd * p.kh + kh) * p.kw + kw;
    let copad = p.co16 * 16u;
    let o = ((chunk * taps + tap) * p.cpad + k.c) * copad + k.g * 8u + 4u * (lane & 1u);
    bpart[o] = mine.x;
    bpart[o + 1u] = mine.y;
    bpart[o + 2u] = mine.z;
    bpart[o + 3u] = mine.w;
}

@compute @workgroup_size(8)
fn conv_direct_backward_weight(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    let lane = tl.y;
    let cols = p.kd * p.ci * p.kh * ((p.kw + 3u) / 4u) * ((p.co + 7u) / 8u);
    let k = direct_column(tl.x % cols, p.kh, (p.kw + 3u) / 4u);
    let chunk = tl.x / cols;
    let span = chunk_rows(chunk);
    var acc: Acc32;
    var w = walk_from(span.x);
    let steps = walk_steps(span);
    for (var i = 0u; i < steps; i++) {
        let n = w.n; let od = w.od; let oh = w.oh; let ow0 = w.ow0;
        let zd = i32(od * p.sd + k.kd) - i32(p.pd);
        let zh = i32(oh * p.sh + k.kh) - i32(p.ph);
        if (zd >= 0 && zd < i32(p.id) && zh >= 0 && zh < i32(p.ih)) {
            let ow = ow0 + lane;
            let d = dy_pair(k.g, n, od, oh, ow);
            let x = taps4(n, k.c, zd, zh, i32(ow * p.sw + k.kw0) - i32(p.pw));
            acc = bw_direct_step(acc, x, d.lo, d.hi);
        }
        w = walk_next(w);
    }
    put_direct_dw(acc, k, k.kh, chunk, lane);
}

// Tap row kh's fifth W tap: sums its accumulators (x.x times dy) over the tile's lanes; lanes 0
// and 1 write output channels g * 8..+3 and g * 8 + 4..+7 of tap (kd, kh, 4) to part[chunk].
fn put_direct_dw_tap4(b: Acc8, k: DirectColumn, kh: u32, chunk: u32, lane: u32) {
    let lo = tile_sum(b.a0);
    let hi = tile_sum(b.a1);
    if (lane >= 2u) { return; }
    let v = select(lo, hi, lane == 1u);
    let tap = (k.kd * p.kh + kh) * p.kw + 4u;
    let o = ((chunk * p.kd * p.kh * p.kw + tap) * p.cpad + k.c) * (p.co16 * 16u) + k.g * 8u + 4u * lane;
    bpart[o] = v.x;
    bpart[o + 1u] = v.y;
    bpart[o + 2u] = v.z;
    bpart[o + 3u] = v.w;
}

// Two positions of a step (x: their 4 W taps, d: their dy), each accumulator through both
// in a row (conv_tex_weight.wgsl's chain8: one load and store for two multiply-adds).
fn bw_direct_step2(acc: Acc32, x: vec4<f32>, d: DyPair, y: vec4<f32>, e: DyPair) -> Acc32 {
    return Acc32(
        array<vec4<f32>, 4>(acc.lo[0] + x.x * d.lo + y.x * e.lo, acc.lo[1] + x.y * d.lo + y.y * e.lo,
                            acc.lo[2] + x.z * d.lo + y.z * e.lo, acc.lo[3] + x.w * d.lo + y.w * e.lo),
        array<vec4<f32>, 4>(acc.hi[0] + x.x * d.hi + y.x * e.hi, acc.hi[1] + x.y * d.hi + y.y * e.hi,
                            acc.hi[2] + x.z * d.hi + y.z * e.hi, acc.hi[3] + x.w * d.hi + y.w * e.hi));
}

// The same for a fifth W tap (x.x, y.x) and its 8 channels' accumulators.
fn bw_tap1_step2(b: Acc8, x: vec4<f32>, d: DyPair, y: vec4<f32>, e: DyPair) -> Acc8 {
    return Acc8(b.a0 + x.x * d.lo + y.x * e.lo, b.a1 + x.x * d.hi + y.x * e.hi);
}

// The weight gradient for 5 x 5 taps (H x W: the first layer's 5^3), a tile taking them all: each dy pair
// fetched feeds 5 tap rows' windows of 4 W taps and their fifth taps alone (17 texel fetches
// for 200 multiply-adds, against 40 fetches for 320, 120 of them on zero-weight taps), and
// the tap rows off the grid read zeros from taps4 and tap1 instead of being skipped. A lane takes two
// positions a step, ow and ow + 8, so that each accumulator gets 2 multiply-adds a step.
@compute @workgroup_size(8)
fn conv_direct_backward_weight_k5(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    let lane = tl.y;
    let cols = p.kd * p.ci * ((p.co + 7u) / 8u);
    let k = direct_column(tl.x % cols, 1u, 1u);
    let chunk = tl.x / cols;
    let span = chunk_rows(chunk);
    var a0: Acc32; var a1: Acc32; var a2: Acc32; var a3: Acc32; var a4: Acc32;
    var b0: Acc8; var b1: Acc8; var b2: Acc8; var b3: Acc8; var b4: Acc8;
    var w = walk_from(span.x);
    // Steps of 16 columns: the lane's two positions ow and ow + 8.
    let steps = walk_steps_by(span, 16u);
    for (var i = 0u; i < steps; i++) {
        let n = w.n; let od = w.od; let oh = w.oh; let ow0 = w.ow0;
        let zd = i32(od * p.sd + k.kd) - i32(p.pd);
        let zh = i32(oh * p.sh) - i32(p.ph);
        // No `if` for depths off the grid: they read zeros (stage_row), and lavapipe would run
        // the body anyway, writing every accumulator through the condition's lane mask.
        let ow = ow0 + lane;
        let d = dy_pair(k.g, n, od, oh, ow);
        let e = dy_pair(k.g, n, od, oh, ow + 8u);
        let ws = i32(ow * p.sw) - i32(p.pw);
        let vs = ws + 8 * i32(p.sw);
        a0 = bw_direct_step2(a0, taps4(n, k.c, zd, zh, ws), d, taps4(n, k.c, zd, zh, vs), e);
        a1 = bw_direct_step2(a1, taps4(n, k.c, zd, zh + 1, ws), d, taps4(n, k.c, zd, zh + 1, vs), e);
        a2 = bw_direct_step2(a2, taps4(n, k.c, zd, zh + 2, ws), d, taps4(n, k.c, zd, zh + 2, vs), e);
        a3 = bw_direct_step2(a3, taps4(n, k.c, zd, zh + 3, ws), d, taps4(n, k.c, zd, zh + 3, vs), e);
        a4 = bw_direct_step2(a4, taps4(n, k.c, zd, zh + 4, ws), d, taps4(n, k.c, zd, zh + 4, vs), e);
        b0 = bw_tap1_step2(b0, tap1(n, k.c, zd, zh, ws + 4), d, tap1(n, k.c, zd, zh, vs + 4), e);
        b1 = bw_tap1_step2(b1, tap1(n, k.c, zd, zh + 1, ws + 4), d, tap1(n, k.c, zd, zh + 1, vs + 4), e);
        b2 = bw_tap1_step2(b2, tap1(n, k.c, zd, zh + 2, ws + 4), d, tap1(n, k.c, zd, zh + 2, vs + 4), e);
        b3 = bw_tap1_step2(b3, tap1(n, k.c, zd, zh + 3, ws + 4), d, tap1(n, k.c, zd, zh + 3, vs + 4), e);
        b4 = bw_tap1_step2(b4, tap1(n, k.c, zd, zh + 4, ws + 4), d, tap1(n, k.c, zd, zh + 4, vs + 4), e);
        w = walk_next_by(w, 16u);
    }
    put_direct_dw(a0, k, 0u, chunk, lane);
    put_direct_dw(a1, k, 1u, chunk, lane);
    put_direct_dw(a2, k, 2u, chunk, lane);
    put_direct_dw(a3, k, 3u, chunk, lane);
    put_direct_dw(a4, k, 4u, chunk, lane);
    put_direct_dw_tap4(b0, k, 0u, chunk, lane);
    put_direct_dw_tap4(b1, k, 1u, chunk, lane);
    put_direct_dw_tap4(b2, k, 2u, chunk, lane);
    put_direct_dw_tap4(b3, k, 3u, chunk, lane);
    put_direct_dw_tap4(b4, k, 4u, chunk, lane);
}


// ---- weight gradient, the 3 x 3 taps of a depth a lane on the stage (stride 1, <= 8 outputs) --
// The narrow heads' (16 -> 3 or 5, 3x3) weight gradient without packing x: a lane owns a kernel
// depth kd and one input channel c (pair kd * ci + c) with all 9 of its (kh, kw) taps, for 4
// output channels (`_3x3`) or 8 (`_3x3x8`), and walks strips of 16 output columns down their
// rows. A step (a row of a strip) fetches, from each of the 3 input rows its taps read, the 5
// stage texels (20 W voxels: the strip starts `lead` columns early so that they are whole
// texels) that hold the 18 its 16 positions x 3 W taps read, and multiplies them by the
// positions' dy, which comes as in the tiles of conv_tex_weight.wgsl (a texel a lane, handed
// around by shuffles): one set of dy fetches and shuffles serves all 3 rows. With a tap row a
// lane (as before) they served a third of the multiply-adds, and the 16 -> 3 head at 128 x 128
// took 1.14x longer on an AMD EPYC Zen 3 (README "A kernel depth a lane"). Fewer lanes: where kd
// * ci is not a multiple of 8, more of them idle. Each accumulator (9 or 18 vec4) takes its
// step's 16 multiply-adds in a row (chain16): lavapipe keeps them in memory (README "Weight
// gradients an accumulator at a time"). The channel-quad tiles there need x packed, a texture
// store per texel (~13x a fetch on lavapipe, `rendernet bench --operands`), where
// src/ops/conv_pack.rs copies x into the stage with no dispatch when its rows are whole staging
// rows. Writes part like the tiles (a row's three taps are consecutive rows of it). Params: the
// conv's geometry; cpad = ceil(ci / 4) * 4; nchunks, chunk (strip rows per chunk: n * od *
// strips * oh in all), total = tiles.

// Columns a strip starts before its first output column: pw + lead is a multiple of 4.
fn stage_lead() -> u32 {
    return (4u - p.pw % 4u) % 4u;
}

// Strips of 16 output columns a row (the first `lead` columns early).
fn stage_strips() -> u32 {
    return (p.ow + stage_lead() + 15u) / 16u;
}

// A step: output row oh of strip s at depth od of item n.
struct StripWalk { n: u32, od: u32, s: u32, oh: u32 }

fn strip_walk_from(row: u32) -> StripWalk {
    let strips = stage_strips();
    return StripWalk(row / (p.oh * strips * p.od), (row / (p.oh * strips)) % p.od, (row / p.oh) % strips, row % p.oh);
}

fn strip_walk_next(w: StripWalk) -> StripWalk {
    let oh = w.oh + 1u;
    let wh = oh == p.oh;
    let s = w.s + u32(wh);
    let ws = s == stage_strips();
    let od = w.od + u32(ws);
    let wd = od == p.od;
    return StripWalk(w.n + u32(wd), select(od, 0u, wd), select(s, 0u, ws), select(oh, 0u, wh));
}

// The lane's pair (BwLane's q: the channel; tap: its depth's first tap (kd, 0, 0)) and its
// chunk's strip rows.
fn stage_lane(tl: vec3<u32>) -> BwLane {
    let groups = (p.kd * p.ci + 7u) / 8u;
    let pair = (tl.x % groups) * 8u + tl.y;
    let chunk = tl.x / groups;
    let bp = BwPair(chunk, 0u, pair, min(pair / p.ci, p.kd - 1u) * 9u, pair % p.ci);
    let begin = chunk * p.chunk;
    let span = vec2<u32>(begin, min(begin + p.chunk, p.n * p.od * stage_strips() * p.oh));
    return BwLane(bp, pair < p.kd * p.ci, tap_axes(bp.tap), span, tl.y, tl.z);
}

// W voxels 16 s - lead - pw .. + 19 of the lane's input row at the step for its tap row kh (s0.x
// first): 5 whole texels.
struct Xs20 { s0: vec4<f32>, s1: vec4<f32>, s2: vec4<f32>, s3: vec4<f32>, s4: vec4<f32> }

fn stage_xs20(w: StripWalk, b: BwLane, kh: u32) -> Xs20 {
    let zd = i32(w.od * p.sd + b.k.x) - i32(p.pd);
    let zh = i32(w.oh + kh) - i32(p.ph);
    let r = stage_row(w.n, b.bp.q, zd, zh);
    let j = i32(4u * w.s) - i32((stage_lead() + p.pw) / 4u);
    return Xs20(stage_row_texel(r, j), stage_row_texel(r, j + 1), stage_row_texel(r, j + 2), stage_row_texel(r, j + 3), stage_row_texel(r, j + 4));
}

// The lane's dy texel of quad `quad` for the step's half `half` (8 columns): column 16 s + 8
// half - lead + lane (wrapping below 0: dy_texel reads zero there).
fn strip_dy(w: StripWalk, b: BwLane, half: u32, quad: u32) -> vec4<f32> {
    return dy_texel(Walk(w.n, w.od, w.oh, 16u * w.s + 8u * half), b.lane - stage_lead(), quad);
}

// The step's 16 positions' dy of 4 output channels: position j's from lane base + j's texel of
// g0 (j < 8) or g1.
struct Dy16 { d: array<vec4<f32>, 16> }

fn dy16(g0: vec4<f32>, g1: vec4<f32>, base: u32) -> Dy16 {
    return Dy16(shuffle16(g0, g1, base));
}

// The step's dy of quad `quad` (dy16 of the lanes' two texels).
fn strip_dy16(w: StripWalk, b: BwLane, quad: u32) -> Dy16 {
    return dy16(strip_dy(w, b, 0u, quad), strip_dy(w, b, 1u, quad), b.base);
}

// a + sum over the 16 positions j of x_j d_j, x_j the j-th of the voxels v0.x .. v3.w: one
// accumulator through 16 multiply-adds in a row.
fn chain16(a: vec4<f32>, v0: vec4<f32>, v1: vec4<f32>, v2: vec4<f32>, v3: vec4<f32>, d: Dy16) -> vec4<f32> {
    return a + v0.x * d.d[0] + v0.y * d.d[1] + v0.z * d.d[2] + v0.w * d.d[3]
             + v1.x * d.d[4] + v1.y * d.d[5] + v1.z * d.d[6] + v1.w * d.d[7]
             + v2.x * d.d[8] + v2.y * d.d[9] + v2.z * d.d[10] + v2.w * d.d[11]
             + v3.x * d.d[12] + v3.y * d.d[13] + v3.z * d.d[14] + v3.w * d.d[15];
}

// Voxels 1..4 and 2..5 of the 8 in texels a, b.
fn shift1(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(a.y, a.z, a.w, b.x);
}

fn shift2(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(a.z, a.w, b.x, b.y);
}

// The three W taps' accumulators of 4 output channels.
struct Acc3 { t0: vec4<f32>, t1: vec4<f32>, t2: vec4<f32> }

// A tap row's three W taps over the step (tap k reads voxels k .. k + 15 of the 20).
fn row16(a: Acc3, x: Xs20, d: Dy16) -> Acc3 {
    return Acc3(chain16(a.t0, x.s0, x.s1, x.s2, x.s3, d),
                chain16(a.t1, shift1(x.s0, x.s1), shift1(x.s1, x.s2), shift1(x.s2, x.s3), shift1(x.s3, x.s4), d),
                chain16(a.t2, shift2(x.s0, x.s1), shift2(x.s1, x.s2), shift2(x.s2, x.s3), shift2(x.s3, x.s4), d));
}

// dw of the lane's channel at tap row kh's three taps, output channels col..col + 3.
fn put_row_dw3(b: BwLane, kh: u32, a: Acc3, col: u32) {
    let copad = p.co16 * 16u;
    let o = ((b.bp.chunk * p.kd * p.kh * p.kw + b.bp.tap + 3u * kh) * p.cpad + b.bp.q) * copad + col;
    let next = p.cpad * copad;
    put_dw(o, 0u, 1u, a.t0);
    put_dw(o + next, 0u, 1u, a.t1);
    put_dw(o + 2u * next, 0u, 1u, a.t2);
}

@compute @workgroup_size(8)
fn conv_direct_backward_weight_3x3(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    let b = stage_lane(tl);
    var a0: Acc3; var a1: Acc3; var a2: Acc3;
    var w = strip_walk_from(b.span.x);
    for (var i = b.span.x; i < b.span.y; i++) {
        let d = strip_dy16(w, b, 0u);
        a0 = row16(a0, stage_xs20(w, b, 0u), d);
        a1 = row16(a1, stage_xs20(w, b, 1u), d);
        a2 = row16(a2, stage_xs20(w, b, 2u), d);
        w = strip_walk_next(w);
    }
    if (!b.live) { return; }
    put_row_dw3(b, 0u, a0, 0u); put_row_dw3(b, 1u, a1, 0u); put_row_dw3(b, 2u, a2, 0u);
}

@compute @workgroup_size(8)
fn conv_direct_backward_weight_3x3x8(ids: LaneIds) {
    let tl = lane_tile1(ids);
    if (tl.x >= p.total) { return; }
    let b = stage_lane(tl);
    var a0: Acc3; var a1: Acc3; var a2: Acc3;
    var h0: Acc3; var h1: Acc3; var h2: Acc3;
    var w = strip_walk_from(b.span.x);
    for (var i = b.span.x; i < b.span.y; i++) {
        let x0 = stage_xs20(w, b, 0u); let x1 = stage_xs20(w, b, 1u); let x2 = stage_xs20(w, b, 2u);
        let d = strip_dy16(w, b, 0u);
        a0 = row16(a0, x0, d); a1 = row16(a1, x1, d); a2 = row16(a2, x2, d);
        let e = strip_dy16(w, b, 1u);
        h0 = row16(h0, x0, e); h1 = row16(h1, x1, e); h2 = row16(h2, x2, e);
        w = strip_walk_next(w);
    }
    if (!b.live) { return; }
    put_row_dw3(b, 0u, a0, 0u); put_row_dw3(b, 1u, a1, 0u); put_row_dw3(b, 2u, a2, 0u);
    put_row_dw3(b, 0u, h0, 4u); put_row_dw3(b, 1u, h1, 4u); put_row_dw3(b, 2u, h2, 4u);
}
