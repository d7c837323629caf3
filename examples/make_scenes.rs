//! Writes the test scenes (`bevy_caustics::scenes`) to `assets/scenes/*.gltf` + `.bin`.
//!
//! `cargo run --release --example make_scenes [-- OUT_DIR]`

fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "assets/scenes".into());
    for scene in bevy_caustics::scenes::all() {
        if let Err(e) = bevy_caustics::scenes::gltf::write_gltf(&scene, std::path::Path::new(&dir))
        {
            eprintln!("error: cannot write {}: {e}", scene.name);
            std::process::exit(2);
        }
        println!("wrote {dir}/{}.gltf", scene.name);
    }
}
