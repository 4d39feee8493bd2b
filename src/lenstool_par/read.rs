//! The text layer of a `.par` file: blocks, keywords and values, and their interpretation
//! into [`LenstoolPar`] (see the parent module for the conventions).

use std::collections::HashMap;

use glam::DVec2;

use super::{LenstoolPar, ParComponent, ParError, ParPotential, ParPotfile, Radius, Z_MATCH_TOL};
use crate::cosmology::Cosmology;
use crate::sky::SkyReference;

/// One `keyword values...` line of a block.
#[derive(Debug, Clone)]
struct Entry {
    line: usize,
    values: Vec<String>,
}

/// A block: header words, first line, entries by keyword (the last one wins, as in Lenstool).
#[derive(Debug, Clone)]
struct Block {
    header: String,
    line: usize,
    entries: HashMap<String, Entry>,
}

/// Parses the text of a `.par` file (`source_name` is used in messages). Comments start at
/// `#`; blocks run from a header line to `end`; `fini` ends the file.
pub fn parse_par(text: &str, source_name: &str) -> Result<LenstoolPar, ParError> {
    let blocks = read_blocks(text, source_name)?;
    let name = |b: &Block| b.header.split_whitespace().next().unwrap_or("").to_string();
    let mut cx = Ctx {
        file: source_name,
        reference: None,
    };
    // The reference first: `_wcs` centres need it wherever `runmode` stands.
    if let Some(b) = blocks.iter().find(|b| name(b) == "runmode") {
        cx.reference = cx.reference(b)?;
    }
    let mut cosmology = None;
    let mut potentials = Vec::new();
    let mut potfiles = Vec::new();
    let mut z_values: Vec<(f64, &Block)> = Vec::new();
    for b in &blocks {
        let name = name(b);
        match name.as_str() {
            "cosmologie" | "cosmology" => cosmology = Some(cx.cosmology(b)?),
            "potentiel" | "potential" => {
                let (p, z) = cx.potential(b)?;
                potentials.push(p);
                z_values.push((z, b));
            }
            _ if name.starts_with("potfile") => {
                let (p, z) = cx.potfile(b)?;
                potfiles.push(p);
                z_values.push((z, b));
            }
            _ => {}
        }
    }
    let cosmology = cosmology.ok_or_else(|| cx.model("no `cosmologie` block"))?;
    let &(z_lens, _) = z_values
        .first()
        .ok_or_else(|| cx.model("no `potentiel` or `potfile` block"))?;
    if let Some((z, b)) = z_values
        .iter()
        .find(|(z, _)| (z - z_lens).abs() > Z_MATCH_TOL)
    {
        return Err(cx.unsupported(
            b,
            format!("z_lens = {z} differs from {z_lens} (multi-plane models are not supported)"),
        ));
    }
    Ok(LenstoolPar {
        source_name: source_name.to_string(),
        reference: cx.reference,
        cosmology,
        z_lens,
        potentials,
        potfiles,
    })
}

/// Splits the text into blocks.
fn read_blocks(text: &str, file: &str) -> Result<Vec<Block>, ParError> {
    let mut blocks = Vec::new();
    let mut open: Option<Block> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let body = raw.split('#').next().unwrap_or("").trim();
        let mut words = body.split_whitespace();
        let Some(first) = words.next() else { continue };
        match open.as_mut() {
            None if first == "fini" => break,
            None => {
                let header = body.split_whitespace().collect::<Vec<_>>().join(" ");
                open = Some(Block {
                    header,
                    line,
                    entries: HashMap::new(),
                });
            }
            Some(_) if first == "end" => blocks.extend(open.take()),
            Some(b) => {
                let values = words.map(str::to_string).collect();
                b.entries.insert(first.to_string(), Entry { line, values });
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

/// A `cosmologie` keyword, the test its value (and omegaM) must pass, and the message.
type FlatCheck = (&'static str, fn(f64, f64) -> bool, &'static str);

/// Interprets blocks, with the file name for messages and the frame's sky reference.
struct Ctx<'a> {
    file: &'a str,
    reference: Option<SkyReference>,
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
const POTFILE_KEYS: [&str; 14] = [
    "filein",
    "zlens",
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
];

impl Ctx<'_> {
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
    fn req(&self, b: &Block, key: &'static str, k: usize) -> Result<f64, ParError> {
        self.opt(b, key, k)?.ok_or_else(|| ParError::Missing {
            file: self.file.into(),
            line: b.line,
            block: b.header.clone(),
            keyword: key,
        })
    }
    /// Fails on a keyword outside `allowed`, naming it and its line.
    fn only(&self, b: &Block, allowed: &[&[&str]], what: &str) -> Result<(), ParError> {
        let known = |k: &str| allowed.iter().any(|s| s.contains(&k)) || k.starts_with("mag");
        let mut unknown: Vec<_> = b.entries.iter().filter(|(k, _)| !known(k)).collect();
        unknown.sort_by_key(|(_, e)| e.line);
        match unknown.first() {
            None => Ok(()),
            Some((k, e)) => Err(ParError::Unsupported {
                file: self.file.into(),
                line: e.line,
                block: b.header.clone(),
                reason: format!("keyword `{k}` is not supported for {what}"),
            }),
        }
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
        let ol_key = if b.entries.contains_key("omegaX") {
            "omegaX"
        } else {
            "lambda"
        };
        let checks: [FlatCheck; 3] = [
            (
                ol_key,
                |v, om| (om + v - 1.0).abs() < 1e-6,
                "only flat models are supported",
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
                    Ok::<_, ParError>(match (self.opt(b, kpc, 0)?, self.opt(b, arcsec, 0)?) {
                        // Lenstool: a non-zero kpc value wins over the arcsec one.
                        (Some(r), _) if r != 0.0 => Some(Radius::Kpc(r)),
                        (_, Some(r)) => Some(Radius::Arcsec(r)),
                        (kpc, None) => kpc.map(Radius::Kpc),
                    })
                };
                let missing = |keyword| ParError::Missing {
                    file: self.file.into(),
                    line: b.line,
                    block: b.header.clone(),
                    keyword,
                };
                let r_core = radius("core_radius_kpc", "core_radius")?
                    .ok_or_else(|| missing("core_radius_kpc"))?;
                let r_cut = radius("cut_radius_kpc", "cut_radius")?
                    .ok_or_else(|| missing("cut_radius_kpc"))?;
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
        for key in ["vdscatter", "rcutscatter"] {
            if let (Some(m), Some(e)) = (self.opt(b, key, 0)?, b.entries.get(key)) {
                if m != 0.0 {
                    return Err(self.bad(b, key, e, "random scatter (mode != 0) is not supported"));
                }
            }
        }
        let radius = |arcsec: &'static str, kpc: &'static str, k: usize| {
            Ok::<_, ParError>(match self.opt(b, arcsec, k)? {
                Some(r) => Radius::Arcsec(r),
                None => Radius::Kpc(self.req(b, kpc, k)?),
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
        Ok((p, self.req(b, "zlens", 0)?))
    }
}
