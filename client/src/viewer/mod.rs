//! The windowed viewer: a winit window that mirrors a server's world on the GPU, flies
//! through it, and edits it.
//!
//! - `link` ([`Link`]): the connection (world stream, status polls, edits) on a tokio runtime;
//! - `fly` ([`Fly`]): WASD + mouse-look camera control;
//! - `pick` ([`edit_for_click`]): which voxel a click edits, and the preview of what a
//!   right click would place (a local instance, drawn only on this window's GPU);
//! - `hud` ([`draw_hud`]): the text overlay;
//! - `markers` ([`place_markers`], [`draw_markers`]): the other people here, from the
//!   presence table: a box at each camera (local instances) and their names;
//! - `present` ([`Presenter`]): showing frames in the window;
//! - this module: the window's event loop, which owns the [`Mirror`] and the [`GpuWorld`]
//!   and applies stream messages in order on its own thread.
//!
//! Controls: click to capture the mouse, then W/A/S/D/Space/Shift fly, the mouse looks,
//! the left button erases and the right button places the selected material, 1–9 or the
//! wheel select it, M cycles the render mode, Esc releases the mouse (a second Esc quits).

mod error;
mod fly;
mod hud;
mod link;
mod markers;
mod pick;
mod present;

pub use error::ViewerError;
pub use fly::{Fly, Move};
pub use hud::draw_hud;
pub use link::{Event, Link};
pub use markers::{draw_markers, marker_material, marker_materials, place_markers, project};
use pick::place_preview;
pub use pick::{Click, edit_for_click};
pub use present::Presenter;

use crate::client::{PresenceUpdate, ServerAddress};
use crate::frame::{Frame, Mode};
use crate::gpu::{Gpu, GpuError, GpuWorld, Renderers, Shot};
use crate::light::{DEFAULT_LIT_BOUNCES, DEFAULT_PATHTRACE_BOUNCES, LitOptions};
use crate::mirror::Mirror;
use naadf_world::camera::Camera;
use naadf_world::entity::local::LocalInstances;
use naadf_world::raysets::fixed_cameras;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{CursorGrabMode, Window, WindowId};

/// How long to wait before rejoining after the stream ended.
const REJOIN_DELAY: Duration = Duration::from_secs(1);
/// Touchpad scroll pixels per material step.
const SCROLL_STEP: f64 = 40.0;
/// How long closing waits for edits still in flight.
const EDIT_DRAIN: Duration = Duration::from_secs(10);
/// Presence is published at most this often while the view changes, and at least this
/// often regardless (the server forgets an entry 5 s after its last update).
const PRESENCE_EVERY: Duration = Duration::from_millis(100);
const PRESENCE_AT_LEAST: Duration = Duration::from_secs(1);

/// What the viewer shows and where it gets it.
#[derive(Clone, Debug)]
pub struct ViewerOptions {
    /// The server.
    pub server: ServerAddress,
    /// Window size (logical pixels).
    pub size: (u32, u32),
    /// Starting camera (by default the first of the benchmark cameras).
    pub camera: Option<Camera>,
    /// Render mode.
    pub mode: Mode,
    /// Flying speed in voxels per second (by default an eighth of the world's width).
    pub speed: Option<f64>,
    /// Quit after this many frames of the world.
    pub frames: Option<u32>,
    /// With `frames`: write the last frame (HUD included) here as PNG.
    pub screenshot: Option<PathBuf>,
    /// Give up when no world arrived in this time.
    pub timeout: Duration,
}

/// How a viewer session ended.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ViewerSummary {
    /// Frames shown.
    pub frames: u32,
    /// The mirrored world's version at the end.
    pub version: u64,
    /// Its digest.
    pub digest: String,
    /// Edits sent.
    pub edits: u32,
    /// The adapter.
    pub adapter: String,
}

/// Opens the window and runs until it is closed (or `frames` are shown).
pub fn run(opts: ViewerOptions) -> Result<ViewerSummary, ViewerError> {
    let event_loop = EventLoop::<Event>::with_user_event()
        .build()
        .map_err(|e| ViewerError::Window(e.to_string()))?;
    let proxy = Mutex::new(event_loop.create_proxy());
    let link = Link::connect(&opts.server, move |e| {
        if let Ok(p) = proxy.lock() {
            // Fails only once the window has closed: nothing is waiting for events then.
            let _ = p.send_event(e);
        }
    })?;
    let mut mirror = Mirror::new(None).with_max_world_bytes(opts.server.max_world_bytes);
    link.join(join_request(&mut mirror));
    let mut app = App {
        opts,
        link,
        mirror,
        started: Instant::now(),
        window: None,
        gfx: None,
        fly: None,
        material: 1,
        scroll: 0.0,
        grabbed: false,
        clients: 0,
        notice: String::new(),
        rejoin_at: None,
        fps: 0.0,
        last_frame: None,
        frames: 0,
        edits: 0,
        title: String::new(),
        presence: PresenceUpdate {
            session: crate::connect::session_client_seq(),
            name: presence_name(),
            tool: "view".into(),
            ..PresenceUpdate::default()
        },
        published: None,
        result: Ok(()),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewerError::Window(e.to_string()))?;
    let unanswered = app.link.finish_edits(EDIT_DRAIN);
    if unanswered > 0 {
        tracing::warn!("{unanswered} edits were still unanswered when the viewer closed");
    }
    app.result?;
    let world = app.mirror.world();
    Ok(ViewerSummary {
        frames: app.frames,
        version: world.map_or(0, |w| w.version()),
        digest: world.map_or_else(String::new, |w| w.digest().to_string()),
        edits: app.edits,
        adapter: app.gfx.map_or_else(String::new, |g| g.gpu.describe()),
    })
}

/// Everything on the GPU side.
struct Graphics {
    gpu: Gpu,
    presenter: Presenter,
    renderers: Renderers,
    world: Option<GpuWorld>,
}

impl Graphics {
    /// One frame of `mode` of the synced world: the lit modes with their defaults
    /// (docs/RENDERING.md §3a–e), the path tracer adding one sample per frame while the view
    /// and the world stay the same.
    fn render(&mut self, camera: &Camera, size: (u32, u32), mode: Mode) -> Result<Frame, GpuError> {
        let Graphics {
            gpu, renderers, world, ..
        } = self;
        let gw = world
            .as_ref()
            .ok_or_else(|| GpuError::Unsupported("no world on the device yet".into()))?;
        let lit = LitOptions::default();
        let light = |bounces| lit.light(bounces).map_err(GpuError::Unsupported);
        let radiance = if mode == Mode::PathTrace {
            renderers.path_tracer.add_sample(
                gpu,
                gw,
                &Shot::new(*camera, size, light(DEFAULT_PATHTRACE_BOUNCES)?, lit.seed),
            )?
        } else if let Some(r) = renderers.temporal_mut(mode) {
            r.frame(
                gpu,
                gw,
                &Shot::new(*camera, size, light(DEFAULT_LIT_BOUNCES)?, lit.seed),
            )?;
            r.radiance(gpu)?
        } else {
            return renderers.renderer.render(gpu, gw, camera, size, mode, false);
        };
        Ok(radiance.tone_mapped(lit.exposure))
    }
}

struct App {
    opts: ViewerOptions,
    link: Link,
    mirror: Mirror,
    started: Instant,
    window: Option<Arc<Window>>,
    gfx: Option<Graphics>,
    fly: Option<Fly>,
    material: u16,
    /// Scroll not yet turned into material steps.
    scroll: f64,
    grabbed: bool,
    clients: u32,
    /// The latest edit result or connection news, shown in the HUD.
    notice: String,
    rejoin_at: Option<Instant>,
    fps: f64,
    last_frame: Option<Instant>,
    frames: u32,
    edits: u32,
    /// The window title shown now (version and clients; updated when they change).
    title: String,
    /// What this window publishes about itself, and when it last did.
    presence: PresenceUpdate,
    published: Option<Instant>,
    result: Result<(), ViewerError>,
}

/// The mirror's join request, with the presence table.
fn join_request(mirror: &mut Mirror) -> naadf_proto::v1::JoinRequest {
    naadf_proto::v1::JoinRequest {
        presence: true,
        ..mirror.join_request()
    }
}

/// The name this window shows the others: `NAADF_NAME`, or the system's user name.
fn presence_name() -> String {
    ["NAADF_NAME", "USER", "USERNAME"]
        .iter()
        .find_map(|k| std::env::var(k).ok().filter(|v| !v.is_empty()))
        .unwrap_or_else(|| "viewer".into())
}

impl App {
    /// Records a fatal error and closes.
    fn fail(&mut self, el: &ActiveEventLoop, e: ViewerError) {
        if self.result.is_ok() {
            self.result = Err(e);
        }
        el.exit();
    }

    fn open_window(&mut self, el: &ActiveEventLoop) -> Result<(), ViewerError> {
        let attrs = Window::default_attributes()
            .with_title("naadf")
            .with_inner_size(winit::dpi::LogicalSize::new(self.opts.size.0, self.opts.size.1));
        let window = Arc::new(
            el.create_window(attrs)
                .map_err(|e| ViewerError::Window(e.to_string()))?,
        );
        let (gpu, surface) = Gpu::for_window(window.clone())?;
        // The first spawn, preview or marker of another client should not freeze the view
        // while the pipelines with the instance walk compile.
        gpu.prepare_instance_variants();
        let size = window.inner_size();
        let presenter = Presenter::new(&gpu, surface, (size.width, size.height))?;
        let mut renderers = Renderers::new(&gpu);
        renderers.gi.profile = true;
        self.gfx = Some(Graphics {
            gpu,
            presenter,
            renderers,
            world: None,
        });
        self.window = Some(window);
        Ok(())
    }

    fn set_grab(&mut self, grab: bool) {
        let Some(w) = &self.window else { return };
        if grab {
            // Locked keeps the pointer still; X11 only confines. Either serves mouse look,
            // and without either (some headless servers) the raw motion still arrives.
            let _ = w
                .set_cursor_grab(CursorGrabMode::Locked)
                .or_else(|_| w.set_cursor_grab(CursorGrabMode::Confined));
        } else {
            let _ = w.set_cursor_grab(CursorGrabMode::None);
        }
        w.set_cursor_visible(!grab);
        self.grabbed = grab;
    }

    fn key(&mut self, el: &ActiveEventLoop, code: KeyCode, down: bool) {
        let movement = match code {
            KeyCode::KeyW => Some(Move::Forward),
            KeyCode::KeyS => Some(Move::Back),
            KeyCode::KeyA => Some(Move::Left),
            KeyCode::KeyD => Some(Move::Right),
            KeyCode::Space => Some(Move::Up),
            KeyCode::ShiftLeft | KeyCode::ShiftRight => Some(Move::Down),
            _ => None,
        };
        if let (Some(m), Some(fly)) = (movement, &mut self.fly) {
            fly.set(m, down);
            return;
        }
        if !down {
            return;
        }
        match code {
            KeyCode::Escape if self.grabbed => self.set_grab(false),
            KeyCode::Escape => el.exit(),
            KeyCode::KeyM => {
                let i = Mode::ALL.iter().position(|&m| m == self.opts.mode).unwrap_or(0);
                self.opts.mode = Mode::ALL[(i + 1) % Mode::ALL.len()];
            }
            _ => {
                let digits = [
                    KeyCode::Digit1,
                    KeyCode::Digit2,
                    KeyCode::Digit3,
                    KeyCode::Digit4,
                    KeyCode::Digit5,
                    KeyCode::Digit6,
                    KeyCode::Digit7,
                    KeyCode::Digit8,
                    KeyCode::Digit9,
                ];
                if let Some(d) = digits.iter().position(|&k| k == code) {
                    self.select_material(d as i64 + 1, false);
                }
            }
        }
    }

    /// Selects material `m` (or steps by `m` when `relative`), among the world's solid
    /// materials (1 ..= len − 1), wrapping around.
    fn select_material(&mut self, m: i64, relative: bool) {
        let count = self.mirror.world().map_or(2, |w| w.materials().len()).max(2) as i64 - 1;
        let m = if relative {
            i64::from(self.material) - 1 + m
        } else {
            m - 1
        };
        self.material = (m.rem_euclid(count) + 1) as u16;
    }

    fn click(&mut self, button: MouseButton) {
        if !self.grabbed {
            self.set_grab(true);
            return;
        }
        let click = match button {
            MouseButton::Left => Click::Erase,
            MouseButton::Right => Click::Place(self.material),
            _ => return,
        };
        let (Some(world), Some(fly), Some(gfx)) = (self.mirror.world(), &self.fly, &self.gfx) else {
            return;
        };
        if let Some(ops) = edit_for_click(world, &fly.camera, gfx.presenter.size(), click) {
            self.link.edit(ops);
            self.edits += 1;
        }
    }

    fn network(&mut self, el: &ActiveEventLoop, e: Event) {
        match e {
            Event::Message(m) => {
                if let Err(e) = self.mirror.handle(&m) {
                    self.fail(el, e.into());
                }
            }
            Event::StreamEnded { why, fatal: true } => self.fail(el, ViewerError::Refused(why)),
            Event::StreamEnded { why, fatal: false } => {
                self.notice = format!("{why}; rejoining");
                self.rejoin_at = Some(Instant::now() + REJOIN_DELAY);
            }
            Event::Clients(n) => self.clients = n,
            Event::Edited(Ok(v)) => self.notice = format!("edit applied at v{v}"),
            Event::Edited(Err(e)) => self.notice = format!("edit not applied: {e}"),
        }
    }

    /// Renders, overlays the HUD and presents one frame; counts it and, at `frames`,
    /// writes the screenshot and quits.
    fn redraw(&mut self, el: &ActiveEventLoop) -> Result<(), ViewerError> {
        let (Some(world), Some(gfx)) = (self.mirror.world(), &mut self.gfx) else {
            if self.started.elapsed() > self.opts.timeout {
                return Err(ViewerError::Timeout(self.opts.timeout, self.notice.clone()));
            }
            return Ok(());
        };
        GpuWorld::follow(&mut gfx.world, &gfx.gpu, world)?;
        let fly = self.fly.get_or_insert_with(|| {
            let camera = self.opts.camera.unwrap_or_else(|| fixed_cameras(world.size())[0]);
            let width = f64::from(world.size().voxels()[0]);
            Fly::new(camera, self.opts.speed.unwrap_or(width / 8.0))
        });
        let now = Instant::now();
        if let Some(last) = self.last_frame {
            let dt = (now - last).as_secs_f64().max(1e-6);
            fly.advance(dt.min(0.25));
            self.fps = if self.fps == 0.0 {
                1.0 / dt
            } else {
                0.9 * self.fps + 0.1 / dt
            };
        }
        self.last_frame = Some(now);
        let size = gfx.presenter.size();
        let others: Vec<_> = self
            .mirror
            .presence()
            .iter()
            .filter(|e| e.session != self.presence.session)
            .cloned()
            .collect();
        // While the window edits, what a right click would place shows where it would go
        // (key 0); the other people show as boxes at their cameras (keys from 1).
        let mut locals = if self.grabbed {
            place_preview(world, &fly.camera, size, self.material)
        } else {
            LocalInstances::default()
        };
        place_markers(&mut locals, world, &others, fly.camera.pos, 1);
        if let Some(gw) = gfx.world.as_mut().filter(|gw| *gw.locals() != locals) {
            gw.set_locals(&locals);
            gw.sync(world)?;
        }
        let mut frame = match gfx.render(&fly.camera, size, self.opts.mode) {
            // `gi` is the default; an adapter that cannot run it (or `roma`, whose maps
            // need a large binding, or `irradiance`) shows albedo instead.
            Err(e) if matches!(self.opts.mode, Mode::Gi | Mode::Roma | Mode::Irradiance) => {
                self.notice = format!("{} is not available here ({e}); showing albedo", self.opts.mode.name());
                self.opts.mode = Mode::Albedo;
                gfx.render(&fly.camera, size, Mode::Albedo)?
            }
            r => r?,
        };
        let swatch = world.materials().get(self.material).map(|m| m.albedo.map(srgb8));
        let mode = match self.opts.mode {
            Mode::PathTrace => format!("pathtrace {} spp", gfx.renderers.path_tracer.samples()),
            m => m.name().to_owned(),
        };
        let mut lines = vec![format!(
            "{:.1} fps {:.1} ms  v{}  {} clients  {mode}",
            self.fps,
            1e3 / self.fps.max(1e-3),
            world.version(),
            self.clients,
        )];
        if self.opts.mode == Mode::Gi
            && let Some(times) = gfx.renderers.gi.pass_times(&gfx.gpu)
        {
            lines.extend(pass_time_lines(&times));
        }
        if !self.notice.is_empty() {
            lines.push(self.notice.clone());
        }
        lines.push(format!("material {}", self.material));
        draw_hud(&mut frame.rgba, frame.width, frame.height, &lines, swatch);
        let title = format!("naadf v{} ({} clients)", world.version(), self.clients);
        if title != self.title
            && let Some(w) = &self.window
        {
            w.set_title(&title);
            self.title = title;
        }
        draw_markers(&mut frame, &fly.camera, &others);
        draw_crosshair(&mut frame);
        let camera = fly.camera;
        publish_presence(
            &self.link,
            (&mut self.presence, &mut self.published),
            &camera,
            world,
            size,
        );
        gfx.presenter.present(&gfx.gpu, &frame)?;
        self.frames += 1;
        if self.opts.frames == Some(self.frames) {
            if let Some(path) = &self.opts.screenshot {
                let png = frame.png().map_err(GpuError::from)?;
                std::fs::write(path, png).map_err(|e| ViewerError::Screenshot(path.clone(), e))?;
            }
            el.exit();
        }
        Ok(())
    }
}

/// Publishes where the window looks and points through `link`, when that changed (at most
/// every [`PRESENCE_EVERY`]) or [`PRESENCE_AT_LEAST`] went by since `published`.
fn publish_presence(
    link: &Link,
    (presence, published): (&mut PresenceUpdate, &mut Option<Instant>),
    camera: &Camera,
    world: &naadf_world::World,
    size: (u32, u32),
) {
    let next = PresenceUpdate {
        position: Some(camera.pos),
        forward: Some(camera.basis().forward),
        pointer: pick::pointed_voxel(world, camera, size),
        ..presence.clone()
    };
    let since = published.map_or(Duration::MAX, |t| t.elapsed());
    if (next != *presence && since >= PRESENCE_EVERY) || since >= PRESENCE_AT_LEAST {
        *presence = next.clone();
        *published = Some(Instant::now());
        link.publish(next);
    }
}

/// Linear albedo to an sRGB byte.
fn srgb8(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// A small cross at the centre of the frame, inverted against the picture.
fn draw_crosshair(frame: &mut Frame) {
    let (w, h) = (frame.width as i64, frame.height as i64);
    for d in -6..=6i64 {
        for (x, y) in [(w / 2 + d, h / 2), (w / 2, h / 2 + d)] {
            if (0..w).contains(&x) && (0..h).contains(&y) {
                let i = ((y * w + x) * 4) as usize;
                for c in &mut frame.rgba[i..i + 3] {
                    *c = 255 - *c;
                }
            }
        }
    }
}

impl ApplicationHandler<Event> for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.window.is_none()
            && let Err(e) = self.open_window(el)
        {
            self.fail(el, e);
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::Resized(s) => {
                if let Some(g) = &mut self.gfx
                    && let Err(e) = g.presenter.resize(&g.gpu, (s.width, s.height))
                {
                    self.fail(el, e.into());
                }
            }
            WindowEvent::Focused(false) => {
                if let Some(f) = &mut self.fly {
                    f.release_all();
                }
                self.set_grab(false);
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    self.key(el, code, event.state == ElementState::Pressed);
                }
            }
            WindowEvent::MouseInput {
                state: ElementState::Pressed,
                button,
                ..
            } => self.click(button),
            WindowEvent::MouseWheel { delta, .. } => {
                // Lines step at once; touchpad pixels add up to a step per SCROLL_STEP.
                self.scroll += match delta {
                    MouseScrollDelta::LineDelta(_, y) => f64::from(y) * SCROLL_STEP,
                    MouseScrollDelta::PixelDelta(p) => p.y,
                };
                let steps = (self.scroll / SCROLL_STEP).trunc();
                if steps != 0.0 {
                    self.scroll -= steps * SCROLL_STEP;
                    self.select_material(-(steps as i64), true);
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(el) {
                    self.fail(el, e);
                }
            }
            _ => {}
        }
    }

    fn device_event(&mut self, _: &ActiveEventLoop, _: winit::event::DeviceId, event: DeviceEvent) {
        if let (DeviceEvent::MouseMotion { delta }, true, Some(fly)) = (event, self.grabbed, &mut self.fly) {
            fly.look(delta.0, delta.1);
        }
    }

    fn user_event(&mut self, el: &ActiveEventLoop, e: Event) {
        self.network(el, e);
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if self.rejoin_at.is_some_and(|t| Instant::now() >= t) {
            self.rejoin_at = None;
            self.link.join(join_request(&mut self.mirror));
        }
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }
}

/// The GI passes' GPU times for the HUD, a few passes per line.
fn pass_time_lines(times: &[(crate::gpu::GiPass, f64)]) -> Vec<String> {
    times
        .chunks(5)
        .map(|row| {
            row.iter()
                .map(|(p, ms)| format!("{} {ms:.2}", p.entry().trim_start_matches("gi_")))
                .collect::<Vec<_>>()
                .join("  ")
        })
        .collect()
}
