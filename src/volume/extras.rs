//! Caustics volumes declared in glTF: a node whose `extras` hold a `caustics_volume` object
//! gets a [`CausticsVolume`] (the plugin runs [`volumes_from_gltf`] every frame in `Update`).

use bevy::prelude::*;

use crate::components::{CausticsVolume, VolumeFace};

/// A volume declared on a glTF node: `extras` with a `caustics_volume` object (see
/// docs/volumes.md for the keys). The node's transform places the box.
pub fn volume_from_extras(json: &str) -> Option<CausticsVolume> {
    let v: serde_json::Value = serde_json::from_str(json).ok()?;
    let o = v.get("caustics_volume")?;
    let mut vol = CausticsVolume::default();
    let face = |s: &serde_json::Value| -> Option<VolumeFace> {
        Some(match s.as_str()? {
            "PosX" | "+X" => VolumeFace::PosX,
            "NegX" | "-X" => VolumeFace::NegX,
            "PosY" | "+Y" => VolumeFace::PosY,
            "NegY" | "-Y" => VolumeFace::NegY,
            "PosZ" | "+Z" => VolumeFace::PosZ,
            "NegZ" | "-Z" => VolumeFace::NegZ,
            _ => return None,
        })
    };
    let faces = |k: &str| -> Option<Vec<VolumeFace>> {
        o.get(k)?
            .as_array()
            .map(|a| a.iter().filter_map(face).collect())
    };
    if let Some(s) = o.get("size").and_then(|s| s.as_array())
        && s.len() == 3
    {
        let c = |i: usize| s[i].as_f64().unwrap_or(1.0) as f32;
        vol.size = Vec3::new(c(0), c(1), c(2));
    }
    let u = |k: &str| o.get(k).and_then(|x| x.as_u64());
    if let Some(x) = u("slabs") {
        vol.slabs = x.min(u32::MAX as u64) as u32;
    }
    if let Some(x) = o.get("photons").and_then(|x| x.as_i64()) {
        vol.photons = x.clamp(i32::MIN as i64, i32::MAX as i64) as i32;
    }
    if let Some(x) = u("projector_resolution") {
        vol.projector_resolution = x.min(u32::MAX as u64) as u32;
    }
    if let Some(x) = u("gbuffer_resolution") {
        vol.gbuffer_resolution = x.min(u32::MAX as u64) as u32;
    }
    if let Some(x) = u("progressive") {
        vol.progressive = x.min(u32::MAX as u64) as u32;
    }
    if let Some(f) = o.get("entry").and_then(face) {
        vol.entry = f;
    }
    if let Some(f) = faces("exit") {
        vol.exit = f;
    }
    if let Some(f) = faces("culling") {
        vol.culling = f;
    }
    Some(vol)
}

/// Insert a [`CausticsVolume`] on glTF nodes whose extras declare one.
pub fn volumes_from_gltf(
    mut commands: Commands,
    nodes: Query<(Entity, &bevy::gltf::GltfExtras), Without<CausticsVolume>>,
) {
    for (e, extras) in &nodes {
        if let Some(v) = volume_from_extras(&extras.value) {
            commands.entity(e).insert(v);
        }
    }
}
