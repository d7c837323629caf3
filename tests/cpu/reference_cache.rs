//! The cached converged references (`assets/reference/*_128.exr`) are current: their recipe
//! is the one the report would use today, and a cheap re-render of each scene (2^19 photons,
//! another seed) agrees with the cached image within its noise, block by block.

use bevy_caustics::reference::cache::converged_recipe;
use bevy_caustics::reference::{CausticImage, TraceSettings, trace};
use bevy_caustics::scenes;

/// Sums of `img` over `b x b` blocks (luminance).
fn blocks(img: &CausticImage, b: u32) -> Vec<f64> {
    let n = img.width / b;
    let mut out = vec![0.0; (n * n) as usize];
    for y in 0..img.height {
        for x in 0..img.width {
            let p = img.data[(y * img.width + x) as usize];
            let l = 0.2126 * p.x as f64 + 0.7152 * p.y as f64 + 0.0722 * p.z as f64;
            out[((y / b) * n + x / b) as usize] += l;
        }
    }
    out
}

#[test]
fn cached_references_are_current() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/reference");
    for desc in [
        scenes::mirror_wall(),
        scenes::glass_slab(),
        scenes::glass_sphere(),
        scenes::pool(),
        scenes::ring(),
        scenes::empty(),
        scenes::closed::gem_room(),
    ] {
        let name = &desc.name;
        let meta = std::fs::read_to_string(root.join(format!("{name}_128.json")))
            .unwrap_or_else(|e| panic!("{name}: recipe: {e}"));
        let recipe: serde_json::Value = serde_json::from_str(&meta).unwrap();
        assert_eq!(
            recipe,
            converged_recipe(name, 128),
            "{name}: cached with another recipe; run `cargo run --release --example report`"
        );
        let cached = CausticImage::read_exr(root.join(format!("{name}_128.exr"))).unwrap();
        let (tlas, lights, cam) = desc.to_trace(128, 128);
        let fresh = trace(
            &tlas,
            &lights,
            &cam,
            &TraceSettings {
                photons_per_light: 1 << 19,
                seed: 7,
                ..Default::default()
            },
            None,
        )
        .image;
        let (a, b) = (blocks(&fresh, 32), blocks(&cached, 32));
        let total: f64 = b.iter().sum();
        let l1: f64 = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).sum();
        let energy = a.iter().sum::<f64>() / total.max(1e-30) - 1.0;
        println!(
            "{name}: cached {total:.3e}, re-render energy {:+.2} %, block L1 {:.2} %",
            energy * 100.0,
            l1 / total.max(1e-30) * 100.0
        );
        if name == "empty" {
            assert_eq!(total, 0.0);
            assert_eq!(a.iter().sum::<f64>(), 0.0);
            continue;
        }
        // Noise of 2^19 photons per light: at most about 2.5 % (pool) over 32² blocks.
        assert!(
            energy.abs() < 0.02,
            "{name}: energy {:+.2} %",
            energy * 100.0
        );
        assert!(
            l1 / total < 0.06,
            "{name}: block L1 {:.2} %",
            l1 / total * 100.0
        );
    }
}
