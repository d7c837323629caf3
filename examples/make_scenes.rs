//! Writes the test scenes (`bevy_caustics::scenes`) to `assets/scenes/*.gltf` + `.bin`.
//!
//! `cargo run --release --example make_scenes [-- OUT_DIR]`

use std::path::PathBuf;

use clap::Parser;

/// Write the test scenes (`bevy_caustics::scenes`) as glTF (`NAME.gltf` + `NAME.bin`).
///
/// A file that cannot be written prints one line and exits with status 2.
#[derive(Parser, Debug)]
#[command(name = "make_scenes")]
struct Cli {
    /// Folder the scenes are written to, relative to the working directory.
    #[arg(value_name = "OUT_DIR", default_value = "assets/scenes")]
    dir: PathBuf,
}

fn main() {
    let dir = Cli::parse().dir;
    for scene in bevy_caustics::scenes::all() {
        if let Err(e) = bevy_caustics::scenes::gltf::write_gltf(&scene, &dir) {
            eprintln!("error: cannot write {}: {e}", scene.name);
            std::process::exit(2);
        }
        println!("wrote {}/{}.gltf", dir.display(), scene.name);
    }
}
