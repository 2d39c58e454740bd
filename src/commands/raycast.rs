//! `naadf raycast WORLD [--method naadf|nodf|grid] < rays.jsonl`

use super::load_world;
use anyhow::{Context, Result, bail};
use naadf_world::traverse::{Hit, Method, Ray, Tracer};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::io::{BufRead, BufWriter, Write};
use std::path::PathBuf;

/// Arguments of `raycast`.
#[derive(clap::Args)]
pub struct Args {
    /// World file.
    world: PathBuf,
    /// Traversal method.
    #[arg(long, default_value = "naadf", value_parser = ["naadf", "nodf", "grid"])]
    method: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RayLine {
    o: [f64; 3],
    d: [f64; 3],
}

#[derive(Serialize)]
struct HitLine {
    hit: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    voxel: Option<[u32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    normal: Option<[i32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    t: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    material: Option<u16>,
    /// Set for entity hits (the voxel and normal are then entity-local).
    #[serde(skip_serializing_if = "Option::is_none")]
    entity: Option<u32>,
}

impl From<Option<Hit>> for HitLine {
    fn from(h: Option<Hit>) -> Self {
        HitLine {
            hit: h.is_some(),
            voxel: h.map(|h| h.voxel),
            normal: h.map(|h| h.normal),
            t: h.map(|h| h.t),
            material: h.map(|h| h.material),
            entity: h.and_then(|h| h.entity),
        }
    }
}

/// Lines traced per parallel batch.
const BATCH: usize = 1 << 16;

/// Traces each input ray and prints one result line per ray, in input order.
pub fn run(a: Args) -> Result<()> {
    let world = load_world(&a.world)?;
    let method = Method::parse(&a.method).expect("clap restricts the values");
    let tracer = Tracer::new(&world, method)?;
    let stdin = std::io::stdin().lock();
    let mut out = BufWriter::new(std::io::stdout().lock());
    let mut lines = stdin.lines().enumerate();
    loop {
        let mut rays = Vec::with_capacity(BATCH);
        for (n, line) in lines.by_ref() {
            let line = line.context("cannot read standard input")?;
            if line.trim().is_empty() {
                continue;
            }
            let r: RayLine = serde_json::from_str(&line)
                .with_context(|| format!("line {}: expected {{\"o\":[x,y,z],\"d\":[x,y,z]}}", n + 1))?;
            match Ray::new(r.o, r.d) {
                Ok(ray) => rays.push(ray),
                Err(e) => bail!("line {}: {e}", n + 1),
            }
            if rays.len() == BATCH {
                break;
            }
        }
        if rays.is_empty() {
            break;
        }
        // Slices of rays, whose instance walks go as batches (`Tracer::trace_many`).
        let hits: Vec<Option<Hit>> = rays
            .par_chunks(naadf_world::entity::bvh::batch::BATCH)
            .flat_map_iter(|c| tracer.trace_many(c))
            .collect();
        for h in hits {
            serde_json::to_writer(&mut out, &HitLine::from(h))?;
            out.write_all(b"\n")?;
        }
    }
    out.flush()?;
    Ok(())
}
