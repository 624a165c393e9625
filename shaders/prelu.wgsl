// PReLU with one learned slope per channel (the paper's activation; alpha initialised to 0).
// x is [N, C, S...] flattened to [N, C, S]. Forward y = x for x > 0, alpha[c] * x otherwise.
// Backward dx = dy * (x > 0 ? 1 : alpha[c]); the alpha gradient is Σ_{n,s} dy * x over x <= 0,
// written per element (`contrib`) or per invocation (`partial`, the row kernels) and summed
// deterministically by reduce.wgsl. The first two entry points serve any S; the row kernels,
// faster, S a multiple of 4.

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
