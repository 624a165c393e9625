//! The graph executor: build a network from ops, run it forwards, derive its backward pass,
//! and record a whole training step into one submit.
//!
//! A [`Graph`] holds values (inputs, parameters, node outputs) and nodes (an [`Op`] applied
//! to values). Shapes are inferred as nodes are added; a mismatch is an error naming the
//! node and the shapes. An [`Executor`] owns the GPU tensors for one graph.

mod exec;
mod flat;
mod fuse;
mod optim;
mod op;
pub mod params;
pub mod profile;
pub mod resize_conv;

pub use exec::{Executor, StepStats};
pub use profile::OpTime;
pub use op::Op;
pub use params::Init;

use crate::error::{Error, Result};

/// A value in a graph: an input, a parameter, or a node's output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Value(pub(crate) usize);

/// What a value is.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// Fed by the caller each run (voxels, pose, light, targets). May ask for a gradient.
    Input,
    /// Learned; initialised by `Init`, saved in checkpoints, updated by the optimizer.
    Param(Init),
    /// Computed by a node.
    Node,
}

/// Name, shape and kind of a value.
#[derive(Clone, Debug)]
pub struct ValueInfo {
    /// Unique name (parameters use it as their safetensors name).
    pub name: String,
    /// Shape, inferred for node outputs.
    pub shape: Vec<usize>,
    /// Input, parameter or node output.
    pub kind: Kind,
}

/// One op applied to input values, producing one output value.
#[derive(Clone, Debug)]
pub struct Node {
    /// Name for error messages and statistics.
    pub name: String,
    /// The op.
    pub op: Op,
    /// Its inputs, in the op's order (see [`Op`]).
    pub inputs: Vec<Value>,
    /// Its output.
    pub output: Value,
}

/// A network under construction or ready to execute. Nodes are kept in the order they were
/// added, which is a valid execution order since a node can only use existing values.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    pub(crate) values: Vec<ValueInfo>,
    pub(crate) nodes: Vec<Node>,
}

impl Graph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    fn add_value(&mut self, name: &str, shape: &[usize], kind: Kind) -> Result<Value> {
        if self.values.iter().any(|v| v.name == name) {
            return Err(Error::Invalid(format!("graph: the name '{name}' is used twice")));
        }
        if shape.is_empty() || shape.contains(&0) {
            return Err(Error::Invalid(format!("graph: '{name}' has an empty shape {shape:?}")));
        }
        self.values.push(ValueInfo { name: name.to_string(), shape: shape.to_vec(), kind });
        Ok(Value(self.values.len() - 1))
    }

    /// Declares an input fed by the caller.
    pub fn input(&mut self, name: &str, shape: &[usize]) -> Result<Value> {
        self.add_value(name, shape, Kind::Input)
    }

    /// Declares a learned parameter.
    pub fn param(&mut self, name: &str, shape: &[usize], init: Init) -> Result<Value> {
        self.add_value(name, shape, Kind::Param(init))
    }

    /// Applies `op` to `inputs`; the output's shape is inferred and checked here.
    pub fn apply(&mut self, name: &str, op: Op, inputs: &[Value]) -> Result<Value> {
        let shapes: Vec<&[usize]> = inputs.iter().map(|v| self.values[v.0].shape.as_slice()).collect();
        let shape = op.infer(&shapes).map_err(|e| Error::Shape {
            op: format!("node '{name}' ({})", op.name()),
            msg: format!("{e} (input shapes {shapes:?})"),
        })?;
        let output = self.add_value(name, &shape, Kind::Node)?;
        self.nodes.push(Node { name: name.to_string(), op, inputs: inputs.to_vec(), output });
        Ok(output)
    }

    /// Information about a value.
    pub fn info(&self, v: Value) -> &ValueInfo {
        &self.values[v.0]
    }

    /// Finds a value by name.
    pub fn value(&self, name: &str) -> Option<Value> {
        self.values.iter().position(|v| v.name == name).map(Value)
    }

    /// All parameters, in declaration order.
    pub fn params(&self) -> Vec<Value> {
        (0..self.values.len()).map(Value).filter(|v| matches!(self.values[v.0].kind, Kind::Param(_))).collect()
    }

    /// FLOPs (2 per multiply-add) of one forward pass, counting convolutions and the
    /// projection; a training step costs about three times this.
    pub fn forward_flops(&self) -> f64 {
        let shape = |v: &Value| self.values[v.0].shape.as_slice();
        self.nodes
            .iter()
            .map(|n| {
                let ins: Vec<&[usize]> = n.inputs.iter().map(shape).collect();
                2.0 * n.op.macs(&ins, shape(&n.output)) as f64
            })
            .sum()
    }

    /// The nodes, in execution order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }
}
