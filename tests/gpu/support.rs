//! What the GPU test binaries share: the lock that runs their Bevy apps one at a time, the
//! adapter check and the examples' executables.

use std::path::PathBuf;
use std::sync::Mutex;

use bevy_caustics::headless::find_adapter;

/// Bevy apps run one at a time, each on a small target.
pub static GPU: Mutex<()> = Mutex::new(());

/// `true` with a Vulkan adapter; without one, a panic (or `false`, a skip, only where
/// BEVY_CAUSTICS_ALLOW_NO_GPU is set: a developer machine).
pub fn require_gpu() -> bool {
    match find_adapter() {
        Ok(name) => {
            println!("adapter: {name}");
            true
        }
        Err(e) if std::env::var_os("BEVY_CAUSTICS_ALLOW_NO_GPU").is_some() => {
            println!("skipped: {e}");
            false
        }
        Err(e) => panic!("{e}"),
    }
}

/// The built example `name` (cargo builds the examples before the tests).
pub fn example_exe(name: &str) -> PathBuf {
    // target/release/deps/<test>-* -> target/release/examples/<name>
    let exe = std::env::current_exe().unwrap();
    exe.parent()
        .unwrap()
        .parent()
        .unwrap()
        .join("examples")
        .join(name)
}
