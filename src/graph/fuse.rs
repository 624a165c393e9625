//! Ops the executor runs as one: a PReLU computed by the conv before it where nothing else
//! reads the conv's output (see `Executor::prelu_fusions`).

use super::{Executor, Node, Op};
use crate::gpu::Gpu;

impl Executor {
    /// Which nodes also compute the PReLU after them (see `Op::fuses_prelu`): node k when
    /// node k + 1 is a PReLU of its output, nothing else reads that output (`last`: the
    /// PReLU's own backward reads it, so in practice this is a forward-only run) and nobody
    /// asked to keep it. The output then never goes through memory: on lavapipe a PReLU
    /// pass cost about a tenth of the tiny forward.
    pub(super) fn prelu_fusions(&self, gpu: &Gpu, nodes: &[Node], last: &[usize]) -> Vec<bool> {
        let mut fused = vec![false; nodes.len()];
        for k in 0..nodes.len().saturating_sub(1) {
            let (n, next) = (&nodes[k], &nodes[k + 1]);
            if !matches!(next.op, Op::Prelu) || next.inputs[0] != n.output || last[n.output.0] != k + 1 || self.persistent(n.output) {
                continue;
            }
            let shapes: Vec<&[usize]> = n.inputs.iter().map(|i| self.graph.values[i.0].shape.as_slice()).collect();
            fused[k] = n.op.fuses_prelu(gpu, &shapes);
        }
        fused
    }
}
