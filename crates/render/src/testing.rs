//! Checks integrators owe every volume (feature `testing`): the image and
//! the projection do not depend on how many threads render them.

use rayon::ThreadPoolBuilder;
use voxless_core::{Camera, Control, Prepare};
use voxless_transfer::TransferFunction;

use crate::{RenderSettings, project, render};

/// Renders and projects `volume` on 1 and on 2 threads and panics unless
/// both agree bit for bit.
pub fn assert_thread_independent<P: Prepare>(
    name: &str,
    volume: &P,
    camera: &Camera,
    tf: &TransferFunction,
    settings: &RenderSettings,
) {
    let run = |threads: usize| {
        let pool = ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        pool.install(|| {
            let image =
                render(volume, camera, tf, settings, &Control::new()).expect("not cancelled");
            let prepared = crate::prepare(volume, tf, settings);
            let column = project(
                &prepared,
                camera,
                settings.width,
                settings.height,
                &Control::new(),
            )
            .expect("not cancelled");
            (image.pixels, column)
        })
    };
    let (a, b) = (run(1), run(2));
    assert!(
        a.0 == b.0,
        "{name}: the render differs between 1 and 2 threads"
    );
    assert!(
        a.1.iter()
            .map(|v| v.to_bits())
            .eq(b.1.iter().map(|v| v.to_bits())),
        "{name}: the projection differs between 1 and 2 threads"
    );
}
