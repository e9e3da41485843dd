//! What the cosmological snapshot readers share: particle types by number or
//! name, the region a reader keeps, and the unit system a file states.
//!
//! Gadget, AREPO, GIZMO and SWIFT number their particle types 0–5 (0 gas,
//! 1 dark matter, 2 and 3 further dark-matter or disk/bulge species, 4
//! stars, 5 black holes); Tipsy's gas, dark and star arrays map onto 0, 1
//! and 4 so that one `--part-type` means the same in every format.
//!
//! A [`Region`] lets a reader drop particles as it streams them, so that the
//! memory a read needs is bounded by what falls inside, not by the file.

use std::path::{Path, PathBuf};

use crate::IoError;

/// The names of the particle types, by number (6: SWIFT's neutrinos).
pub const PART_TYPE_NAMES: [&str; 7] = ["gas", "dm", "disk", "bulge", "stars", "bh", "neutrinos"];

/// Other words users write for the types (`--part-type dark`).
const ALIASES: [(&str, u32); 8] = [
    ("dark", 1),
    ("darkmatter", 1),
    ("dark_matter", 1),
    ("star", 4),
    ("blackholes", 5),
    ("black_holes", 5),
    ("sinks", 5),
    ("baryons", 0),
];

/// The particle type a number (`0`–`6`) or name (`gas`, `dm`, `disk`,
/// `bulge`, `stars`, `bh`, `neutrinos`, and a few aliases such as `dark`,
/// `star`) means; `None` for anything else. Case and surrounding blanks are
/// ignored.
pub fn part_type_named(s: &str) -> Option<u32> {
    let s = s.trim().to_ascii_lowercase();
    if let Ok(n) = s.parse::<u32>() {
        return (n < PART_TYPE_NAMES.len() as u32).then_some(n);
    }
    if let Some(i) = PART_TYPE_NAMES.iter().position(|n| *n == s) {
        return Some(i as u32);
    }
    ALIASES.iter().find(|(n, _)| *n == s).map(|(_, t)| *t)
}

/// "1 (dm)": a type number with its name, for messages.
pub fn part_type_label(t: u32) -> String {
    match PART_TYPE_NAMES.get(t as usize) {
        Some(name) => format!("{t} ({name})"),
        None => t.to_string(),
    }
}

/// The type a reader picks when none is asked for: gas (0) when the file
/// holds any, else the first type with particles, else 0.
pub fn default_part_type(counts: &[u64]) -> u32 {
    if counts.first().copied().unwrap_or(0) > 0 {
        return 0;
    }
    counts.iter().position(|&n| n > 0).unwrap_or(0) as u32
}

/// The error for a type a file does not hold: it lists the counts per type.
pub fn missing_part_type(path: &Path, wanted: u32, counts: &[u64]) -> IoError {
    let present: Vec<String> = counts
        .iter()
        .enumerate()
        .filter(|(_, n)| **n > 0)
        .map(|(t, n)| format!("{} × {n}", part_type_label(t as u32)))
        .collect();
    IoError::format(
        path,
        format!(
            "no particles of type {} (types present: {})",
            part_type_label(wanted),
            if present.is_empty() {
                "none".to_string()
            } else {
                present.join(", ")
            }
        ),
    )
}

/// What a snapshot's headers say, without reading its particles (for
/// `voxless info` and for the metadata of outputs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SnapshotHeader {
    /// The code or format: "SWIFT", "Gadget-4", "AREPO", "GIZMO",
    /// "Gadget", "Gadget binary (format 2, little-endian)", "Tipsy
    /// (big-endian)".
    pub code: String,
    /// The files, in order.
    pub files: Vec<PathBuf>,
    /// Particles per type over all files.
    pub counts: Vec<u64>,
    /// The periodic box's sides, when the file states one.
    pub box_size: Option<[f64; 3]>,
    pub time: Option<f64>,
    pub redshift: Option<f64>,
    pub units: Option<Units>,
    /// Per type with particles: the fields (datasets, blocks, columns).
    pub fields: Vec<(u32, Vec<String>)>,
    /// The mass of every particle of a type without per-particle masses.
    pub mass_table: Vec<f64>,
}

/// The header of the snapshot at `path` in `format`; `None` for formats
/// that are not snapshots.
pub fn snapshot_header(
    path: &Path,
    format: crate::ParticleFormat,
) -> Result<Option<SnapshotHeader>, IoError> {
    use crate::ParticleFormat as F;
    Ok(Some(match format {
        F::GadgetBinary => {
            let g = crate::gadget_bin::open_gadget_binary(path)?;
            let h = &g.header;
            let counts = h.npart_total.to_vec();
            let mut fields = Vec::new();
            for (t, &n) in counts.iter().enumerate() {
                if n == 0 {
                    continue;
                }
                let mut f: Vec<String> = vec!["POS".into(), "VEL".into(), "ID".into()];
                let has = |b: &str| g.blocks.iter().any(|x| x.trim() == b);
                if has("MASS") && h.mass[t] == 0.0 {
                    f.push("MASS".into());
                }
                if t == 0 {
                    f.extend(
                        ["U", "RHO", "HSML"]
                            .iter()
                            .filter(|b| has(b))
                            .map(|b| b.to_string()),
                    );
                }
                fields.push((t as u32, f));
            }
            SnapshotHeader {
                code: format!(
                    "Gadget binary (format {}, {}-endian{})",
                    g.format,
                    if g.big_endian { "big" } else { "little" },
                    if g.double_positions {
                        ", float64 positions"
                    } else {
                        ""
                    }
                ),
                files: g.files.clone(),
                counts,
                box_size: (h.box_size > 0.0).then_some([h.box_size; 3]),
                time: Some(h.time),
                redshift: Some(h.redshift),
                units: None,
                fields,
                mass_table: h.mass.to_vec(),
            }
        }
        F::Tipsy => {
            let h = crate::tipsy::tipsy_header(path)?;
            let counts = vec![h.nsph as u64, h.ndark as u64, 0, 0, h.nstar as u64, 0];
            let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
            let mut fields = Vec::new();
            if h.nsph > 0 {
                fields.push((
                    0,
                    names(&[
                        "mass", "pos", "vel", "rho", "temp", "hsmooth", "metals", "phi",
                    ]),
                ));
            }
            if h.ndark > 0 {
                fields.push((1, names(&["mass", "pos", "vel", "eps", "phi"])));
            }
            if h.nstar > 0 {
                fields.push((
                    4,
                    names(&["mass", "pos", "vel", "metals", "tform", "eps", "phi"]),
                ));
            }
            SnapshotHeader {
                code: format!(
                    "Tipsy ({}-endian)",
                    if h.big_endian { "big" } else { "little" }
                ),
                files: vec![path.to_path_buf()],
                counts,
                time: Some(h.time),
                fields,
                ..Default::default()
            }
        }
        #[cfg(feature = "hdf5")]
        F::Hdf5 if crate::hdf5_kind(path)? == crate::Hdf5Kind::Gadget => {
            let g = crate::hdf5::open_gadget_hdf5(path)?;
            SnapshotHeader {
                code: g.code_name.to_string(),
                files: g.files,
                counts: g.total,
                box_size: g.box_size,
                time: g.time,
                redshift: g.redshift,
                units: g.units,
                fields: g.fields,
                mass_table: g.mass_table,
            }
        }
        _ => return Ok(None),
    }))
}

/// The files of a snapshot written as several (`snap_033.0.hdf5`,
/// `snap_033.1.hdf5`, … or `snap_033.0`, `snap_033.1`, …), found from any
/// one of them, from the stem (`snap_033`, which is no file itself) or from
/// a directory holding only them (`snapdir_033/`). In the order of their
/// numbers; the numbers need not be complete (the reader compares them with
/// the count its header states). `None` when `path` is none of these.
pub fn snapshot_files(path: &Path) -> Option<Vec<PathBuf>> {
    if path.is_dir() {
        let mut stem: Option<(String, String)> = None;
        let mut found = Vec::new();
        for entry in std::fs::read_dir(path).ok()?.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue;
            }
            let (s, k, ext) = split_numbered(&name)?;
            match &stem {
                None => stem = Some((s.to_string(), ext.to_string())),
                Some((a, b)) if a == s && b == ext => {}
                _ => return None,
            }
            found.push((k, entry.path()));
        }
        found.sort();
        return (!found.is_empty()).then(|| found.into_iter().map(|(_, p)| p).collect());
    }
    let name = path.file_name()?.to_string_lossy().into_owned();
    let dir = path.parent().unwrap_or(Path::new(""));
    let (stem, ext) = match split_numbered(&name) {
        Some((s, _, ext)) if path.is_file() => (s.to_string(), ext.to_string()),
        _ if !path.exists() => {
            // A stem: the first file of the set carries number 0.
            let ext = ["", ".hdf5", ".h5"]
                .into_iter()
                .find(|e| dir.join(format!("{name}.0{e}")).is_file())?;
            (name.clone(), ext.to_string())
        }
        _ => return None,
    };
    let mut found: Vec<(u64, PathBuf)> = std::fs::read_dir(if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    })
    .ok()?
    .flatten()
    .filter_map(|e| {
        let n = e.file_name().to_string_lossy().into_owned();
        let (s, k, x) = split_numbered(&n)?;
        (s == stem && x == ext).then(|| (k, dir.join(&n)))
    })
    .collect();
    found.sort();
    // One file alone named like a member is a plain file, not a set.
    (found.len() > 1 || (found.len() == 1 && !path.is_file()))
        .then(|| found.into_iter().map(|(_, p)| p).collect())
}

/// The file that stands for `path` when reading a header or sniffing a
/// format: the first file of the multi-file snapshot `path` names (its
/// stem or directory), else `path` itself.
pub fn first_file(path: &Path) -> PathBuf {
    match snapshot_files(path) {
        Some(files) if !path.is_file() => files[0].clone(),
        _ => path.to_path_buf(),
    }
}

/// `stem.K.ext` → (stem, K, ".ext"), `stem.K` → (stem, K, "") for the
/// extensions of snapshot files.
fn split_numbered(name: &str) -> Option<(&str, u64, &str)> {
    let (rest, ext) = match name.rsplit_once('.') {
        Some((r, e)) if e.eq_ignore_ascii_case("hdf5") || e.eq_ignore_ascii_case("h5") => {
            (r, &name[r.len()..])
        }
        _ => (name, ""),
    };
    let (stem, k) = rest.rsplit_once('.')?;
    if stem.is_empty() || k.is_empty() || !k.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some((stem, k.parse().ok()?, ext))
}

/// The file of a set numbered `k` that is missing: `stem.k.ext` next to the
/// first one (for the error naming it).
pub fn member_path(first: &Path, k: usize) -> PathBuf {
    let name = first
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    match split_numbered(&name) {
        Some((stem, _, ext)) => first.with_file_name(format!("{stem}.{k}{ext}")),
        None => first.to_path_buf(),
    }
}

/// A box of interest: a reader keeps the particles within `pad` of it (the
/// reach of their kernels), measuring periodically when `period` is set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
    /// Distance added on every side.
    pub pad: f64,
    /// The periodic box (lower corner, side lengths): a particle is kept
    /// when any of its images is inside.
    pub period: Option<([f64; 3], [f64; 3])>,
}

impl Region {
    /// Whether a particle at `p` can touch the region.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        (0..3).all(|a| {
            let (lo, hi) = (self.lo[a] - self.pad, self.hi[a] + self.pad);
            match self.period {
                Some((_, size)) if size[a] > 0.0 && hi - lo < size[a] => {
                    // The image of p nearest above lo.
                    let x = lo + (p[a] - lo).rem_euclid(size[a]);
                    x <= hi
                }
                Some((_, size)) if size[a] > 0.0 => true,
                _ => p[a] >= lo && p[a] <= hi,
            }
        })
    }

    /// Whether an axis-aligned box `[lo, hi]` of particles can hold one
    /// that touches the region (for skipping whole cells of a file).
    pub fn overlaps(&self, lo: [f64; 3], hi: [f64; 3]) -> bool {
        (0..3).all(|a| {
            let (rlo, rhi) = (self.lo[a] - self.pad, self.hi[a] + self.pad);
            match self.period {
                Some((_, size)) if size[a] > 0.0 => {
                    if rhi - rlo >= size[a] || hi[a] - lo[a] >= size[a] {
                        return true;
                    }
                    // Shift the cell to its image starting nearest above rlo.
                    let shift = lo[a] - (rlo + (lo[a] - rlo).rem_euclid(size[a]));
                    let (clo, chi) = (lo[a] - shift, hi[a] - shift);
                    // It may also overlap from the image one period below.
                    clo <= rhi || chi - size[a] >= rlo
                }
                _ => lo[a] <= rhi && hi[a] >= rlo,
            }
        })
    }
}

/// The unit system a snapshot states, as CGS factors of its internal units.
/// Coordinates stay as stored (comoving in cosmological runs); `comoving`
/// says whether they are.
#[derive(Clone, Debug, PartialEq)]
pub struct Units {
    /// One internal length unit in centimetres.
    pub length_cm: f64,
    /// One internal mass unit in grams.
    pub mass_g: f64,
    /// One internal velocity unit in cm/s.
    pub velocity_cm_s: f64,
    /// Where the factors come from ("SWIFT Units group", "Gadget Header
    /// UnitLength_in_cm", …).
    pub source: String,
    /// Whether positions are comoving (cosmological runs).
    pub comoving: bool,
    /// The Hubble parameter h when lengths and masses carry h⁻¹ (Gadget,
    /// AREPO, GIZMO), else `None`.
    pub hubble: Option<f64>,
}

impl Units {
    /// The length unit in the astronomers' word nearest to it ("Mpc",
    /// "kpc", "pc", "km", "cm") and the internal unit in that word, e.g.
    /// `("Mpc", 1.0)` for 3.0857e24 cm.
    pub fn length_name(&self) -> (&'static str, f64) {
        const NAMES: [(&str, f64); 5] = [
            ("Mpc", 3.085_677_581_491_367e24),
            ("kpc", 3.085_677_581_491_367e21),
            ("pc", 3.085_677_581_491_367e18),
            ("km", 1e5),
            ("cm", 1.0),
        ];
        for (name, cm) in NAMES {
            if self.length_cm >= 0.5 * cm {
                return (name, self.length_cm / cm);
            }
        }
        ("cm", self.length_cm)
    }

    /// The mass unit in solar masses when it is astronomical, else grams:
    /// `("Msun", 1e10)` for 1.989e43 g.
    pub fn mass_name(&self) -> (&'static str, f64) {
        // The solar mass SWIFT and swiftsimio use (IAU 2015 nominal GM over G).
        const MSUN_G: f64 = 1.988_415_86e33;
        if self.mass_g >= 1e-3 * MSUN_G {
            ("Msun", self.mass_g / MSUN_G)
        } else {
            ("g", self.mass_g)
        }
    }

    /// One line for notes and `voxless info`: "length 1 Mpc, mass 1e10
    /// Msun, velocity 1 km/s (SWIFT Units group; comoving)".
    pub fn describe(&self) -> String {
        let (l, lf) = self.length_name();
        let (m, mf) = self.mass_name();
        let mut extra = vec![self.source.clone()];
        if self.comoving {
            extra.push("positions comoving, as stored".into());
        }
        if let Some(h) = self.hubble {
            extra.push(format!("lengths and masses in h⁻¹ units, h = {h}"));
        }
        format!(
            "length {} {l}, mass {} {m}, velocity {} km/s ({})",
            short(lf),
            short(mf),
            short(self.velocity_cm_s / 1e5),
            extra.join("; ")
        )
    }

    /// The unit of a projected mass column density, mass per area, e.g.
    /// "1e10 Msun / Mpc^2" (h⁻¹ factors written out when they apply).
    pub fn column_density(&self) -> String {
        let (l, lf) = self.length_name();
        let (m, mf) = self.mass_name();
        let h = if self.hubble.is_some() { " h" } else { "" };
        let unit = |f: f64, name: &str| {
            if (f - 1.0).abs() < 1e-5 {
                name.to_string()
            } else {
                format!("{} {name}", short(f))
            }
        };
        format!("{}{h} / ({})^2", unit(mf, m), unit(lf, l))
    }
}

/// A number in few digits ("1", "1e10", "3.086e24", "0.7").
fn short(v: f64) -> String {
    // Six significant digits: 1.00000001 is 1.
    let v: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    if v == 0.0 || ((1e-3..1e5).contains(&v.abs()) && (v * 1e4).fract().abs() < 1e-6) {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let s = format!("{v:.4e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        format!("{m}e{e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn types_by_number_and_name() {
        assert_eq!(part_type_named("0"), Some(0));
        assert_eq!(part_type_named(" GAS "), Some(0));
        assert_eq!(part_type_named("dm"), Some(1));
        assert_eq!(part_type_named("dark"), Some(1));
        assert_eq!(part_type_named("stars"), Some(4));
        assert_eq!(part_type_named("bh"), Some(5));
        assert_eq!(part_type_named("6"), Some(6));
        assert_eq!(part_type_named("7"), None);
        assert_eq!(part_type_named("quarks"), None);
        assert_eq!(default_part_type(&[0, 5, 0, 0, 2, 0]), 1);
        assert_eq!(default_part_type(&[3, 5, 0, 0, 2, 0]), 0);
        assert_eq!(default_part_type(&[0; 6]), 0);
        let e = missing_part_type(Path::new("s"), 4, &[0, 8, 0, 0, 0, 0]).to_string();
        assert!(e.contains("4 (stars)") && e.contains("1 (dm) × 8"), "{e}");
    }

    #[test]
    fn multi_file_sets_from_a_member_the_stem_or_the_directory() {
        let dir = std::env::temp_dir().join(format!("voxless-sets-{}", std::process::id()));
        let snapdir = dir.join("snapdir_007");
        std::fs::create_dir_all(&snapdir).unwrap();
        for k in [0, 1, 2, 10] {
            std::fs::write(snapdir.join(format!("snap_007.{k}.hdf5")), b"x").unwrap();
        }
        std::fs::write(dir.join("single.0.hdf5"), b"x").unwrap();
        let want: Vec<PathBuf> = [0, 1, 2, 10]
            .iter()
            .map(|k| snapdir.join(format!("snap_007.{k}.hdf5")))
            .collect();
        assert_eq!(snapshot_files(&snapdir), Some(want.clone()));
        assert_eq!(snapshot_files(&want[2]), Some(want.clone()));
        assert_eq!(
            snapshot_files(&snapdir.join("snap_007")),
            Some(want.clone())
        );
        assert_eq!(snapshot_files(&dir.join("single.0.hdf5")), None);
        assert_eq!(snapshot_files(&dir.join("nothing")), None);
        assert_eq!(member_path(&want[0], 5), snapdir.join("snap_007.5.hdf5"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn regions_wrap_in_a_periodic_box() {
        let r = Region {
            lo: [9.0, 0.0, 0.0],
            hi: [11.0, 10.0, 10.0],
            pad: 0.5,
            period: Some(([0.0; 3], [10.0; 3])),
        };
        // x in [8.5, 11.5] wraps to [8.5, 10) ∪ [0, 1.5].
        assert!(r.contains([9.0, 5.0, 5.0]));
        assert!(r.contains([1.2, 5.0, 5.0]));
        assert!(!r.contains([2.0, 5.0, 5.0]));
        assert!(!r.contains([8.0, 5.0, 5.0]));
        assert!(r.overlaps([1.0, 0.0, 0.0], [2.0, 1.0, 1.0]));
        assert!(!r.overlaps([2.0, 0.0, 0.0], [8.0, 1.0, 1.0]));
        assert!(r.overlaps([7.0, 0.0, 0.0], [8.6, 1.0, 1.0]));
        let open = Region { period: None, ..r };
        assert!(!open.contains([1.2, 5.0, 5.0]));
        assert!(!open.overlaps([1.0, 0.0, 0.0], [2.0, 1.0, 1.0]));
    }

    #[test]
    fn units_read_in_astronomers_words() {
        let u = Units {
            length_cm: 3.085_677_581_491_367e24,
            mass_g: 1.988_41e43,
            velocity_cm_s: 1e5,
            source: "SWIFT Units group".into(),
            comoving: true,
            hubble: None,
        };
        assert_eq!(u.length_name().0, "Mpc");
        assert!((u.length_name().1 - 1.0).abs() < 1e-9);
        assert_eq!(u.column_density(), "1e10 Msun / (Mpc)^2");
        assert!(u.describe().contains("length 1 Mpc"), "{}", u.describe());
        let g = Units {
            length_cm: 3.085_678e21,
            hubble: Some(0.7),
            ..u
        };
        assert_eq!(g.column_density(), "1e10 Msun h / (kpc)^2");
    }
}
