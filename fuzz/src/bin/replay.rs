//! Fuzz target `replay`: see [`naadf_fuzz::replay`].

fn main() {
    afl::fuzz!(|data: &[u8]| naadf_fuzz::replay(data));
}
