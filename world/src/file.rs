//! World files (`.naadf`).
