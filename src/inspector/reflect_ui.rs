//! A small `Reflect` editor: structs as grids, enums as combo boxes (a new variant's fields
//! from their types' `Default`), numbers as drag values bounded by the field's range attribute
//! (`#[reflect(@1.0_f32..=4.0_f32)]` on the component's field), colours as pickers.
//!
//! Edits go to a clone of the component and are applied only when something changed, so an
//! open panel does not mark the component changed every frame (a volume would rebuild).

use std::ops::RangeInclusive;

use bevy::prelude::*;
use bevy::reflect::enums::{DynamicEnum, DynamicVariant, VariantInfo};
use bevy::reflect::structs::DynamicStruct;
use bevy::reflect::{NamedField, PartialReflect, ReflectMut, TypeRegistry};
use bevy_egui::egui;

/// A field's valid range, from its `#[reflect(@a..=b)]` attribute.
#[derive(Clone, Debug, PartialEq)]
pub enum Range {
    /// No attribute.
    None,
    /// `RangeInclusive<f32>`.
    F32(RangeInclusive<f32>),
    /// `RangeInclusive<u32>`.
    U32(RangeInclusive<u32>),
    /// `RangeInclusive<i32>`.
    I32(RangeInclusive<i32>),
}

impl Range {
    /// The range attribute of `field`.
    pub fn of(field: Option<&NamedField>) -> Self {
        let Some(f) = field else {
            return Self::None;
        };
        if let Some(r) = f.get_attribute::<RangeInclusive<f32>>() {
            Self::F32(r.clone())
        } else if let Some(r) = f.get_attribute::<RangeInclusive<u32>>() {
            Self::U32(r.clone())
        } else if let Some(r) = f.get_attribute::<RangeInclusive<i32>>() {
            Self::I32(r.clone())
        } else {
            Self::None
        }
    }
}

/// Edit `value`; true when it changed.
pub fn edit(
    ui: &mut egui::Ui,
    id: egui::Id,
    value: &mut dyn PartialReflect,
    range: &Range,
    registry: &TypeRegistry,
) -> bool {
    if let Some(v) = value.try_downcast_mut::<f32>() {
        return drag(
            ui,
            v,
            if let Range::F32(r) = range {
                Some(r)
            } else {
                None
            },
        );
    }
    if let Some(v) = value.try_downcast_mut::<u32>() {
        return drag(
            ui,
            v,
            if let Range::U32(r) = range {
                Some(r)
            } else {
                None
            },
        );
    }
    if let Some(v) = value.try_downcast_mut::<i32>() {
        return drag(
            ui,
            v,
            if let Range::I32(r) = range {
                Some(r)
            } else {
                None
            },
        );
    }
    if let Some(v) = value.try_downcast_mut::<u64>() {
        return drag(ui, v, None);
    }
    if let Some(v) = value.try_downcast_mut::<bool>() {
        return ui.checkbox(v, "").changed();
    }
    if let Some(c) = value.try_downcast_mut::<Color>() {
        let s = c.to_srgba();
        let mut rgba = [s.red, s.green, s.blue, s.alpha];
        let changed = ui.color_edit_button_rgba_unmultiplied(&mut rgba).changed();
        if changed {
            *c = Color::srgba(rgba[0], rgba[1], rgba[2], rgba[3]);
        }
        return changed;
    }
    match value.reflect_mut() {
        ReflectMut::Struct(s) => {
            let info = s.get_represented_struct_info();
            let mut changed = false;
            egui::Grid::new(id)
                .num_columns(2)
                .striped(true)
                .show(ui, |ui| {
                    for i in 0..s.field_len() {
                        let name = s.name_at(i).unwrap_or("?").to_string();
                        let range = Range::of(info.and_then(|inf| inf.field_at(i)));
                        ui.label(&name).on_hover_text(range_text(&range));
                        if let Some(f) = s.field_at_mut(i) {
                            changed |= edit(ui, id.with(&name), f, &range, registry);
                        }
                        ui.end_row();
                    }
                });
            changed
        }
        ReflectMut::Enum(e) => {
            let current = e.variant_name().to_string();
            let mut chosen = None;
            if let Some(info) = e.get_represented_enum_info() {
                egui::ComboBox::from_id_salt(id.with("variant"))
                    .selected_text(&current)
                    .show_ui(ui, |ui| {
                        for v in info.iter() {
                            if ui.selectable_label(v.name() == current, v.name()).clicked()
                                && v.name() != current
                            {
                                chosen = Some(v);
                            }
                        }
                    });
            } else {
                ui.label(&current);
            }
            if let Some(v) = chosen {
                return switch_variant(e, v, registry);
            }
            let mut changed = false;
            if e.field_len() > 0 {
                let fields: Vec<Option<&NamedField>> = match e
                    .get_represented_enum_info()
                    .and_then(|i| i.variant(&current))
                {
                    Some(VariantInfo::Struct(s)) => {
                        (0..e.field_len()).map(|i| s.field_at(i)).collect()
                    }
                    _ => vec![None; e.field_len()],
                };
                ui.end_row();
                ui.label("");
                egui::Grid::new(id.with("fields"))
                    .num_columns(2)
                    .show(ui, |ui| {
                        for (i, info) in fields.into_iter().enumerate() {
                            let name = e.name_at(i).map(str::to_string).unwrap_or(format!("{i}"));
                            let range = Range::of(info);
                            ui.label(&name).on_hover_text(range_text(&range));
                            if let Some(f) = e.field_at_mut(i) {
                                changed |= edit(ui, id.with(&name), f, &range, registry);
                            }
                            ui.end_row();
                        }
                    });
            }
            changed
        }
        ReflectMut::List(l) => {
            ui.label(format!("{} items", l.len()));
            false
        }
        _ => {
            ui.label(format!("{value:?}"));
            false
        }
    }
}

/// Switch the enum `e` to variant `v`, its fields at their types' `Default`. False (and `e`
/// unchanged) when a field's type has no registered `Default`.
pub fn switch_variant(
    e: &mut dyn bevy::reflect::enums::Enum,
    v: &VariantInfo,
    registry: &TypeRegistry,
) -> bool {
    match default_variant(v, registry) {
        Some(dynamic) => e.try_apply(&dynamic).is_ok(),
        None => false,
    }
}

/// A variant with every field at its type's `Default`; `None` when a field type has none.
pub fn default_variant(v: &VariantInfo, registry: &TypeRegistry) -> Option<DynamicEnum> {
    match v {
        VariantInfo::Unit(u) => Some(DynamicEnum::new(u.name(), DynamicVariant::Unit)),
        VariantInfo::Struct(s) => {
            let mut fields = DynamicStruct::default();
            for f in s.iter() {
                let default = registry.get_type_data::<ReflectDefault>(f.type_id())?;
                fields.insert_boxed(f.name(), default.default().into_partial_reflect());
            }
            Some(DynamicEnum::new(s.name(), DynamicVariant::Struct(fields)))
        }
        VariantInfo::Tuple(_) => None,
    }
}

/// A drag value, bounded by `range` if given; a value already outside it is shown as it is
/// (the validator clamps it, with a warning).
fn drag<T: egui::emath::Numeric>(
    ui: &mut egui::Ui,
    v: &mut T,
    range: Option<&RangeInclusive<T>>,
) -> bool {
    let speed = (v.to_f64().abs() * 0.01).clamp(0.001, 1000.0);
    let mut d = egui::DragValue::new(v).speed(speed);
    if let Some(r) = range {
        d = d.range(r.clone()).clamp_existing_to_range(false);
    }
    ui.add(d).changed()
}

fn range_text(r: &Range) -> String {
    match r {
        Range::None => "no limit".into(),
        Range::F32(r) => format!("range [{}, {}]", r.start(), r.end()),
        Range::U32(r) => format!("range [{}, {}]", r.start(), r.end()),
        Range::I32(r) => format!("range [{}, {}]", r.start(), r.end()),
    }
}
