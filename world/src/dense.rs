//! Dense decode.
