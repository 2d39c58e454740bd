//! Fuzz target `world_file`: see [`naadf_fuzz::world_file`].

fn main() {
    afl::fuzz!(|data: &[u8]| naadf_fuzz::world_file(data));
}
