// PReLU with one learned slope per channel (the paper's activation; alpha initialised to 0).
// x is [N, C, S...] flattened to [N, C, S]. Forward y = x for x > 0, alpha[c] * x otherwise.
// Backward dx = dy * (x > 0 ? 1 : alpha[c]); the alpha gradient is Σ_{n,s} dy * x over x <= 0,
// written per element (`contrib`) or per invocation (`partial`, `wpartial`) and summed
// deterministically by reduce.wgsl. The first two entry points serve any S; the row kernels
// S a multiple of 4; the window kernels, fastest on lavapipe, S a multiple of 4 in tensors of
// at least 64 KiB on CPU adapters (src/ops/prelu.rs picks).

struct Params { n: u32, c: u32, s: u32 }
@group(0) @binding(0) var<uniform> p: Params;

@group(0) @binding(1) var<storage, read> fx: array<f32>;
@group(0) @binding(2) var<storage, read> falpha: array<f32>;
@group(0) @binding(3) var<storage, read_write> fy: array<f32>;

@compute @workgroup_size(64)
fn prelu_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    let x = fx[i];
    let ch = (i / p.s) % p.c;
    fy[i] = select(falpha[ch] * x, x, x > 0.0);
}

@group(0) @binding(1) var<storage, read> bx: array<f32>;
@group(0) @binding(2) var<storage, read> balpha: array<f32>;
@group(0) @binding(3) var<storage, read> bdy: array<f32>;
@group(0) @binding(4) var<storage, read_write> bdx: array<f32>;
@group(0) @binding(5) var<storage, read_write> contrib: array<f32>;

@compute @workgroup_size(64)
fn prelu_backward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    let x = bx[i];
    let dy = bdy[i];
    let ch = (i / p.s) % p.c;
    let pos = x > 0.0;
    bdx[i] = select(balpha[ch] * dy, dy, pos);
    contrib[i] = select(dy * x, 0.0, pos);
}

// ---- rows: S a multiple of 4, a row = one (n, c) run of S values ----
// llvmpipe runs every storage load or store as a loop over the 8 SIMD lanes and divides
// lane by lane, so these kernels move four values an access (vec4) and find the channel and
// load its slope once per invocation, for `p.per` vec4s of one row. Workgroup g covers chunk
// g % chunks of row g / chunks. The backward writes each invocation's share of the slope's
// gradient to `partial` (64 a chunk, in row-major order) instead of a value per element:
// a reduce then sums chunks * 64 values per row instead of S.
struct RowParams { rows: u32, c: u32, s4: u32, chunks: u32, per: u32 }
@group(0) @binding(0) var<uniform> q: RowParams;

@group(0) @binding(1) var<storage, read> fx4: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> fy4: array<vec4<f32>>;

// The row, and the first vec4 (in the row) of this invocation's strided run, of group g.
fn row_start(wid: vec3<u32>, nwg: vec3<u32>, lid: u32) -> vec2<u32> {
    let g = wid.x + wid.y * nwg.x;
    let row = g / q.chunks;
    return vec2<u32>(row, (g - row * q.chunks) * 64u * q.per + lid);
}

@compute @workgroup_size(64)
fn prelu_forward_rows(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>,
                      @builtin(num_workgroups) nwg: vec3<u32>) {
    let rs = row_start(wid, nwg, lid);
    if (rs.x >= q.rows) { return; }
    let a = falpha[rs.x % q.c];
    let base = rs.x * q.s4;
    for (var j = 0u; j < q.per; j++) {
        let k = rs.y + 64u * j;
        if (k < q.s4) {
            let x = fx4[base + k];
            fy4[base + k] = select(a * x, x, x > vec4<f32>(0.0));
        }
    }
}

@group(0) @binding(1) var<storage, read> bx4: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> bdy4: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> bdx4: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> partial: array<f32>;

@compute @workgroup_size(64)
fn prelu_backward_rows(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>,
                       @builtin(num_workgroups) nwg: vec3<u32>) {
    let rs = row_start(wid, nwg, lid);
    if (rs.x >= q.rows) { return; }
    let a = balpha[rs.x % q.c];
    let base = rs.x * q.s4;
    var acc = vec4<f32>(0.0);
    for (var j = 0u; j < q.per; j++) {
        let k = rs.y + 64u * j;
        if (k < q.s4) {
            let x = bx4[base + k];
            let dy = bdy4[base + k];
            let pos = x > vec4<f32>(0.0);
            bdx4[base + k] = select(a * dy, dy, pos);
            acc += select(dy * x, vec4<f32>(0.0), pos);
        }
    }
    partial[(wid.x + wid.y * nwg.x) * 64u + lid] = (acc.x + acc.y) + (acc.z + acc.w);
}

// ---- windows: x (and dy) read as 64 KiB uniform blocks, four a dispatch ----
// On lavapipe a per-lane uniform load is a gather, ~16x cheaper than a storage-buffer load
// (`rendernet bench --operands`), but one binding holds at most 64 KiB: 4096 vec4s. A
// dispatch covers vec4s [start4, end4) of the tensor, up to four windows: window k holds
// vec4s from start4 + 4096 k and is read from its binding (wx0..wx3), which begins at vec4
// base4[k] (its own start but for the tensor's last window, which ends at the tensor's end).
// Four a dispatch, not one: each lavapipe dispatch waits for its threads, and a loaded
// machine made one dispatch per window slower than the storage loads it saved. llvmpipe
// runs all four loads and keeps one (masking, not branching), still ~4x cheaper than one
// storage load. An invocation takes `per` vec4s of one row and one window (per divides s4
// and 4096): one slope load and, in the backward, one slope-gradient partial at index
// first vec4 / per.
struct WinParams { base4: vec4<u32>, c: u32, s4: u32, start4: u32, end4: u32, per: u32 }
@group(0) @binding(0) var<uniform> w: WinParams;
@group(0) @binding(1) var<uniform> wx0: array<vec4<f32>, 4096>;
@group(0) @binding(2) var<uniform> wx1: array<vec4<f32>, 4096>;
@group(0) @binding(3) var<uniform> wx2: array<vec4<f32>, 4096>;
@group(0) @binding(4) var<uniform> wx3: array<vec4<f32>, 4096>;
@group(0) @binding(5) var<storage, read> walpha: array<f32>;
@group(0) @binding(6) var<storage, read_write> wy4: array<vec4<f32>>;

// The first vec4 of this invocation's run.
fn first_vec4(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return w.start4 + (gid.x + gid.y * nwg.x * 64u) * w.per;
}

// The slope of vec4 f's row.
fn slope_at(f: u32) -> f32 {
    return walpha[(f / w.s4) % w.c];
}

// The dispatch's window of vec4 f, and f's index in that window's binding.
fn window_of(f: u32) -> vec2<u32> {
    let k = (f - w.start4) >> 12u;
    return vec2<u32>(k, f - w.base4[k]);
}

fn x_at(wl: vec2<u32>) -> vec4<f32> {
    let l = wl.y;
    return select(select(wx0[l], wx1[l], wl.x == 1u), select(wx2[l], wx3[l], wl.x == 3u), wl.x >= 2u);
}

@compute @workgroup_size(64)
fn prelu_forward_window(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let first = first_vec4(gid, nwg);
    if (first >= w.end4) { return; }
    let a = slope_at(first);
    let wl = window_of(first);
    for (var j = 0u; j < w.per; j++) {
        let x = x_at(wl + vec2<u32>(0u, j));
        wy4[first + j] = select(a * x, x, x > vec4<f32>(0.0));
    }
}

@group(0) @binding(6) var<uniform> wdy0: array<vec4<f32>, 4096>;
@group(0) @binding(7) var<uniform> wdy1: array<vec4<f32>, 4096>;
@group(0) @binding(8) var<uniform> wdy2: array<vec4<f32>, 4096>;
@group(0) @binding(9) var<uniform> wdy3: array<vec4<f32>, 4096>;
@group(0) @binding(10) var<storage, read_write> wdx4: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> wpartial: array<f32>;

fn dy_at(wl: vec2<u32>) -> vec4<f32> {
    let l = wl.y;
    return select(select(wdy0[l], wdy1[l], wl.x == 1u), select(wdy2[l], wdy3[l], wl.x == 3u), wl.x >= 2u);
}

@compute @workgroup_size(64)
fn prelu_backward_window(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let first = first_vec4(gid, nwg);
    if (first >= w.end4) { return; }
    let a = slope_at(first);
    let wl = window_of(first);
    var acc = vec4<f32>(0.0);
    for (var j = 0u; j < w.per; j++) {
        let x = x_at(wl + vec2<u32>(0u, j));
        let dy = dy_at(wl + vec2<u32>(0u, j));
        let pos = x > vec4<f32>(0.0);
        wdx4[first + j] = select(a * dy, dy, pos);
        acc += select(dy * x, vec4<f32>(0.0), pos);
    }
    wpartial[first / w.per] = (acc.x + acc.y) + (acc.z + acc.w);
}
