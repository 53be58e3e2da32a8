//! Test harness: every GPU test runs on a context with `VK_LAYER_KHRONOS_validation` and a
//! debug messenger. When the context is dropped (after all its objects were destroyed, so
//! leaks are reported too), any collected warning or error fails the test that caused it.
//! With `HFGI_VALIDATION_LOG=path`, one line per checked context is appended there, so CI can
//! print how many contexts were checked and how many messages appeared.
#![allow(dead_code)]

pub mod scenes;

use std::io::Write;
use std::ops::Deref;
use std::sync::{Arc, Mutex};

use hfgi::vk::{Context, ContextOptions, Recorder};

/// The `hfgi` binary (package `hfgi-cli`): beside the test executable's `deps/` folder, or
/// `HFGI_EXE`. `cargo test` builds test harnesses, not this binary: `tools/test` runs `cargo
/// build --bins` first; a bare `cargo test` may see a missing or stale binary.
pub fn hfgi_exe() -> std::path::PathBuf {
    if let Some(p) = std::env::var_os("HFGI_EXE") {
        return p.into();
    }
    let exe = std::env::current_exe().expect("the test executable's path");
    let dir = exe.parent().and_then(|d| d.parent()).expect("the target directory");
    let p = dir.join(format!("hfgi{}", std::env::consts::EXE_SUFFIX));
    assert!(p.is_file(), "{} is missing: build the CLI (`cargo build -p hfgi-cli`)", p.display());
    p
}

pub struct Gpu {
    ctx: Option<Context>,
    store: Arc<Mutex<Vec<String>>>,
    /// Set by tests that trigger validation errors on purpose (logged as "deliberate").
    pub deliberate: bool,
}

/// Synchronization validation in the tests: on unless `HFGI_SYNC_VALIDATION=0`.
fn sync_validation() -> bool {
    std::env::var("HFGI_SYNC_VALIDATION").map_or(true, |v| v != "0")
}

/// A validated headless context (lavapipe in CI). Panics with the reason if none can be made.
pub fn gpu() -> Gpu {
    let ctx = Context::headless_with(&ContextOptions {
        validation: Some(true),
        device_filter: None,
        sync_validation: Some(sync_validation()),
    })
    .unwrap_or_else(|e| panic!("cannot create a validated Vulkan context: {e}"));
    let store = ctx.validation_store();
    Gpu { ctx: Some(ctx), store, deliberate: false }
}

impl Deref for Gpu {
    type Target = Context;
    fn deref(&self) -> &Context {
        self.ctx.as_ref().expect("context alive")
    }
}

/// Destroys the context and returns every validation message it produced.
pub fn finish(mut gpu: Gpu) -> Vec<String> {
    drop(gpu.ctx.take());
    std::mem::take(&mut *gpu.store.lock().unwrap())
}

impl Drop for Gpu {
    fn drop(&mut self) {
        drop(self.ctx.take());
        let messages = std::mem::take(&mut *self.store.lock().unwrap());
        let test = std::thread::current().name().unwrap_or("?").to_string();
        if let Ok(path) = std::env::var("HFGI_VALIDATION_LOG") {
            if let Ok(mut f) = std::fs::OpenOptions::new().create(true).append(true).open(path) {
                let kind = if self.deliberate { "deliberate" } else { "checked" };
                let _ = writeln!(f, "{test}\t{kind}\t{}", messages.len());
            }
        }
        if !messages.is_empty() && !std::thread::panicking() {
            panic!("{test}: the validation layer reported {} message(s):\n{}", messages.len(), messages.join("\n"));
        }
    }
}

/// Max |a − b| over two slices of equal length.
pub fn max_abs_diff(a: &[f32], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(&x, &y)| (x as f64 - y).abs()).fold(0.0, f64::max)
}

/// A deterministic rough test field: a few sines plus hashed value noise.
pub fn rough_field(w: usize, h: usize, seed: u32) -> hfgi::scene::HeightField {
    let hash = |x: usize, y: usize| {
        let mut v = (x as u32).wrapping_mul(0x9E37_79B1)
            ^ (y as u32).wrapping_mul(0x85EB_CA77)
            ^ seed.wrapping_mul(0xC2B2_AE3D);
        v ^= v >> 15;
        v = v.wrapping_mul(0x2C1B_3C6D);
        v ^= v >> 12;
        (v & 0xFFFF) as f32 / 65535.0
    };
    let data = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32, (k / w) as f32);
            8.0 * (x * 0.21).sin() * (y * 0.13).cos() + 3.0 * (x * 0.05 + y * 0.07).sin() + 2.0 * hash(k % w, k / w)
        })
        .collect();
    hfgi::scene::HeightField::new("test field", w, h, data, 16384).unwrap()
}

/// One frame of `scene` on a fresh `Renderer` (recorded into one command buffer, submitted and
/// waited for), its layers read back.
pub fn render_layers(ctx: &Context, scene: &hfgi::scene::model::Scene) -> hfgi::frame::ShadingLayers {
    render_with(ctx, scene, |ctx, r| r.read_layers(ctx).unwrap())
}

/// Records one frame of `r` into one command buffer, submits it and waits; returns the stages
/// recorded.
pub fn record_frame(ctx: &Context, r: &mut hfgi::frame::Renderer) -> Vec<String> {
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(ctx, cmd, None);
        r.record(&mut rec);
        Ok(rec.stages().to_vec())
    })
    .unwrap()
}

/// Records one frame of `scene` into one submit and waits, then returns what `read` reads back
/// from the renderer (before it is destroyed).
pub fn render_with<T>(
    ctx: &Context,
    scene: &hfgi::scene::model::Scene,
    read: impl FnOnce(&Context, &hfgi::frame::Renderer) -> T,
) -> T {
    let mut r = hfgi::frame::Renderer::new(ctx, scene).unwrap();
    record_frame(ctx, &mut r);
    let out = read(ctx, &r);
    r.destroy(ctx);
    out
}

/// The named debug buffers (`Renderer::debug_buffers`) of one frame of `scene`.
pub fn debug_buffers(ctx: &Context, scene: &hfgi::scene::model::Scene) -> Vec<(String, Vec<f32>)> {
    render_with(ctx, scene, |ctx, r| r.debug_buffers(ctx).unwrap())
}

/// The values of debug buffer `name` (panics naming it when absent).
pub fn find_buffer<'a>(buffers: &'a [(String, Vec<f32>)], name: &str) -> &'a [f32] {
    &buffers.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no buffer {name}")).1
}
