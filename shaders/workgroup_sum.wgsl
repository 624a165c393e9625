// The sum of one value per invocation over a 64-invocation workgroup in a fixed-order tree,
// so results do not depend on scheduling (bit-identical reruns). Prepended by reduce.wgsl and
// loss.wgsl. Every invocation of the workgroup must call it (it has barriers); each gets the
// total.
var<workgroup> partial: array<f32, 64>;

fn workgroup_sum(lid: u32, s: f32) -> f32 {
    partial[lid] = s;
    workgroupBarrier();
    for (var w = 32u; w > 0u; w >>= 1u) {
        if (lid < w) { partial[lid] += partial[lid + w]; }
        workgroupBarrier();
    }
    return partial[0];
}
