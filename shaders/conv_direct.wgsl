// prepend: conv_fast.wgsl, conv_tex.wgsl, conv_tex_pack.wgsl, conv_tex_weight.wgsl
// The direct kernels of convs with few input channels (the first layer: 1 -> 8, 5^3, stride 2),
// which the buffer family runs with kernel taps folded into channels (the texture family did too,
// until its folded packing proved the slow part: it writes about kh * kw / (sh * sw) texels per
// input value, each assembled lane by lane, and took as long as the conv itself, 1->8 5^3 s2 on
// 64^3, lavapipe 22.3 / AMD Zen 3: ~9.5 of ~19 ms forward). Here each lane reads the input where
// it is, in the stage texture below: two texels per window row and chunk of 4 W taps, its own 4
// values picked with vector selects. The forward multiplies them by 8 output channels' weights,
// fetched one texel a lane and broadcast by subgroup shuffles, over the texture family's tiles (a
// subgroup of 8 lanes = 8 outputs along W, 8 rows each) per group of 8 output channels (their
// weight gradients, which read the same stage: conv_direct_weight.wgsl). Compiled appended to
// conv_fast.wgsl, conv_tex.wgsl, conv_tex_pack.wgsl and conv_tex_weight.wgsl (their Params,
// bindings, bias4, put_raw, and the forward tiles' lane_tile, tile_taps, next_tap, Rows, slide,
// Acc8, Tile8, tile8, mac_rows8, broadcast8, put_tile8, falpha).

// ---- the stage: the input, 4 voxels along W a texel ----------------------------------------
// Stage texel (j, h, (n * ci + c) * id + d) holds x[n, c, d, h, 4j..4j+3] (zero past iw): the
// kernels below read their operand as texels (a storage-buffer load is a loop over the 8 lanes
// on llvmpipe 22.3: 67 ns per 8-lane vector on a Zen 3, a storage-texture texel 9 ns,
// `rendernet bench --operands`). Written from `src` with one vec4 load per texel when iw is a
// multiple of 4 (conv_direct_stage_w4), else four scalar ones. Dispatched as
// (ceil(ceil(iw / 4) * ih / 64), id, n * ci); parameters the conv's (n, ci, id, ih, iw).
fn stage_pos(gid: vec3<u32>) -> vec4<u32> {
    let w4n = (p.iw + 3u) / 4u;
    // (j, h, layer, valid)
    return vec4<u32>(gid.x % w4n, gid.x / w4n, gid.z * p.id + gid.y, u32(gid.x < w4n * p.ih));
}

// Texel s (stage_pos) from a row of any width: four scalar loads, zero past the row's end.
fn stage_texel_of(s: vec4<u32>) -> vec4<f32> {
    let row = (s.z * p.ih + s.y) * p.iw;
    var v = vec4<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let w = 4u * s.x + k;
        if (w < p.iw) { v[k] = src[row + w]; }
    }
    return v;
}

@compute @workgroup_size(64)
fn conv_direct_stage(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = stage_pos(gid);
    if (s.w == 0u) { return; }
    textureStore(tdst, s.xyz, stage_texel_of(s));
}

// The same texels into a staging buffer (conv_tex_pack.wgsl, staging_pitch; `dst` of conv_fast.wgsl).
@compute @workgroup_size(64)
fn conv_direct_stage_buf(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = stage_pos(gid);
    if (s.w == 0u) { return; }
    dst[staged(s.xyz, staging_pitch((p.iw + 3u) / 4u), p.ih)] = stage_texel_of(s);
}

@compute @workgroup_size(64)
fn conv_direct_stage_w4(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = stage_pos(gid);
    if (s.w == 0u) { return; }
    textureStore(tdst, s.xyz, src4[(s.z * p.ih + s.y) * (p.iw / 4u) + s.x]);
}

@compute @workgroup_size(64)
fn conv_direct_stage_w4_buf(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = stage_pos(gid);
    if (s.w == 0u) { return; }
    dst[staged(s.xyz, staging_pitch(p.iw / 4u), p.ih)] = src4[(s.z * p.ih + s.y) * (p.iw / 4u) + s.x];
}

// The same copy (iw a multiple of 4) through uniform windows (conv_tex_pack.wgsl's wc0..wc3 and
// pdst; see src/gpu/window.rs) on CPU adapters: a dispatch stages texels [first, first + len)
// (texel t = source vec4 t), window k holding texels first + 4096 k.. from index at[k]. llvmpipe
// runs all four windows' loads and a select keeps one: still ~4x cheaper than a storage load.
struct StageWin { at: vec4<u32>, first: u32, len: u32, w4n: u32, ih: u32 }
@group(0) @binding(0) var<uniform> sk: StageWin;

// Texel i of the dispatch and its place in the stage.
struct StageTexel { at: vec3<u32>, v: vec4<f32> }

fn stage_window_texel(i: u32) -> StageTexel {
    let k = i >> 12u;
    let l = sk.at[k] + (i & 4095u);
    let v = select(select(wc0[l], wc1[l], k == 1u), select(wc2[l], wc3[l], k == 3u), k >= 2u);
    let t = sk.first + i;
    let row = t / sk.w4n;
    return StageTexel(vec3<u32>(t % sk.w4n, row % sk.ih, row / sk.ih), v);
}

@compute @workgroup_size(64)
fn conv_direct_stage_window(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= sk.len) { return; }
    let t = stage_window_texel(gid.x);
    textureStore(pdst, t.at, t.v);
}

// The same texels into a staging buffer (see staging_pitch).
@compute @workgroup_size(64)
fn conv_direct_stage_window_buf(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= sk.len) { return; }
    let t = stage_window_texel(gid.x);
    pbuf[staged(t.at, staging_pitch(sk.w4n), sk.ih)] = t.v;
}

// Texel j (W voxels 4j..4j+3) of row zh at depth zd of input channel c of item n in the stage,
// zero off the grid.
fn stage_texel(n: u32, c: u32, zd: i32, zh: i32, j: i32) -> vec4<f32> {
    return stage_row_texel(stage_row(n, c, zd, zh), j);
}

// Row zh at depth zd of channel c of item n in the stage: (row, layer) clamped to the grid, and
// whether it is on it.
struct StageRow { y: i32, layer: i32, inside: bool }

fn stage_row(n: u32, c: u32, zd: i32, zh: i32) -> StageRow {
    let layer = (i32(n * p.ci + c) * i32(p.id)) + clamp(zd, 0, i32(p.id) - 1);
    return StageRow(clamp(zh, 0, i32(p.ih) - 1), layer, zd >= 0 && zd < i32(p.id) && zh >= 0 && zh < i32(p.ih));
}

// Texel j of stage row r, zero off the grid.
fn stage_row_texel(r: StageRow, j: i32) -> vec4<f32> {
    let w4n = i32((p.iw + 3u) / 4u);
    let at = vec3<i32>(clamp(j, 0, w4n - 1), r.y, r.layer);
    return select(vec4<f32>(0.0), textureLoad(tx, at), r.inside && j >= 0 && j < w4n);
}

// Values off..off+3 of the 8 values of texels a, b (off in 0..3): a lane's 4 W taps.
fn window4(a: vec4<f32>, b: vec4<f32>, off: u32) -> vec4<f32> {
    let v1 = vec4<f32>(a.y, a.z, a.w, b.x);
    let v2 = vec4<f32>(a.z, a.w, b.x, b.y);
    let v3 = vec4<f32>(a.w, b.x, b.y, b.z);
    return select(select(select(a, v1, off == 1u), v2, off == 2u), v3, off == 3u);
}

// Row zh's 4 taps from W input position `ws` (the lane's window start plus the chunk's first
// tap) at depth zd of channel c.
fn taps4(n: u32, c: u32, zd: i32, zh: i32, ws: i32) -> vec4<f32> {
    let j = ws >> 2u;
    return window4(stage_texel(n, c, zd, zh, j), stage_texel(n, c, zd, zh, j + 1), u32(ws & 3));
}

// Eight rows `step` apart from row zh on: each row's 4 W taps from `ws` (see taps4).
fn taps_rows(n: u32, c: u32, zd: i32, zh: i32, step: i32, ws: i32) -> Rows {
    return Rows(taps4(n, c, zd, zh, ws), taps4(n, c, zd, zh + step, ws), taps4(n, c, zd, zh + 2 * step, ws),
                taps4(n, c, zd, zh + 3 * step, ws), taps4(n, c, zd, zh + 4 * step, ws), taps4(n, c, zd, zh + 5 * step, ws),
                taps4(n, c, zd, zh + 6 * step, ws), taps4(n, c, zd, zh + 7 * step, ws));
}

// The weights of input channel c at taps (kd, kh, kw0..kw0+3) for tile t's 8 output channels:
// lane l fetches texel (tap kw0 + l / 2, output channels 4 * (l % 2)..+3 of the group), the
// o4 = 2 * (cg % 2) + l % 2 texel of its 16-channel group, zero past the kernel.
fn direct_weights(t: FwdTile, lane: u32, base: u32, c: u32, kd: u32, kh: u32, kw0: u32) -> array<vec4<f32>, 8> {
    let wx = i32((t.cg / 2u) * 16u + 2u * (t.cg % 2u) + (lane & 1u));
    let kk = kw0 + lane / 2u;
    let tap = (kd * p.kh + kh) * p.kw + min(kk, p.kw - 1u);
    let wl = textureLoad(tw, vec2<i32>(wx + i32((c % 4u) * 4u), i32(tap * (p.cpad / 4u) + c / 4u)));
    return broadcast8(select(vec4<f32>(0.0), wl, kk < p.kw), base);
}

@compute @workgroup_size(64)
fn conv_direct_forward(ids: LaneIds) { forward_direct(ids, false); }

@compute @workgroup_size(64)
fn conv_direct_forward_prelu(ids: LaneIds) { forward_direct(ids, true); }

fn forward_direct(ids: LaneIds, act: bool) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    let t = fwd_tile_of(tl.x, tl.y, (p.co + 7u) / 8u);
    var a = tile8(t.cg * 8u);
    // One loop over (kd, c, kh, chunk of 4 W taps), as conv_tex.wgsl's tiles walk their taps
    // (tile_taps): the walker's (kh, kw, q) count (c, kh, chunk).
    let chunks = (p.kw + 3u) / 4u;
    let ts = tile_taps(t.od, p.ci * p.kh * chunks);
    var k = Tap(ts.kd0, 0u, 0u, 0u);
    for (var i = ts.y0; i < ts.y1; i++) {
        let zd = ts.d0 + i32(k.kd);
        let zh = i32(t.oh0 * p.sh + k.kw) - i32(p.ph);
        let ws = i32(t.ow * p.sw + 4u * k.q) - i32(p.pw);
        a = mac_rows8(a, taps_rows(t.n, k.kh, zd, zh, i32(p.sh), ws), direct_weights(t, tl.y, tl.z, k.kh, k.kd, k.kw, 4u * k.q));
        k = next_tap(k, p.ci, p.kh, chunks);
    }
    put_tile8(t, t.cg * 8u, a, act);
}

// Tap `ws` alone of row zh (in .x; the kernel's fifth W tap).
fn tap1(n: u32, c: u32, zd: i32, zh: i32, ws: i32) -> vec4<f32> {
    let v = stage_texel(n, c, zd, zh, ws >> 2u);
    let o = ws & 3;
    return vec4<f32>(select(select(v.x, v.y, o == 1), select(v.z, v.w, o == 3), o >= 2), 0.0, 0.0, 0.0);
}

fn tap1_rows(n: u32, c: u32, zd: i32, zh: i32, ws: i32) -> Rows {
    return Rows(tap1(n, c, zd, zh, ws), tap1(n, c, zd, zh + 2, ws), tap1(n, c, zd, zh + 4, ws), tap1(n, c, zd, zh + 6, ws),
                tap1(n, c, zd, zh + 8, ws), tap1(n, c, zd, zh + 10, ws), tap1(n, c, zd, zh + 12, ws), tap1(n, c, zd, zh + 14, ws));
}

// Tile += one tap (x.x of each row) times its 8 channels' weights w[0], w[1].
fn mac_rows8_tap1(a: Tile8, x: Rows, w: array<vec4<f32>, 8>) -> Tile8 {
    return Tile8(Acc8(a.a0.a0 + x.r0.x * w[0], a.a0.a1 + x.r0.x * w[1]), Acc8(a.a1.a0 + x.r1.x * w[0], a.a1.a1 + x.r1.x * w[1]),
                 Acc8(a.a2.a0 + x.r2.x * w[0], a.a2.a1 + x.r2.x * w[1]), Acc8(a.a3.a0 + x.r3.x * w[0], a.a3.a1 + x.r3.x * w[1]),
                 Acc8(a.a4.a0 + x.r4.x * w[0], a.a4.a1 + x.r4.x * w[1]), Acc8(a.a5.a0 + x.r5.x * w[0], a.a5.a1 + x.r5.x * w[1]),
                 Acc8(a.a6.a0 + x.r6.x * w[0], a.a6.a1 + x.r6.x * w[1]), Acc8(a.a7.a0 + x.r7.x * w[0], a.a7.a1 + x.r7.x * w[1]));
}

// The same for a 5 x 5 kernel (H x W) at row stride 2 (the first layer's 5^3 s2), each input
// row fetched once: tap rows kh and kh + 2 read the same rows but one, so the 5 tap rows take
// 19 row fetches instead of 40 (the most of this kernel's time on lavapipe); and the fifth W
// tap is multiplied alone, not as a 4-tap chunk of which 3 taps are zero.
@compute @workgroup_size(64)
fn conv_direct_forward_k5s2(ids: LaneIds) { forward_direct_k5s2(ids, false); }

@compute @workgroup_size(64)
fn conv_direct_forward_k5s2_prelu(ids: LaneIds) { forward_direct_k5s2(ids, true); }

fn forward_direct_k5s2(ids: LaneIds, act: bool) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    let t = fwd_tile_of(tl.x, tl.y, (p.co + 7u) / 8u);
    let zh = i32(t.oh0 * 2u) - i32(p.ph);
    let ws = i32(t.ow * p.sw) - i32(p.pw);
    var a = tile8(t.cg * 8u);
    // One loop over (kd, c) (see conv_direct_forward).
    let ts = tile_taps(t.od, p.ci);
    var k = Tap(ts.kd0, 0u, 0u, 0u);
    for (var i = ts.y0; i < ts.y1; i++) {
        let zd = ts.d0 + i32(k.kd);
        let kd = k.kd;
        let c = k.q;
        let even = taps_rows(t.n, c, zd, zh, 2, ws);
        let odd = taps_rows(t.n, c, zd, zh + 1, 2, ws);
        a = mac_rows8(a, even, direct_weights(t, tl.y, tl.z, c, kd, 0u, 0u));
        a = mac_rows8(a, odd, direct_weights(t, tl.y, tl.z, c, kd, 1u, 0u));
        let even2 = slide(even, taps4(t.n, c, zd, zh + 16, ws));
        a = mac_rows8(a, even2, direct_weights(t, tl.y, tl.z, c, kd, 2u, 0u));
        a = mac_rows8(a, slide(odd, taps4(t.n, c, zd, zh + 17, ws)), direct_weights(t, tl.y, tl.z, c, kd, 3u, 0u));
        a = mac_rows8(a, slide(even2, taps4(t.n, c, zd, zh + 18, ws)), direct_weights(t, tl.y, tl.z, c, kd, 4u, 0u));
        // W tap 4.
        let e = tap1_rows(t.n, c, zd, zh, ws + 4);
        let o = tap1_rows(t.n, c, zd, zh + 1, ws + 4);
        a = mac_rows8_tap1(a, e, direct_weights(t, tl.y, tl.z, c, kd, 0u, 4u));
        a = mac_rows8_tap1(a, o, direct_weights(t, tl.y, tl.z, c, kd, 1u, 4u));
        let e2 = slide(e, tap1(t.n, c, zd, zh + 16, ws + 4));
        a = mac_rows8_tap1(a, e2, direct_weights(t, tl.y, tl.z, c, kd, 2u, 4u));
        a = mac_rows8_tap1(a, slide(o, tap1(t.n, c, zd, zh + 17, ws + 4)), direct_weights(t, tl.y, tl.z, c, kd, 3u, 4u));
        a = mac_rows8_tap1(a, slide(e2, tap1(t.n, c, zd, zh + 18, ws + 4)), direct_weights(t, tl.y, tl.z, c, kd, 4u, 4u));
        k = next_tap(k, 1u, 1u, p.ci);
    }
    put_tile8(t, t.cg * 8u, a, act);
}

// ---- backward input of a 1-channel conv, 5^3 kernel, stride 2 (the first layer) -----------
// dx[n, 0, z, y, x] = Σ_o Σ_k w[o, 0, kd, kh, kw] dy[n, o, (z + pd - kd) / 2, (y + ph - kh) / 2,
// (x + pw - kw) / 2] over the taps where all three divide. The phase split (conv_fast.wgsl's
// header) runs it as 8 stride-1 convs of one output channel on the 4-channel tile: 3/4 of its
// FMAs multiply padding, a fetched dy texel feeds 4 useful ones, and 8 dispatches pack 8
// sub-kernels. Here one dispatch covers every phase, and each fetched dy texel feeds 2 columns
// x 3 rows: a lane takes the two dx columns x + pw = 2c, 2c + 1 (W taps kw = 2t and 2t + 1 both
// meet dy column c - t), 16 rows each at one depth, so a tile of 8 lanes covers 16 columns.
// Along H, row r of a tile meets dy row i0 + m through tap kh = 4 + s + r - 2m (s the parity of
// the tile's first row plus ph; i0 chosen so): the 16 rows share 11 fetched dy rows, 3 taps a
// row, and the step's weights (2 fetches, 10 shuffles) serve them all (16 rows rather than 8:
// 1.17x on the first layer, 1->8 on 64^3, on an AMD EPYC Zen 3). Along D the tile's phase
// bounds the loop. Params: the dispatch geometry of the backward input (input dy: ci its
// channels, cpad its packed channels; output dx: co = 1), the conv's kernel (5), stride (2)
// and pads. Weights: the forward's texture (1 input channel: texel (16
// * (o / 16) + (o / 4) % 4, tap) holds output channels o..o+3).

// W6: one parity's weights of a dy quad at (kd, kw) for tap rows kh = s - 1 .. s + 4, zero off
// the kernel: m1 = kh s - 1, w0 .. w4 = kh s .. s + 4.
struct W6 { m1: vec4<f32>, w0: vec4<f32>, w1: vec4<f32>, w2: vec4<f32>, w3: vec4<f32>, w4: vec4<f32> }

// Lane l's two weight texels of quad q at depth tap kd: tap rows l / 2 and 4, kw = l % 2 + 2t.
struct BiTexels { a: vec4<f32>, b: vec4<f32> }

fn bi_texels(lane: u32, kd: u32, t: u32, q: u32) -> BiTexels {
    let kw = (lane & 1u) + 2u * t;
    let x = i32((q / 4u) * 16u + q % 4u);
    // kw = 5 (odd lanes at t = 2) is past the kernel: its texels are zero, read in bounds.
    let kc = min(kw, 4u);
    let a = textureLoad(tw, vec2<i32>(x, i32((kd * 5u + lane / 2u) * 5u + kc)));
    let b = textureLoad(tw, vec2<i32>(x, i32((kd * 5u + 4u) * 5u + kc)));
    return BiTexels(select(vec4<f32>(0.0), a, kw < 5u), select(vec4<f32>(0.0), b, kw < 5u));
}

// Parity par's W6 from the tile's texels.
fn bi_weights(w: BiTexels, base: u32, par: u32, s: bool) -> W6 {
    let k0 = subgroupShuffle(w.a, base + par);
    let k1 = subgroupShuffle(w.a, base + 2u + par);
    let k2 = subgroupShuffle(w.a, base + 4u + par);
    let k3 = subgroupShuffle(w.a, base + 6u + par);
    let k4 = subgroupShuffle(w.b, base + par);
    let z = vec4<f32>(0.0);
    return W6(select(z, k0, s), select(k0, k1, s), select(k1, k2, s), select(k2, k3, s), select(k3, k4, s), select(k4, z, s));
}

// Rows r0..r6 (r7 unused): dy rows zh..zh + 6 of column zw.
fn dy_rows7(n: u32, q: u32, zd: u32, zh: i32, zw: i32) -> Rows {
    return Rows(tex_x(n, q, zd, zh, zw), tex_x(n, q, zd, zh + 1, zw), tex_x(n, q, zd, zh + 2, zw), tex_x(n, q, zd, zh + 3, zw),
                tex_x(n, q, zd, zh + 4, zw), tex_x(n, q, zd, zh + 5, zw), tex_x(n, q, zd, zh + 6, zw), vec4<f32>(0.0));
}

// One column's 8 rows (lo: 0..3, hi: 4..7) += their three taps each.
struct Col8 { lo: vec4<f32>, hi: vec4<f32> }

fn bi_mac(a: Col8, d: Rows, w: W6) -> Col8 {
    return Col8(a.lo + vec4<f32>(dot(d.r0, w.w4) + dot(d.r1, w.w2) + dot(d.r2, w.w0),
                                 dot(d.r1, w.w3) + dot(d.r2, w.w1) + dot(d.r3, w.m1),
                                 dot(d.r1, w.w4) + dot(d.r2, w.w2) + dot(d.r3, w.w0),
                                 dot(d.r2, w.w3) + dot(d.r3, w.w1) + dot(d.r4, w.m1)),
                a.hi + vec4<f32>(dot(d.r2, w.w4) + dot(d.r3, w.w2) + dot(d.r4, w.w0),
                                 dot(d.r3, w.w3) + dot(d.r4, w.w1) + dot(d.r5, w.m1),
                                 dot(d.r3, w.w4) + dot(d.r4, w.w2) + dot(d.r5, w.w0),
                                 dot(d.r4, w.w3) + dot(d.r5, w.w1) + dot(d.r6, w.m1)));
}

// dx value at `pos` of item n (one channel), if `ok`.
fn put_dx(n: u32, pos: u32, ok: bool, v: f32) {
    if (ok) { fy[n * p.ycs + pos] = v; }
}

// Column x's rows oh0.. of (n, od), those inside dx; written out, not looped over an array
// (which lavapipe would keep in memory and index lane by lane).
fn put_col8(n: u32, od: u32, oh0: u32, x: i32, a: Col8) {
    // A tile's second 8 rows may start past the last row (oh0 >= oh): nothing to write (rows
    // then wraps, but every write needs ok).
    let ok = x >= 0 && x < i32(p.ow) && oh0 < p.oh;
    let pos = p.yoff + od * p.ysd + oh0 * p.ysh + u32(x) * p.ysw;
    let rows = p.oh - oh0;
    put_dx(n, pos, ok, a.lo.x);
    put_dx(n, pos + p.ysh, ok && rows > 1u, a.lo.y);
    put_dx(n, pos + 2u * p.ysh, ok && rows > 2u, a.lo.z);
    put_dx(n, pos + 3u * p.ysh, ok && rows > 3u, a.lo.w);
    put_dx(n, pos + 4u * p.ysh, ok && rows > 4u, a.hi.x);
    put_dx(n, pos + 5u * p.ysh, ok && rows > 5u, a.hi.y);
    put_dx(n, pos + 6u * p.ysh, ok && rows > 6u, a.hi.z);
    put_dx(n, pos + 7u * p.ysh, ok && rows > 7u, a.hi.w);
}

// Dispatched as (column blocks x row blocks, ceil(od / 8), n) workgroups of 8 tiles, one depth
// each: the tile's coordinates come from workgroup ids, whose divisions lavapipe does once, not
// per lane (a per-lane division by a runtime value is a scalar loop; with this kernel's short
// loop the tile's setup took a fifth of its time).
@compute @workgroup_size(64)
fn conv_direct_backward_input_k5s2(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32,
                                   @builtin(subgroup_invocation_id) sid: u32) {
    // Tiles: 16 columns (from x + pw = 2 * (pw / 2)) x 16 rows at one depth.
    let hblocks = (p.oh + 15u) / 16u;
    let cb = wg.x / hblocks;
    let oh0 = (wg.x % hblocks) * 16u;
    let od = wg.y * 8u + li / 8u;
    let n = wg.z;
    if (od >= p.od) { return; }
    let lane = sid & 7u;
    let base = sid & ~7u;
    let cq = p.cpad / 4u;
    // Depth: taps kd = zp % 2 + 2u meet dy depth zp / 2 - u; u from u0 to u1.
    let zp = od + p.pd;
    let kd0 = zp & 1u;
    let zb = i32(zp / 2u);
    let u0 = u32(max(zb - i32(p.id) + 1, 0));
    let u1 = u32(clamp(zb + 1, 0, i32(3u - kd0)));
    // Rows: the tile's first row plus ph is 4 + s + 2 i0.
    let b = i32(oh0 + p.ph);
    let s = (b & 1) == 1;
    let i0 = (b - 4 - (b & 1)) / 2;
    // Columns: x + pw = 2c (even taps) and 2c + 1 (odd), both reading dy column c - t.
    let c = cb * 8u + lane + p.pw / 2u;
    let x0 = i32(2u * c) - i32(p.pw);
    let bias = vec4<f32>(bias4(0u).x);
    var e = Col8(bias, bias);
    var o = Col8(bias, bias);
    // Rows 8..15 (e2, o2) meet dy rows i0 + 4 .. i0 + 10 through the same taps.
    var e2 = e;
    var o2 = o;
    // One loop over (u, t, q) (see tile_taps): the walker's (kd, kh, q) count them.
    var k = Tap(u0, 0u, 0u, 0u);
    for (var i = u0 * 3u * cq; i < max(u0, u1) * 3u * cq; i++) {
        let zd = u32(zb - i32(k.kd));
        let zw = i32(c) - i32(k.kh);
        let d = dy_rows7(n, k.q, zd, i0, zw);
        let d2 = Rows(d.r4, d.r5, d.r6, tex_x(n, k.q, zd, i0 + 7, zw), tex_x(n, k.q, zd, i0 + 8, zw),
                      tex_x(n, k.q, zd, i0 + 9, zw), tex_x(n, k.q, zd, i0 + 10, zw), vec4<f32>(0.0));
        let w = bi_texels(lane, kd0 + 2u * k.kd, k.kh, k.q);
        let we = bi_weights(w, base, 0u, s);
        let wo = bi_weights(w, base, 1u, s);
        e = bi_mac(e, d, we);
        o = bi_mac(o, d, wo);
        e2 = bi_mac(e2, d2, we);
        o2 = bi_mac(o2, d2, wo);
        k = next_tap(k, 3u, 1u, cq);
    }
    put_col8(n, od, oh0, x0, e);
    put_col8(n, od, oh0, x0 + 1, o);
    put_col8(n, od, oh0 + 8u, x0, e2);
    put_col8(n, od, oh0 + 8u, x0 + 1, o2);
}
