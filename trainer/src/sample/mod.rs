//! Point samplers: analytic shapes and meshes.
