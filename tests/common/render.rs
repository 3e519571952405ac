//! Helpers shared by the rendering tests (`tests/render.rs`, `tests/render_canopy.rs`),
//! included with `#[path = "common/render.rs"] mod render_common;`.
#![allow(dead_code)]
use std::path::PathBuf;
use std::sync::Mutex;
use sylva::render::headless::Renderer;

static RENDERER: Mutex<Option<Renderer>> = Mutex::new(None);

/// Runs `f` with the test binary's shared renderer. Without an adapter it prints a note and
/// returns, unless `SYLVA_REQUIRE_ADAPTER` is set (CI), in which case it panics.
pub fn with_renderer(f: impl FnOnce(&mut Renderer)) {
    let mut guard = RENDERER.lock().unwrap_or_else(|e| e.into_inner());
    if guard.is_none() {
        match Renderer::new() {
            Ok(r) => *guard = Some(r),
            Err(e) => {
                if std::env::var_os("SYLVA_REQUIRE_ADAPTER").is_some() {
                    panic!("SYLVA_REQUIRE_ADAPTER is set but no adapter was found: {e}");
                }
                eprintln!("skipping: {e}");
                return;
            }
        }
    }
    if let Some(r) = guard.as_mut() {
        f(r)
    }
}

/// `target/tmp/render/`, created: where the tests write the images they render.
pub fn out_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("render");
    std::fs::create_dir_all(&d).unwrap();
    d
}
