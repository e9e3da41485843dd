//! Changes the page makes to a tab's scene description: JSON merge patches
//! (RFC 7396: objects merge, `null` removes a key) over the description's
//! serde form, limited to the view.
//!
//! Invariant: a patch can change how the data is looked at, never which
//! files are read. Data paths (particle, cell, scalar and tessellation
//! files, per-particle arrays) are not patchable; a colormap file only as
//! the one the server was started with. So a page — or anyone holding the
//! token — can make the server read nothing it was not started on.

use serde_json::{Map, Value};
use voxless::SceneDesc;

use crate::app::App;
use crate::session::ImportedPreset;

/// The keys of each table the page may change; `*` means every key.
const PATCHABLE: &[(&str, &[&str])] = &[
    ("camera", &["*"]),
    ("image", &["spp"]),
    (
        "transfer",
        &[
            "colormap",
            "colormap_points",
            "colormap_file",
            "opacity",
            "opacity_points",
            "value_range",
        ],
    ),
    ("render", &["*"]),
    ("light", &["*"]),
    (
        "particles",
        &[
            "attribute",
            "radius_scale",
            "neighbours",
            "weight_scale",
            "attribute_range",
            "classification",
        ],
    ),
    ("amr", &["field", "color_field", "reconstruction"]),
    ("tets", &["mode", "k", "layers", "lod_pixels"]),
];

/// `desc` with `patch` merged in (see the module docs). `imported` are the
/// tab's imported presets: `{"transfer": {"preset": NAME}}` picks one.
pub fn apply_patch(
    app: &App,
    desc: &SceneDesc,
    imported: &[ImportedPreset],
    patch: &Value,
) -> Result<SceneDesc, String> {
    let Value::Object(tables) = patch else {
        return Err("a patch must be a JSON object of scene tables".into());
    };
    let mut patch = patch.clone();
    // An imported preset becomes explicit control points, so the scene
    // file the tab saves holds the colours themselves.
    if let Some(name) = tables
        .get("transfer")
        .and_then(|t| t.get("preset"))
        .and_then(Value::as_str)
    {
        let p = imported
            .iter()
            .find(|p| p.name == name)
            .ok_or_else(|| format!("no imported colormap named '{name}'"))?;
        let t = patch["transfer"].as_object_mut().expect("checked above");
        t.remove("preset");
        t.insert(
            "colormap_points".into(),
            serde_json::json!(p.colormap_points),
        );
        t.insert("colormap".into(), Value::Null);
        t.insert("colormap_file".into(), Value::Null);
        if let Some(o) = &p.opacity_points {
            t.insert("opacity_points".into(), serde_json::json!(o));
        }
    }
    check_patchable(app, &patch)?;
    let mut value = serde_json::to_value(desc).map_err(|e| e.to_string())?;
    // A new log scale without a new value range: the old range is in the
    // other units, so it goes and the data's range comes back.
    let log_changes = patch
        .get("render")
        .and_then(|r| r.get("log_scale"))
        .is_some();
    let range_given = patch
        .get("transfer")
        .and_then(|t| t.get("value_range"))
        .is_some();
    // A new colour or opacity field: ranges pinned in the old field's units
    // go too (unless the patch gives new ones).
    let field_changes = patch.pointer("/amr/field").is_some();
    let colour_changes = patch.pointer("/particles/attribute").is_some();
    merge(&mut value, &patch);
    if field_changes
        && !range_given
        && let Some(t) = value.get_mut("transfer").and_then(Value::as_object_mut)
    {
        t.remove("value_range");
    }
    if colour_changes
        && patch.pointer("/particles/attribute_range").is_none()
        && let Some(p) = value.get_mut("particles").and_then(Value::as_object_mut)
    {
        p.remove("attribute_range");
    }
    if log_changes
        && !range_given
        && let Some(t) = value.get_mut("transfer").and_then(Value::as_object_mut)
    {
        t.remove("value_range");
    }
    serde_json::from_value(value).map_err(|e| format!("scene: {e}"))
}

/// Refuses tables and keys outside [`PATCHABLE`] (see the module docs).
fn check_patchable(app: &App, patch: &Value) -> Result<(), String> {
    let Value::Object(tables) = patch else {
        return Err("a patch must be a JSON object".into());
    };
    for (table, value) in tables {
        let Some((_, keys)) = PATCHABLE.iter().find(|(t, _)| t == table) else {
            return Err(format!("'{table}' cannot be changed from the page"));
        };
        if keys.contains(&"*") {
            continue;
        }
        let Value::Object(fields) = value else {
            return Err(format!("'{table}' must be a table"));
        };
        for (key, v) in fields {
            if !keys.contains(&key.as_str()) {
                return Err(format!("'{table}.{key}' cannot be changed from the page"));
            }
            if table == "particles" && key == "attribute" && !v.is_null() {
                // A column of the file, or the scene's own attribute: never
                // a new path.
                let name = v.as_str().unwrap_or("");
                let own = app
                    .initial
                    .particles
                    .as_ref()
                    .and_then(|p| p.attribute.as_deref());
                let column = app
                    .particle_columns
                    .iter()
                    .any(|c| c.eq_ignore_ascii_case(name));
                if !(column || own == Some(name)) {
                    return Err(format!(
                        "particles.attribute can only name a column of the particle file ({})",
                        app.particle_columns.join(", ")
                    ));
                }
            }
            if key == "colormap_file" && !v.is_null() {
                let known = app.colormap_file.as_ref().map(|f| f.0.as_str());
                if v.as_str() != known {
                    return Err(
                        "transfer.colormap_file can only be the file the server was started with"
                            .into(),
                    );
                }
            }
        }
    }
    Ok(())
}

/// RFC 7396 merge of `patch` into `target`.
fn merge(target: &mut Value, patch: &Value) {
    match patch {
        Value::Object(p) => {
            if !target.is_object() {
                *target = Value::Object(Map::new());
            }
            let t = target.as_object_mut().expect("made an object above");
            for (k, v) in p {
                if v.is_null() {
                    t.remove(k);
                } else {
                    merge(t.entry(k.clone()).or_insert(Value::Null), v);
                }
            }
        }
        other => *target = other.clone(),
    }
}

/// Samples per imported colormap (sRGB control points in the scene).
const PRESET_SAMPLES: usize = 256;

/// Every preset of a ParaView preset file (JSON text) as control points.
pub fn import_presets(text: &str) -> Result<Vec<ImportedPreset>, String> {
    let path = std::path::Path::new("imported.json");
    let names = crate::app::preset_names(text, path)?;
    let mut out = Vec::new();
    for name in names {
        let m = voxless::transfer::parse_colormap_json(text, Some(&name), path)
            .or_else(|_| voxless::transfer::parse_colormap_json(text, None, path))
            .map_err(|e| e.to_string())?;
        let colormap_points = (0..PRESET_SAMPLES)
            .map(|i| {
                let x = i as f32 / (PRESET_SAMPLES - 1) as f32;
                let [r, g, b] = m.colormap.srgb(x);
                [x, r, g, b]
            })
            .collect();
        let opacity_points = m
            .opacity
            .as_ref()
            .map(|o| o.0.points().iter().map(|&(x, y)| [x, y]).collect());
        out.push(ImportedPreset {
            name: m.name,
            colormap_points,
            opacity_points,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_follows_rfc_7396() {
        let mut t = serde_json::json!({"a": {"b": 1, "c": 2}, "d": 3});
        merge(
            &mut t,
            &serde_json::json!({"a": {"b": null, "e": 4}, "d": [1]}),
        );
        assert_eq!(t, serde_json::json!({"a": {"c": 2, "e": 4}, "d": [1]}));
    }
}
