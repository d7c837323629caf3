//! The inspector's logic without a GPU (issue 13): the timings and counters it reads from the
//! render diagnostics, its colour ramp at the extremes, and its `Reflect` editor (no edit
//! without input, so an open panel never marks a component changed; enum variants switch with
//! their fields' defaults; fields carry their valid ranges). The README's snippet and
//! examples/minimal.rs are kept identical in `readme.rs`.

use std::ops::RangeInclusive;

use bevy::prelude::*;
use bevy::reflect::enums::Enum;
use bevy::reflect::{PartialReflect, ReflectMut, TypeRegistry};
use bevy_caustics::inspector::model::{Stats, log_scale, ramp};
use bevy_caustics::inspector::reflect_ui::{Range, edit, switch_variant};
use bevy_caustics::prelude::*;
use bevy_egui::egui;

#[test]
fn stats_from_diagnostics() {
    let entries = [
        (
            "render/caustics/aaps/trace/elapsed_gpu",
            vec![3.0, 1.0, 2.0],
        ),
        ("render/caustics/aaps/trace/elapsed_cpu", vec![0.1]),
        (
            "render/caustics/aaps/trace/compute_shader_invocations",
            vec![1e6],
        ),
        ("render/caustics/composite/elapsed_cpu", vec![0.5, 0.7]),
        ("render/caustics/aaps/photons_emitted", vec![10.0, 65_536.0]),
        ("render/main_pass/elapsed_gpu", vec![9.0]),
        ("fps", vec![60.0]),
    ];
    let s = Stats::from_diagnostics(entries.iter().map(|(p, v)| (*p, v.clone())));
    let names: Vec<(&str, &str)> = s
        .timings
        .iter()
        .map(|t| (t.pass.as_str(), t.clock))
        .collect();
    // The GPU clock where there is one, the CPU clock where there is only that.
    assert_eq!(
        names,
        [
            ("caustics/aaps/trace", "gpu"),
            ("caustics/composite", "cpu")
        ]
    );
    assert_eq!(s.timings[0].median(), 2.0);
    assert!((s.total_ms() - 2.7).abs() < 1e-12);
    // Counters: their last value; pass fields and other paths are not counters.
    assert_eq!(s.counters.len(), 1);
    assert_eq!(s.counters["aaps/photons_emitted"], 65_536.0);
    // Nothing in, nothing out; a history of NaN has a median of 0.
    assert_eq!(Stats::from_diagnostics(Vec::new()), Stats::default());
    let nan = Stats::from_diagnostics([("render/caustics/x/elapsed_gpu", vec![f64::NAN])]);
    assert_eq!(nan.timings[0].median(), 0.0);
}

#[test]
fn ramp_and_log_scale_at_the_extremes() {
    for v in [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -1.0,
        0.0,
        1e-30,
        1e30,
    ] {
        let t = log_scale(v, 100.0, 1e6);
        assert!((0.0..=1.0).contains(&t), "{v}: {t}");
        assert!(
            ramp(t)
                .iter()
                .all(|c| c.is_finite() && (0.0..=1.0).contains(c))
        );
        assert!(ramp(v).iter().all(|c| c.is_finite()));
    }
    assert_eq!(log_scale(100.0, 100.0, 1e6), 0.0);
    assert_eq!(log_scale(1e6, 100.0, 1e6), 1.0);
    assert!((log_scale(1e4, 100.0, 1e6) - 0.5).abs() < 1e-6);
    // A degenerate range maps everything to the low end.
    assert_eq!(log_scale(5.0, 1.0, 1.0), 0.0);
    assert_eq!(log_scale(5.0, f32::NAN, 10.0), 0.0);
    let near = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
    assert!(near(ramp(0.0), [0.05, 0.03, 0.35]));
    assert!(near(ramp(1.0), [0.8, 0.05, 0.02]));
}

fn registry() -> TypeRegistry {
    let mut r = TypeRegistry::default();
    r.register::<Caustics>();
    r.register::<AapsSettings>();
    r.register::<CausticLight>();
    r.register::<CausticMaterial>();
    r.register::<CausticsVolume>();
    r.register::<CausticsVolumeGizmos>();
    r.register::<u64>();
    r.register::<Color>();
    r
}

/// Draw the editor over `value` for a few frames with no input; true if it reported a change
/// or the value differs afterwards.
fn edits_without_input<T: PartialReflect + Clone + PartialEq>(value: &T) -> bool {
    let registry = registry();
    let ctx = egui::Context::default();
    let mut copy = value.clone();
    let mut changed = false;
    for _ in 0..3 {
        let out = ctx.run_ui(egui::RawInput::default(), |ui| {
            changed |= edit(
                ui,
                egui::Id::new("t"),
                copy.as_partial_reflect_mut(),
                &Range::None,
                &registry,
            );
        });
        assert!(!out.shapes.is_empty(), "the editor drew nothing");
    }
    changed || copy != *value
}

#[test]
fn reflect_editor_changes_nothing_without_input() {
    assert!(!edits_without_input(&Caustics::default()));
    assert!(!edits_without_input(&AapsSettings::default()));
    assert!(!edits_without_input(&CausticLight::default()));
    assert!(!edits_without_input(&CausticMaterial::glass(1.5)));
    assert!(!edits_without_input(&CausticsVolume::default()));
    assert!(!edits_without_input(&CausticsVolumeGizmos::default()));
    // Out-of-range values are shown as they are, not clamped by the editor behind the user's
    // back (the validator clamps them, with a warning naming the entity and field).
    let wild = AapsSettings {
        target_area: f32::NAN,
        atlas_resolution: 0,
        splat_scale: 1e30,
        ..Default::default()
    };
    let registry = registry();
    let ctx = egui::Context::default();
    let mut copy = wild.clone();
    let _ = ctx.run_ui(egui::RawInput::default(), |ui| {
        edit(ui, egui::Id::new("w"), &mut copy, &Range::None, &registry);
    });
    assert!(copy.target_area.is_nan() && copy.atlas_resolution == 0 && copy.splat_scale == 1e30);
}

#[test]
fn reflect_editor_switches_variants_with_defaults() {
    let registry = registry();
    let mut c = Caustics::default();
    let ReflectMut::Struct(s) = c.reflect_mut() else {
        panic!("Caustics is a struct");
    };
    let quality = s.field_mut("quality").unwrap();
    let ReflectMut::Enum(e) = quality.reflect_mut() else {
        panic!("quality is an enum");
    };
    let info = e.get_represented_enum_info().unwrap();
    assert!(switch_variant(
        e,
        info.variant("Custom").unwrap(),
        &registry
    ));
    assert_eq!(c.quality, CausticsQuality::Custom { photons: 0 });
    // Technique: unit variants.
    let ReflectMut::Struct(s) = c.reflect_mut() else {
        unreachable!()
    };
    let ReflectMut::Enum(e) = s.field_mut("technique").unwrap().reflect_mut() else {
        unreachable!()
    };
    let info = e.get_represented_enum_info().unwrap();
    assert!(switch_variant(
        e,
        info.variant("Volume").unwrap(),
        &registry
    ));
    assert_eq!(c.technique, CausticsTechnique::Volume);
    // A material switches kind with default fields.
    let mut m = CausticMaterial::glass(1.5);
    let ReflectMut::Enum(e) = m.reflect_mut() else {
        unreachable!()
    };
    let info = e.get_represented_enum_info().unwrap();
    assert!(switch_variant(
        e,
        info.variant("Mirror").unwrap(),
        &registry
    ));
    assert!(matches!(m, CausticMaterial::Mirror { .. }));
    // Without a registered Default for a field's type the switch is refused, unchanged.
    let mut q = CausticsQuality::Low;
    let info = q.get_represented_enum_info().unwrap();
    let v = info.variant("Custom").unwrap();
    let ReflectMut::Enum(e) = q.reflect_mut() else {
        unreachable!()
    };
    assert!(!switch_variant(e, v, &TypeRegistry::empty()));
    assert_eq!(q, CausticsQuality::Low);
}

#[test]
fn fields_carry_their_valid_ranges() {
    let range = |info: &bevy::reflect::structs::StructInfo, name: &str| {
        let i = info.index_of(name).unwrap();
        Range::of(info.field_at(i))
    };
    let aaps = AapsSettings::default();
    let info = aaps.get_represented_struct_info().unwrap();
    assert_eq!(range(info, "atlas_resolution"), Range::U32(8..=1024));
    assert_eq!(range(info, "budget_floor_share"), Range::F32(0.0..=1.0));
    assert_eq!(range(info, "adaptive"), Range::None);
    let v = CausticsVolume::default();
    let info = v.get_represented_struct_info().unwrap();
    assert_eq!(range(info, "slabs"), Range::U32(1..=64));
    assert_eq!(range(info, "photons"), Range::I32(0..=16_777_216));
    // Every default lies inside its range.
    for (value, info) in [
        (
            &aaps as &dyn PartialReflect,
            aaps.get_represented_struct_info().unwrap(),
        ),
        (
            &v as &dyn PartialReflect,
            v.get_represented_struct_info().unwrap(),
        ),
    ] {
        let bevy::reflect::ReflectRef::Struct(s) = value.reflect_ref() else {
            unreachable!()
        };
        for i in 0..s.field_len() {
            let f = s.field_at(i).unwrap();
            match Range::of(info.field_at(i)) {
                Range::F32(r) => assert!(in_range(&r, *f.try_downcast_ref::<f32>().unwrap())),
                Range::U32(r) => assert!(in_range(&r, *f.try_downcast_ref::<u32>().unwrap())),
                Range::I32(r) => assert!(in_range(&r, *f.try_downcast_ref::<i32>().unwrap())),
                Range::None => {}
            }
        }
    }
}

fn in_range<T: PartialOrd>(r: &RangeInclusive<T>, v: T) -> bool {
    r.contains(&v)
}

/// Every caustics component is registered by `CausticsPlugin` with `ReflectComponent` and
/// `ReflectDefault`, so bevy-inspector-egui's world inspector lists, adds and edits it, and
/// Bevy Remote Protocol (the type registry plus reflect serialisation to JSON) reads and
/// writes it: each default goes to JSON and back unchanged, and is inserted on an entity and
/// read back through `ReflectComponent`, as `bevy_remote`'s `world.insert_components` does.
#[test]
fn every_component_is_registered_for_editors_and_remote() {
    use bevy::ecs::reflect::ReflectComponent;
    use bevy::reflect::serde::{TypedReflectDeserializer, TypedReflectSerializer};
    use bevy::reflect::std_traits::ReflectDefault;
    use serde::de::DeserializeSeed;
    use std::any::TypeId;

    let mut app = App::new();
    app.add_plugins((MinimalPlugins, CausticsPlugin));
    let types = [
        ("Caustics", TypeId::of::<Caustics>()),
        ("AapsSettings", TypeId::of::<AapsSettings>()),
        ("ImageSpaceSettings", TypeId::of::<ImageSpaceSettings>()),
        ("PhotonMapSettings", TypeId::of::<PhotonMapSettings>()),
        ("CausticsStereo", TypeId::of::<CausticsStereo>()),
        ("CausticLight", TypeId::of::<CausticLight>()),
        ("CausticMaterial", TypeId::of::<CausticMaterial>()),
        ("CausticsVolume", TypeId::of::<CausticsVolume>()),
        ("CausticsVolumeGizmos", TypeId::of::<CausticsVolumeGizmos>()),
    ];
    let registry = app.world().resource::<AppTypeRegistry>().clone();
    let registry = registry.read();
    let entity = app.world_mut().spawn_empty().id();
    for (name, id) in types {
        let reg = registry
            .get(id)
            .unwrap_or_else(|| panic!("{name} is not registered by CausticsPlugin"));
        let component = reg
            .data::<ReflectComponent>()
            .unwrap_or_else(|| panic!("{name} lacks #[reflect(Component)]"));
        let default = reg
            .data::<ReflectDefault>()
            .unwrap_or_else(|| panic!("{name} lacks #[reflect(Default)]"))
            .default();
        let json = serde_json::to_string(&TypedReflectSerializer::new(
            default.as_partial_reflect(),
            &registry,
        ))
        .unwrap_or_else(|e| panic!("{name} does not serialise to JSON: {e}"));
        let back = TypedReflectDeserializer::new(reg, &registry)
            .deserialize(&mut serde_json::Deserializer::from_str(&json))
            .unwrap_or_else(|e| panic!("{name}: JSON {json} does not come back: {e}"));
        assert_eq!(
            back.reflect_partial_eq(default.as_partial_reflect()),
            Some(true),
            "{name}: {json} comes back different"
        );
        let mut e = app.world_mut().entity_mut(entity);
        component.insert(&mut e, back.as_partial_reflect(), &registry);
        let stored = component
            .reflect(app.world().entity(entity))
            .unwrap_or_else(|| panic!("{name} was not inserted"));
        assert_eq!(
            stored.reflect_partial_eq(default.as_partial_reflect()),
            Some(true),
            "{name} inserted differs"
        );
    }
}
