//! Where each module's parameters lie in the model's flat parameter array.
//!
//! Modules are stored in post-order (children before their parent, left subtree first). Each
//! module's parameters are contiguous:
//!
//! | module | parameters, in order |
//! |---|---|
//! | leaf | center c (3), axes A (3×3, row-major), hidden a: W (N×3) b (N), hidden b: W (N×N) b (N), output: w (N) b (1) |
//! | node | center c (3), axes A (3×3, row-major), hidden a′: W (N×(2N+3)) b (N), hidden b′: W (N×N) b (N), output: w (N) b (1) |
//!
//! Every module normalizes the point as x′ = A·(x − c) (Carcenac §5: rotation into the PCA box
//! of its control points, scaled into [−H/2, H/2]). A leaf's a layer reads x′; a node's a′
//! layer reads the concatenation [b of the left child (N), b of the right child (N), x′ (3)],
//! so that a node knows where it blends its children, not only what they computed. Every
//! module keeps its own output layer, so any subtree can be evaluated on its own (the gradual
//! memorization of the paper's Fig. 6); the model's field is the root's output. Weight matrices
//! are row-major: one row per output neuron. The trainer uses this same layout, so converting
//! a trained model to a blob is a cast.
//!
//! Blob format version 1 stored nodes without c and A and with an N×2N a′; the loader rejects
//! those blobs by their version (see [`crate::blob`]).

/// Largest hidden-layer width N a model may have.
pub const MAX_WIDTH: usize = 16;
/// Largest tree height (leaf = 1) a model may have; bounds the evaluation recursion.
pub const MAX_HEIGHT: usize = 16;
/// Parameters of a module's input normalization (center and 3×3 axes), the first of every
/// module's parameters.
pub const NORMALIZATION_LEN: usize = 12;

/// Multiply–accumulates of one normalization x′ = A·(x − c), and of its transpose Aᵀ·δ.
const NORMALIZATION_MACS: usize = 9;

/// Leaf or node.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ModuleKind {
    /// Learns one feature from the 3 input coordinates: 3 → N → N → 1.
    Leaf,
    /// Blends the last hidden layers of its two children, knowing its own normalized position:
    /// 2N + 3 → N → N → 1.
    Node,
}

impl ModuleKind {
    /// The byte that stores this kind in a blob's tree.
    pub const fn code(self) -> u8 {
        match self {
            ModuleKind::Leaf => 0,
            ModuleKind::Node => 1,
        }
    }

    /// The kind a tree byte names.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(ModuleKind::Leaf),
            1 => Some(ModuleKind::Node),
            _ => None,
        }
    }
}

/// A dense layer's place inside its module's parameters.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct DenseLayout {
    /// Inputs per neuron.
    pub inputs: usize,
    /// Neurons.
    pub outputs: usize,
    /// Offset of the row-major weight matrix (outputs × inputs).
    pub weights: usize,
    /// Offset of the biases (outputs).
    pub biases: usize,
}

impl DenseLayout {
    const fn at(offset: usize, inputs: usize, outputs: usize) -> Self {
        DenseLayout {
            inputs,
            outputs,
            weights: offset,
            biases: offset + inputs * outputs,
        }
    }

    /// One past the last parameter of the layer.
    pub const fn end(&self) -> usize {
        self.biases + self.outputs
    }
}

/// The parameter layout of one module.
///
/// ```
/// use neurosurf_core::implicit::{ModuleKind, ModuleLayout};
/// let leaf = ModuleLayout::new(ModuleKind::Leaf, 9);
/// assert_eq!(leaf.trainable_len(), 136); // Carcenac's leaf: 3→9→9→1
/// assert_eq!(leaf.len, 148);
/// let node = ModuleLayout::new(ModuleKind::Node, 9);
/// assert_eq!(node.hidden_a.inputs, 21); // [b_left, b_right, x′]
/// assert_eq!(node.trainable_len(), 298); // 21→9→9→1
/// assert_eq!(node.len, 310);
/// ```
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct ModuleLayout {
    /// Leaf or node.
    pub kind: ModuleKind,
    /// Hidden width N.
    pub width: usize,
    /// First hidden layer (a, or a′ for nodes).
    pub hidden_a: DenseLayout,
    /// Second hidden layer (b).
    pub hidden_b: DenseLayout,
    /// Output neuron.
    pub output: DenseLayout,
    /// Offset of the first trained parameter (after the module's normalization).
    pub trainable_start: usize,
    /// Total parameters of the module.
    pub len: usize,
}

impl ModuleLayout {
    /// The layout of a `kind` module with hidden width `width`.
    pub const fn new(kind: ModuleKind, width: usize) -> Self {
        let (start, inputs) = match kind {
            ModuleKind::Leaf => (NORMALIZATION_LEN, 3),
            ModuleKind::Node => (NORMALIZATION_LEN, 2 * width + 3),
        };
        let hidden_a = DenseLayout::at(start, inputs, width);
        let hidden_b = DenseLayout::at(hidden_a.end(), width, width);
        let output = DenseLayout::at(hidden_b.end(), width, 1);
        ModuleLayout {
            kind,
            width,
            hidden_a,
            hidden_b,
            output,
            trainable_start: start,
            len: output.end(),
        }
    }

    /// Number of trained parameters (everything but the module's normalization).
    pub const fn trainable_len(&self) -> usize {
        self.len - self.trainable_start
    }

    /// Multiply–accumulates to evaluate the field (`gradient = false`) or the field and its
    /// gradient of this module alone, as the core does it (every module's normalization counts
    /// 9, and a node's a′ layer has 2N + 3 inputs).
    ///
    /// The gradient runs in reverse mode: the transposed pass costs one more MAC per weight of the
    /// hidden layers (a node's position columns included), plus 9 for the normalization's
    /// transpose Aᵀ and N for the output (counted here for every module, although only the
    /// root's output is used). Carcenac's forward recurrence (§4) would cost
    /// [`ModuleLayout::forward_mode_mac_count`].
    ///
    /// ```
    /// use neurosurf_core::implicit::{ModuleKind, ModuleLayout};
    /// let leaf = ModuleLayout::new(ModuleKind::Leaf, 9);
    /// assert_eq!(leaf.mac_count(false), 126);
    /// assert_eq!(leaf.mac_count(true), 252);
    /// assert_eq!(leaf.forward_mode_mac_count(), 477);
    /// let node = ModuleLayout::new(ModuleKind::Node, 9);
    /// assert_eq!(node.mac_count(false), 288); // 9 + 21·9 + 9·9 + 9
    /// assert_eq!(node.mac_count(true), 576);
    /// assert_eq!(node.forward_mode_mac_count(), 1125);
    /// ```
    pub const fn mac_count(&self, gradient: bool) -> usize {
        let hidden = self.hidden_a.inputs * self.width + self.width * self.width;
        let field = hidden + self.width + NORMALIZATION_MACS;
        if gradient {
            field + hidden + self.width + NORMALIZATION_MACS
        } else {
            field
        }
    }

    /// Multiply–accumulates of Φ and ∇Φ by forward-mode tangents (Carcenac §4): three tangents
    /// per MAC of the dense layers, the tangents of the normalized position x′ being the
    /// columns of A (so a leaf's first-layer tangents are the columns of W·A).
    pub const fn forward_mode_mac_count(&self) -> usize {
        let dense = self.hidden_a.inputs * self.width + self.width * self.width + self.width;
        dense * 4 + NORMALIZATION_MACS
    }
}

#[cfg(test)]
mod tests {
    use super::{ModuleKind, ModuleLayout, NORMALIZATION_LEN};

    /// The documented table, offset by offset, for both kinds at N = 9: c, A, then W and b of
    /// a (a′: 21 inputs, [b_left, b_right, x′]), of b, and the output.
    #[test]
    fn offsets_follow_the_documented_table() {
        let leaf = ModuleLayout::new(ModuleKind::Leaf, 9);
        let node = ModuleLayout::new(ModuleKind::Node, 9);
        for (layout, inputs) in [(leaf, 3), (node, 21)] {
            assert_eq!(layout.trainable_start, NORMALIZATION_LEN);
            assert_eq!(layout.hidden_a.inputs, inputs);
            assert_eq!(layout.hidden_a.weights, 12);
            assert_eq!(layout.hidden_a.biases, 12 + 9 * inputs);
            assert_eq!(layout.hidden_b.weights, 12 + 9 * inputs + 9);
            assert_eq!(layout.hidden_b.biases, layout.hidden_b.weights + 81);
            assert_eq!(layout.output.weights, layout.hidden_b.biases + 9);
            assert_eq!(layout.output.biases, layout.output.weights + 9);
            assert_eq!(layout.len, layout.output.biases + 1);
        }
        assert_eq!((leaf.len, node.len), (148, 310));
        // The node's share of the MACs: 9 for x′, 21·9 + 9·9 + 9 for its layers, twice with
        // the transposed pass.
        assert_eq!(node.mac_count(false), 9 + 21 * 9 + 81 + 9);
        assert_eq!(node.mac_count(true), 2 * node.mac_count(false));
        for width in 1..=super::MAX_WIDTH {
            let node = ModuleLayout::new(ModuleKind::Node, width);
            assert_eq!(node.hidden_a.inputs, 2 * width + 3);
            assert_eq!(
                node.len,
                NORMALIZATION_LEN + (2 * width + 4) * width + (width + 1) * width + width + 1
            );
        }
    }
}
