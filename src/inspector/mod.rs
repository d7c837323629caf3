//! The editor inspector (cargo feature `inspector`): one egui window over the caustics
//! cameras, lights, volumes and casters, their components edited live through `Reflect`, the
//! passes' GPU milliseconds and the techniques' counters from the render diagnostics, and
//! live colour-mapped images of the caustics buffer and the AAPS task buffer.
//!
//! ```ignore
//! app.add_plugins((DefaultPlugins, CausticsPlugin, CausticsInspectorPlugin));
//! ```
//!
//! Without [`CausticsInspectorPlugin`] nothing of it runs. F1 shows and hides the window.

pub mod images;
pub mod model;
pub mod reflect_ui;

use bevy::diagnostic::{DiagnosticsStore, FrameTimeDiagnosticsPlugin};
use bevy::pbr::{MeshMaterial3d, StandardMaterial};
use bevy::prelude::*;
use bevy::render::diagnostic::RenderDiagnosticsPlugin;
use bevy_egui::{
    EguiContext, EguiPlugin, EguiPrimaryContextPass, EguiTextureHandle, EguiUserTextures,
    PrimaryEguiContext, egui,
};

pub use images::{InspectorImages, LiveImage, LiveKind};
pub use model::{EntityKind, PassTiming, Stats};

use crate::scene::collect::derived_caustic_material;
use crate::{
    AapsSettings, CausticLight, CausticMaterial, Caustics, CausticsDebugView, CausticsVolume,
    CausticsVolumeGizmos,
};

/// Adds the caustics inspector window (and `EguiPlugin`, `RenderDiagnosticsPlugin` and
/// `FrameTimeDiagnosticsPlugin` if the app has not added them: an app that adds any of those
/// itself adds it before this plugin, as Bevy refuses a plugin added twice).
#[derive(Default)]
pub struct CausticsInspectorPlugin;

/// The inspector's state.
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct CausticsInspector {
    /// The window is shown (F1 toggles).
    pub open: bool,
    /// The entity whose components are edited.
    pub selected: Option<Entity>,
    /// Frames of timing history plotted per pass.
    pub history: usize,
}

impl Default for CausticsInspector {
    fn default() -> Self {
        Self {
            open: true,
            selected: None,
            history: 120,
        }
    }
}

impl Plugin for CausticsInspectorPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<EguiPlugin>() {
            app.add_plugins(EguiPlugin::default());
        }
        if !app.is_plugin_added::<RenderDiagnosticsPlugin>() {
            app.add_plugins(RenderDiagnosticsPlugin);
        }
        if !app.is_plugin_added::<FrameTimeDiagnosticsPlugin>() {
            app.add_plugins(FrameTimeDiagnosticsPlugin::default());
        }
        app.init_resource::<CausticsInspector>()
            .add_systems(Update, toggle_with_f1)
            .add_systems(EguiPrimaryContextPass, inspector_window);
        images::build(app);
    }
}

fn toggle_with_f1(keys: Option<Res<ButtonInput<KeyCode>>>, mut state: ResMut<CausticsInspector>) {
    if keys.is_some_and(|k| k.just_pressed(KeyCode::F1)) {
        state.open = !state.open;
    }
}

/// One row of the entity list.
struct Row {
    entity: Entity,
    kind: EntityKind,
    name: String,
}

fn entity_rows(world: &mut World) -> Vec<Row> {
    let mut rows = Vec::new();
    let name = |e: Entity, n: Option<&Name>| {
        n.map(|n| n.as_str().to_string())
            .unwrap_or_else(|| format!("{e}"))
    };
    let mut q = world.query::<(
        Entity,
        Option<&Name>,
        Has<Caustics>,
        Has<CausticLight>,
        Has<CausticsVolume>,
        Option<&CausticMaterial>,
        Option<&MeshMaterial3d<StandardMaterial>>,
    )>();
    let materials = world.resource::<Assets<StandardMaterial>>();
    for (e, n, cam, light, volume, over, std) in q.iter(world) {
        let caster = match (over, std) {
            (Some(m), _) => !matches!(m, CausticMaterial::Receiver { .. }),
            (None, Some(h)) => materials.get(&h.0).is_some_and(|m| {
                !matches!(
                    derived_caustic_material(m),
                    CausticMaterial::Receiver { .. }
                )
            }),
            _ => false,
        };
        for (has, kind) in [
            (cam, EntityKind::Camera),
            (light, EntityKind::Light),
            (volume, EntityKind::Volume),
            (caster, EntityKind::Caster),
        ] {
            if has {
                rows.push(Row {
                    entity: e,
                    kind,
                    name: name(e, n),
                });
            }
        }
    }
    rows.sort_by(|a, b| (a.kind, &a.name).cmp(&(b.kind, &b.name)));
    rows
}

/// Edit component `T` of `entity` through `Reflect`; the component is written only when an
/// edit changed it.
fn edit_component<
    T: Component<Mutability = bevy::ecs::component::Mutable>
        + Reflect
        + bevy::reflect::TypePath
        + Clone,
>(
    world: &mut World,
    entity: Entity,
    ui: &mut egui::Ui,
    registry: &bevy::reflect::TypeRegistry,
) -> bool {
    let Some(current) = world.get::<T>(entity) else {
        return false;
    };
    let mut copy = current.clone();
    let title = T::type_path().rsplit("::").next().unwrap_or("component");
    let mut changed = false;
    egui::CollapsingHeader::new(title)
        .default_open(true)
        .show(ui, |ui| {
            changed = reflect_ui::edit(
                ui,
                egui::Id::new((title, entity)),
                copy.as_partial_reflect_mut(),
                &reflect_ui::Range::None,
                registry,
            );
        });
    if changed && let Some(mut c) = world.get_mut::<T>(entity) {
        *c = copy;
    }
    changed
}

fn inspector_window(world: &mut World) {
    if !world.resource::<CausticsInspector>().open {
        // Closed: the live images stop (written once, so the resource is not re-extracted).
        if world.resource::<InspectorImages>().open {
            world.resource_mut::<InspectorImages>().open = false;
        }
        return;
    }
    let mut contexts = world.query_filtered::<&mut EguiContext, With<PrimaryEguiContext>>();
    let Some(ctx) = contexts
        .iter_mut(world)
        .next()
        .map(|mut c| c.get_mut().clone())
    else {
        return;
    };
    let rows = entity_rows(world);
    let mut state = world.resource::<CausticsInspector>().clone();
    if state
        .selected
        .is_none_or(|e| !rows.iter().any(|r| r.entity == e))
    {
        state.selected = rows.first().map(|r| r.entity);
    }
    let stats = {
        let store = world.resource::<DiagnosticsStore>();
        let keep = state.history;
        let stats = Stats::from_diagnostics(store.iter().filter_map(|d| {
            let p = d.path().as_str();
            p.starts_with("render/caustics/").then(|| {
                let v: Vec<f64> = d.values().copied().collect();
                let skip = v.len().saturating_sub(keep);
                (p, v[skip..].to_vec())
            })
        }));
        let fps = store
            .get(&FrameTimeDiagnosticsPlugin::FPS)
            .and_then(|d| d.smoothed());
        (stats, fps)
    };
    // The camera and volume whose images are shown: the selected one, else the first.
    let camera = selected_or_first::<Caustics>(world, state.selected, &rows, EntityKind::Camera);
    let registry = world.resource::<AppTypeRegistry>().clone();
    let registry = registry.read();
    let mut live = world.resource::<InspectorImages>().clone();
    live.open = true;
    live.camera = camera;
    live.volume =
        selected_or_first::<CausticsVolume>(world, state.selected, &rows, EntityKind::Volume);
    let slabs = live
        .volume
        .and_then(|e| world.get::<CausticsVolume>(e))
        .map_or(1, |v| v.slabs.clamp(1, 64));
    let textures: Vec<Option<egui::TextureId>> = {
        let mut user = world.resource_mut::<EguiUserTextures>();
        live.images
            .iter()
            .map(|i| {
                i.shown
                    .then(|| user.add_image(EguiTextureHandle::Weak(i.image.id())))
            })
            .collect()
    };
    let sizes: Vec<UVec2> = {
        let images = world.resource::<Assets<Image>>();
        live.images
            .iter()
            .map(|i| {
                images
                    .get(&i.image)
                    .map(|im| im.size())
                    .unwrap_or(UVec2::ONE)
            })
            .collect()
    };
    // The full height on the left, like an editor's inspector.
    let height = (ctx.content_rect().height() - 16.0).max(100.0);
    egui::Window::new("Caustics")
        .anchor(egui::Align2::LEFT_TOP, [8.0, 8.0])
        .default_width(340.0)
        .min_height(height)
        .max_height(height)
        .vscroll(true)
        .show(&ctx, |ui| {
            entity_list(ui, &rows, &mut state);
            ui.separator();
            if let Some(e) = state.selected {
                selected_components(world, e, ui, &registry);
            }
            ui.separator();
            performance(ui, &stats.0, stats.1);
        });
    egui::Window::new("Caustics images")
        .anchor(egui::Align2::RIGHT_TOP, [-8.0, 8.0])
        .default_width(300.0)
        .max_height(height)
        .vscroll(true)
        .show(&ctx, |ui| {
            live_images(ui, &mut live, slabs, &textures, &sizes);
        });
    // Written back only when changed: the images resource is extracted on change.
    if *world.resource::<CausticsInspector>() != state {
        *world.resource_mut::<CausticsInspector>() = state;
    }
    if *world.resource::<InspectorImages>() != live {
        *world.resource_mut::<InspectorImages>() = live;
    }
}

/// `selected` if it has component `C`, else the first listed entity of `kind`.
fn selected_or_first<C: Component>(
    world: &World,
    selected: Option<Entity>,
    rows: &[Row],
    kind: EntityKind,
) -> Option<Entity> {
    selected
        .filter(|e| world.get::<C>(*e).is_some())
        .or_else(|| rows.iter().find(|r| r.kind == kind).map(|r| r.entity))
}

fn entity_list(ui: &mut egui::Ui, rows: &[Row], state: &mut CausticsInspector) {
    egui::CollapsingHeader::new("Entities")
        .default_open(true)
        .show(ui, |ui| {
            let mut last = None;
            for r in rows {
                if last != Some(r.kind) {
                    ui.label(egui::RichText::new(r.kind.heading()).strong());
                    last = Some(r.kind);
                }
                if ui
                    .selectable_label(state.selected == Some(r.entity), format!("  {}", r.name))
                    .clicked()
                {
                    state.selected = Some(r.entity);
                }
            }
            if rows.is_empty() {
                ui.label("no caustics cameras, lights, volumes or casters");
            }
        });
}

fn selected_components(
    world: &mut World,
    e: Entity,
    ui: &mut egui::Ui,
    registry: &bevy::reflect::TypeRegistry,
) {
    edit_component::<Caustics>(world, e, ui, registry);
    edit_component::<AapsSettings>(world, e, ui, registry);
    edit_component::<CausticLight>(world, e, ui, registry);
    edit_component::<CausticMaterial>(world, e, ui, registry);
    edit_component::<CausticsVolume>(world, e, ui, registry);
    edit_component::<CausticsVolumeGizmos>(world, e, ui, registry);
    if world.get::<Caustics>(e).is_some() {
        pass_switches(world, e, ui);
        ui.horizontal(|ui| {
            if world.get::<AapsSettings>(e).is_none() && ui.button("Add AapsSettings").clicked() {
                world.entity_mut(e).insert(AapsSettings::default());
            }
            let gizmos = world.get::<CausticsVolumeGizmos>(e).is_some();
            let mut on = gizmos;
            ui.checkbox(&mut on, "volume gizmos");
            if on != gizmos {
                if on {
                    world.entity_mut(e).insert(CausticsVolumeGizmos::default());
                } else {
                    world.entity_mut(e).remove::<CausticsVolumeGizmos>();
                }
            }
        });
    }
    if world.get::<CausticMaterial>(e).is_none()
        && let Some(h) = world.get::<MeshMaterial3d<StandardMaterial>>(e)
        && let Some(m) = world.resource::<Assets<StandardMaterial>>().get(&h.0)
    {
        let derived = derived_caustic_material(m);
        ui.label(format!("derived from its StandardMaterial: {derived:?}"));
        if ui.button("Override with CausticMaterial").clicked() {
            world.entity_mut(e).insert(derived);
        }
    }
}

/// Switches for the passes that can run or not on their own, each a shortcut for the setting
/// that controls it (the setting stays the single source of truth): the composite (the debug
/// view `Hidden`), AAPS's small-splat MSAA pass (`msaa_threshold` 0 or its default) and density
/// update (`adaptive`), the volumes' blur pass (`blur_radius` 0 or 1) and differential updates.
fn pass_switches(world: &mut World, camera: Entity, ui: &mut egui::Ui) {
    let Some(c) = world.get::<Caustics>(camera).cloned() else {
        return;
    };
    ui.label(egui::RichText::new("Passes").strong());
    let mut composite = c.debug_view != CausticsDebugView::Hidden;
    if ui.checkbox(&mut composite, "composite").changed()
        && let Some(mut c) = world.get_mut::<Caustics>(camera)
    {
        c.debug_view = if composite {
            CausticsDebugView::Off
        } else {
            CausticsDebugView::Hidden
        };
    }
    match c.technique {
        crate::CausticsTechnique::Aaps => {
            let a = world
                .get::<AapsSettings>(camera)
                .cloned()
                .unwrap_or_default();
            let (mut msaa, mut update) = (a.msaa_threshold > 0.0, a.adaptive);
            let m = ui.checkbox(&mut msaa, "AAPS small-splat MSAA").changed();
            let u = ui.checkbox(&mut update, "AAPS density update").changed();
            if m || u {
                let default_msaa = AapsSettings::default().msaa_threshold;
                let mut a = a;
                a.msaa_threshold = if msaa { default_msaa } else { 0.0 };
                a.adaptive = update;
                world.entity_mut(camera).insert(a);
            }
        }
        crate::CausticsTechnique::Volume => {
            let mut q = world.query::<&mut CausticsVolume>();
            let first = q.iter(world).next().cloned();
            if let Some(v) = first {
                let (mut blur, mut diff) = (v.blur_radius > 0, v.differential);
                let b = ui
                    .checkbox(&mut blur, "volume blur (all volumes)")
                    .changed();
                let d = ui
                    .checkbox(&mut diff, "volume differential updates")
                    .changed();
                if b || d {
                    for mut v in q.iter_mut(world) {
                        v.blur_radius = if blur { v.blur_radius.max(1) } else { 0 };
                        v.differential = diff;
                    }
                }
            }
        }
        crate::CausticsTechnique::ImageSpace => {
            let a = world
                .get::<crate::ImageSpaceSettings>(camera)
                .cloned()
                .unwrap_or_default();
            let mut denoise = a.denoise;
            if ui.checkbox(&mut denoise, "image-space SVGF").changed() {
                let mut a = a;
                a.denoise = denoise;
                world.entity_mut(camera).insert(a);
            }
        }
        crate::CausticsTechnique::PhotonMap => {
            let a = world
                .get::<crate::PhotonMapSettings>(camera)
                .cloned()
                .unwrap_or_default();
            let mut progressive = a.progressive;
            if ui
                .checkbox(&mut progressive, "photon map progressive")
                .changed()
            {
                let mut a = a;
                a.progressive = progressive;
                world.entity_mut(camera).insert(a);
            }
        }
        crate::CausticsTechnique::Reference => {}
    }
}

fn performance(ui: &mut egui::Ui, stats: &Stats, fps: Option<f64>) {
    egui::CollapsingHeader::new("Performance")
        .default_open(true)
        .show(ui, |ui| {
            ui.label(format!(
                "{} fps · caustics {:.2} ms ({} passes)",
                fps.map_or("–".to_string(), |f| format!("{f:.1}")),
                stats.total_ms(),
                stats.timings.len()
            ));
            egui::Grid::new("caustics_timings")
                .num_columns(3)
                .striped(true)
                .show(ui, |ui| {
                    for t in &stats.timings {
                        ui.label(t.pass.trim_start_matches("caustics/"));
                        ui.label(format!("{:.3} ms {}", t.median(), t.clock));
                        sparkline(ui, &t.history);
                        ui.end_row();
                    }
                });
            if !stats.counters.is_empty() {
                ui.label(egui::RichText::new("Counters (last frame)").strong());
                egui::Grid::new("caustics_counters")
                    .num_columns(2)
                    .striped(true)
                    .show(ui, |ui| {
                        for (k, v) in &stats.counters {
                            ui.label(k.as_str());
                            ui.label(format!("{v:.0}"));
                            ui.end_row();
                        }
                    });
            }
        });
}

/// A small rolling plot of `values`, scaled to its maximum.
fn sparkline(ui: &mut egui::Ui, values: &[f64]) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(90.0, 16.0), egui::Sense::hover());
    let max = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    if values.len() < 2 || max <= 0.0 {
        return;
    }
    let n = values.len() as f32 - 1.0;
    let points: Vec<egui::Pos2> = values
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let y = if v.is_finite() { (v / max) as f32 } else { 0.0 };
            egui::pos2(
                rect.left() + rect.width() * i as f32 / n,
                rect.bottom() - rect.height() * y,
            )
        })
        .collect();
    ui.painter().add(egui::Shape::line(
        points,
        egui::Stroke::new(1.0, egui::Color32::LIGHT_GREEN),
    ));
}

fn live_images(
    ui: &mut egui::Ui,
    live: &mut InspectorImages,
    slabs: u32,
    textures: &[Option<egui::TextureId>],
    sizes: &[UVec2],
) {
    const FACES: [&str; 6] = ["+X", "-X", "+Y", "-Y", "+Z", "-Z"];
    for (i, image) in live.images.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.checkbox(&mut image.shown, image.kind.label());
            match image.kind {
                LiveKind::SlabGBuffer if image.shown => {
                    let mut k = live.slab_layer.min(2 * slabs - 1);
                    ui.add(egui::DragValue::new(&mut k).range(0..=2 * slabs - 1))
                        .on_hover_text("layer: G_near of slab k is 2k, G_far 2k + 1");
                    live.slab_layer = k;
                }
                LiveKind::RsmLayer if image.shown => {
                    const LAYERS: [&str; 3] = ["opaque", "caster front", "caster back"];
                    let k = live.rsm_layer;
                    egui::ComboBox::from_id_salt("caustics_rsm_layer")
                        .selected_text(format!("light {} {}", k / 3, LAYERS[(k % 3) as usize]))
                        .show_ui(ui, |ui| {
                            for l in 0..12 {
                                let text = format!("light {} {}", l / 3, LAYERS[(l % 3) as usize]);
                                ui.selectable_value(&mut live.rsm_layer, l, text);
                            }
                        });
                }
                LiveKind::ProjectorTiles if image.shown => {
                    egui::ComboBox::from_id_salt("caustics_tiles_face")
                        .selected_text(FACES[live.face.min(5) as usize])
                        .show_ui(ui, |ui| {
                            for (f, name) in FACES.iter().enumerate() {
                                ui.selectable_value(&mut live.face, f as u32, *name);
                            }
                        });
                }
                _ => {}
            }
        });
        if let (true, Some(Some(id))) = (image.shown, textures.get(i)) {
            let size = sizes.get(i).copied().unwrap_or(UVec2::ONE);
            let w = ui.available_width().min(size.x as f32 * 1.4);
            let h = w * size.y as f32 / size.x as f32;
            ui.image(egui::load::SizedTexture::new(*id, [w, h]));
            if !image.kind.is_normals() {
                legend(ui, image);
            }
        }
    }
}

/// The colour ramp with its range, low to high on a log scale.
fn legend(ui: &mut egui::Ui, image: &mut LiveImage) {
    ui.horizontal(|ui| {
        let (rect, _) = ui.allocate_exact_size(egui::vec2(120.0, 12.0), egui::Sense::hover());
        let steps = 24;
        for s in 0..steps {
            let c = model::ramp((s as f32 + 0.5) / steps as f32);
            let x0 = rect.left() + rect.width() * s as f32 / steps as f32;
            let x1 = rect.left() + rect.width() * (s + 1) as f32 / steps as f32;
            ui.painter().rect_filled(
                egui::Rect::from_x_y_ranges(x0..=x1, rect.y_range()),
                0.0,
                egui::Color32::from(egui::Rgba::from_rgb(c[0], c[1], c[2])),
            );
        }
        let unit = image.kind.unit();
        let (lo, hi) = image.range;
        ui.add(
            egui::DragValue::new(&mut image.range.0)
                .speed(lo * 0.05)
                .range(1e-6..=hi)
                .suffix(format!(" {unit}")),
        );
        ui.label("to");
        ui.add(
            egui::DragValue::new(&mut image.range.1)
                .speed(hi * 0.05)
                .range(lo..=1e9)
                .suffix(format!(" {unit}")),
        );
    });
}
