//! The arguments several commands share, each defined once: which preset world to build
//! (`generate`, `serve`, benchmarks), how a server or a relay listens (`serve`, `relay`),
//! the lit modes' options and the frame's size, mode and camera (`render`, `frame`,
//! `view`, `render-node`, benchmarks), with their parsers.

use super::BuildLimit;
use anyhow::{Context, Result};
use naadf_client::Mode;
use naadf_client::light::irradiance::IrradianceOptions;
use naadf_client::light::roma::RomaOptions;
use naadf_client::light::{LitOptions, Sky, Sun};
use naadf_server::net::frontend::{Frontend, Reflection};
use naadf_world::camera::Camera;
use naadf_world::preset::Preset;
use naadf_world::{ChunkSource, World, WorldSize};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

/// Which procedural world to make (`generate`, `serve` and the benchmarks).
#[derive(clap::Args)]
pub struct PresetArgs {
    /// Preset: `terrain`, `test` or `tiled:<file.vox>`.
    #[arg(long, default_value = "terrain")]
    pub preset: String,
    /// World size `X,Y,Z` in voxels (multiples of 64); default: the preset's.
    #[arg(long, value_parser = parse_size)]
    pub size: Option<WorldSize>,
    /// Seed of the generator.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub limit: BuildLimit,
}

impl PresetArgs {
    /// The chunk source these arguments describe.
    pub fn source(&self) -> Result<Box<dyn ChunkSource>> {
        Ok(Preset::parse(&self.preset)?.source(self.size, self.seed)?)
    }

    /// Builds the world with a progress bar.
    pub fn generate(&self) -> Result<World> {
        let source = self.source()?;
        self.limit.build(&*source, &format!("preset '{}'", self.preset))
    }
}

/// Parses `X,Y,Z` for clap.
pub fn parse_size(s: &str) -> Result<WorldSize, String> {
    WorldSize::parse(s).map_err(|e| e.to_string())
}

/// How a server or a relay listens and how far its clients may fall behind: the options
/// `serve` and `relay` share.
#[derive(clap::Args)]
pub struct ListenArgs {
    /// TLS certificate chain (PEM) for the gRPC listener (gRPC, gRPC-web and the page); needs
    /// --tls-key. Read again every 10 s and on SIGHUP:
    /// a changed pair that loads serves the connections opened after it.
    #[arg(long, requires = "tls_key")]
    pub tls_cert: Option<PathBuf>,
    /// TLS private key (PEM); needs --tls-cert.
    #[arg(long, requires = "tls_cert")]
    pub tls_key: Option<PathBuf>,
    /// Largest request message, in bytes.
    #[arg(long, default_value_t = Frontend::default().max_message_bytes)]
    pub max_message_bytes: usize,
    /// Deltas a client may fall behind before its stream is cut (it joins again with its
    /// cache).
    #[arg(long, default_value_t = Frontend::default().slow_client_events)]
    pub slow_client_events: usize,
    /// Bytes a client may fall behind (deltas it has not read) before its stream is cut.
    #[arg(long, default_value_t = Frontend::default().slow_clients.client_bytes)]
    pub slow_client_bytes: u64,
    /// Bytes the subscribed clients together may fall behind; over it, the stream of every
    /// one that is not reading (more than a sixteenth of --slow-client-bytes queued) is cut.
    #[arg(long, default_value_t = Frontend::default().slow_clients.total_bytes)]
    pub slow_clients_total_bytes: u64,
    /// Most connections open at a time on each listener (gRPC and HTTP). At the cap, a
    /// newcomer closes the oldest connection that has not sent a complete request yet, or
    /// waits until one closes. Default: from the descriptor limit (its soft limit raised
    /// to the hard one), less 64 kept back: a quarter for HTTP, the rest for gRPC, at most
    /// 4096 and 16384. Keep twice this plus 64 under the descriptor limit.
    #[arg(long)]
    pub max_connections: Option<usize>,
    /// Close a connection whose peer sent nothing for this many seconds (unfinished
    /// handshakes and requests, dead peers); gRPC connections are pinged at a third of it,
    /// so live ones stay open.
    #[arg(long, default_value_t = Frontend::default().connections.idle_timeout.as_secs_f64())]
    pub idle_timeout: f64,
    /// Close a connection that has not sent a complete request head this many seconds
    /// after it was accepted (a TLS handshake, HTTP/2 settings and ping answers do not
    /// count), and an HTTP/1 connection whose next request head takes longer.
    #[arg(long, default_value_t = Frontend::default().connections.request_deadline.as_secs_f64())]
    pub request_deadline: f64,
    /// Who may use gRPC server reflection (what generic tools such as grpcurl read): `open`
    /// (anyone), `token` (callers with a token the server knows; not for a relay, which
    /// holds none) or `off`. Default: `token` on a server with tokens, `open` otherwise.
    #[arg(long, value_parser = Reflection::parse)]
    pub reflection: Option<Reflection>,
}

impl ListenArgs {
    /// The client-facing settings, listening on `grpc` and `http`.
    pub fn frontend(&self, grpc: SocketAddr, http: SocketAddr) -> Result<Frontend> {
        Ok(Frontend {
            grpc,
            http,
            tls: self.tls_cert.clone().zip(self.tls_key.clone()),
            max_message_bytes: self.max_message_bytes,
            connections: naadf_server::net::conn::ConnLimits {
                max_connections: self.max_connections,
                idle_timeout: super::seconds(self.idle_timeout, "--idle-timeout")?.max(Duration::from_millis(100)),
                request_deadline: super::seconds(self.request_deadline, "--request-deadline")?
                    .max(Duration::from_millis(100)),
            },
            slow_client_events: self.slow_client_events,
            slow_clients: naadf_server::shared::SlowClientLimits {
                client_bytes: self.slow_client_bytes,
                total_bytes: self.slow_clients_total_bytes,
            },
            reflection: self.reflection,
        })
    }
}

/// The options of the lit modes (docs/RENDERING.md §3a–e; `render`, `frame`).
#[derive(clap::Args)]
pub struct LightArgs {
    /// Samples per pixel in total (pathtrace; default 64).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    spp: Option<u32>,
    /// Seed of the random samples: the same seed, device and inputs give the same image.
    #[arg(long)]
    seed: Option<u32>,
    /// Scattered rays after the camera ray (default 8 for pathtrace, 3 for baseline, gi, roma
    /// and irradiance).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=i64::from(naadf_client::light::MAX_BOUNCES)))]
    bounces: Option<u32>,
    /// The sky: `physical` (default) or `uniform:L` / `uniform:R,G,B` (linear radiance).
    #[arg(long, value_parser = Sky::parse)]
    sky: Option<Sky>,
    /// The sun: `off` or `AZ,EL,E` (azimuth from +Z toward +X and elevation in degrees,
    /// irradiance). Default: `300,30,3` under the physical sky, off under a uniform one.
    #[arg(long, value_parser = parse_sun)]
    sun: Option<SunArg>,
    /// Exposure: the PNG holds sRGB(ACES(radiance · exposure)).
    #[arg(long)]
    exposure: Option<f32>,
    /// Candidate directions of `--mode roma`'s occupancy maps: 1, 4, 9 or 16 (default 16).
    #[arg(long, value_name = "K")]
    roma_directions: Option<u32>,
    /// How far `--mode roma` looks for occluders of ambient occlusion, in voxels (up to 256;
    /// default 32).
    #[arg(long, value_name = "VOXELS")]
    ao_range: Option<f64>,
    /// Rays per frame `--mode irradiance` spends refreshing its cache (default 262144).
    #[arg(long, value_name = "N")]
    irradiance_rays: Option<u32>,
}

/// A parsed `--sun` (`off` is a value, so it is not an `Option` itself).
#[derive(Clone, Copy, Debug)]
pub struct SunArg(Option<Sun>);

fn parse_sun(s: &str) -> Result<SunArg, String> {
    Sun::parse(s).map(SunArg)
}

impl LightArgs {
    /// The options given, by name (for a mode that takes none).
    #[cfg(feature = "gpu")]
    pub fn given(&self) -> Vec<&'static str> {
        let flags = [
            ("--spp", self.spp.is_some()),
            ("--seed", self.seed.is_some()),
            ("--bounces", self.bounces.is_some()),
            ("--sky", self.sky.is_some()),
            ("--sun", self.sun.is_some()),
            ("--exposure", self.exposure.is_some()),
        ];
        let mut given: Vec<_> = flags.iter().filter(|f| f.1).map(|f| f.0).collect();
        given.extend(self.tier_options().iter().filter(|o| o.2).map(|o| o.1));
        given
    }

    /// The options that belong to one lit mode alone: the mode, the flag, and whether it
    /// was given.
    #[cfg(feature = "gpu")]
    fn tier_options(&self) -> [(Mode, &'static str, bool); 3] {
        [
            (Mode::Roma, "--roma-directions", self.roma_directions.is_some()),
            (Mode::Roma, "--ao-range", self.ao_range.is_some()),
            (Mode::Irradiance, "--irradiance-rays", self.irradiance_rays.is_some()),
        ]
    }

    /// The first option given that belongs to a lit mode other than `mode`.
    #[cfg(feature = "gpu")]
    pub fn foreign_to(&self, mode: Mode) -> Option<&'static str> {
        self.tier_options()
            .into_iter()
            .find(|o| o.2 && o.0 != mode)
            .map(|o| o.1)
    }

    /// The options given, over the defaults of docs/RENDERING.md.
    pub fn options(&self) -> Result<LitOptions> {
        let d = LitOptions::default();
        let options = LitOptions {
            spp: self.spp.unwrap_or(d.spp),
            seed: self.seed.unwrap_or(d.seed),
            bounces: self.bounces,
            sky: self.sky,
            sun: self.sun.map(|s| s.0),
            exposure: self.exposure.unwrap_or(d.exposure),
            roma: RomaOptions {
                directions: self.roma_directions.unwrap_or(d.roma.directions),
                ao_range: self.ao_range.unwrap_or(d.roma.ao_range),
            },
            irradiance: IrradianceOptions {
                rays: self.irradiance_rays.unwrap_or(d.irradiance.rays),
            },
            ..d
        };
        options.check().map_err(anyhow::Error::msg)?;
        Ok(options)
    }
}

/// Parses `WxH`.
pub fn parse_image_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or("expected WxH, e.g. 1280x720")?;
    let p = |v: &str| v.trim().parse::<u32>().map_err(|e| format!("'{v}': {e}"));
    Ok((p(w)?, p(h)?))
}

/// Parses a render-pass mode name.
pub fn parse_mode(s: &str) -> Result<Mode, String> {
    Mode::parse(s).ok_or_else(|| {
        let names: Vec<_> = Mode::ALL.iter().map(|m| m.name()).collect();
        format!("unknown mode '{s}' (one of: {})", names.join(", "))
    })
}

/// Reads a camera given inline or as a file.
pub fn read_camera(arg: &str) -> Result<Camera> {
    let text = if arg.trim_start().starts_with('{') {
        arg.to_owned()
    } else {
        std::fs::read_to_string(arg).with_context(|| format!("cannot read camera file {arg}"))?
    };
    Ok(Camera::from_json(&text)?)
}
