//! Fuzz target `proto`: see [`naadf_fuzz::proto`].

fn main() {
    afl::fuzz!(|data: &[u8]| naadf_fuzz::proto(data));
}
