//! [`forward_volume!`](crate::forward_volume): a [`Volume`](crate::Volume)
//! impl that hands every hook on to an inner volume but the ones it names.

/// Writes, inside an `impl Volume for …` block, every [`Volume`] hook as a
/// call of the same hook on an inner volume — all but the ones named after
/// `except` (written by hand in the same block) and `default` (left to the
/// trait's default, which then builds on this impl's own methods).
///
/// A prepared context (or any other wrapper) that forwards this way gets a
/// hook added to the trait later forwarded too, so it keeps the inner
/// volume's fast path instead of silently falling back to the trait's
/// default.
///
/// ```text
/// forward_volume! { to self.volume; except intervals, tile_view; default sample_in }
/// ```
///
/// * `to …` is how the inner volume is reached from `self`: a field path
///   (`self.volume`, `self.0`) or `*self` (for `&V`, whose inner volume is
///   one dereference away). It must begin with `self` (written by the
///   caller, so the generated methods may use it).
/// * `except a, b` are hooks this impl writes itself. Writing one without
///   naming it here does not compile (two definitions of the hook).
/// * `default a, b` are hooks this impl leaves to the trait's default: the
///   default then calls this impl's own methods (a context whose `sample`
///   differs from its volume's keeps the default `sample_in`, which calls
///   that `sample`, rather than the volume's).
/// * A name that is no hook of [`Volume`] does not compile. The clauses
///   come in this order, each at most once; both leave the hook out of
///   the forwarding (the two words tell the reader why).
///
/// A wrapper that changes the field rather than preparing it (mirror
/// instances reflect points and rays) must name every hook that takes a
/// point or a ray; one added to the trait later is forwarded to the
/// unchanged inner volume until it is named there, so adding a hook means
/// reading such wrappers too.
///
/// Forwarded hooks call the inner volume with method syntax, exactly as
/// hand-written forwarding would; `sample_values_lanes` is
/// `#[inline(always)]` (it is generic over the lane type and hot).
///
/// ```
/// use voxless_core::{Interval, IntervalQuery, Range1, Ray, Volume};
///
/// /// A volume prepared to hide what lies beyond `far`.
/// struct Near<'a, V> {
///     volume: &'a V,
///     far: f32,
/// }
///
/// impl<V: Volume> Volume for Near<'_, V> {
///     voxless_core::forward_volume! {
///         to self.volume;
///         except intervals;
///         // The inner volume's own would reach past `far`: the trait's
///         // defaults build these on `intervals` below.
///         default intervals_chunk, tile_view, project_image, line_integral;
///     }
///     fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
///         let t = Range1::new(t.lo, t.hi.min(self.far));
///         if !t.is_empty() {
///             self.volume.intervals(ray, t, query, out)
///         }
///     }
/// }
/// ```
///
/// A hook added to [`Volume`] must be added here too: to the list under
/// `@hooks` and to the `@same` rules. A test of the contract suite
/// (`testing::hooks`) compares the trait's hooks with this list.
///
/// [`Volume`]: crate::Volume
#[macro_export]
macro_rules! forward_volume {
    // `to *self …`: the inner volume is `*self` (for `&V`).
    (to * $this:ident
        $(; except $($own:ident),+ $(,)?)?
        $(; default $($kept:ident),+ $(,)?)? $(;)?) => {
        $crate::forward_volume!(@hooks [$this] [(*$this)] [$($($own)+)? $($($kept)+)?]);
    };
    // `to self.field …`.
    (to $this:ident $(. $field:tt)*
        $(; except $($own:ident),+ $(,)?)?
        $(; default $($kept:ident),+ $(,)?)? $(;)?) => {
        $crate::forward_volume!(
            @hooks [$this] [$this $(. $field)*] [$($($own)+)? $($($kept)+)?]
        );
    };

    // Every hook of the trait, each written unless it is skipped.
    (@hooks [$this:ident] [$($inner:tt)*] [$($skip:ident)*]) => {
        $($crate::forward_volume!(@known $skip);)*
        $crate::forward_volume!(@hook bounds [$($skip)*] {
            fn bounds(&$this) -> $crate::Aabb {
                $($inner)*.bounds()
            }
        });
        $crate::forward_volume!(@hook value_range [$($skip)*] {
            fn value_range(&$this) -> $crate::Range1 {
                $($inner)*.value_range()
            }
        });
        $crate::forward_volume!(@hook attribute_range [$($skip)*] {
            fn attribute_range(&$this) -> Option<$crate::Range1> {
                $($inner)*.attribute_range()
            }
        });
        $crate::forward_volume!(@hook sample [$($skip)*] {
            fn sample(&$this, p: $crate::Vec3) -> Option<$crate::Sample> {
                $($inner)*.sample(p)
            }
        });
        $crate::forward_volume!(@hook gradient [$($skip)*] {
            fn gradient(&$this, p: $crate::Vec3) -> $crate::Vec3 {
                $($inner)*.gradient(p)
            }
        });
        $crate::forward_volume!(@hook sample_with_gradient [$($skip)*] {
            fn sample_with_gradient(
                &$this,
                p: $crate::Vec3,
            ) -> Option<($crate::Sample, $crate::Vec3)> {
                $($inner)*.sample_with_gradient(p)
            }
        });
        $crate::forward_volume!(@hook sample_in [$($skip)*] {
            fn sample_in(
                &$this,
                p: $crate::Vec3,
                interval: &$crate::Interval,
            ) -> Option<$crate::Sample> {
                $($inner)*.sample_in(p, interval)
            }
        });
        $crate::forward_volume!(@hook sample_with_gradient_in [$($skip)*] {
            fn sample_with_gradient_in(
                &$this,
                p: $crate::Vec3,
                interval: &$crate::Interval,
            ) -> Option<($crate::Sample, $crate::Vec3)> {
                $($inner)*.sample_with_gradient_in(p, interval)
            }
        });
        $crate::forward_volume!(@hook classified [$($skip)*] {
            fn classified(&$this) -> bool {
                $($inner)*.classified()
            }
        });
        $crate::forward_volume!(@hook packet_sampling [$($skip)*] {
            fn packet_sampling(&$this) -> bool {
                $($inner)*.packet_sampling()
            }
        });
        $crate::forward_volume!(@hook sample_batch_values [$($skip)*] {
            fn sample_batch_values(
                &$this,
                batch: &$crate::SampleBatch,
                out: &mut Vec<f32>,
            ) -> bool {
                $($inner)*.sample_batch_values(batch, out)
            }
        });
        $crate::forward_volume!(@hook samples_in_lanes [$($skip)*] {
            fn samples_in_lanes(&$this) -> bool {
                $($inner)*.samples_in_lanes()
            }
        });
        $crate::forward_volume!(@hook sample_values_lanes [$($skip)*] {
            #[inline(always)]
            fn sample_values_lanes<L: $crate::Lanes>(
                &$this,
                hints: &[u32; $crate::simd::LANES],
                p: [L; 3],
                live: u32,
            ) -> L {
                $($inner)*.sample_values_lanes(hints, p, live)
            }
        });
        $crate::forward_volume!(@hook sample_batch [$($skip)*] {
            fn sample_batch(
                &$this,
                batch: &$crate::SampleBatch,
                gradient: bool,
                out: &mut Vec<(Option<$crate::Sample>, $crate::Vec3)>,
            ) {
                $($inner)*.sample_batch(batch, gradient, out)
            }
        });
        $crate::forward_volume!(@hook intervals [$($skip)*] {
            fn intervals(
                &$this,
                ray: &$crate::Ray,
                t: $crate::Range1,
                query: &$crate::IntervalQuery,
                out: &mut Vec<$crate::Interval>,
            ) {
                $($inner)*.intervals(ray, t, query, out)
            }
        });
        $crate::forward_volume!(@hook intervals_chunk [$($skip)*] {
            fn intervals_chunk(
                &$this,
                ray: &$crate::Ray,
                t: $crate::Range1,
                query: &$crate::IntervalQuery,
                out: &mut Vec<$crate::Interval>,
                max: usize,
            ) -> Option<f32> {
                $($inner)*.intervals_chunk(ray, t, query, out, max)
            }
        });
        $crate::forward_volume!(@hook tile_view [$($skip)*] {
            fn tile_view(
                &$this,
                view: &$crate::View,
            ) -> Option<Box<dyn $crate::TileIntervals + '_>> {
                $($inner)*.tile_view(view)
            }
        });
        $crate::forward_volume!(@hook project_image [$($skip)*] {
            fn project_image(
                &$this,
                camera: &$crate::Camera,
                width: u32,
                height: u32,
                control: &$crate::Control,
            ) -> Option<Result<Vec<f32>, $crate::Cancelled>> {
                $($inner)*.project_image(camera, width, height, control)
            }
        });
        $crate::forward_volume!(@hook line_integral [$($skip)*] {
            fn line_integral(&$this, ray: &$crate::Ray, t: $crate::Range1) -> f64 {
                $($inner)*.line_integral(ray, t)
            }
        });
    };

    // One hook: written unless its name is in the list.
    (@hook $hook:ident [] { $($item:tt)* }) => { $($item)* };
    (@hook $hook:ident [$first:ident $($rest:ident)*] $item:tt) => {
        $crate::forward_volume!(@same $hook $first [$($rest)*] $item);
    };
    // A listed name that is no hook falls through to the error below.
    (@known $name:ident) => {
        $crate::forward_volume!(@same $name $name [] {
            compile_error!(concat!(
                "forward_volume!: `", stringify!($name), "` is not a hook of Volume"
            ));
        });
    };
    // Whether two names are the same hook: one rule per hook (macros
    // cannot compare two names otherwise).
    (@same bounds bounds $($_:tt)*) => {};
    (@same value_range value_range $($_:tt)*) => {};
    (@same attribute_range attribute_range $($_:tt)*) => {};
    (@same sample sample $($_:tt)*) => {};
    (@same gradient gradient $($_:tt)*) => {};
    (@same sample_with_gradient sample_with_gradient $($_:tt)*) => {};
    (@same sample_in sample_in $($_:tt)*) => {};
    (@same sample_with_gradient_in sample_with_gradient_in $($_:tt)*) => {};
    (@same classified classified $($_:tt)*) => {};
    (@same packet_sampling packet_sampling $($_:tt)*) => {};
    (@same sample_batch_values sample_batch_values $($_:tt)*) => {};
    (@same samples_in_lanes samples_in_lanes $($_:tt)*) => {};
    (@same sample_values_lanes sample_values_lanes $($_:tt)*) => {};
    (@same sample_batch sample_batch $($_:tt)*) => {};
    (@same intervals intervals $($_:tt)*) => {};
    (@same intervals_chunk intervals_chunk $($_:tt)*) => {};
    (@same tile_view tile_view $($_:tt)*) => {};
    (@same project_image project_image $($_:tt)*) => {};
    (@same line_integral line_integral $($_:tt)*) => {};
    (@same $hook:ident $other:ident $rest:tt $item:tt) => {
        $crate::forward_volume!(@hook $hook $rest $item);
    };
}
