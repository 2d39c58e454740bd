//! Fuzz target `ops`: see [`naadf_fuzz::ops`].

fn main() {
    afl::fuzz!(|data: &[u8]| naadf_fuzz::ops(data));
}
