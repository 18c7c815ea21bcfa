//! Where each module's parameters lie in the model's flat parameter array.
//!
//! Modules are stored in post-order (children before their parent, left subtree first). Each
//! module's parameters are contiguous:
//!
//! | module | parameters, in order |
//! |---|---|
//! | leaf | center c (3), axes A (3×3, row-major), hidden a: W (N×3) b (N), hidden b: W (N×N) b (N), output: w (N) b (1) |
//! | node | hidden a′: W (N×2N) b (N), hidden b′: W (N×N) b (N), output: w (N) b (1) |
//!
//! A leaf normalizes its input as x′ = A·(x − c) (Carcenac §5: rotation into the PCA box of its
//! control points, scaled into [−H/2, H/2]). A node's a′ layer reads the concatenation
//! [b of the left child, b of the right child]. Every module keeps its own output layer, so any
//! subtree can be evaluated on its own (the gradual memorization of the paper's Fig. 6); the
//! model's field is the root's output. Weight matrices are row-major: one row per output neuron.
//! The trainer uses this same layout, so converting a trained model to a blob is a cast.

/// Largest hidden-layer width N a model may have.
pub const MAX_WIDTH: usize = 16;
/// Largest tree height (leaf = 1) a model may have; bounds the evaluation recursion.
pub const MAX_HEIGHT: usize = 16;
/// Parameters of a leaf's input normalization (center and 3×3 axes).
pub const NORMALIZATION_LEN: usize = 12;

/// Leaf or node.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ModuleKind {
    /// Learns one feature from the 3 input coordinates: 3 → N → N → 1.
    Leaf,
    /// Blends the last hidden layers of its two children: 2N → N → N → 1.
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
    /// Offset of the first trained parameter (after a leaf's normalization).
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

    /// Number of trained parameters (everything but a leaf's normalization).
    pub const fn trainable_len(&self) -> usize {
        self.len - self.trainable_start
    }

    /// Multiply–accumulates to evaluate the field (`gradient = false`) or the field and its
    /// gradient of this module alone, as the core does it (the normalization of a leaf counts 9).
    ///
    /// The gradient runs in reverse mode: the transposed pass costs one more MAC per weight of the
    /// hidden layers, plus 9 for a leaf's normalization and N for the output (counted here for
    /// every module, although only the root's output is used). Carcenac's forward recurrence
    /// (§4) would cost [`ModuleLayout::forward_mode_mac_count`].
    ///
    /// ```
    /// use neurosurf_core::implicit::{ModuleKind, ModuleLayout};
    /// let leaf = ModuleLayout::new(ModuleKind::Leaf, 9);
    /// assert_eq!(leaf.mac_count(false), 126);
    /// assert_eq!(leaf.mac_count(true), 252);
    /// assert_eq!(leaf.forward_mode_mac_count(), 477);
    /// ```
    pub const fn mac_count(&self, gradient: bool) -> usize {
        let hidden = self.hidden_a.inputs * self.width + self.width * self.width;
        let normalization = match self.kind {
            ModuleKind::Leaf => 9,
            ModuleKind::Node => 0,
        };
        let field = hidden + self.width + normalization;
        if gradient {
            field + hidden + self.width + normalization
        } else {
            field
        }
    }

    /// Multiply–accumulates of Φ and ∇Φ by forward-mode tangents (Carcenac §4): three tangents
    /// per MAC of the dense layers, a leaf's first-layer tangents being the columns of W·A.
    pub const fn forward_mode_mac_count(&self) -> usize {
        let dense = self.hidden_a.inputs * self.width + self.width * self.width + self.width;
        let normalization = match self.kind {
            ModuleKind::Leaf => 9,
            ModuleKind::Node => 0,
        };
        dense * 4 + normalization
    }
}
