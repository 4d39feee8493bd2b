//! The text layer of a `.par` file: blocks, keywords and values, and their interpretation
//! into [`LenstoolPar`] (see the parent module for the conventions).

use std::cell::RefCell;
use std::collections::HashMap;

use glam::DVec2;

use super::{
    FreeMass, LenstoolPar, ParComponent, ParError, ParOptions, ParPotential, ParPotfile,
    ParRedshiftPrior, ParSourceZ, ParWarning, Radius, Z_MATCH_TOL,
};
use crate::cosmology::{Cosmology, LensPlane};
use crate::inversion::RedshiftPrior;
use crate::sky::SkyReference;

/// One `keyword values...` line of a block.
#[derive(Debug, Clone)]
struct Entry {
    line: usize,
    values: Vec<String>,
}

/// A block: header words, first line, entries by keyword (the last one wins, as in Lenstool),
/// and the lines of keywords a block may repeat (`z_m_limit`), in order.
#[derive(Debug, Clone)]
struct Block {
    header: String,
    line: usize,
    entries: HashMap<String, Entry>,
    repeated: Vec<Entry>,
}

/// The keyword of a line an `image` block repeats, one per system.
const Z_M_LIMIT: &str = "z_m_limit";

/// Parses the text of a `.par` file (`source_name` is used in messages) with the default
/// [`ParOptions`]: a model with potentials at several redshifts is refused.
pub fn parse_par(text: &str, source_name: &str) -> Result<LenstoolPar, ParError> {
    parse_par_with(text, source_name, &ParOptions::default())
}

/// Parses the text of a `.par` file as Lenstool reads it (`init_grille.c`, `flire`): `#`
/// starts a comment anywhere on a line; a line whose first word names a Lenstool block opens
/// it and the block runs to its `end`; any other line between blocks (a stray `end`, a word
/// Lenstool does not know) is skipped, with a warning for unknown words; `fini` (or
/// Lenstool-HPC's `finish`) ends the file. With `options.single_plane`, potentials at another
/// redshift than the first one are moved to its plane (see [`ParOptions`]).
pub fn parse_par_with(
    text: &str,
    source_name: &str,
    options: &ParOptions,
) -> Result<LenstoolPar, ParError> {
    let mut warnings = Vec::new();
    let blocks = read_blocks(text, source_name, &mut warnings)?;
    let name = |b: &Block| b.header.split_whitespace().next().unwrap_or("").to_string();
    let mut cx = Ctx {
        file: source_name,
        reference: None,
        warnings: RefCell::new(warnings),
    };
    // The reference first: `_wcs` centres need it wherever `runmode` stands.
    if let Some(b) = blocks.iter().find(|b| name(b) == "runmode") {
        cx.reference = cx.reference(b)?;
    }
    let mut cosmology = None;
    let mut potentials = Vec::new();
    let mut potfiles = Vec::new();
    let mut redshift_priors = Vec::new();
    let mut source_z = ParSourceZ::default();
    // Lenstool gives the k-th `limit` block to the k-th potential, whatever number its header
    // writes (Lenstool-HPC's `module_readParameters_limit`; MACS J1149's CATS `m1149.par`
    // writes `limit 2` after two potentials and `limit 5` after its sixth).
    let mut limits = Vec::new();
    // (z, block, index in potentials or potfiles, is a potfile)
    let mut z_values: Vec<(f64, &Block, usize, bool)> = Vec::new();
    for b in &blocks {
        let name = name(b);
        if name.starts_with("cosmolog") {
            cosmology = Some(cx.cosmology(b)?);
        } else if name.starts_with("potent") {
            let (p, z) = cx.potential(b)?;
            z_values.push((z, b, potentials.len(), false));
            potentials.push(p);
        } else if name.starts_with("potfile") {
            let (p, z) = cx.potfile(b)?;
            z_values.push((z, b, potfiles.len(), true));
            potfiles.push(p);
        } else if name.starts_with("limit") {
            limits.push(b);
        } else if name.starts_with("image") {
            redshift_priors.extend(b.repeated.iter().flat_map(|e| cx.redshift_priors(e)));
        } else if name == "source" {
            // As written: read only for catalogue rows without a redshift.
            let raw = |key: &str| b.entries.get(key).map(|e| (e.values.clone(), e.line));
            source_z = ParSourceZ {
                z_source: raw("z_source"),
                dist_z: raw("dist_z"),
            };
        }
    }
    for (p, b) in potentials.iter_mut().zip(limits) {
        if matches!(p.component, ParComponent::Dpie { .. }) {
            p.free_mass = free_mass(b, &cx);
        }
    }
    let cosmology =
        cosmology.ok_or_else(|| cx.model(&format!("no `cosmologie` block{}", other_kind(text))))?;
    let &(z_lens, main, _, _) = z_values
        .first()
        .ok_or_else(|| cx.model("no `potentiel` or `potfile` block"))?;
    for &(z, b, k, is_potfile) in &z_values {
        if (z - z_lens).abs() <= Z_MATCH_TOL {
            continue;
        }
        if !options.single_plane {
            return Err(cx.unsupported(
                b,
                format!(
                    "z_lens = {z} differs from z_lens = {z_lens} of block `{}` (line {}): \
                     multi-plane models (potentials at several redshifts) are not supported; \
                     the single-plane approximation puts every potential at z = {z_lens} \
                     (`wslap maps --single-plane`, or the app's setting \"Lenstool models at \
                     several redshifts: single-plane approximation\")",
                    main.header, main.line
                ),
            ));
        }
        // Angular sizes are kept: kpc radii become arcsec on the block's own plane.
        let plane = LensPlane::new(cosmology, z).map_err(|source| ParError::Cosmology {
            file: source_name.into(),
            source,
        })?;
        let to_arcsec = |r: &mut Radius| *r = Radius::Arcsec(r.arcsec(&plane));
        if is_potfile {
            to_arcsec(&mut potfiles[k].r_core);
            to_arcsec(&mut potfiles[k].r_cut);
        } else if let ParComponent::Dpie { r_core, r_cut, .. } = &mut potentials[k].component {
            to_arcsec(r_core);
            to_arcsec(r_cut);
            if let Some(f) = &mut potentials[k].free_mass {
                f.r_core
                    .iter_mut()
                    .chain(f.r_cut.iter_mut())
                    .for_each(to_arcsec);
            }
        }
        cx.warn_about(
            b.line,
            format!(
                "single-plane approximation: block `{}` at z = {z} is moved to z_lens = {z_lens} \
                 (its angular sizes and velocity dispersion are kept; its deflection then \
                 scales with D_ls/D_s of z_lens, and lensing between the planes is ignored)",
                b.header
            ),
            Some(b.header.clone()),
        );
    }
    Ok(LenstoolPar {
        source_name: source_name.to_string(),
        reference: cx.reference,
        cosmology,
        z_lens,
        potentials,
        potfiles,
        redshift_priors,
        source_z,
        warnings: cx.warnings.into_inner(),
    })
}

/// The uniform priors (mode 1: `v_disp 1 150 450 0.1`) the `limit` block `b` puts on a dPIE's
/// mass: `v_disp`, the core and the cut radius; `None` when it puts none. A prior's low end is
/// kept where it is above 0 (one from 0 gives no least mass: the written value stays). As in a
/// `potentiel` block, a radius's kpc line wins over its arcsec line whatever it says, so the
/// arcsec line is read only where the block has no kpc line. Lines of mode 0 (fixed) and 3
/// (a Gaussian, which a `bestopt.par` writes for every fitted value) keep the written value
/// without a word: the block is only read for this, and the model is evaluated without it. A
/// line of mode 1 that does not read as `1 low high` with `0 <= low <= high`, or of any other
/// mode, is passed over with a warning on `cx` naming it, since the value is then taken as
/// written.
fn free_mass(b: &Block, cx: &Ctx<'_>) -> Option<FreeMass> {
    // None without the line; Some(None) for one that frees nothing here; Some(Some(the low
    // end if above 0)) for a uniform prior.
    let prior = |key: &str| {
        let e = b.entries.get(key)?;
        let v: Vec<f64> = e
            .values
            .iter()
            .take(3)
            .map_while(|v| v.parse().ok())
            .collect();
        let not_read = |what: &str| {
            cx.warn(
                e.line,
                format!(
                    "`{key} {}` in `{}` (line {}) is not {what}: not read, so `{key}` keeps its \
                     written value",
                    e.values.join(" "),
                    b.header,
                    b.line
                ),
            );
            Some(None)
        };
        match v[..] {
            [1.0, low, high] if low >= 0.0 && low <= high && high.is_finite() => {
                Some(Some((low > 0.0).then_some(low)))
            }
            [1.0, ..] => not_read("a uniform prior `1 low high` with 0 <= low <= high"),
            [0.0 | 3.0, ..] => Some(None),
            _ => not_read("a prior of mode 0 (fixed), 1 (uniform) or 3 (Gaussian)"),
        }
    };
    let radius = |kpc: &str, arcsec: &str| match prior(kpc) {
        Some(low) => low.map(|low| low.map(Radius::Kpc)),
        None => prior(arcsec).flatten().map(|low| low.map(Radius::Arcsec)),
    };
    let (sigma, core, cut) = (
        prior("v_disp").flatten(),
        radius("core_radius_kpc", "core_radius"),
        radius("cut_radius_kpc", "cut_radius"),
    );
    (sigma.is_some() || core.is_some() || cut.is_some()).then_some(FreeMass {
        line: b.line,
        sigma_v_km_s: sigma.flatten(),
        r_core: core.flatten(),
        r_cut: cut.flatten(),
    })
}

/// Whether Lenstool opens a block for the first word of a line between blocks (the names and
/// prefixes `init_grille.c` compares).
fn is_lenstool_block(word: &str) -> bool {
    // With the English names of Lenstool's newer `best.par` files (`field`, `large`).
    const EXACT: [&str; 11] = [
        "runmode",
        "field",
        "cleanlens",
        "source",
        "shapemodel",
        "shapelimit",
        "cline",
        "champ",
        "vfield",
        "vfieldlimit",
        "cosmolimit",
    ];
    const PREFIXES: [&str; 12] = [
        "image", "grille", "grid", "potent", "limit", "potfile", "multi", "dynfile", "grande",
        "large", "observ", "cosmolog",
    ];
    EXACT.contains(&word) || PREFIXES.iter().any(|p| word.starts_with(p))
}

/// Whether `line` is one of the fit's statistics at the head of a Lenstool output `.par`: a
/// name and a number separated by a colon, e.g. `Chi2pos: 664.746`.
fn is_fit_statistic(line: &str) -> bool {
    line.rsplit_once(':')
        .is_some_and(|(name, value)| !name.trim().is_empty() && value.trim().parse::<f64>().is_ok())
}

/// Splits the text into blocks as Lenstool does (see [`parse_par_with`]).
fn read_blocks(
    text: &str,
    file: &str,
    warnings: &mut Vec<ParWarning>,
) -> Result<Vec<Block>, ParError> {
    let mut blocks = Vec::new();
    let mut open: Option<Block> = None;
    // Inside a run of lines Lenstool skips (after an unknown word, up to a block or an `end`).
    let mut skipping = false;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let body = raw.split('#').next().unwrap_or("").trim();
        let mut words = body.split_whitespace();
        let Some(first) = words.next() else { continue };
        match open.as_mut() {
            None if first == "fini" || first == "finish" => break,
            None if first == "end" => skipping = false,
            None if is_lenstool_block(first) => {
                skipping = false;
                let header = body.split_whitespace().collect::<Vec<_>>().join(" ");
                open = Some(Block {
                    header,
                    line,
                    entries: HashMap::new(),
                    repeated: Vec::new(),
                });
            }
            // The fit's statistics Lenstool writes above the blocks of its `best.par` and
            // `bestopt.par` (`Chi2tot: 665.099`, `log(Evidence) : -430.734`): not blocks, and
            // no cause for a warning on every published model.
            None if blocks.is_empty() && is_fit_statistic(body) => {}
            None => {
                if !skipping {
                    warnings.push(ParWarning {
                        file: file.into(),
                        line,
                        moved_block: None,
                        message: format!(
                            "`{first}` is not a Lenstool block: skipped, with the lines after \
                             it, up to the next block or `end` (Lenstool skips it too)"
                        ),
                    });
                }
                skipping = true;
            }
            Some(_) if first == "end" => blocks.extend(open.take()),
            Some(b) => {
                let entry = Entry {
                    line,
                    values: words.map(str::to_string).collect(),
                };
                if first == Z_M_LIMIT {
                    b.repeated.push(entry.clone());
                }
                b.entries.insert(first.to_string(), entry);
            }
        }
    }
    if let Some(b) = open {
        return Err(ParError::Syntax {
            file: file.into(),
            line: b.line,
            reason: format!("block `{}` has no `end`", b.header),
        });
    }
    Ok(blocks)
}

/// Messages for a value that is not a number, by position after the keyword.
const VALUE_MUST_BE_NUMBER: [&str; 3] = [
    "value 1 must be a number",
    "value 2 must be a number",
    "value 3 must be a number",
];

/// Why a `cosmologie` block whose densities do not add to 1 is refused, in its own keywords.
fn flat_reason(om_key: &str, ol_key: &str) -> &'static str {
    match (om_key, ol_key) {
        ("omegaM", "omegaX") => "only flat models are supported: omegaM + omegaX must be 1",
        ("omegaM", _) => "only flat models are supported: omegaM + lambda must be 1",
        (_, "omegaX") => "only flat models are supported: omega + omegaX must be 1",
        _ => "only flat models are supported: omega + lambda must be 1",
    }
}

/// A `cosmologie` keyword, the test its value (and omegaM) must pass, and the message.
type FlatCheck = (&'static str, fn(f64, f64) -> bool, &'static str);

/// Interprets blocks, with the file name for messages, the frame's sky reference and the
/// warnings so far.
struct Ctx<'a> {
    file: &'a str,
    reference: Option<SkyReference>,
    warnings: RefCell<Vec<ParWarning>>,
}

/// Keywords a `potentiel` block may hold besides the ones a profile reads.
const POTENTIAL_COMMON: [&str; 4] = ["profil", "profile", "nid", "z_lens"];
const DPIE_KEYS: [&str; 13] = [
    "x_centre",
    "y_centre",
    "x_centre_wcs",
    "y_centre_wcs",
    "ellipticite",
    "ellipticity",
    "ellip_pot",
    "angle_pos",
    "core_radius",
    "core_radius_kpc",
    "cut_radius",
    "cut_radius_kpc",
    "v_disp",
];
const SHEAR_KEYS: [&str; 8] = [
    "x_centre",
    "y_centre",
    "x_centre_wcs",
    "y_centre_wcs",
    "gamma",
    "ellipticite",
    "angle_pos",
    "kappa",
];
/// Lenstool reads the scatter keywords by their first letters (`vdscat...`,
/// `rcutscat...`); both spellings seen in published files are taken.
const POTFILE_KEYS: [&str; 17] = [
    "filein",
    "zlens",
    "z_lens",
    "type",
    "profil",
    "corekpc",
    "core",
    "cutkpc",
    "cut",
    "mag0",
    "sigma",
    "slope",
    "vdslope",
    "vdscatter",
    "rcutscatter",
    "vdscat",
    "rcutscat",
];

/// Every keyword Lenstool reads in a `potentiel` block (`r_potentiel.c`; `mag...` and
/// `virial...` by prefix). Others are ignored by Lenstool, and so here, with a warning.
const LENSTOOL_POTENTIAL_KEYS: [&str; 41] = [
    "profil",
    "profile",
    "nid",
    "x_centre",
    "y_centre",
    "x_centre_wcs",
    "y_centre_wcs",
    "pmass",
    "ellip_pot",
    "ellipticite",
    "ellipticity",
    "gamma",
    "angle_pos",
    "phi",
    "core_radius",
    "scale_radius",
    "re",
    "core_radius_kpc",
    "scale_radius_kpc",
    "re_kpc",
    "cut_radius",
    "virial_radius",
    "r200",
    "cut_radius_kpc",
    "virial_radius_kpc",
    "r200_kpc",
    "v_disp",
    "sigma_e",
    "exponent",
    "alpha",
    "exposant",
    "n",
    "beta",
    "concentration",
    "c",
    "rc_slope",
    "z_lens",
    "masse",
    "m200",
    "mass",
    "rhos",
];

/// Every keyword Lenstool reads in a `potfile` block (`r_potfile.c`; `vdscat...` and
/// `rcutscat...` by prefix).
const LENSTOOL_POTFILE_KEYS: [&str; 20] = [
    "filein",
    "type",
    "zlens",
    "z_lens",
    "mag0",
    "r200",
    "select",
    "core",
    "corekpc",
    "cut",
    "cutkpc",
    "slope",
    "m200slope",
    "sigma",
    "vdslope",
    "c200slope",
    "a",
    "m200",
    "b",
    "c200",
];

/// Whether Lenstool reads keyword `k` in a block of kind `what` (`"potfile"` or a potential).
fn lenstool_reads(k: &str, what: &str) -> bool {
    if what.contains("potfile") {
        LENSTOOL_POTFILE_KEYS.contains(&k) || k.starts_with("vdscat") || k.starts_with("rcutscat")
    } else {
        LENSTOOL_POTENTIAL_KEYS.contains(&k) || k.starts_with("mag") || k.starts_with("virial")
    }
}

impl Ctx<'_> {
    /// A `z_m_limit n id flag v1 v2 precision` line of an `image` block: system `id`'s
    /// redshift fixed at `v1` (flag 0, as a `best.par` writes the fitted value), uniform on
    /// `[v1, v2]` (flag 1) or a normal of mean `v1` and width `v2` (flag 3, a `bestopt.par`'s
    /// posterior). Lenstool's own output files may list several ids before the flag (`n A3a
    /// A4a 3 1.51 0.04 0.001`: families of one source, sharing its redshift): each is given the
    /// prior. A line that says none of these is skipped with a warning: the image block is
    /// not the model's, so it is never a reason to refuse the file.
    fn redshift_priors(&self, e: &Entry) -> Vec<ParRedshiftPrior> {
        let skip = |why: String| {
            self.warn(e.line, format!("`{Z_M_LIMIT}` {why}: skipped"));
            Vec::new()
        };
        let values = e.values.as_slice();
        // With a precision after the values the flag is fourth from the end, whatever the
        // number of ids; without one (five words) it is third.
        let flag_at = values.len().saturating_sub(4).max(2);
        let (Some(ids), Some([flag, v1, v2, ..])) = (values.get(1..flag_at), values.get(flag_at..))
        else {
            return skip("needs `n id flag value1 value2`".into());
        };
        let id = ids.join(" ");
        let number = |text: &str| text.parse::<f64>().ok().filter(|v| v.is_finite());
        let (Some(v1), Some(v2)) = (number(v1), number(v2)) else {
            return skip(format!("values `{v1}` and `{v2}` must be numbers"));
        };
        let z_ok = |z: f64| z > 0.0 && z < 20.0;
        let prior = match flag.as_str() {
            "0" if z_ok(v1) => RedshiftPrior::Fixed(v1),
            "1" if z_ok(v1) && z_ok(v2) && v2 > v1 => RedshiftPrior::Range([v1, v2]),
            "3" if z_ok(v1) && v2 > 0.0 => RedshiftPrior::Normal([v1, v2]),
            "0" | "1" | "3" => {
                return skip(format!(
                    "of system {id}: flag {flag} with values {v1} and {v2} is not a redshift \
                     prior (flag 0: a redshift in (0, 20); 1: low < high; 3: a mean and a \
                     width above 0)"
                ))
            }
            _ => {
                return skip(format!(
                    "of system {id}: flag `{flag}` is not read here (0 fixed, 1 uniform, 3 \
                     normal)"
                ))
            }
        };
        ids.iter()
            .map(|id| ParRedshiftPrior {
                line: e.line,
                system: id.clone(),
                prior,
            })
            .collect()
    }

    fn warn(&self, line: usize, message: String) {
        self.warn_about(line, message, None);
    }
    /// A warning on `line`; `moved_block` is the header of the block it says the single-plane
    /// approximation moved, if it says so.
    fn warn_about(&self, line: usize, message: String, moved_block: Option<String>) {
        self.warnings.borrow_mut().push(ParWarning {
            file: self.file.into(),
            line,
            message,
            moved_block,
        });
    }
    fn model(&self, reason: &str) -> ParError {
        ParError::Model {
            file: self.file.into(),
            reason: reason.into(),
        }
    }
    fn unsupported(&self, b: &Block, reason: String) -> ParError {
        ParError::Unsupported {
            file: self.file.into(),
            line: b.line,
            block: b.header.clone(),
            reason,
        }
    }
    fn bad(&self, b: &Block, key: &'static str, e: &Entry, reason: &'static str) -> ParError {
        ParError::BadValue {
            file: self.file.into(),
            line: e.line,
            block: b.header.clone(),
            keyword: key,
            value: e.values.join(" "),
            reason,
        }
    }
    /// Value number `k` of `key` as a finite number, or `None` when `key` is absent.
    fn opt(&self, b: &Block, key: &'static str, k: usize) -> Result<Option<f64>, ParError> {
        let Some(e) = b.entries.get(key) else {
            return Ok(None);
        };
        let v = e.values.get(k).and_then(|s| s.parse::<f64>().ok());
        match v {
            Some(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(self.bad(b, key, e, VALUE_MUST_BE_NUMBER[k.min(2)])),
        }
    }
    /// Value number `k` of the radius `key` (kpc or arcsec), refused on its own line when
    /// negative: later checks see it converted to arcsec, not as written.
    fn radius(&self, b: &Block, key: &'static str, k: usize) -> Result<Option<f64>, ParError> {
        let r = self.opt(b, key, k)?;
        match (r, b.entries.get(key)) {
            (Some(v), Some(e)) if v < 0.0 => Err(self.bad(b, key, e, "a radius must be 0 or more")),
            _ => Ok(r),
        }
    }
    fn req(&self, b: &Block, key: &'static str, k: usize) -> Result<f64, ParError> {
        self.opt(b, key, k)?.ok_or_else(|| self.missing(b, key))
    }
    /// The error for a keyword `b` must hold and does not.
    fn missing(&self, b: &Block, key: &'static str) -> ParError {
        ParError::Missing {
            file: self.file.into(),
            line: b.line,
            block: b.header.clone(),
            keyword: key,
        }
    }
    /// Fails on a keyword outside `allowed` that Lenstool reads (it would change the model),
    /// naming it and its line; a keyword Lenstool does not read is ignored with a warning, as
    /// Lenstool ignores it.
    fn only(&self, b: &Block, allowed: &[&[&str]], what: &str) -> Result<(), ParError> {
        let known = |k: &str| allowed.iter().any(|s| s.contains(&k)) || k.starts_with("mag");
        let mut unknown: Vec<_> = b.entries.iter().filter(|(k, _)| !known(k)).collect();
        unknown.sort_by_key(|(_, e)| e.line);
        for (k, e) in unknown {
            if lenstool_reads(k, what) {
                return Err(ParError::Unsupported {
                    file: self.file.into(),
                    line: e.line,
                    block: b.header.clone(),
                    reason: format!("keyword `{k}` is not supported for {what}"),
                });
            }
            self.warn(
                e.line,
                format!(
                    "block `{}`: `{k}` is not a keyword Lenstool reads there: ignored (as by \
                     Lenstool)",
                    b.header
                ),
            );
        }
        Ok(())
    }

    fn reference(&self, b: &Block) -> Result<Option<SkyReference>, ParError> {
        let Some(e) = b.entries.get("reference") else {
            return Ok(None);
        };
        match self.req(b, "reference", 0)? as i64 {
            0 => Ok(None),
            1 | 3 => {
                let (ra, dec) = (self.req(b, "reference", 1)?, self.req(b, "reference", 2)?);
                SkyReference::new(ra, dec)
                    .map(Some)
                    .ok_or_else(|| self.bad(b, "reference", e, "not a valid sky position"))
            }
            _ => Err(self.bad(b, "reference", e, "only modes 0, 1 and 3 are supported")),
        }
    }

    fn cosmology(&self, b: &Block) -> Result<Cosmology, ParError> {
        let h0 = self.req(b, "H0", 0)?;
        let om_key = if b.entries.contains_key("omegaM") {
            "omegaM"
        } else {
            "omega"
        };
        let om = self.req(b, om_key, 0)?;
        // Each value is checked on its own line first, so a typo is blamed where it is.
        if !Cosmology::h0_allowed(h0) {
            return Err(self.bad(
                b,
                "H0",
                &b.entries["H0"],
                "H0 must be above 0 and at most 500 km/s/Mpc",
            ));
        }
        if !Cosmology::omega_m_allowed(om) {
            let reason = "the matter density of a flat universe must be 0 to 1";
            return Err(self.bad(b, om_key, &b.entries[om_key], reason));
        }
        let ol_key = if b.entries.contains_key("omegaX") {
            "omegaX"
        } else {
            "lambda"
        };
        let checks: [FlatCheck; 3] = [
            (
                ol_key,
                |v, om| (om + v - 1.0).abs() < 1e-6,
                flat_reason(om_key, ol_key),
            ),
            ("wX", |v, _| v == -1.0, "only wX = -1 is supported"),
            ("wa", |v, _| v == 0.0, "only wa = 0 is supported"),
        ];
        for (key, ok, reason) in checks {
            if let (Some(v), Some(e)) = (self.opt(b, key, 0)?, b.entries.get(key)) {
                if !ok(v, om) {
                    return Err(self.bad(b, key, e, reason));
                }
            }
        }
        Cosmology::new(h0, om).map_err(|source| ParError::Cosmology {
            file: self.file.into(),
            source,
        })
    }

    /// Centre in arcsec from `x_centre`/`y_centre` or the `_wcs` keywords (needs a reference).
    fn center(&self, b: &Block) -> Result<DVec2, ParError> {
        let (xw, yw) = (
            self.opt(b, "x_centre_wcs", 0)?,
            self.opt(b, "y_centre_wcs", 0)?,
        );
        if let (Some(ra), Some(dec)) = (xw, yw) {
            let Some(r) = self.reference else {
                return Err(self.unsupported(b, "x_centre_wcs needs `runmode reference`".into()));
            };
            return Ok(r.to_offset_arcsec(ra, dec));
        }
        let x = self.opt(b, "x_centre", 0)?.unwrap_or(0.0);
        Ok(DVec2::new(x, self.opt(b, "y_centre", 0)?.unwrap_or(0.0)))
    }

    fn potential(&self, b: &Block) -> Result<(ParPotential, f64), ParError> {
        let key = if b.entries.contains_key("profile") {
            "profile"
        } else {
            "profil"
        };
        let profile = self.req(b, key, 0)?;
        let z = self.req(b, "z_lens", 0)?;
        let component = match profile as i64 {
            81 => {
                self.only(b, &[&POTENTIAL_COMMON, &DPIE_KEYS], "profile 81")?;
                let radius = |kpc: &'static str, arcsec: &'static str| {
                    let (in_kpc, in_arcsec) = (self.radius(b, kpc, 0)?, self.radius(b, arcsec, 0)?);
                    Ok::<_, ParError>(match (in_kpc, in_arcsec) {
                        // Lenstool: a non-zero kpc value wins over the arcsec one.
                        (Some(r), _) if r != 0.0 => Some(Radius::Kpc(r)),
                        (_, Some(r)) => Some(Radius::Arcsec(r)),
                        (kpc, None) => kpc.map(Radius::Kpc),
                    })
                };
                // Lenstool's default core is 0 (singular).
                let r_core =
                    radius("core_radius_kpc", "core_radius")?.unwrap_or(Radius::Arcsec(0.0));
                let r_cut = radius("cut_radius_kpc", "cut_radius")?.ok_or_else(|| {
                    let mut ignored: Vec<_> = b
                        .entries
                        .iter()
                        .filter(|(k, _)| !lenstool_reads(k, "profile 81"))
                        .collect();
                    ignored.sort_by_key(|(_, e)| e.line);
                    let names: Vec<_> = ignored.iter().map(|(k, _)| format!("`{k}`")).collect();
                    let also = match names.is_empty() {
                        true => String::new(),
                        false => format!(
                            "; {} are not Lenstool keywords (Lenstool ignores them)",
                            names.join(", ")
                        ),
                    };
                    self.unsupported(
                        b,
                        format!(
                            "no `cut_radius_kpc` or `cut_radius`: Lenstool's default, an \
                             infinite cut radius, is not supported{also}"
                        ),
                    )
                })?;
                let e = match (
                    self.opt(b, "ellipticite", 0)?,
                    self.opt(b, "ellipticity", 0)?,
                ) {
                    (Some(e), _) | (None, Some(e)) => e,
                    // Lenstool: emass = 2 epot / (1 + epot^2).
                    _ => self
                        .opt(b, "ellip_pot", 0)?
                        .map_or(0.0, |p| 2.0 * p / (1.0 + p * p)),
                };
                ParComponent::Dpie {
                    center_arcsec: self.center(b)?,
                    sigma_v_km_s: self.req(b, "v_disp", 0)?,
                    r_core,
                    r_cut,
                    ellipticity: e,
                    pa_deg: self.opt(b, "angle_pos", 0)?.unwrap_or(0.0),
                }
            }
            14 => {
                self.only(b, &[&POTENTIAL_COMMON, &SHEAR_KEYS], "profile 14")?;
                if let (Some(k), Some(e)) = (self.opt(b, "kappa", 0)?, b.entries.get("kappa")) {
                    if k != 0.0 {
                        return Err(self.bad(
                            b,
                            "kappa",
                            e,
                            "a shear with a mass sheet is not supported",
                        ));
                    }
                }
                let gamma = match self.opt(b, "gamma", 0)? {
                    Some(g) => g,
                    None => self.req(b, "ellipticite", 0)?,
                };
                ParComponent::Shear {
                    center_arcsec: self.center(b)?,
                    gamma,
                    pa_deg: self.opt(b, "angle_pos", 0)?.unwrap_or(0.0),
                }
            }
            other => {
                return Err(self.unsupported(
                    b,
                    format!("profil {other} is not supported (only 81, dPIE, and 14, shear)"),
                ))
            }
        };
        let p = ParPotential {
            block: b.header.clone(),
            line: b.line,
            component,
            mag: self.opt(b, "mag", 0)?,
            z_lens: z,
            free_mass: None,
        };
        Ok((p, z))
    }

    fn potfile(&self, b: &Block) -> Result<(ParPotfile, f64), ParError> {
        self.only(b, &[&POTFILE_KEYS], "a potfile")?;
        let filein = b.entries.get("filein").ok_or_else(|| ParError::Missing {
            file: self.file.into(),
            line: b.line,
            block: b.header.clone(),
            keyword: "filein",
        })?;
        let (mode, path) = (filein.values.first(), filein.values.get(1));
        let (Some("1" | "3"), Some(path)) = (mode.map(String::as_str), path) else {
            return Err(self.bad(b, "filein", filein, "expected `filein 1|3 <catalogue>`"));
        };
        for key in ["type", "profil"] {
            if let (Some(t), Some(e)) = (self.opt(b, key, 0)?, b.entries.get(key)) {
                if t != 81.0 {
                    return Err(self.bad(b, key, e, "only dPIE members (81) are supported"));
                }
            }
        }
        for key in ["vdscatter", "rcutscatter", "vdscat", "rcutscat"] {
            if let (Some(m), Some(e)) = (self.opt(b, key, 0)?, b.entries.get(key)) {
                if m != 0.0 {
                    return Err(self.bad(b, key, e, "random scatter (mode != 0) is not supported"));
                }
            }
        }
        let radius = |arcsec: &'static str, kpc: &'static str, k: usize| {
            Ok::<_, ParError>(match self.radius(b, arcsec, k)? {
                Some(r) => Radius::Arcsec(r),
                None => Radius::Kpc(
                    self.radius(b, kpc, k)?
                        .ok_or_else(|| self.missing(b, kpc))?,
                ),
            })
        };
        let p = ParPotfile {
            block: b.header.clone(),
            line: b.line,
            filein: path.clone(),
            mag0: self.req(b, "mag0", 0)?,
            // (mode, v1, v2): Lenstool evaluates at v1 (see the module documentation).
            sigma_km_s: self.req(b, "sigma", 1)?,
            r_core: radius("core", "corekpc", 0)?,
            r_cut: radius("cut", "cutkpc", 1)?,
            slope: self.opt(b, "slope", 1)?.unwrap_or(4.0),
            vdslope: self.opt(b, "vdslope", 1)?.unwrap_or(4.0),
        };
        if !(p.slope > 0.0 && p.vdslope > 0.0) {
            return Err(self.unsupported(b, "slope and vdslope must be positive".into()));
        }
        let z_key = if b.entries.contains_key("zlens") {
            "zlens"
        } else {
            "z_lens"
        };
        Ok((p, self.req(b, z_key, 0)?))
    }
}

/// What a text without a `cosmologie` block is instead, when it is plainly another kind of
/// file the user has (a catalogue, a JSON model): a clause for the error, else "".
fn other_kind(text: &str) -> &'static str {
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'));
    let Some(first) = first else {
        return "";
    };
    if first.starts_with('{') {
        return ": this looks like a JSON model file, not a Lenstool .par (give it with --model)";
    }
    let fields: Vec<&str> = first.split_whitespace().collect();
    let numbers = fields.iter().skip(1).take(6);
    if fields.len() >= 7 && numbers.clone().all(|f| f.parse::<f64>().is_ok()) {
        return ": this looks like a Lenstool catalogue (id x y a b theta z or mag ...), not a \
                parameter file (.par): give it with --images or --members (in the app, as the \
                image or member catalogue)";
    }
    ""
}
