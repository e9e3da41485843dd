use super::*;

fn key(frame: f64, eye: V3, look_at: V3) -> KeyframeDesc {
    KeyframeDesc {
        frame: Some(frame),
        eye: Some(eye),
        look_at: Some(look_at),
        up: Some([0.0, 0.0, 1.0]),
        ..Default::default()
    }
}

fn path(keys: Vec<KeyframeDesc>) -> Result<Option<CameraPath>, SceneError> {
    CameraPath::new(&CameraDesc {
        keyframes: Some(keys),
        ..Default::default()
    })
}

/// Four keyframes, unevenly spaced, around and over a point.
fn tour() -> CameraPath {
    path(vec![
        key(0.0, [4.0, 0.0, 1.0], [0.0, 0.0, 0.0]),
        key(7.0, [0.0, 4.0, 2.0], [0.5, 0.0, 0.0]),
        key(10.0, [-3.0, 1.0, 0.5], [0.0, 0.2, 0.0]),
        key(30.0, [0.0, -5.0, 3.0], [0.0, 0.0, 0.1]),
    ])
    .unwrap()
    .unwrap()
}

#[test]
fn a_path_passes_through_every_keyframe_exactly() {
    let p = tour();
    for (i, f) in [0.0, 7.0, 10.0, 30.0].into_iter().enumerate() {
        assert_eq!(p.at(f), p.poses[i], "keyframe {i}");
    }
    // And the camera the renderer gets there is the keyframe's.
    let d = p.apply(&SceneDesc::default(), 7.0);
    assert_eq!(d.camera.eye, Some([0.0, 4.0, 2.0]));
    assert_eq!(d.camera.look_at, Some([0.5, 0.0, 0.0]));
    assert_eq!(d.camera.up, Some([0.0, 0.0, 1.0]));
}

/// Velocity of `f` at `t` from the left and the right, by central
/// differences on either side.
fn one_sided(f: &dyn Fn(f64) -> f64, t: f64, h: f64) -> (f64, f64) {
    let left = (3.0 * f(t) - 4.0 * f(t - h) + f(t - 2.0 * h)) / (2.0 * h);
    let right = (-3.0 * f(t) + 4.0 * f(t + h) - f(t + 2.0 * h)) / (2.0 * h);
    (left, right)
}

#[test]
fn positions_are_c1_across_and_between_keyframes() {
    let p = tour();
    let h = 1e-4;
    for a in 0..3 {
        let eye = |t: f64| p.at(t).eye[a];
        let look = |t: f64| p.at(t).look_at[a];
        for f in [&eye as &dyn Fn(f64) -> f64, &look] {
            // Across the inner keyframes: the velocity does not jump.
            for k in [7.0, 10.0] {
                let (l, r) = one_sided(f, k, h);
                assert!(
                    (l - r).abs() <= 1e-5 * (1.0 + l.abs()),
                    "axis {a} at {k}: {l} vs {r}"
                );
            }
            // Between them: continuous too (no jump between close points).
            let mut t = 0.5;
            while t < 29.5 {
                let (l, r) = one_sided(f, t, h);
                assert!((l - r).abs() <= 1e-5 * (1.0 + l.abs()), "axis {a} at {t}");
                t += 0.37;
            }
        }
    }
}

#[test]
fn orientation_turns_smoothly_without_roll() {
    let p = tour();
    // Every keyframe has up +z; the path's up never leaves the plane that
    // holds +z and the look direction (no roll), and is a unit vector.
    let mut t = 0.0;
    while t <= 30.0 {
        let q = p.at(t);
        let f = unit(sub(q.look_at, q.eye));
        let up = q.up;
        assert!((dot(up, up) - 1.0).abs() < 1e-9);
        let right = cross(f, [0.0, 0.0, 1.0]);
        // up · right stays ~0: the horizon is level (up to the slerp's
        // difference from the spline's look direction, small).
        let roll = dot(up, unit(right)).abs();
        assert!(roll < 0.35, "t = {t}: roll {roll}");
        assert!(up[2] > 0.0, "t = {t}: up {up:?} flipped");
        t += 0.25;
    }
}

#[test]
fn two_identical_keyframes_are_a_still_camera() {
    let k = key(0.0, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0]);
    let mut k2 = k.clone();
    k2.frame = Some(10.0);
    let p = path(vec![k, k2]).unwrap().unwrap();
    let first = p.at(0.0);
    // The up vector as the renderer uses it: across the look direction.
    let level = |q: &PathPose| {
        let f = unit(sub(q.look_at, q.eye));
        unit(sub(q.up, f.map(|c| c * dot(q.up, f))))
    };
    for t in [0.5, 3.3, 9.9, 10.0, 12.0] {
        let q = p.at(t);
        for a in 0..3 {
            assert!((q.eye[a] - first.eye[a]).abs() < 1e-12);
            assert!((q.look_at[a] - first.look_at[a]).abs() < 1e-12);
            assert!((level(&q)[a] - level(&first)[a]).abs() < 1e-9);
        }
        assert!((q.fov - first.fov).abs() < 1e-9);
    }
}

#[test]
fn bad_paths_are_refused_by_name() {
    let k = |f| key(f, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
    let e = path(vec![k(0.0)]).unwrap_err().to_string();
    assert!(e.contains("at least two"), "{e}");
    let e = path(vec![k(5.0), k(2.0)]).unwrap_err().to_string();
    assert!(
        e.contains("keyframes[1].frame") && e.contains("increasing"),
        "{e}"
    );
    let e = path(vec![k(0.0), k(0.0)]).unwrap_err().to_string();
    assert!(e.contains("increasing"), "{e}");
    let mut no_eye = k(3.0);
    no_eye.eye = None;
    let e = path(vec![k(0.0), no_eye]).unwrap_err().to_string();
    assert!(e.contains("keyframes[1].eye"), "{e}");
    let mut along = k(3.0);
    along.up = Some([1.0, 0.0, 0.0]);
    let e = path(vec![k(0.0), along]).unwrap_err().to_string();
    assert!(e.contains("keyframes[1].up"), "{e}");
    let mut ortho = k(3.0);
    ortho.orthographic = Some(2.0);
    let e = path(vec![k(0.0), ortho]).unwrap_err().to_string();
    assert!(e.contains("orthographic"), "{e}");
    assert!(
        CameraPath::new(&CameraDesc::default()).unwrap().is_none(),
        "no keyframes, no path"
    );
}

#[test]
fn keyframes_by_time_count_in_the_path_rate() {
    let mut a = key(0.0, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
    let mut b = key(0.0, [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]);
    (a.frame, a.time) = (None, Some(0.0));
    (b.frame, b.time) = (None, Some(2.0));
    let camera = |keys: Vec<KeyframeDesc>, fps| CameraDesc {
        keyframes: Some(keys),
        fps,
        ..Default::default()
    };
    // 2 s at the default 24 fps is frame 48; at 30 fps, frame 60.
    let p = CameraPath::new(&camera(vec![a.clone(), b.clone()], None))
        .unwrap()
        .unwrap();
    assert_eq!(p.span(), (0.0, 48.0));
    assert_eq!(p.at(48.0).eye, [0.0, 1.0, 0.0]);
    let p = CameraPath::new(&camera(vec![a.clone(), b.clone()], Some(30.0)))
        .unwrap()
        .unwrap();
    assert_eq!(p.span(), (0.0, 60.0));
    let e = CameraPath::new(&camera(vec![a.clone(), b.clone()], Some(0.0))).unwrap_err();
    assert!(e.to_string().contains("camera.fps"), "{e}");
    // A keyframe with both, or neither, is refused by name.
    b.frame = Some(3.0);
    let e = CameraPath::new(&camera(vec![a, b], None))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("keyframes[1].frame") && e.contains("time"),
        "{e}"
    );
}

#[test]
fn orthographic_heights_interpolate() {
    let mut a = key(0.0, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
    let mut b = key(4.0, [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]);
    a.orthographic = Some(2.0);
    b.orthographic = Some(4.0);
    let p = path(vec![a, b]).unwrap().unwrap();
    assert!((p.at(2.0).orthographic.unwrap() - 3.0).abs() < 1e-12);
    let d = p.apply(&SceneDesc::default(), 1.0);
    assert_eq!(d.camera.projection, Some(ProjectionName::Orthographic));
    assert!((d.camera.ortho_height.unwrap() - 2.5).abs() < 1e-6);
}

#[test]
fn data_frames_follow_the_path_as_asked() {
    let n = [0, 10, 20, 30];
    let span = (0.0, 239.0);
    let hold = |t| data_frame(t, &n, Some(FollowName::Hold), span);
    assert_eq!(
        [hold(0.0), hold(9.0), hold(10.0), hold(25.0), hold(200.0)],
        [0, 0, 10, 20, 30]
    );
    let near = |t| data_frame(t, &n, Some(FollowName::Nearest), span);
    assert_eq!(
        [near(4.0), near(6.0), near(26.0), near(200.0)],
        [0, 10, 30, 30]
    );
    let stretch = |t| data_frame(t, &n, Some(FollowName::Stretch), span);
    assert_eq!(
        [stretch(0.0), stretch(40.0), stretch(120.0), stretch(239.0)],
        [0, 10, 20, 30]
    );
    // Before the first data frame, hold shows the first.
    assert_eq!(data_frame(0.0, &[3, 4], None, span), 3);
}
