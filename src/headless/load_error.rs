//! A glTF the loader refuses, told in one line of ours: the path and the loader's reason.
//!
//! Left alone, Bevy's asset server logs the failure itself, at ERROR, once per handle that
//! asked for the file (the glTF and its `Scene0`: twice), each time with the backtrace the
//! loader's `BevyError` captured when `RUST_BACKTRACE` is set. The tools (the headless
//! renderer, the glTF viewer) report the failure themselves, so [`quiet_reported_load_failures`]
//! (a `LogPlugin::custom_layer`) drops the asset server's events that name a file registered
//! with [`report_load_failures_of`], and [`load_failure_reason`] gives the reason without
//! the backtrace. Any other file's failure (a texture, say) is logged as before.
//!
//! A loader can also panic (the `gltf` crate does on an accessor index out of range); Bevy
//! catches it and fails the asset, but Rust's panic hook has printed the panic and its
//! backtrace first. While a [`LoaderPanicCapture`] is held, a panic on an asset-loading
//! thread is kept for [`load_failure_reason`] instead.

use std::fmt::Write as _;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, Once, PoisonError};

use bevy::app::App;
use bevy::asset::AssetLoadError;
use bevy::gltf::GltfError;
use bevy::log::BoxedLayer;
use bevy::log::tracing::field::{Field, Visit};
use bevy::log::tracing::{Event, Level, Subscriber};
use bevy::log::tracing_subscriber::Layer;
use bevy::log::tracing_subscriber::layer::Context;

/// Asset paths (as given to the asset server) whose load failures the caller reports itself.
static REPORTED: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// The caller reports the load failure of `asset_path` (the path given to the asset server,
/// relative to its root, e.g. `scene.gltf`) itself: the asset server's own ERROR about it is
/// dropped where [`quiet_reported_load_failures`] is the log's custom layer.
pub fn report_load_failures_of(asset_path: &str) {
    let mut paths = REPORTED.lock().unwrap_or_else(PoisonError::into_inner);
    if !paths.iter().any(|p| p == asset_path) {
        paths.push(asset_path.to_string());
    }
}

/// A `LogPlugin::custom_layer` that drops the asset server's errors about the files
/// registered with [`report_load_failures_of`] (Bevy's other logs are untouched).
pub fn quiet_reported_load_failures(_: &mut App) -> Option<BoxedLayer> {
    Some(Box::new(QuietReported))
}

/// The tools' log: warnings and errors only (Bevy's start-up INFO lines, the "software
/// rendering" warning of a CPU adapter such as lavapipe and bevy_egui's note on a missing
/// texture-binding-array feature are left out), with the asset
/// server's errors about files the tool reports itself dropped
/// ([`quiet_reported_load_failures`]). `RUST_LOG` still overrides it.
pub fn tool_log_plugin() -> bevy::log::LogPlugin {
    bevy::log::LogPlugin {
        level: Level::WARN,
        filter: "wgpu=error,naga=warn,bevy_render::renderer=error,bevy_egui::render=error"
            .to_string(),
        custom_layer: quiet_reported_load_failures,
        ..Default::default()
    }
}

/// Live [`LoaderPanicCapture`]s.
static CAPTURES: AtomicUsize = AtomicUsize::new(0);
/// The message of the last panic captured on an asset-loading thread.
static LOADER_PANIC: Mutex<Option<String>> = Mutex::new(None);

/// While one is alive, a panic on one of Bevy's asset-loading threads (`IO Task Pool (n)`,
/// where loaders run; Bevy catches it and fails the asset with
/// [`AssetLoadError::AssetLoaderPanic`]) is not printed but kept for
/// [`load_failure_reason`]. Any other panic goes to the panic hook that was set before.
/// Hold one while the file the caller reports itself loads.
pub struct LoaderPanicCapture(());

impl LoaderPanicCapture {
    /// Start capturing (the panic hook is wrapped once per process).
    pub fn start() -> Self {
        static HOOK: Once = Once::new();
        HOOK.call_once(|| {
            let previous = std::panic::take_hook();
            std::panic::set_hook(Box::new(move |info| {
                let loader_thread = std::thread::current()
                    .name()
                    .is_some_and(|n| n.starts_with("IO Task Pool"));
                if !loader_thread || CAPTURES.load(Ordering::SeqCst) == 0 {
                    return previous(info);
                }
                let payload = info.payload();
                let message = payload
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown panic".into());
                *LOADER_PANIC.lock().unwrap_or_else(PoisonError::into_inner) = Some(message);
            }));
        });
        CAPTURES.fetch_add(1, Ordering::SeqCst);
        Self(())
    }
}

impl Drop for LoaderPanicCapture {
    fn drop(&mut self) {
        CAPTURES.fetch_sub(1, Ordering::SeqCst);
    }
}

/// The loader's reason `err` failed, in one line: no backtrace, no asset-server preamble.
pub fn load_failure_reason(err: &AssetLoadError) -> String {
    let text = match err {
        AssetLoadError::AssetLoaderPanic { loader_name, .. } => {
            let panic = LOADER_PANIC
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .take();
            match panic {
                Some(m) => format!("{loader_name} panicked: {m}"),
                None => format!("{loader_name} panicked"),
            }
        }
        AssetLoadError::AssetLoaderError(e) => match e.error().downcast_ref::<GltfError>() {
            Some(g) => g.to_string(),
            // `BevyError`'s text ends in a newline and, if one was captured, the backtrace.
            None => e.error().to_string(),
        },
        AssetLoadError::MissingLabel { label, .. } if label.starts_with("Scene") => {
            format!("it has no scene (no {label} in the file)")
        }
        e => e.to_string(),
    };
    // The first line: a nested `BevyError` (a texture the glTF loader waited for) carries its
    // backtrace after a newline too.
    let line = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("unknown error");
    unsupported_extensions(line).unwrap_or_else(|| line.to_string())
}

/// A refusal for required extensions the loader does not read (the parser's text, as in
/// `load_failure_reason`), told by name with what to do instead of the parser's "Missing data"
/// for every accessor or texture they hold; `None` where the reason is another.
pub fn unsupported_extensions(reason: &str) -> Option<String> {
    // The `gltf` crate's text: `extensionsRequired[0] = "KHR_draco_mesh_compression":
    // Unsupported extension`, among the other validation errors, `;`-separated.
    let names: Vec<&str> = reason
        .split(';')
        .filter_map(|e| e.find("extensionsRequired[").map(|at| e[at..].trim()))
        .filter(|e| e.ends_with("Unsupported extension"))
        .filter_map(|e| e.split('"').nth(1))
        .collect();
    if names.is_empty() {
        return None;
    }
    let hints: Vec<&str> = names
        .iter()
        .filter_map(|n| match *n {
            "KHR_draco_mesh_compression" | "EXT_meshopt_compression" => Some(
                "decode the compressed geometry first (`npx @gltf-transform/cli copy in.glb out.glb`)",
            ),
            "EXT_texture_webp" => Some(
                "convert the WebP textures to PNG (`npx @gltf-transform/cli png in.glb out.glb --formats '*'`)",
            ),
            _ => None,
        })
        .collect();
    let mut text = format!(
        "it requires glTF extension{} {} that Bevy's glTF loader does not read",
        if names.len() > 1 { "s" } else { "" },
        names.join(", ")
    );
    if !hints.is_empty() {
        write!(text, ": {}", hints.join("; ")).ok();
    }
    Some(text)
}

/// The layer behind [`quiet_reported_load_failures`]: an event it refuses is refused for the
/// whole subscriber (`Layer::event_enabled`), so no other layer formats it.
struct QuietReported;

impl<S: Subscriber> Layer<S> for QuietReported {
    fn event_enabled(&self, event: &Event<'_>, _: Context<'_, S>) -> bool {
        let meta = event.metadata();
        if *meta.level() != Level::ERROR || !meta.target().starts_with("bevy_asset") {
            return true;
        }
        let paths = REPORTED.lock().unwrap_or_else(PoisonError::into_inner);
        if paths.is_empty() {
            return true;
        }
        let mut message = Message(String::new());
        event.record(&mut message);
        // The asset server quotes the path: 'scene.gltf' or 'scene.gltf#Scene0'.
        !paths
            .iter()
            .any(|p| message.0.contains(&format!("'{p}'")) || message.0.contains(&format!("'{p}#")))
    }
}

/// An event's `message` field as text.
struct Message(String);

impl Visit for Message {
    fn record_debug(&mut self, field: &Field, value: &dyn core::fmt::Debug) {
        if field.name() == "message" {
            let _ = write!(self.0, "{value:?}");
        }
    }

    fn record_str(&mut self, field: &Field, value: &str) {
        if field.name() == "message" {
            self.0.push_str(value);
        }
    }
}
