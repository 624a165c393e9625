//! Operand packings an op made, kept for its own backward in the same run. A conv's weight
//! gradient reads its input packed exactly as its forward packed it (the same texture layout
//! of the same tensor), so a training step that keeps the forward's texture until the
//! backward skips one packing dispatch, and one pass over the activations, per conv (~9% of
//! a tiny training step on lavapipe, README "Benchmarks"). Inside one backward too: a
//! transposed conv packs its dy for its input gradient and again, the same way, as its
//! weight gradient's input; the projection packs its dy for both gradients. And the
//! resampling packs its grid and sampling map for its forward and again for its pose
//! gradient (the inverse renderer's runs).
//!
//! The executor says which node it is recording and whether what it packs is kept until the
//! node's backward ends ([`Gpu::recording_node`]: in a forward when that backward will want
//! it, always in the backward itself); the packing code asks for its texture with
//! [`Gpu::operand_texture`], naming the tensor and the packing's parameters, and skips the
//! packing when the texture already holds it. A kept texture is a scratch texture that skips
//! the pool until the executor releases the node after its backward ([`Gpu::release_kept`])
//! or the run ends. The packed tensor cannot change in between: every op that packs an input
//! lists it in `Op::saves` (its backward reads it), so the planner keeps it alive until the
//! backward, and nothing writes a live value. An op that packed an input it does not save
//! could find a stale texture, if the input's buffer went to another tensor of that shape.

use super::Gpu;
use super::memo::{ACTIVE, TexKey};
use super::Tensor;

thread_local! {
    /// Whether the node being recorded would keep its packings for its backward, whether or
    /// not a memo is active: what [`Gpu::keeping_packs`] answers, so a run that makes fresh
    /// objects (`Executor::reuse_gpu_objects(false)`) runs the same kernels as one that reuses.
    static NODE_KEEPS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// One kept packing: the node that made it, the tensor and packing it holds.
struct Kept {
    node: usize,
    source: (wgpu::Buffer, u64),
    key: Vec<u8>,
    tex: TexKey,
    view: wgpu::TextureView,
}

/// The kept packings of a recording, and the node being recorded.
#[derive(Default)]
pub(crate) struct KeptOperands {
    kept: Vec<Kept>,
    /// The node being recorded, and whether its packings are kept until its backward ends.
    pub(super) node: Option<(usize, bool)>,
}

impl KeptOperands {
    /// The kept packing of `source` by `key` into a texture of kind `tex` made by the node
    /// being recorded (its forward, or its backward so far), if any.
    fn find(&self, source: &(wgpu::Buffer, u64), key: &[u8], tex: TexKey) -> Option<wgpu::TextureView> {
        let (node, _) = self.node?;
        self.kept.iter().find(|k| k.node == node && k.source == *source && k.key == key && k.tex == tex).map(|k| k.view.clone())
    }

    /// Whether the packings of the node being recorded are kept.
    fn keeping(&self) -> Option<usize> {
        self.node.and_then(|(n, keep)| keep.then_some(n))
    }

    /// Takes node `node`'s kept textures (all of them with `None`), for the pool.
    pub(crate) fn take(&mut self, node: Option<usize>) -> Vec<(TexKey, wgpu::TextureView)> {
        let (gone, stay) = std::mem::take(&mut self.kept).into_iter().partition(|k| node.is_none_or(|n| k.node == n));
        self.kept = stay;
        gone.into_iter().map(|k| (k.tex, k.view)).collect::<Vec<_>>()
    }
}

impl Gpu {
    /// The executor: node `node`'s forward or backward is being recorded (`None`: neither),
    /// and whether the operand textures it packs are kept until its backward ends.
    pub(crate) fn recording_node(&self, node: Option<(usize, bool)>) {
        NODE_KEEPS.with(|k| k.set(node.is_some_and(|(_, keep)| keep)));
        ACTIVE.with(|a| {
            if let Some(m) = a.borrow_mut().as_mut() {
                m.kept.node = node;
            }
        });
    }

    /// Whether the node being recorded keeps the operand textures it packs for its backward
    /// (a training or backward run through its weights): a forward that packs nothing then
    /// leaves the packing to the backward, at no saving.
    pub(crate) fn keeping_packs(&self) -> bool {
        NODE_KEEPS.with(|k| k.get())
    }

    /// The executor, after node `node`'s backward: its kept textures go back to the pool.
    pub(crate) fn release_kept(&self, node: usize) {
        ACTIVE.with(|a| {
            if let Some(m) = a.borrow_mut().as_mut() {
                m.release_kept(Some(node));
            }
        });
    }

    /// An rgba32f scratch texture of `size` to pack `source` into, and whether it already
    /// holds that packing: the one the node being recorded kept (see the module note). The
    /// packing is named by `kind` (one letter per packing kernel) and `params` (its uniform
    /// block, which fixes the layout). Outside a recording, or for a node whose packings are
    /// not kept, a plain scratch texture.
    pub(crate) fn operand_texture(&self, source: &Tensor, kind: u8, params: &[u8], size: [usize; 3], dim: wgpu::TextureDimension) -> (wgpu::TextureView, bool) {
        let src = (source.buffer().clone(), source.offset());
        let (key, tex) = ([&[kind][..], params].concat(), (size, dim));
        let (found, keeper) = ACTIVE.with(|a| a.borrow().as_ref().map_or((None, None), |m| (m.kept.find(&src, &key, tex), m.kept.keeping())));
        if let Some(view) = found {
            return (view, true);
        }
        let Some(node) = keeper else { return (self.scratch_texture(size, dim), false) };
        let view = self.pooled_texture(size, dim);
        ACTIVE.with(|a| {
            if let Some(m) = a.borrow_mut().as_mut() {
                m.kept.kept.push(Kept { node, source: src, key, tex, view: view.clone() });
            }
        });
        (view, false)
    }
}
