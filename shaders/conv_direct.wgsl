// prepend: conv_fast.wgsl, conv_tex.wgsl
// The direct forward of convs with few input channels (the first layer: 1 -> 8, 5^3, stride 2),
// where the texture family otherwise folds kernel taps into channels (conv_fast_pack_folded_tex).
// That packing wrote kh * kw / (sh * sw) texels per input value, each assembled lane by lane,
// and took more time than the conv itself (1->8 5^3 s2 on 64^3 on lavapipe 22.3 / AMD Zen 3:
// ~9.5 of ~19 ms). Here each lane reads the input where it is: the stage texture of
// conv_fast_stage_tex (4 voxels along W a texel), two texels per window row and chunk of 4 W
// taps, picks the 4 values of its own window with vector selects, and multiplies them by the
// 8 output channels' weights, fetched one texel a lane and broadcast by subgroup shuffles.
// Tiles are the texture family's (a subgroup of 8 lanes = 8 outputs along W, 8 rows each),
// over groups of 8 output channels. Compiled appended to conv_fast.wgsl and conv_tex.wgsl
// (their Params, lane_tile, Acc8, mac8, bias4 and put_raw); binds the stage as `tx` and the
// unfolded packed weights (conv_fast_pack_weights_tex) as `tw`.

// Texel j (W voxels 4j..4j+3) of row zh at depth zd of input channel c of item n in the stage,
// zero off the grid.
fn stage_texel(n: u32, c: u32, zd: i32, zh: i32, j: i32) -> vec4<f32> {
    let inside = zd >= 0 && zd < i32(p.id) && zh >= 0 && zh < i32(p.ih) && j >= 0 && j < i32((p.iw + 3u) / 4u);
    let layer = (i32(n * p.ci + c) * i32(p.id)) + clamp(zd, 0, i32(p.id) - 1);
    let at = vec3<i32>(clamp(j, 0, i32((p.iw + 3u) / 4u) - 1), clamp(zh, 0, i32(p.ih) - 1), layer);
    return select(vec4<f32>(0.0), textureLoad(tx, at), inside);
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

// Tile t: item, group of 8 output channels, depth, first row, lane's column.
struct DirectTile { n: u32, g: u32, od: u32, oh0: u32, ow: u32 }

fn direct_tile(t: u32, lane: u32) -> DirectTile {
    let wblocks = (p.ow + 7u) / 8u;
    let hblocks = (p.oh + 7u) / 8u;
    let groups = (p.co + 7u) / 8u;
    var r = t;
    let wb = r % wblocks; r /= wblocks;
    let hb = r % hblocks; r /= hblocks;
    let od = r % p.od; r /= p.od;
    return DirectTile(r / groups, r % groups, od, hb * 8u, wb * 8u + lane);
}

fn put_direct(t: DirectTile, r: u32, a: Acc8) {
    let oh = t.oh0 + r;
    if (oh >= p.oh) { return; }
    let pos = p.yoff + t.od * p.ysd + oh * p.ysh + t.ow * p.ysw;
    put_raw(t.n, t.g * 8u, pos, t.ow, a.a0);
    put_raw(t.n, t.g * 8u + 4u, pos, t.ow, a.a1);
}

@compute @workgroup_size(64)
fn conv_direct_forward(ids: LaneIds) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    let lane = tl.y;
    let base = tl.z;
    let t = direct_tile(tl.x, lane);
    let cq = p.cpad / 4u;
    var a0 = Acc8(bias4(t.g * 8u), bias4(t.g * 8u + 4u));
    var a1 = a0; var a2 = a0; var a3 = a0; var a4 = a0; var a5 = a0; var a6 = a0; var a7 = a0;
    // Lane l fetches weight texel (tap kw0 + l / 2, output channels g*8 + 4 * (l % 2)..+3): the
    // o4 = 2 * (g % 2) + l % 2 texel of its 16-channel group.
    let wx = i32((t.g / 2u) * 16u + 2u * (t.g % 2u) + (lane & 1u));
    let zsh = i32(p.sh);
    for (var kd = 0u; kd < p.kd; kd++) {
        let zd = i32(t.od * p.sd + kd) - i32(p.pd);
        if (zd < 0 || zd >= i32(p.id)) { continue; }
        for (var c = 0u; c < p.ci; c++) {
            for (var kh = 0u; kh < p.kh; kh++) {
                let zh = i32(t.oh0 * p.sh + kh) - i32(p.ph);
                for (var kw0 = 0u; kw0 < p.kw; kw0 += 4u) {
                    let kk = kw0 + lane / 2u;
                    let tap = (kd * p.kh + kh) * p.kw + min(kk, p.kw - 1u);
                    let wl = textureLoad(tw, vec2<i32>(wx + i32((c % 4u) * 4u), i32(tap * cq + c / 4u)));
                    let wt = select(vec4<f32>(0.0), wl, kk < p.kw);
                    let w = array<vec4<f32>, 8>(
                        subgroupShuffle(wt, base), subgroupShuffle(wt, base + 1u), subgroupShuffle(wt, base + 2u), subgroupShuffle(wt, base + 3u),
                        subgroupShuffle(wt, base + 4u), subgroupShuffle(wt, base + 5u), subgroupShuffle(wt, base + 6u), subgroupShuffle(wt, base + 7u));
                    let ws = i32(t.ow * p.sw + kw0) - i32(p.pw);
                    a0 = mac8(a0, taps4(t.n, c, zd, zh, ws), w);
                    a1 = mac8(a1, taps4(t.n, c, zd, zh + zsh, ws), w);
                    a2 = mac8(a2, taps4(t.n, c, zd, zh + 2 * zsh, ws), w);
                    a3 = mac8(a3, taps4(t.n, c, zd, zh + 3 * zsh, ws), w);
                    a4 = mac8(a4, taps4(t.n, c, zd, zh + 4 * zsh, ws), w);
                    a5 = mac8(a5, taps4(t.n, c, zd, zh + 5 * zsh, ws), w);
                    a6 = mac8(a6, taps4(t.n, c, zd, zh + 6 * zsh, ws), w);
                    a7 = mac8(a7, taps4(t.n, c, zd, zh + 7 * zsh, ws), w);
                }
            }
        }
    }
    put_direct(t, 0u, a0); put_direct(t, 1u, a1); put_direct(t, 2u, a2); put_direct(t, 3u, a3);
    put_direct(t, 4u, a4); put_direct(t, 5u, a5); put_direct(t, 6u, a6); put_direct(t, 7u, a7);
}
