//! Work the executor does not dispatch: a PReLU computed by the conv before it where nothing
//! else reads the conv's output (see `Executor::prelu_fusions`), and channel ranges that are
//! a range of their input's buffer (see `Executor::narrow_views`).

use super::{Executor, Node, Op};
use crate::error::Result;
use crate::gpu::{Gpu, Tensor};

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

    /// For each node, the byte offset into its input's buffer where its output starts when
    /// the node is a `Narrow` whose output is that contiguous range (a batch of one: channels
    /// `start..` are one block), the offset meets the device's binding alignment and nobody
    /// asked to keep the output; `None` for every other node. Such an output is a view, not
    /// a copy: the Phong heads' three channel ranges cost three dispatches (3% of the tiny
    /// forward on lavapipe) before. The input must then live as long as the view (`run`
    /// extends its last use).
    pub(super) fn narrow_views(&self, gpu: &Gpu, nodes: &[Node]) -> Vec<Option<u64>> {
        let align = u64::from(gpu.limits.min_storage_buffer_offset_alignment).max(16);
        nodes
            .iter()
            .map(|n| {
                let Op::Narrow(start, _) = n.op else { return None };
                let x = &self.graph.values[n.inputs[0].0].shape;
                let offset = (start * x[2..].iter().product::<usize>() * 4) as u64;
                (x[0] == 1 && offset.is_multiple_of(align) && !self.persistent(n.output)).then_some(offset)
            })
            .collect()
    }

    /// Extends each viewed input's last use (`last`, by schedule position) to its views' last
    /// use, later nodes first so that a view of a view extends both.
    pub(super) fn keep_viewed_alive(&self, gpu: &Gpu, nodes: &[Node], last: &mut [usize]) {
        for (k, v) in self.narrow_views(gpu, nodes).iter().enumerate().rev() {
            if v.is_some() {
                let (i, o) = (nodes[k].inputs[0].0, nodes[k].output.0);
                last[i] = last[i].max(last[o]);
            }
        }
    }

    /// Node `n`'s output as bytes `offset..` of its input's buffer (see `narrow_views`).
    pub(super) fn view_of(&self, n: &Node, offset: u64) -> Result<Tensor> {
        let x = self.values[n.inputs[0].0].as_ref().expect("scheduled");
        Tensor::view(x.clone().into_buffer(), x.offset() + offset, &self.graph.values[n.output.0].shape)
    }
}
