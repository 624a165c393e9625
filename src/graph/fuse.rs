//! Work the executor does not dispatch: a PReLU computed by the conv before it where nothing
//! else reads the conv's output (see `Executor::prelu_fusions`), a channel range read in place
//! by the sigmoid after it (`Executor::range_sigmoids`), channel ranges that are a range of
//! their input's buffer (`Executor::narrow_views`), and packings a backward would make again
//! (`Executor::kept_packings`).

use super::exec::bytes;
use super::{Executor, Kind, Node, Op, Value};
use crate::error::Result;
use crate::gpu::{Gpu, Tensor};
use crate::ops;

/// What a run does not dispatch, node by node (see [`Executor::fusions`]).
pub(super) struct Fusions {
    /// Node k also writes the PReLU at k + 1 (`Executor::prelu_fusions`).
    pub(super) prelu: Vec<bool>,
    /// Node k's output is a view at this byte offset of its input (`Executor::narrow_views`).
    pub(super) views: Vec<Option<u64>>,
    /// Node k is a range the sigmoid at k + 1 reads in place (`Executor::range_sigmoids`).
    pub(super) ranges: Vec<bool>,
    /// Node k's forward keeps the operand textures it packs for its backward, which packs
    /// them again otherwise (`Executor::kept_packings`).
    pub(super) packs: Vec<bool>,
}

/// Which values the backward run `bw` (node by node) produces a gradient of: the outputs of
/// the nodes it runs, among `values` values.
pub(super) fn produced_by_backward(nodes: &[Node], bw: &[bool], values: usize) -> Vec<bool> {
    let mut p = vec![false; values];
    for (k, n) in nodes.iter().enumerate() {
        p[n.output.0] = bw[k];
    }
    p
}

impl Executor {
    /// Which nodes also compute the PReLU after them (see `Op::fuses_prelu`): node k when
    /// node k + 1 is a PReLU of its output, nothing else reads that output (`last`: the
    /// PReLU's own backward reads it, so in practice this is a forward-only run) and nobody
    /// asked to keep it. The output then never goes through memory: on lavapipe a PReLU
    /// pass cost about a tenth of the tiny forward.
    fn prelu_fusions(&self, gpu: &Gpu, nodes: &[Node], last: &[usize]) -> Vec<bool> {
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
    /// forward on lavapipe) before. The input must then live as long as the view
    /// ([`Executor::fusions`] extends its last use).
    ///
    /// A concatenation of parameters laid out back to back (`flat::Joint`) is likewise a
    /// view, at offset 0 of its first part: the heads' weights and biases took six dispatches
    /// of every forward, six more of every backward.
    fn narrow_views(&self, gpu: &Gpu, nodes: &[Node]) -> Vec<Option<u64>> {
        let align = u64::from(gpu.limits.min_storage_buffer_offset_alignment).max(16);
        nodes
            .iter()
            .map(|n| {
                if matches!(n.op, Op::ConcatAxis0(_)) {
                    return self.flat.joint(n.output).map(|_| 0);
                }
                let Op::Narrow(start, _) = n.op else { return None };
                let x = &self.graph.values[n.inputs[0].0].shape;
                let offset = (start * x[2..].iter().product::<usize>() * 4) as u64;
                (x[0] == 1 && offset.is_multiple_of(align) && !self.persistent(n.output)).then_some(offset)
            })
            .collect()
    }

    /// Which nodes are a `Narrow` whose output only the `Sigmoid` right after it reads (the
    /// Phong heads' maps; a sigmoid's backward reads its output, not its input), that nobody
    /// asked to keep or to have the gradient of. The sigmoid then reads the range in place
    /// (`sigmoid::forward_range`) and writes its gradient into the range's channels of the
    /// input's (`sigmoid::backward_range`): at any batch size the range is never copied, nor
    /// its gradient written over the whole input and added.
    fn range_sigmoids(&self, nodes: &[Node], last: &[usize]) -> Vec<bool> {
        let reads = |k: usize, n: &Node| nodes.get(k + 1).is_some_and(|s| matches!(s.op, Op::Sigmoid) && s.inputs[0] == n.output);
        let free = |v: Value| !self.persistent(v) && !self.grad_wanted[v.0];
        nodes.iter().enumerate().map(|(k, n)| matches!(n.op, Op::Narrow(..)) && reads(k, n) && last[n.output.0] == k + 1 && free(n.output)).collect()
    }

    /// A channel range's gradient `dy` (node `n`: a `Narrow`, or a `Sigmoid` that read its range
    /// in place) into channels `start..` of `h`'s gradient: written whole (zero outside the
    /// range) on `h`'s first gradient, added into the range's channels after.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn range_backward(&mut self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, n: &Node, h: Value, start: usize, dy: &Tensor, total: &mut u64) -> Result<()> {
        let seen = self.grads[h.0].is_some();
        let dx = match self.grads[h.0].clone() {
            Some(t) => t,
            None => self.first_grad(gpu, h, total)?,
        };
        match (&n.op, seen) {
            (Op::Narrow(..), false) => ops::concat::narrow_backward(gpu, pass, dy, start, &dx),
            (Op::Narrow(..), true) => ops::concat::narrow_backward_add(gpu, pass, dy, start, &dx),
            _ => ops::sigmoid::backward_range(gpu, pass, self.values[n.output.0].as_ref().expect("a sigmoid keeps its output"), dy, start, &dx, seen),
        }
    }

    /// The tensor of `v`'s first gradient, which later contributions are added to: in the flat
    /// gradient buffer for a parameter (see `Flat`), from the pool otherwise; its bytes go to
    /// `total`.
    ///
    /// A joint of parameters' output (`flat::Joint`) gets its view of the flat gradients, and
    /// its parts that want one their ranges of it: its backward then has nothing to copy.
    pub(super) fn first_grad(&mut self, gpu: &Gpu, v: Value, total: &mut u64) -> Result<Tensor> {
        let shape = self.graph.values[v.0].shape.clone();
        let t = if matches!(self.graph.values[v.0].kind, Kind::Param(_)) {
            self.flat.grad(gpu, &self.graph, v)?
        } else if let Some(parts) = self.flat.joint(v).map(|j| j.parts.clone()) {
            for p in parts.into_iter().filter(|p| self.grad_wanted[p.0]) {
                self.grads[p.0] = Some(self.flat.grad(gpu, &self.graph, p)?);
            }
            self.flat.joint_grad(gpu, &self.graph, v)?
        } else {
            self.pool.tensor(gpu, &shape)?
        };
        *total += bytes(&shape);
        self.grads[v.0] = Some(t.clone());
        Ok(t)
    }

    /// Whether add node `n` can hand its output's gradient `dy` on as input `i`'s first
    /// gradient, the same tensor with no copy: `i` is a computed or fed value (a parameter's
    /// gradient lives in the flat buffer, `first_grad`), nobody asked for the output's
    /// gradient, and dy is a pooled tensor of `i`'s shape (a view may outlive its buffer).
    /// Later contributions to `i` are then summed into dy in place, which nothing reads again.
    pub(super) fn hands_on(&self, n: &Node, i: Value, dy: &Tensor) -> bool {
        matches!(n.op, super::Op::Add)
            && !matches!(self.graph.values[i.0].kind, Kind::Param(_))
            && self.flat.joint(i).is_none()
            && !self.grad_wanted[n.output.0]
            && !dy.is_view()
            && dy.shape() == self.graph.values[i.0].shape.as_slice()
    }

    /// The nodes of backward run `bw` whose backward differentiates an input past their first
    /// (a conv's weights, the resampling's pose): that gradient packs the input as the
    /// forward did, so the forward keeps its packings (gpu/kept.rs).
    fn kept_packings(&self, nodes: &[Node], bw: &[bool]) -> Vec<bool> {
        let produced = produced_by_backward(nodes, bw, self.graph.values.len());
        let wants_grad = |i: &Value| self.grad_wanted[i.0] || produced[i.0];
        let past_first = |n: &Node| n.inputs.iter().enumerate().skip(1).any(|(j, i)| wants_grad(i) && n.op.differentiable(j));
        nodes.iter().zip(bw).map(|(n, &b)| b && past_first(n)).collect()
    }

    /// What a run over `nodes` (`bw`: which of them run backward) does not dispatch, decided
    /// once before recording, with the last use (`last`, by schedule position) of each input a
    /// channel range reads in place extended: to its sigmoid's position, and a view's input to its views' last use (later
    /// nodes first so that a view of a view extends both).
    pub(super) fn fusions(&self, gpu: &Gpu, nodes: &[Node], bw: &[bool], last: &mut [usize]) -> Fusions {
        let prelu = self.prelu_fusions(gpu, nodes, last);
        let ranges = self.range_sigmoids(nodes, last);
        // A range its sigmoid reads in place is not made at all, so it needs no view either.
        let views: Vec<Option<u64>> = self.narrow_views(gpu, nodes).into_iter().zip(&ranges).map(|(v, &r)| v.filter(|_| !r)).collect();
        for (k, &fused) in ranges.iter().enumerate() {
            if fused {
                let i = nodes[k].inputs[0].0;
                last[i] = last[i].max(k + 1);
            }
        }
        for (k, v) in views.iter().enumerate().rev() {
            if v.is_some() {
                let (i, o) = (nodes[k].inputs[0].0, nodes[k].output.0);
                last[i] = last[i].max(last[o]);
            }
        }
        Fusions { prelu, views, ranges, packs: self.kept_packings(nodes, bw) }
    }

    /// Node `n`'s output as bytes `offset..` of its input's buffer (see `narrow_views`).
    pub(super) fn view_of(&self, n: &Node, offset: u64) -> Result<Tensor> {
        let x = self.values[n.inputs[0].0].as_ref().expect("scheduled");
        Tensor::view(x.clone().into_buffer(), x.offset() + offset, &self.graph.values[n.output.0].shape)
    }
}

/// The input and first channel of the range that node `k` reads in place: a `Sigmoid` after a
/// `Narrow` that `ranges` (`Executor::range_sigmoids`) fused with it.
pub(super) fn sigmoid_range(nodes: &[Node], ranges: &[bool], k: usize) -> Option<(Value, usize)> {
    match (k.checked_sub(1).map(|j| (ranges[j], &nodes[j].op)), &nodes[k].op) {
        (Some((true, Op::Narrow(start, _))), Op::Sigmoid) => Some((nodes[k - 1].inputs[0], *start)),
        _ => None,
    }
}
