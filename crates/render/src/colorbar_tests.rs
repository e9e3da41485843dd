use super::*;
use voxless_transfer::{Colormap, OpacityMap};

fn tf() -> TransferFunction {
    TransferFunction::new(
        Colormap::preset("viridis").unwrap(),
        OpacityMap::preset("linear").unwrap(),
    )
}

fn spec(label: Option<&str>) -> ColorbarSpec {
    ColorbarSpec {
        lo: 0.0,
        hi: 2.5e-4,
        log10: false,
        label: label.map(str::to_string),
    }
}

/// A uniform image whose pixels the bar must leave alone where it is not.
fn grey(w: u32, h: u32, v: f32) -> Image {
    let mut im = Image::new(w, h);
    im.pixels.fill([v, v, v, 1.0]);
    im
}

#[test]
fn bar_ends_are_the_transfer_function_at_one_and_zero() {
    let tf = tf();
    let mut im = grey(640, 360, 0.2);
    let l = draw_colorbar(&mut im, &tf, &spec(Some("density"))).unwrap();
    let px = |x: u32, y: u32| im.pixels[(y * im.width + x) as usize];
    let c1 = tf.color(1.0);
    let c0 = tf.color(0.0);
    for x in l.bar.x0..l.bar.x1 {
        assert_eq!(px(x, l.bar.y0), [c1.x, c1.y, c1.z, 1.0]);
        assert_eq!(px(x, l.bar.y1 - 1), [c0.x, c0.y, c0.z, 1.0]);
    }
    // Colours change monotonically in between (viridis gets brighter upwards).
    let mid = px(l.bar.x0, (l.bar.y0 + l.bar.y1) / 2);
    assert!(mid[1] > c0.y && mid[1] < c1.y);
    // Inset from the right edge by a few percent, about 70 % tall.
    assert!(l.bar.x1 < 640 - 5 && l.bar.x1 > 640 - 30, "{l:?}");
    assert!((l.bar.y1 - l.bar.y0) as f32 > 0.5 * 360.0, "{l:?}");
    assert_eq!(l.scale, 2);
}

#[test]
fn labels_draw_ink_and_outline_only_inside_the_strip() {
    let tf = tf();
    for bg in [0.0, 0.5, 1.0] {
        let before = grey(640, 360, bg);
        let mut im = before.clone();
        let l = draw_colorbar(&mut im, &tf, &spec(Some("temperature"))).unwrap();
        let (mut white, mut black, mut title) = (0, 0, 0);
        for y in 0..360u32 {
            for x in 0..640u32 {
                let i = (y * 640 + x) as usize;
                if im.pixels[i] == before.pixels[i] {
                    continue;
                }
                let s = l.strip;
                assert!(
                    x >= s.x0 && x < s.x1 && y >= s.y0 && y < s.y1,
                    "pixel ({x}, {y}) drawn outside {s:?}"
                );
                // Left of the bar: text and tick marks.
                if x < l.bar.x0 - 1 {
                    match im.pixels[i] {
                        [1.0, 1.0, 1.0, 1.0] => white += 1,
                        [0.0, 0.0, 0.0, 1.0] => black += 1,
                        p => panic!("unexpected label colour {p:?}"),
                    }
                }
                if y + 1 < l.bar.y0 {
                    title += 1;
                }
            }
        }
        // White text with a dark outline reads on any background: the ink
        // stands out on dark ones, the outline on light ones.
        assert!(bg == 1.0 || white > 100, "bg {bg}: {white} white");
        assert!(bg == 0.0 || black > 100, "bg {bg}: {black} black");
        assert!(title > 50, "the title is drawn above the bar");
        assert!(l.strip.x0 > 640 / 2, "{l:?}");
    }
}

#[test]
fn title_says_log10_and_ticks_are_compact() {
    let mut s = spec(Some("density"));
    assert_eq!(s.title().as_deref(), Some("density"));
    s.log10 = true;
    assert_eq!(s.title().as_deref(), Some("log10 density"));
    s.label = None;
    assert_eq!(s.title().as_deref(), Some("log10"));
    let cases = [
        (0.0, "0"),
        (-0.0, "0"),
        (0.5, "0.5"),
        (1.0, "1"),
        (-1.5, "-1.5"),
        (123.456, "123.5"),
        (0.00125, "0.00125"),
        (2.5e-4, "2.5e-4"),
        (1.25e-7, "1.25e-7"),
        (12345.0, "12345"),
        (3.0e6, "3e6"),
        (-4.2e9, "-4.2e9"),
        (f32::NAN, "nan"),
    ];
    for (v, want) in cases {
        assert_eq!(format_tick(v), want, "{v}");
    }
}

#[test]
fn tiny_and_odd_images_do_not_panic_and_keep_their_size() {
    let tf = tf();
    for (w, h) in [
        (1, 1),
        (2, 2),
        (3, 3),
        (16, 16),
        (16, 400),
        (400, 16),
        (5, 300),
        (300, 5),
        (40, 30),
        (64, 36),
    ] {
        let mut im = grey(w, h, 0.5);
        let mut long = spec(Some("a very long field name that cannot fit anywhere"));
        long.lo = -1.234_567e-30;
        long.hi = 9.876_543e30;
        let l = draw_colorbar(&mut im, &tf, &long);
        assert_eq!(im.pixels.len(), (w * h) as usize);
        if let Some(l) = l {
            let s = l.strip;
            assert!(s.x0 <= s.x1 && s.x1 <= w && s.y1 <= h, "{w}×{h}: {l:?}");
            assert!(l.bar.x0 < l.bar.x1 && l.bar.y0 < l.bar.y1, "{w}×{h}: {l:?}");
        }
        if (w, h) == (16, 16) {
            assert!(l.is_some(), "a 16×16 image still gets a bar");
        }
    }
}
