//! Single scattering on the packet path: the free flights of a packet's
//! camera rays march together ([`run_passes`]: one [`Volume::sample_batch`]
//! per pass for every ray still flying), then the shadow rays from their
//! scattering events do the same.
//!
//! Each flight places its samples with the same cursor and the same random
//! numbers as the per-ray path ([`crate::scatter::path`]) and sums the
//! same `σ·len`, so the two draw the same image up to the order of the
//! sums inside the volume's batch (the tests compare them). Delta tracking
//! stays on the per-ray path: its tentative collisions are one sample at a
//! time, drawn from the previous one.

use voxless_core::{Interval, Ray, Sample, Vec3, Volume};

use crate::Tile;
use crate::ctx::Ctx;
use crate::cursor::{Cursor, RayIntervals, Segment};
use crate::packet::{Integrator, Lane, PassScratch, TileInput, packets, run_passes};
use crate::scatter::{Flight, Noises, Scatter, Shadow, scattered, shadow_cursor, shadow_ray};

/// One free flight of a packet.
struct FlightRay {
    lane: Lane,
    flight: Flight,
    /// Where the event happened and its sample.
    event: Option<(f32, Sample)>,
}

impl Integrator for FlightRay {
    fn lane(&mut self) -> &mut Lane {
        &mut self.lane
    }
    /// A free flight sums `σ·len` and an event's colour is its sample's:
    /// no gradient (the per-ray flights ask for none either).
    fn needs_gradient(_: &Ctx) -> bool {
        false
    }
    #[inline]
    fn feed<V: Volume>(
        &mut self,
        _: &V,
        _: &Ray,
        _: &Interval,
        seg: Segment,
        sample: Option<Sample>,
        _: Vec3,
        ctx: &Ctx,
    ) -> bool {
        let Some(s) = sample else {
            return false;
        };
        match self.flight.feed(ctx, &seg, &s) {
            Some(t) => {
                self.event = Some((t, s));
                true
            }
            None => false,
        }
    }
    fn finish<V: Volume>(&mut self, _: &V, _: &Ray, _: &Ctx) {}
}

/// Scratch reused across the packets of a tile.
#[derive(Default)]
pub(crate) struct ScatterScratch {
    flights: Vec<FlightRay>,
    noises: Vec<Noises>,
    /// Per shadow ray: its camera ray's flight and the event's sample.
    owners: Vec<(usize, Sample)>,
    shadow_rays: Vec<Ray>,
    /// Per shadow ray: its index, cursor and free-flight number.
    shadows: Vec<(usize, Cursor, f32)>,
    shadow_ivs: Vec<RayIntervals>,
    pass: PassScratch,
}

/// Renders sample `sample` of `tile` by single scattering with packets;
/// pixels row-major into `out`. `ivs` holds each camera ray's intervals
/// (started, or complete from a tile view).
#[allow(clippy::too_many_arguments)]
pub(crate) fn render_tile<V: Volume>(
    volume: &V,
    ctx: &Ctx,
    sc: &Scatter,
    tile: Tile,
    sample: u32,
    input: TileInput,
    ivs: &mut [RayIntervals],
    s: &mut ScatterScratch,
    out: &mut Vec<[f32; 4]>,
) {
    out.clear();
    out.resize((tile.w * tile.h) as usize, [0.0; 4]);
    for (px, py, pw, ph) in packets(tile) {
        // 1. The camera rays' free flights.
        s.flights.clear();
        s.noises.clear();
        for y in py..py + ph {
            for x in px..px + pw {
                let r = (y * tile.w + x) as usize;
                let spans = &input.spans[r];
                let n = Noises::new(ctx.settings, sc, (tile.x + x, tile.y + y), sample);
                s.flights.push(FlightRay {
                    lane: Lane::start(
                        r,
                        spans.cursor(&n.rng),
                        spans.is_empty(),
                        (volume, &input.rays[r], &mut ivs[r]),
                        input.query,
                        ctx,
                    ),
                    flight: Flight::new(n.primary),
                    event: None,
                });
                s.noises.push(n);
            }
        }
        run_passes(
            volume,
            ctx,
            (input.rays, ivs),
            input.query,
            &mut s.flights,
            &mut s.pass,
        );
        // 2. A shadow ray from each event the light may reach; the
        // flights are reused for them (lane `r` indexes the shadow rays).
        s.owners.clear();
        s.shadow_rays.clear();
        s.shadows.clear();
        for (i, f) in s.flights.iter().enumerate() {
            let Some((t, sample)) = f.event else {
                continue;
            };
            let r = f.lane.r;
            match shadow_ray(volume, input.rays[r].at(t), ctx, sc).1 {
                Shadow::Known(lit) => out[r] = scattered(ctx, sc, &sample, lit),
                Shadow::Trace(ray, span) => {
                    let k = s.shadow_rays.len();
                    if s.shadow_ivs.len() <= k {
                        s.shadow_ivs.push(RayIntervals::default());
                    }
                    s.shadow_ivs[k].start(span);
                    s.shadow_rays.push(ray);
                    s.owners.push((r, sample));
                    s.shadows
                        .push((k, shadow_cursor(span, &s.noises[i]), s.noises[i].shadow));
                }
            }
        }
        if s.shadow_rays.is_empty() {
            continue;
        }
        s.flights.clear();
        for &(k, cursor, xi) in &s.shadows {
            s.flights.push(FlightRay {
                lane: Lane::start(
                    k,
                    cursor,
                    false,
                    (volume, &s.shadow_rays[k], &mut s.shadow_ivs[k]),
                    input.query,
                    ctx,
                ),
                flight: Flight::new(xi),
                event: None,
            });
        }
        let n = s.shadow_rays.len();
        run_passes(
            volume,
            ctx,
            (&s.shadow_rays, &mut s.shadow_ivs[..n]),
            input.query,
            &mut s.flights,
            &mut s.pass,
        );
        // 3. Lit where the shadow ray got through.
        for f in &s.flights {
            let (r, sample) = &s.owners[f.lane.r];
            let lit = if f.event.is_some() { 0.0 } else { 1.0 };
            out[*r] = scattered(ctx, sc, sample, lit);
        }
    }
}
