//! CPU ray traversal.
