//! Fuzz target `wal`: see [`naadf_fuzz::wal`].

fn main() {
    afl::fuzz!(|data: &[u8]| naadf_fuzz::wal(data));
}
