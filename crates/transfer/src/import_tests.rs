use super::*;
use crate::TransferFunction;
use voxless_core::srgb_to_linear;

/// A ParaView export with two presets: a 3-point cool-to-warm-like map over
/// [-5, 15] with opacity points, and a second map.
const PRESETS: &str = r#"[
  {
    "Name": "Cool to Warm Test",
    "Creator": "hand written",
    "ColorSpace": "RGB",
    "NanColor": [1, 1, 0],
    "RGBPoints": [-5, 0.23, 0.299, 0.754,
                   5, 0.865, 0.865, 0.865,
                  15, 0.706, 0.016, 0.15],
    "Points": [-5, 0.0, 0.5, 0.0,
                5, 0.25, 0.5, 0.0,
               15, 1.0, 0.5, 0.0]
  },
  {
    "Name": "Greens",
    "ColorSpace": "Lab",
    "RGBPoints": [0, 0, 0.2, 0, 1, 0.8, 1, 0.8]
  }
]"#;

fn parse(text: &str, name: Option<&str>) -> Result<ImportedColormap, ImportError> {
    parse_colormap_json(text, name, Path::new("maps/preset.json"))
}

fn close(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= tol)
}

#[test]
fn paraview_preset_colours_and_opacity_at_control_points() {
    let m = parse(PRESETS, Some("Cool to Warm Test")).unwrap();
    assert_eq!(m.name, "Cool to Warm Test");
    assert_eq!(m.colormap.name(), "Cool to Warm Test");
    assert_eq!(m.data_range, [-5.0, 15.0]);
    assert_eq!(m.nan_color, Some([1.0, 1.0, 0.0]));
    assert_eq!(m.color_space, ColorSpace::Rgb);
    let file = [
        (0.0, [0.23, 0.299, 0.754], 0.0),
        (0.5, [0.865, 0.865, 0.865], 0.25),
        (1.0, [0.706, 0.016, 0.15], 1.0),
    ];
    let op = m.opacity.as_ref().unwrap();
    for (x, srgb, o) in file {
        // sRGB as given, linear RGB by the sRGB curve, as colormap_points do.
        assert!(close(m.colormap.srgb(x), srgb, 1e-6), "x {x}");
        let lin = m.colormap.linear(x);
        let want = srgb.map(srgb_to_linear);
        assert!(close(lin.to_array(), want, 1e-6), "x {x}: {lin:?}");
        assert!((op.0.eval(x) - o).abs() < 1e-6, "opacity at {x}");
    }
    // RGB space interpolates the components linearly.
    let q = m.colormap.srgb(0.25);
    assert!(close(q, [0.5475, 0.582, 0.8095], 1e-6), "{q:?}");
    // And the transfer function takes both.
    let tf = TransferFunction::new(m.colormap.clone(), op.clone());
    assert!((tf.opacity(1.0) - 1.0).abs() < 1e-6 && tf.opacity(0.0).abs() < 1e-6);
}

#[test]
fn presets_are_picked_by_name_or_first_and_unknown_names_list_the_file() {
    assert_eq!(parse(PRESETS, None).unwrap().name, "Cool to Warm Test");
    let g = parse(PRESETS, Some("greens")).unwrap();
    assert_eq!(
        (g.name.as_str(), g.color_space),
        ("Greens", ColorSpace::Lab)
    );
    assert!(g.opacity.is_none() && g.nan_color.is_none());
    // Lab keeps the ends and bakes the middle.
    assert!(close(g.colormap.srgb(1.0), [0.8, 1.0, 0.8], 1e-6));
    assert!(g.colormap.points.len() > 2);

    let e = parse(PRESETS, Some("Viridis (matplotlib)"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("preset.json")
            && e.contains("Viridis (matplotlib)")
            && e.contains("Cool to Warm Test")
            && e.contains("Greens"),
        "{e}"
    );
    // A file holding a single object.
    let one = r#"{"Name": "Solo", "RGBPoints": [0, 0, 0, 0, 2, 1, 1, 1]}"#;
    assert_eq!(parse(one, None).unwrap().name, "Solo");
    assert!(close(
        parse(one, None).unwrap().colormap.srgb(0.5),
        [0.5; 3],
        1e-6
    ));
    let e = parse(one, Some("Other")).unwrap_err().to_string();
    assert!(e.contains("Other") && e.contains("Solo"), "{e}");
}

#[test]
fn diverging_space_passes_through_white_like_cool_warm() {
    let text = r#"[{"Name": "cw", "ColorSpace": "Diverging",
        "RGBPoints": [0, 0.230, 0.299, 0.754, 1, 0.706, 0.016, 0.150]}]"#;
    let m = parse(text, None).unwrap();
    let reference = crate::Colormap::preset("cool-warm").unwrap();
    for x in [0.0, 0.25, 0.5, 0.75, 1.0] {
        let (a, b) = (m.colormap.srgb(x), reference.srgb(x));
        assert!(close(a, b, 0.005), "x {x}: {a:?} vs {b:?}");
    }
}

#[test]
fn opacity_midpoint_and_sharpness_follow_paraview() {
    let text = r#"{"Name": "o", "RGBPoints": [0, 0, 0, 0, 10, 1, 1, 1],
        "Points": [0, 0, 0.25, 0, 10, 1, 0.5, 0]}"#;
    let op = parse(text, None).unwrap().opacity.unwrap();
    // The midpoint is where the opacity is halfway.
    assert!((op.0.eval(0.25) - 0.5).abs() < 1e-3, "{}", op.0.eval(0.25));
    let step = r#"{"Name": "s", "RGBPoints": [0, 0, 0, 0, 10, 1, 1, 1],
        "Points": [0, 0.1, 0.5, 1, 10, 0.9, 0.5, 0]}"#;
    let op = parse(step, None).unwrap().opacity.unwrap();
    assert!((op.0.eval(0.49) - 0.1).abs() < 1e-6 && (op.0.eval(0.51) - 0.9).abs() < 1e-6);
}

#[test]
fn matplotlib_lists_evenly_spaced_or_with_x() {
    let m = parse("[[0, 0, 0], [1, 0, 0], [1, 1, 1]]", None).unwrap();
    assert_eq!(m.name, "preset");
    assert!(close(m.colormap.srgb(0.5), [1.0, 0.0, 0.0], 1e-6));
    assert!(close(m.colormap.srgb(0.75), [1.0, 0.5, 0.5], 1e-6));
    let m = parse("[[10, 0, 0, 0], [12, 1, 0, 0], [30, 1, 1, 1]]", None).unwrap();
    assert!(close(m.colormap.srgb(0.1), [1.0, 0.0, 0.0], 1e-6));
    assert_eq!(m.data_range, [10.0, 30.0]);
    let e = parse("[[0, 0, 0], [1, 1, 1]]", Some("x")).unwrap_err();
    assert!(e.to_string().contains("'x'"), "{e}");
}

#[test]
fn malformed_files_are_errors_naming_the_file_and_the_problem() {
    let cases: &[(&str, &str)] = &[
        (
            "[{\"Name\": \"a\", \"RGBPoints\": [0, 1, 1",
            "not valid JSON",
        ),
        ("", "not valid JSON"),
        ("42", "expected a ParaView preset"),
        ("[]", "empty"),
        ("[{\"Name\": \"a\"}, [0, 0, 0]]", "not a mix"),
        (
            "[{\"Name\": \"a\", \"Points\": [0, 1, 0.5, 0]}]",
            "no preset has RGBPoints",
        ),
        ("{\"Name\": \"a\", \"RGBPoints\": [0, 1, 1]}", "quadruples"),
        (
            "{\"Name\": \"a\", \"RGBPoints\": [0, \"red\", 0, 0]}",
            "not a number",
        ),
        (
            "{\"Name\": \"a\", \"RGBPoints\": [0, 0, 0, 0, 1, 255, 0, 0]}",
            "divide them by 255",
        ),
        (
            "{\"Name\": \"a\", \"RGBPoints\": [0, 0, 0, 0, 1, -0.1, 0, 0]}",
            "outside [0, 1]",
        ),
        (
            "{\"Name\": \"a\", \"RGBPoints\": [1, 0, 0, 0, 0, 1, 1, 1]}",
            "must not decrease",
        ),
        (
            "{\"Name\": \"a\", \"RGBPoints\": [1, 0, 0, 0, 1, 1, 1, 1]}",
            "no range",
        ),
        (
            "{\"Name\": \"a\", \"ColorSpace\": \"XYZ\", \"RGBPoints\": [0, 0, 0, 0]}",
            "Diverging",
        ),
        (
            "{\"Name\": \"a\", \"RGBPoints\": [0, 0, 0, 0], \"NanColor\": [1, 1]}",
            "NanColor",
        ),
        (
            "{\"Name\": \"a\", \"RGBPoints\": [0, 0, 0, 0, 1, 1, 1, 1], \"Points\": [0, 2, 0.5, 0]}",
            "opacity 2",
        ),
        (
            "{\"Name\": \"a\", \"RGBPoints\": [0, 0, 0, 0, 1, 1, 1, 1], \"Points\": [1, 0, 0.5, 0, 0, 1, 0.5, 0]}",
            "must not decrease",
        ),
        (
            "{\"Name\": 7, \"RGBPoints\": [0, 0, 0, 0]}",
            "Name must be a string",
        ),
        ("[[0, 0], [1, 1]]", "[r, g, b] or [x, r, g, b]"),
        ("[[0, 0, 0], [0, 1, 1, 1]]", "one form throughout"),
        ("[[0, 0, 0, 0], [1, 2, 0, 0]]", "outside [0, 1]"),
    ];
    for (text, want) in cases {
        let e = parse(text, None).unwrap_err().to_string();
        assert!(e.contains("preset.json") && e.contains(want), "{text}: {e}");
    }
    let e = read_colormap_file(Path::new("no/such/map.json"), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no/such/map.json"), "{e}");
}
