//! The parameters of a graph in one GPU buffer, their gradients in a second and each Adam
//! moment in one more, every tensor a [`Tensor::view`] at an aligned offset. The optimizer
//! then checks and updates all parameters in a few dispatches instead of two per parameter:
//! on lavapipe every dispatch costs tens of microseconds of thread wake-ups whatever it
//! computes (README "Benchmarks"), 60-odd of them per step for the tiny preset's 30 tensors.
//! The gaps between views stay zero, which Adam leaves zero.
//!
//! Parameters that only a concatenation along axis 0 reads (the Phong heads' weights and
//! biases, `nn::rendernet`) lie back to back in its order, from an aligned start: their
//! concatenation is then a view of the buffer ([`Joint`]), made by no dispatch, and its
//! gradient a view of the gradients' buffer that the parts' gradients are ranges of. The
//! parts' own views may then start unaligned: only copies read them one by one. Being a view,
//! a kept concatenation reads what the parameters hold when it is read (after a training
//! step's Adam, the updated values).

use super::{Graph, Kind, Op, Value};
use crate::error::{Error, Result};
use crate::gpu::{Gpu, Tensor};
use std::sync::Arc;

/// A concatenation along axis 0 of parameters nothing else reads, laid out as one view.
pub(crate) struct Joint {
    /// The concatenation's output.
    pub(crate) output: Value,
    /// Its parameters, in order; the first one's offset is the whole's.
    pub(crate) parts: Vec<Value>,
}

/// The concatenations of `graph` that [`Joint`] lays out as views: along axis 0, of distinct
/// parameters that no other node reads (nor this one twice).
fn joints(graph: &Graph) -> Vec<Joint> {
    let mut reads = vec![0usize; graph.values.len()];
    for n in &graph.nodes {
        n.inputs.iter().for_each(|i| reads[i.0] += 1);
    }
    let sole_param = |v: &Value| matches!(graph.values[v.0].kind, Kind::Param(_)) && reads[v.0] == 1;
    graph
        .nodes
        .iter()
        .filter(|n| matches!(n.op, Op::ConcatAxis0(_)) && n.inputs.iter().all(sole_param))
        .map(|n| Joint { output: n.output, parts: n.inputs.clone() })
        .collect()
}

/// The flat buffers and where each parameter lies in them.
pub(crate) struct Flat {
    /// Byte offset of each parameter's view, by value index (`None` for other values).
    offsets: Vec<Option<u64>>,
    /// The concatenations laid out as views.
    joints: Vec<Joint>,
    /// Bytes of each buffer: a multiple of 16, so the whole buffers read as vec4s.
    bytes: u64,
    params: Arc<wgpu::Buffer>,
    grads: Option<Arc<wgpu::Buffer>>,
    moments: Option<(Arc<wgpu::Buffer>, Arc<wgpu::Buffer>)>,
}

impl Flat {
    /// Lays out `graph`'s parameters and uploads their initial values (each from
    /// `init(value)`); returns the layout and each parameter's view, by value index.
    pub(crate) fn new(gpu: &Gpu, graph: &Graph, init: impl Fn(Value) -> Vec<f32>) -> Result<(Flat, Vec<Option<Tensor>>)> {
        // Views start at the device's storage offset alignment, and at least 16 bytes so a
        // view of a multiple of 4 values reads as vec4s.
        let align = u64::from(gpu.limits.min_storage_buffer_offset_alignment).max(16);
        let mut offsets = vec![None; graph.values.len()];
        let joints = joints(graph);
        let size = |v: Value| graph.values[v.0].shape.iter().product::<usize>() as u64 * 4;
        let mut bytes = 0u64;
        for v in graph.params() {
            if offsets[v.0].is_some() {
                continue; // a joint's part, placed with its first
            }
            let parts = joints.iter().find(|j| j.parts.contains(&v)).map_or_else(|| vec![v], |j| j.parts.clone());
            for p in parts {
                offsets[p.0] = Some(bytes);
                bytes += size(p);
            }
            bytes = bytes.div_ceil(align) * align;
        }
        // A graph without parameters still gets a (tiny) buffer so every path is the same.
        let bytes = bytes.max(16);
        gpu.check_binding_size("the parameters, all in one buffer", bytes)?;
        let mut data = vec![0f32; (bytes / 4) as usize];
        for v in graph.params() {
            let at = (offsets[v.0].expect("laid out") / 4) as usize;
            let vals = init(v);
            data[at..at + vals.len()].copy_from_slice(&vals);
        }
        let params = Tensor::from_slice(gpu, &[data.len()], &data)?.into_buffer();
        let flat = Flat { offsets, joints, bytes, params, grads: None, moments: None };
        let views = (0..graph.values.len())
            .map(|i| flat.view(&flat.params, graph, Value(i)).transpose())
            .collect::<Result<Vec<_>>>()?;
        Ok((flat, views))
    }

    /// The buffer every parameter is a view of.
    pub(crate) fn params_buffer(&self) -> &wgpu::Buffer {
        &self.params
    }

    /// `v`'s view into `buffer` (`None` if `v` is not a parameter).
    fn view(&self, buffer: &Arc<wgpu::Buffer>, graph: &Graph, v: Value) -> Option<Result<Tensor>> {
        self.offsets[v.0].map(|at| Tensor::view(buffer.clone(), at, &graph.values[v.0].shape))
    }

    /// The joint whose output is `v`, if `v` is laid out as one ([`Joint`]).
    pub(crate) fn joint(&self, v: Value) -> Option<&Joint> {
        self.joints.iter().find(|j| j.output == v)
    }

    /// The joint that parameter `v` is a part of.
    pub(crate) fn joint_of(&self, v: Value) -> Option<&Joint> {
        self.joints.iter().find(|j| j.parts.contains(&v))
    }

    /// The joint output `v`'s view of `buffer`.
    fn joint_view(&self, buffer: &Arc<wgpu::Buffer>, graph: &Graph, v: Value) -> Result<Tensor> {
        let at = self.joint(v).and_then(|j| self.offsets[j.parts[0].0]).ok_or_else(|| internal(graph, v))?;
        Tensor::view(buffer.clone(), at, &graph.values[v.0].shape)
    }

    /// The joint output `v`'s gradient: its view of the gradients' buffer, which its parts'
    /// gradients are ranges of.
    pub(crate) fn joint_grad(&mut self, gpu: &Gpu, graph: &Graph, v: Value) -> Result<Tensor> {
        let g = self.grad_buffer(gpu)?;
        self.joint_view(&g, graph, v)
    }

    /// The joint output `v`'s views of the parameters, gradients and both Adam moments (the
    /// last three buffers made, zeroed, on first use).
    pub(crate) fn joint_views(&mut self, gpu: &Gpu, graph: &Graph, v: Value) -> Result<[Tensor; 4]> {
        let g = self.joint_grad(gpu, graph, v)?;
        let (m, s) = self.moment_buffers(gpu)?;
        Ok([self.joint_view(&self.params, graph, v)?, g, self.joint_view(&m, graph, v)?, self.joint_view(&s, graph, v)?])
    }

    /// The buffers of the two Adam moments (made, zeroed, on first use).
    fn moment_buffers(&mut self, gpu: &Gpu) -> Result<(Arc<wgpu::Buffer>, Arc<wgpu::Buffer>)> {
        if self.moments.is_none() {
            self.moments = Some((self.zeroed(gpu)?, self.zeroed(gpu)?));
        }
        Ok(self.moments.clone().expect("just made"))
    }

    /// The buffer of the gradients (made, zeroed, on first use).
    fn grad_buffer(&mut self, gpu: &Gpu) -> Result<Arc<wgpu::Buffer>> {
        if self.grads.is_none() {
            self.grads = Some(self.zeroed(gpu)?);
        }
        Ok(self.grads.clone().expect("just made"))
    }

    /// A zeroed buffer the size of the parameters'.
    fn zeroed(&self, gpu: &Gpu) -> Result<Arc<wgpu::Buffer>> {
        Ok(Tensor::zeros(gpu, &[(self.bytes / 4) as usize])?.into_buffer())
    }

    /// Parameter `v`'s gradient tensor (a view; the buffer is made, zeroed, on first use).
    pub(crate) fn grad(&mut self, gpu: &Gpu, graph: &Graph, v: Value) -> Result<Tensor> {
        let g = self.grad_buffer(gpu)?;
        self.view(&g, graph, v).ok_or_else(|| internal(graph, v))?
    }

    /// Parameter `v`'s Adam moments (views; the buffers are made, zeroed, on first use).
    pub(crate) fn moments(&mut self, gpu: &Gpu, graph: &Graph, v: Value) -> Result<(Tensor, Tensor)> {
        let (m, s) = self.moment_buffers(gpu)?;
        let view = |b| self.view(b, graph, v).ok_or_else(|| internal(graph, v))?;
        Ok((view(&m)?, view(&s)?))
    }

    /// The four whole buffers as flat tensors (parameters, gradients, first and second
    /// moments), for one update of everything; `None` until gradients and moments exist.
    pub(crate) fn whole(&self) -> Option<[Tensor; 4]> {
        let (g, (m, s)) = (self.grads.as_ref()?, self.moments.as_ref()?);
        let n = [(self.bytes / 4) as usize];
        let t = |b: &Arc<wgpu::Buffer>| Tensor::from_buffer(b.clone(), &n).expect("sized for the layout");
        Some([t(&self.params), t(g), t(m), t(s)])
    }
}

fn internal(graph: &Graph, v: Value) -> Error {
    debug_assert!(!matches!(graph.values[v.0].kind, Kind::Param(_)));
    Error::Invalid(format!("internal: '{}' is not a parameter and has no place in the flat buffers", graph.values[v.0].name))
}
