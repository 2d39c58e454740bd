//! `naadf status --server URL [--json]`: the server's version, digest and clients.

use super::print_json;
use super::remote::{ServerArgs, block_on};
use anyhow::Result;

/// Arguments of `status`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    server: ServerArgs,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(serde::Serialize)]
struct Status {
    protocol_version: u32,
    size: [u32; 3],
    version: u64,
    growth_seq: u32,
    quiescent: bool,
    digest: String,
    clients: u32,
    user: String,
    role: String,
}

/// Prints the server's state.
pub fn run(a: Args) -> Result<()> {
    let s = block_on(async { Ok(a.server.connect().await?.status().await?) })?;
    let out = Status {
        protocol_version: s.protocol_version,
        size: s.size,
        version: s.version,
        growth_seq: s.growth_seq,
        quiescent: s.quiescent,
        digest: s.digest.to_string(),
        clients: s.clients,
        user: s.user,
        role: s.role,
    };
    if a.json {
        print_json(&out)
    } else {
        println!(
            "version {} (step {}) digest {} quiescent {} clients {} — you are '{}' ({})",
            out.version, out.growth_seq, out.digest, out.quiescent, out.clients, out.user, out.role
        );
        Ok(())
    }
}
