use super::*;
use crate::math::Aabb;
use crate::simd::{LANES, Lanes};
use crate::tiles::{IntervalLists, TileIntervals, TileRays};
use crate::volume::{Interval, Sample};

/// The names of the hooks `Volume` declares, from its source.
fn trait_hooks() -> Vec<String> {
    let src = include_str!("../volume.rs");
    let body = src
        .split_once("pub trait Volume: Send + Sync {")
        .expect("the trait Volume")
        .1;
    let body = &body[..body.find("\n}\n").expect("the end of the trait")];
    body.lines()
        .filter_map(|l| l.strip_prefix("    fn "))
        .map(|l| {
            let end = l.find(|c: char| !(c.is_alphanumeric() || c == '_'));
            l[..end.unwrap_or(l.len())].to_string()
        })
        .collect()
}

/// The names following `pattern` in forward_volume!'s source.
fn macro_names(pattern: &str) -> Vec<String> {
    let src = include_str!("../forward.rs");
    src.match_indices(pattern)
        .map(|(at, _)| {
            let rest = &src[at + pattern.len()..];
            rest[..rest.find(' ').unwrap()].to_string()
        })
        .filter(|name| !name.starts_with('$'))
        .collect()
}

fn sorted(mut v: Vec<String>) -> Vec<String> {
    v.sort();
    v
}

#[test]
fn every_hook_of_the_trait_is_forwarded_and_known_to_the_contract() {
    let hooks = trait_hooks();
    assert!(hooks.len() >= 19, "found only {hooks:?} in volume.rs");
    let known: Vec<String> = HOOKS.iter().map(|(n, _)| n.to_string()).collect();
    assert_eq!(
        known, hooks,
        "testing::HOOKS must list every hook of Volume, in the trait's order"
    );
    assert_eq!(
        macro_names("forward_volume!(@hook "),
        hooks,
        "forward_volume! must write every hook of Volume, in the trait's order"
    );
    assert_eq!(
        sorted(macro_names("(@same ")),
        sorted(hooks.clone()),
        "forward_volume! needs an `@same` rule for every hook"
    );
    // Every capability is compared, once.
    for hook in Hook::ALL {
        let n = HOOKS.iter().filter(|(_, h)| *h == Some(hook)).count();
        assert_eq!(n, 1, "{hook:?} is the check of {n} hooks");
    }
}

/// A volume whose every hook answers something no default does.
struct Probe;

/// A tile view of nothing.
struct Empty;

impl TileIntervals for Empty {
    fn tile_size(&self) -> u32 {
        8
    }
    fn intervals(&self, _: &TileRays, _: &IntervalQuery, _: &mut IntervalLists) {}
}

fn iv(t: Range1) -> Interval {
    Interval {
        hint: 12,
        ..Interval::sampled(t, Range1::new(0.0, 2.0), 0.1)
    }
}

impl Volume for Probe {
    fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::splat(1.0))
    }
    fn value_range(&self) -> Range1 {
        Range1::new(0.0, 2.0)
    }
    fn attribute_range(&self) -> Option<Range1> {
        Some(Range1::new(3.0, 4.0))
    }
    fn sample(&self, _: Vec3) -> Option<Sample> {
        Some(Sample::scalar(1.0))
    }
    fn gradient(&self, _: Vec3) -> Vec3 {
        Vec3::new(1.0, 2.0, 3.0)
    }
    fn sample_with_gradient(&self, _: Vec3) -> Option<(Sample, Vec3)> {
        Some((Sample::scalar(5.0), Vec3::splat(5.0)))
    }
    fn sample_in(&self, _: Vec3, _: &Interval) -> Option<Sample> {
        Some(Sample::scalar(7.0))
    }
    fn sample_with_gradient_in(&self, _: Vec3, _: &Interval) -> Option<(Sample, Vec3)> {
        Some((Sample::scalar(8.0), Vec3::splat(8.0)))
    }
    fn classified(&self) -> bool {
        true
    }
    fn packet_sampling(&self) -> bool {
        true
    }
    fn sample_batch_values(&self, batch: &SampleBatch, out: &mut Vec<f32>) -> bool {
        out.clear();
        out.resize(batch.t.len(), 9.0);
        true
    }
    fn samples_in_lanes(&self) -> bool {
        true
    }
    fn sample_values_lanes<L: Lanes>(&self, _: &[u32; LANES], _: [L; 3], _: u32) -> L {
        L::splat(10.0)
    }
    fn sample_batch(&self, batch: &SampleBatch, _: bool, out: &mut Vec<(Option<Sample>, Vec3)>) {
        out.clear();
        out.resize(batch.t.len(), (Some(Sample::scalar(11.0)), Vec3::ZERO));
    }
    fn intervals(&self, _: &Ray, t: Range1, _: &IntervalQuery, out: &mut Vec<Interval>) {
        out.push(iv(t));
    }
    fn intervals_chunk(
        &self,
        ray: &Ray,
        t: Range1,
        query: &IntervalQuery,
        out: &mut Vec<Interval>,
        _: usize,
    ) -> Option<f32> {
        self.intervals(ray, t, query, out);
        Some(t.hi)
    }
    fn tile_view(&self, _: &View) -> Option<Box<dyn TileIntervals + '_>> {
        Some(Box::new(Empty))
    }
    fn project_image(
        &self,
        _: &Camera,
        width: u32,
        height: u32,
        _: &Control,
    ) -> Option<Result<Vec<f32>, crate::Cancelled>> {
        Some(Ok(vec![13.0; (width * height) as usize]))
    }
    fn line_integral(&self, _: &Ray, _: Range1) -> f64 {
        14.0
    }
}

/// Forwards every hook.
struct Forwarding<V>(V);

impl<V: Volume> Volume for Forwarding<V> {
    crate::forward_volume!(to self.0);
}

/// What a volume answers to the queries `answer` does not ask.
fn queries<V: Volume>(v: &V) -> String {
    let p = Vec3::splat(0.5);
    let ray = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0));
    let t = Range1::new(1.0, 2.0);
    let mut ivs = Vec::new();
    v.intervals(&ray, t, &IntervalQuery::all(), &mut ivs);
    let batch = SampleBatch {
        rays: &[ray],
        offsets: &[0, 2],
        t: &[1.25, 1.5],
        hints: None,
    };
    let mut out = Vec::new();
    v.sample_batch(&batch, true, &mut out);
    let lanes = crate::simd::dispatch(crate::Simd::Portable, Lanes8(v));
    format!(
        "{:?} {:?} {:?} {:?} {:?} {ivs:?} {out:?} {lanes:?} {}",
        v.sample(p),
        v.gradient(p),
        v.sample_with_gradient(p),
        v.sample_in(p, &iv(t)),
        v.sample_with_gradient_in(p, &iv(t)),
        v.line_integral(&ray, t),
    )
}

struct Lanes8<'a, V>(&'a V);

impl<V: Volume> crate::simd::WithLanes for Lanes8<'_, V> {
    type Output = [f32; LANES];
    fn run<L: Lanes>(self) -> [f32; LANES] {
        let p = [L::splat(0.5); 3];
        self.0
            .sample_values_lanes::<L>(&[12; LANES], p, 0xff)
            .to_array()
    }
}

#[test]
fn forwarding_offers_every_hook_of_the_inner_volume() {
    assert_eq!(check_same_hooks(&Probe, &Forwarding(Probe), &[]), [""; 0]);
    assert_eq!(queries(&Forwarding(Probe)), queries(&Probe));
    // A borrowed volume forwards everything too.
    assert_eq!(check_same_hooks(&Probe, &&Probe, &[]), [""; 0]);
    assert_eq!(queries(&&Probe), queries(&Probe));
    // Nothing of the probe is the default.
    struct Bare;
    impl Volume for Bare {
        fn bounds(&self) -> Aabb {
            Probe.bounds()
        }
        fn value_range(&self) -> Range1 {
            Probe.value_range()
        }
        fn sample(&self, p: Vec3) -> Option<Sample> {
            Probe.sample(p)
        }
        fn intervals(&self, ray: &Ray, t: Range1, q: &IntervalQuery, out: &mut Vec<Interval>) {
            Probe.intervals(ray, t, q, out)
        }
    }
    let differ: Vec<Hook> = Hook::ALL[2..].to_vec();
    assert_eq!(check_same_hooks(&Probe, &Bare, &differ), [""; 0]);
}

/// Samples of its own; the rest forwarded, or the trait's default.
struct Own<'a>(&'a Probe);

impl Volume for Own<'_> {
    crate::forward_volume! {
        to self.0;
        except sample, packet_sampling;
        default sample_in, tile_view,
    }
    fn sample(&self, _: Vec3) -> Option<Sample> {
        Some(Sample::scalar(-1.0))
    }
    fn packet_sampling(&self) -> bool {
        false
    }
}

#[test]
fn a_context_overrides_or_keeps_defaults_by_name() {
    let (own, p) = (Own(&Probe), Vec3::splat(0.5));
    assert_eq!(own.sample(p), Some(Sample::scalar(-1.0)));
    // The default `sample_in` samples the context's own `sample`.
    let t = Range1::new(0.0, 1.0);
    assert_eq!(own.sample_in(p, &iv(t)), Some(Sample::scalar(-1.0)));
    assert_eq!(own.gradient(p), Probe.gradient(p));
    let differ = [Hook::PacketSampling, Hook::TileView];
    assert_eq!(check_same_hooks(&Probe, &own, &differ), [""; 0]);
    // Undeclared differences are reported, and so are declared ones that
    // are not there.
    let bad = check_same_hooks(&Probe, &own, &[Hook::Classified]);
    assert_eq!(bad.len(), 3, "{bad:?}");
    assert!(
        bad[0].starts_with("Classified: listed as differing"),
        "{bad:?}"
    );
    assert!(bad[1].starts_with("PacketSampling: the context answers false, its volume true"));
}
