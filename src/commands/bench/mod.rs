//! `naadf bench ...`: the benchmarks, one module each (the helpers they share are in
//! `shared`).
//! Every benchmark measures the compared variants in one run, so that ratios are meaningful
//! on a shared, noisy machine.

mod applied;
mod build;
mod cpu;
mod edit;
mod face_granularity;
mod fanout;
mod flood;
mod frames;
mod gi;
mod gpu;
mod mirror_process;
mod moves;
mod paper;
mod plot;
mod shared;
mod stream;
mod traverse;

use anyhow::Result;

/// Benchmarks.
#[derive(clap::Subcommand)]
pub enum Bench {
    /// Ray throughput of the three traversal methods on fixed cameras.
    Traverse(traverse::TraverseArgs),
    /// Generation, construction and chunk-AADF build times of a preset.
    Build(build::BuildArgs),
    /// Edit latency, change-set sizes, regrowth and replayed edit streams.
    Edit(edit::EditArgs),
    /// The server under load: join, rejoin, edit latency with many mirrors, wire bytes.
    Stream(stream::StreamArgs),
    /// Entity moves under load: `MoveEntities` calls of many entities each, latency to many
    /// mirrors, and the bytes of a move in both delta forms.
    Moves(moves::MovesArgs),
    /// Fan-out through relays: edit→received latency and the server's cost per client, with
    /// every client, relay and the server a process of its own.
    Fanout(fanout::FanoutArgs),
    /// One receive-only client of `bench fanout` (started by it).
    #[command(hide = true)]
    FanoutClient(fanout::FanoutClientArgs),
    /// A server under a descriptor limit flooded with connections that never make a
    /// request: how fast `/health` and `status` answer newcomers, and whether a mirror and
    /// an editor connected before keep going.
    Flood(flood::FloodArgs),
    /// GPU ray throughput of the traversal variants (naadf, nodf, grid, svo, svdag, the hybrid formats), checked against the CPU.
    Gpu(gpu::GpuArgs),
    /// Frames through a server's render nodes: frames per second, latency, routing overhead.
    Frames(frames::FramesArgs),
    /// Image quality of the lit modes against a path-traced reference, and the noise floor.
    Gi(gi::GiArgs),
    /// The paper's comparison: bytes, build time and Mrays/s of naadf, an SVO, an SVDAG, two hybrid formats and the grid.
    Paper(paper::PaperArgs),
}

/// Runs a benchmark.
pub fn run(b: Bench) -> Result<()> {
    match b {
        Bench::Traverse(a) => traverse::run(a),
        Bench::Build(a) => build::run(a),
        Bench::Edit(a) => edit::run(a),
        Bench::Stream(a) => stream::run(a),
        Bench::Moves(a) => moves::run(a),
        Bench::Fanout(a) => fanout::run(a),
        Bench::FanoutClient(a) => fanout::client(a),
        Bench::Flood(a) => flood::run(a),
        Bench::Gpu(a) => gpu::run(a),
        Bench::Frames(a) => frames::run(a),
        Bench::Gi(a) => gi::run(a),
        Bench::Paper(a) => paper::run(a),
    }
}
