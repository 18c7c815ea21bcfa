//! The multiquadric RBF baseline (Carcenac §9).
