//! Fuzz target `vox`: see [`naadf_fuzz::vox`].

fn main() {
    afl::fuzz!(|data: &[u8]| naadf_fuzz::vox(data));
}
