//! Every refusal a front-end makes, in one place: settings out of range,
//! settings that would do nothing, work no machine finishes, what one box
//! of a decomposed render cannot compute, and images that would show
//! nothing. The CLI, the viewer, the Python package and MPI all call these,
//! so they refuse the same things with the same words — an error names the
//! setting (as in the scene file, with its CLI flag) and says what to do.

use voxless_core::{Image, Range1};
use voxless_render::{RayStats, RenderSettings, WorkEstimate};
use voxless_scene::{PixelsName, SceneDesc, TetModeName, TetsDesc};

use crate::{ProjectionDesc, SceneError, VolumeKind, VolumeSummary, WorldFrame};

/// A setting that must be finite and > 0.
pub(crate) fn positive(field: &str, v: f32) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SceneError::setting(
            field,
            format!("{v} must be finite and > 0"),
        ))
    }
}

/// A setting that must be a finite range with `lo ≤ hi`.
pub(crate) fn range(field: &str, lo: f32, hi: f32) -> Result<Range1, SceneError> {
    if lo.is_finite() && hi.is_finite() && lo <= hi {
        Ok(Range1::new(lo, hi))
    } else {
        Err(SceneError::setting(
            field,
            format!("[{lo}, {hi}] is not a finite, increasing range"),
        ))
    }
}

/// Mean samples per camera ray beyond which a render is refused: real data
/// needs thousands (10⁹ particles: ~8,000 at the default radius); a
/// quarter of a million means a radius or step far below the data's scale,
/// and minutes for even a thumbnail.
pub(crate) const MAX_SAMPLES_PER_RAY: f64 = (1u64 << 18) as f64;

/// Samples in all beyond which a render is refused (about a day at 10⁸
/// samples per second).
pub(crate) const MAX_SAMPLES: f64 = 1e13;

/// An error when the field is 0 everywhere (a volume held whole or the
/// whole data of a decomposed one): there would be nothing to render.
pub(crate) fn check_field(data: &VolumeSummary) -> Result<(), SceneError> {
    let range = data.value_range;
    if data.kind == VolumeKind::Materials || range.hi > 0.0 || range.lo < 0.0 {
        return Ok(());
    }
    let (field, why) = match data.kind {
        VolumeKind::Particles => (
            "particles.weights (--weights)",
            "every particle's weight is 0 (or a weight or radius map hides it)",
        ),
        VolumeKind::Amr => ("amr.field (--field)", "every cell's value is 0"),
        _ => ("data", "it holds no mass"),
    };
    Err(SceneError::setting(
        field,
        format!("the field is 0 everywhere, so there is nothing to render: {why}"),
    ))
}

/// A render of `data` (in `frame`) whose estimated `work` (see
/// [`crate::AnyVolume::estimate_work`]; over ranks, the sum of theirs) is
/// absurd is an error with the estimate and the flags that change it,
/// before any work starts; so is a field 0 everywhere ([`check_field`]).
/// Otherwise returns a note when the step was raised to what f32 can
/// resolve along the rays.
pub(crate) fn check_work(
    data: &VolumeSummary,
    frame: &WorldFrame,
    desc: &SceneDesc,
    work: &WorkEstimate,
) -> Result<Option<String>, SceneError> {
    check_field(data)?;
    let extent = frame.length_to_world(data.bounds.diagonal());
    if work.per_ray <= MAX_SAMPLES_PER_RAY && work.total <= MAX_SAMPLES {
        return Ok(work.step_raised.then(|| {
            format!(
                "the ray-marching step is finer than float32 can resolve along the rays \
                 (data extent {extent:.3e}); it was raised to {} units in the last place of \
                 the distance along each ray",
                voxless_render::MIN_STEP_ULPS
            )
        }));
    }
    let given_radius = desc
        .particles
        .as_ref()
        .is_some_and(|p| p.radius.is_some() || p.radii.is_some());
    let (field, fix) = if let Some(step) = desc.render.step {
        (
            "render.step (--step)",
            format!(
                "the step {step} is tiny against the data (extent {extent:.3e}): give a \
                 larger --step"
            ),
        )
    } else if given_radius && work.per_ray > MAX_SAMPLES_PER_RAY {
        (
            "particles.radius (--radius)",
            format!(
                "the particles' supports are tiny against the data (extent {extent:.3e}), and \
                 rays step 1/8 of a support: give a larger --radius (or omit it for one from \
                 the particle spacing), or a --step"
            ),
        )
    } else if work.per_ray > MAX_SAMPLES_PER_RAY {
        (
            "render.step (--step)",
            format!(
                "the data's own step is tiny against its extent ({extent:.3e}) — outliers far \
                 from the rest, or a sampling rate too high: give a --step (e.g. {:.3e}), a \
                 smaller --sampling-rate, or leave out the outliers",
                extent / 2000.0
            ),
        )
    } else {
        (
            "image (--size, --spp)",
            "give a smaller --size or fewer --spp".to_string(),
        )
    };
    Err(SceneError::setting(
        field,
        format!(
            "this render would take about {:.1e} samples per ray, {:.1e} in all (limits \
             {MAX_SAMPLES_PER_RAY:.1e} per ray, {MAX_SAMPLES:.0e} in all): {fix}",
            work.per_ray, work.total
        ),
    ))
}

/// Settings that only act together with another one, given without it,
/// are errors naming both: they would silently do nothing.
pub(crate) fn refuse_settings_without_effect(desc: &SceneDesc) -> Result<(), SceneError> {
    let r = &desc.render;
    let no_iso = r.iso.as_ref().is_none_or(|v| v.is_empty());
    if no_iso && r.iso_opacity.is_some() {
        return Err(SceneError::setting(
            "render.iso_opacity (--iso-opacity)",
            "applies to iso-surfaces: add --iso V",
        ));
    }
    if no_iso && r.volume == Some(false) {
        return Err(SceneError::setting(
            "render.volume (--iso-only)",
            "with the volume off and no iso-surface the image would be empty: add --iso V",
        ));
    }
    if let Some(l) = &desc.light
        && !l.shadows.unwrap_or(false)
    {
        let only_with_shadows = [
            ("light.position (--light-pos)", l.position.is_some()),
            ("light.intensity (--light-intensity)", l.intensity.is_some()),
            ("light.free_flight (--free-flight)", l.free_flight.is_some()),
            ("light.noise (--noise)", l.noise.is_some()),
        ];
        if let Some((field, _)) = only_with_shadows.iter().find(|f| f.1) {
            return Err(SceneError::setting(
                field,
                "applies to single scattering: add --shadows (scene: light.shadows = true)",
            ));
        }
    }
    if let Some(p) = &desc.particles
        && p.kernel != Some(voxless_scene::KernelName::Gaussian)
    {
        for (field, given) in [
            ("particles.kappa (--kappa)", p.kappa.is_some()),
            ("particles.sigma (--sigma)", p.sigma.is_some()),
        ] {
            if given {
                return Err(SceneError::setting(
                    field,
                    "applies to the gaussian kernel only: add --kernel gaussian",
                ));
            }
        }
    }
    Ok(())
}

/// Settings the volume's kind cannot honour are errors naming them.
pub(crate) fn refuse_what_the_kind_cannot_honour(
    kind: VolumeKind,
    settings: &RenderSettings,
) -> Result<(), SceneError> {
    if kind == VolumeKind::Tets
        && settings.light.is_some()
        && settings.scatter.is_none()
        && settings.volume
        && settings.iso.is_empty()
    {
        return Err(SceneError::setting(
            "light (--shade)",
            "a phase-space tessellation's density is constant inside every tet, so the volume \
             has no gradient to shade with; use --shadows for lighting, or --iso V for shaded \
             iso-surfaces",
        ));
    }
    Ok(())
}

/// An error saying why, when `image` shows nothing at all: never a silent
/// black image. The reason is what the rays saw (`seen`, from the film or
/// merged over ranks): no data at all (the camera looks past the data's
/// world `bounds`, or the field is far thinner than a pixel), or only
/// values the transfer function makes transparent.
pub(crate) fn check_visible(
    st: &RenderSettings,
    (lo, hi): ([f64; 3], [f64; 3]),
    seen: &RayStats,
    image: &Image,
) -> Result<(), SceneError> {
    let alpha = image.pixels.iter().fold(0f32, |m, p| m.max(p[3]));
    if alpha >= 0.5 / 255.0 {
        return Ok(());
    }
    let seen = seen.values;
    let point = |p: [f64; 3]| format!("[{:.4e}, {:.4e}, {:.4e}]", p[0], p[1], p[2]);
    let (lo, hi) = (point(lo), point(hi));
    let zero = !(seen.hi > 0.0 || seen.lo < 0.0 || st.log_scale);
    let why = if seen.is_empty() || zero {
        format!(
            "no ray meets any of the field: the camera does not see the data's bounds \
             {lo}..{hi}, or the field there is zero or far thinner than a pixel \
             (check --eye/--look-at, --clip, the radius, or outliers far from the rest)"
        )
    } else {
        let unit = if st.log_scale { "log10 of " } else { "" };
        let shown = |v: f32| {
            if st.log_scale {
                v.max(f32::MIN_POSITIVE).log10()
            } else {
                v
            }
        };
        format!(
            "{unit}the field along the rays lies in [{:.4e}, {:.4e}], which the transfer \
             function (value range [{:.4e}, {:.4e}]) leaves transparent; give a \
             --value-range covering it, another --opacity, or a larger --opacity-scale",
            shown(seen.lo),
            shown(seen.hi),
            st.value_range.lo,
            st.value_range.hi
        )
    };
    Err(SceneError::setting(
        "image",
        format!("the image would be empty: {why}"),
    ))
}

/// An error naming the iso-values when iso-surfaces were asked for but none
/// appears anywhere in the image (`seen`: what its rays saw) — with the range of values the rays did see,
/// in the transfer function's units — so an empty surface is never a silent
/// image.
pub(crate) fn check_iso(settings: &RenderSettings, seen: &RayStats) -> Result<(), SceneError> {
    let st = settings;
    if st.iso.is_empty() || seen.iso_hits > 0 {
        return Ok(());
    }
    let unit = |v: f32| {
        if st.log_scale {
            v.max(f32::MIN_POSITIVE).log10()
        } else {
            v
        }
    };
    let asked: Vec<String> = st.iso.iter().map(|&v| format!("{}", unit(v))).collect();
    let scale = if st.log_scale {
        "log10 of the field"
    } else {
        "the field"
    };
    let seen = seen.values;
    let what = if seen.is_empty() {
        "the rays meet no data".to_string()
    } else {
        format!(
            "{scale} along the rays lies in [{:.4}, {:.4}]",
            unit(seen.lo),
            unit(seen.hi)
        )
    };
    Err(SceneError::setting(
        "render.iso (--iso)",
        format!(
            "no iso-surface at {} appears in the image: {what}; the transfer function's \
             value range is [{:.4}, {:.4}] in the same units",
            asked.join(", "),
            st.value_range.lo,
            st.value_range.hi
        ),
    ))
}

/// Settings whose result one box of a render (or with `projecting`, a
/// projection) decomposed over `ranks` cannot compute alone (`tets`: the
/// tessellation the scene renders, also when it comes from a JaxPM file
/// given as particles).
pub(crate) fn check_ranks(
    desc: &SceneDesc,
    tets: Option<&TetsDesc>,
    ranks: usize,
    projecting: bool,
) -> Result<(), SceneError> {
    if ranks <= 1 {
        return Ok(());
    }
    let why = "under MPI each rank renders only its own box";
    if desc.render.iso.as_ref().is_some_and(|v| !v.is_empty()) {
        return Err(SceneError::setting(
            "render.iso (--iso)",
            format!(
                "iso-surfaces are not rendered on more than one rank yet: {why}, and a crossing \
                 between two samples in different boxes is seen by neither; render them with one \
                 rank"
            ),
        ));
    }
    if desc.light.as_ref().is_some_and(|l| l.shadows == Some(true)) {
        return Err(SceneError::setting(
            "light.shadows (--shadows)",
            format!(
                "single scattering is not rendered on more than one rank: {why}, and shadow rays \
                 cross boxes"
            ),
        ));
    }
    if !desc.meshes.is_empty() || !desc.instances.is_empty() || desc.render.ao.is_some() {
        return Err(SceneError::setting(
            if !desc.meshes.is_empty() {
                "meshes (--mesh)"
            } else if !desc.instances.is_empty() {
                "instances (--mirror)"
            } else {
                "render.ao (--ao)"
            },
            format!(
                "surfaces and mirror instances are not rendered on more than one rank yet: \
                 {why}; render them with one rank"
            ),
        ));
    }
    let (area, key) = match tets {
        Some(t) if t.pixels == Some(PixelsName::Area) => (true, "tets.pixels"),
        _ => area_pixels(desc),
    };
    if area && projecting {
        return Err(SceneError::setting(
            "pixels",
            format!(
                "the pixel-area projection (--pixels area, {key}) of this data runs in one \
                 process (particles with radii, streamed from their files, take it under mpirun \
                 too); under mpirun each rank projects its box through pixel centres (leave it \
                 out, or run voxless project without mpirun)"
            ),
        ));
    }
    let Some(t) = tets else {
        return Ok(());
    };
    if t.lod_pixels.is_some() {
        return Err(SceneError::setting(
            "tets.lod_pixels (--lod)",
            format!("the level of detail is not used on more than one rank: {why}"),
        ));
    }
    if t.mode == Some(TetModeName::Kbuffer) {
        return Err(SceneError::setting(
            "tets.mode (--tet-mode kbuffer)",
            format!(
                "the k-buffer keeps the first k events of each box's part of a ray, not of \
                 the ray ({why}); use the exact mode"
            ),
        ));
    }
    Ok(())
}

/// The pixel integral `pixels` (the `project` command's `--pixels`, Python's
/// `pixels=`) written into `desc` for `projection`, refused where it cannot
/// act: on data other than particles or a tessellation (projected through
/// pixel centres), and the exact pixel area together with a slab (`depth`),
/// which integrates through pixel centres.
pub fn set_projection_pixels(
    desc: &mut SceneDesc,
    pixels: Option<PixelsName>,
    projection: &ProjectionDesc,
) -> Result<(), SceneError> {
    if let Some(p) = pixels {
        if let Some(t) = desc.tets.as_mut() {
            t.pixels = Some(p);
        } else if let Some(q) = desc.particles.as_mut() {
            q.pixels = Some(p);
        } else {
            return Err(SceneError::setting(
                "pixels",
                "--pixels applies to particles and phase-space tessellations (--particles, \
                 --lagrangian, --box, or their scenes); other data is projected through pixel \
                 centres",
            ));
        }
    }
    let (area, key) = area_pixels(desc);
    if area && projection.depth.is_some() {
        return Err(SceneError::setting(
            "pixels",
            format!(
                "area integrates whole lines of sight; with --depth a projection integrates \
                 the slab through pixel centres (leave out --pixels area, or {key} in the scene)"
            ),
        ));
    }
    Ok(())
}

/// Whether the scene asks projections for pixel areas, and the scene key
/// that says so.
fn area_pixels(desc: &SceneDesc) -> (bool, &'static str) {
    let area = |p: Option<PixelsName>| p == Some(PixelsName::Area);
    if desc.tets.as_ref().is_some_and(|t| area(t.pixels)) {
        (true, "tets.pixels")
    } else if desc.particles.as_ref().is_some_and(|p| area(p.pixels)) {
        (true, "particles.pixels")
    } else {
        (false, "")
    }
}
