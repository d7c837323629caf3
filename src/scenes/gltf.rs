//! A minimal glTF 2.0 writer for [`super::SceneDesc`]: one `.gltf` JSON and one `.bin` buffer,
//! with `KHR_lights_punctual`, `KHR_materials_transmission`, `KHR_materials_ior` and
//! `KHR_materials_volume`, which Bevy's loader imports into `DirectionalLight` / `PointLight`
//! / `SpotLight` and `StandardMaterial`.

use std::path::Path;

use serde_json::{Value, json};

use super::{LightKind, SceneDesc};

fn push_f32s(bin: &mut Vec<u8>, v: impl IntoIterator<Item = f32>) {
    for x in v {
        bin.extend_from_slice(&x.to_le_bytes());
    }
}

/// Write `scene` as `dir/<name>.gltf` plus `dir/<name>.bin`.
pub fn write_gltf(scene: &SceneDesc, dir: &Path) -> std::io::Result<()> {
    let mut bin = Vec::<u8>::new();
    let mut views = Vec::<Value>::new();
    let mut accessors = Vec::<Value>::new();
    let mut meshes = Vec::<Value>::new();
    let mut view = |bin: &mut Vec<u8>, start: usize, target: u32| -> usize {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.push(json!({"buffer": 0, "byteOffset": start, "byteLength": bin.len() - start, "target": target}));
        views.len() - 1
    };
    for (mi, m) in scene.meshes.iter().enumerate() {
        let material = scene
            .nodes
            .iter()
            .find(|n| n.mesh == mi)
            .map_or(0, |n| n.material);
        let start = bin.len();
        push_f32s(&mut bin, m.positions.iter().flat_map(|p| p.to_array()));
        let pv = view(&mut bin, start, 34962);
        // glTF needs finite bounds: non-finite positions (stiff cases) stay in the buffer.
        let (lo, hi) = m.positions.iter().filter(|p| p.is_finite()).fold(
            (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)),
            |(a, b), p| (a.min(*p), b.max(*p)),
        );
        accessors.push(
            json!({"bufferView": pv, "componentType": 5126, "count": m.positions.len(),
            "type": "VEC3", "min": lo.to_array(), "max": hi.to_array()}),
        );
        let pos = accessors.len() - 1;
        let mut attributes = json!({"POSITION": pos});
        if let Some(n) = &m.normals {
            let start = bin.len();
            push_f32s(&mut bin, n.iter().flat_map(|p| p.to_array()));
            let nv = view(&mut bin, start, 34962);
            accessors.push(
                json!({"bufferView": nv, "componentType": 5126, "count": n.len(), "type": "VEC3"}),
            );
            attributes["NORMAL"] = json!(accessors.len() - 1);
        }
        let start = bin.len();
        for t in &m.indices {
            for i in t {
                bin.extend_from_slice(&i.to_le_bytes());
            }
        }
        let iv = view(&mut bin, start, 34963);
        accessors.push(json!({"bufferView": iv, "componentType": 5125, "count": m.indices.len() * 3, "type": "SCALAR"}));
        meshes.push(json!({"primitives": [{"attributes": attributes, "indices": accessors.len() - 1, "material": material}]}));
    }
    let materials: Vec<Value> = scene
        .materials
        .iter()
        .map(|m| {
            let p = &m.params;
            let mut v = json!({
                "name": m.name,
                "doubleSided": m.double_sided,
                "pbrMetallicRoughness": {
                    "baseColorFactor": [p.base_color.x, p.base_color.y, p.base_color.z, 1.0],
                    "metallicFactor": p.metallic,
                    "roughnessFactor": p.perceptual_roughness,
                },
            });
            if p.specular_transmission > 0.0 {
                let mut volume = json!({"thicknessFactor": p.thickness,
                    "attenuationColor": p.attenuation_color.to_array()});
                if p.attenuation_distance.is_finite() {
                    volume["attenuationDistance"] = json!(p.attenuation_distance);
                }
                v["extensions"] = json!({
                    "KHR_materials_transmission": {"transmissionFactor": p.specular_transmission},
                    "KHR_materials_ior": {"ior": p.ior},
                    "KHR_materials_volume": volume,
                });
            }
            v
        })
        .collect();
    let mut nodes: Vec<Value> = scene
        .nodes
        .iter()
        .map(|n| {
            json!({"name": n.name, "mesh": n.mesh, "translation": n.translation.to_array(),
                "rotation": n.rotation.to_array(), "scale": n.scale.to_array()})
        })
        .collect();
    let mut lights = Vec::<Value>::new();
    for l in &scene.lights {
        let mut v = json!({"name": l.name, "color": l.color.to_array()});
        match l.kind {
            LightKind::Directional { lux } => {
                v["type"] = json!("directional");
                v["intensity"] = json!(lux);
            }
            LightKind::Point { candela } => {
                v["type"] = json!("point");
                v["intensity"] = json!(candela);
            }
            LightKind::Spot {
                candela,
                inner,
                outer,
            } => {
                v["type"] = json!("spot");
                v["intensity"] = json!(candela);
                v["spot"] = json!({"innerConeAngle": inner, "outerConeAngle": outer});
            }
        }
        lights.push(v);
        nodes.push(
            json!({"name": l.name, "translation": l.translation.to_array(),
            "rotation": l.rotation.to_array(),
            "extensions": {"KHR_lights_punctual": {"light": lights.len() - 1}}}),
        );
    }
    for v in &scene.volumes {
        nodes.push(
            json!({"name": v.name, "translation": v.translation.to_array(),
            "extras": {"caustics_volume": v.extras}}),
        );
    }
    nodes.push(
        json!({"name": "camera", "camera": 0, "translation": scene.camera.translation.to_array(),
        "rotation": scene.camera.rotation.to_array()}),
    );
    let root: Vec<usize> = (0..nodes.len()).collect();
    let bin_name = format!("{}.bin", scene.name);
    let doc = json!({
        "asset": {"version": "2.0", "generator": "bevy_caustics examples/make_scenes.rs"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],
        "scene": 0,
        "scenes": [{"name": scene.name, "nodes": root}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"type": "perspective", "perspective": {"yfov": scene.camera.fov_y, "znear": 0.05, "aspectRatio": 1.0}}],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": bin_name, "byteLength": bin.len()}],
    });
    std::fs::create_dir_all(dir)?;
    std::fs::write(dir.join(&bin_name), &bin)?;
    std::fs::write(
        dir.join(format!("{}.gltf", scene.name)),
        serde_json::to_string_pretty(&doc).map_err(std::io::Error::other)?,
    )
}
