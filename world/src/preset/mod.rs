//! Procedural presets.
