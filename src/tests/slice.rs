use super::*;

#[test]
fn log_scale_is_chosen_for_clumpy_fields_only() {
    // A fluid: most values near 1000, a fringe of tails down to 1e-14.
    let mut fluid = vec![1000.0f32; 900];
    fluid.extend((0..100).map(|i| 10f32.powi(-(i % 14))));
    assert!(!prefers_log(&fluid));
    // The cosmic web: a median near 1 and peaks of 1e3.
    let web: Vec<f32> = (0..1000)
        .map(|i| {
            if i % 97 == 0 {
                3e3
            } else {
                0.5 + (i % 7) as f32 * 0.1
            }
        })
        .collect();
    assert!(prefers_log(&web));
    // Negative values: linear.
    assert!(!prefers_log(&[-1.0, 1.0, 1e6]));
}

#[test]
fn default_ranges_skip_nan_and_floor_log_scale() {
    let r = default_range(&[f32::NAN, 2.0, 5.0], false).unwrap();
    assert_eq!(r, [2.0, 5.0]);
    let r = default_range(&[1e-12, 1e3, 0.0], true).unwrap();
    assert_eq!(r, [3.0 - LOG_DECADES, 3.0]);
    assert!(default_range(&[f32::NAN], false).is_err());
    assert!(default_range(&[0.0, -1.0], true).is_err());
}
