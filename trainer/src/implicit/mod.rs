//! Carcenac modular implicit surfaces: network, Jacobian, Levenberg–Marquardt, trees.
