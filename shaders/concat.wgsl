// prepend: channel_range.wgsl
// Concatenation along the channel axis (axis 1), one part per dispatch: the part
// x [N, Cp, S] occupies channels c0 .. c0 + Cp of y [N, Cy, S] (S = the product of the
// spatial axes, 1 for vectors [N, C]). Forward places a part into the whole; backward
// takes a part's gradient out of dy (concatenation is a permutation of copies, so its
// backward is the same copy the other way round). Concatenation along axis 0 (sibling
// layers' weights [O, ...] into one) is the case N = 1. Narrowing (a channel range of a
// tensor) is concat's backward copy; its own backward, `narrow_backward`, writes the whole
// gradient: the part's gradient on its channels, zero elsewhere; `narrow_backward_add` adds
// a part's gradient into its channels of a gradient already written (by another part).

@group(0) @binding(0) var<uniform> p: ChannelRange;
@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read_write> dst: array<f32>;

// Index in the whole of element i of the part.
fn whole(i: u32) -> u32 {
    return range_to_whole(i, p.s, p.cp, p.cy, p.c0);
}

@compute @workgroup_size(64)
fn concat_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n * p.cp * p.s) { return; }
    dst[whole(i)] = src[i];
}

@compute @workgroup_size(64)
fn concat_backward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n * p.cp * p.s) { return; }
    dst[i] = src[whole(i)];
}

@compute @workgroup_size(64)
fn narrow_backward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n * p.cy * p.s) { return; }
    let r = whole_to_range(i, p.s, p.cp, p.cy, p.c0);
    dst[i] = select(0.0, src[r.i], r.inside);
}

@compute @workgroup_size(64)
fn narrow_backward_add(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n * p.cp * p.s) { return; }
    dst[whole(i)] += src[i];
}
