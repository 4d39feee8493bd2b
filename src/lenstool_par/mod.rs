//! Lenstool parameter files (`.par`) of parametric cluster models, read far enough to evaluate
//! the published models: `runmode` (`reference`), `potentiel` blocks of profile 81 (dPIE,
//! [`Dpie`]) and 14 (external shear, [`ExternalShear`]), `potfile` blocks (cluster members
//! from a catalogue, scaled with luminosity), `cosmologie`, and the `z_m_limit` lines of the
//! `image` block (the priors on the redshifts of multiple-image systems, which a
//! reconstruction takes: [`ParRedshiftPrior`]). Every other block (`grille`, `cline`, ...)
//! and keyword is skipped: a model is evaluated with the values written in its
//! `potentiel` blocks, which in a `bestopt.par` are the fitted ones. `limit` blocks are read
//! for one thing only: the uniform priors a starting `.par` puts on a galaxy's mass
//! ([`FreeMass`]), which a reconstruction takes instead of the written start.
//!
//! The file is read as Lenstool reads it ([`parse_par_with`]): `#` comments anywhere, any
//! whitespace, CR line ends; lines between blocks that do not open a Lenstool block (the stray
//! `end` of many `bestopt.par` files, unknown words such as Lenstool-HPC's `frame`) are skipped;
//! a keyword Lenstool does not read in a `potentiel` or `potfile` block (e.g. `identity`) is
//! ignored with a [`ParWarning`], while one it reads but this reader does not implement is
//! refused; `fini` (or `finish`) ends the file. A dPIE without a core radius, or with
//! `core_radius 0`, has Lenstool's singular core. Potentials at several redshifts are refused
//! unless [`ParOptions::single_plane`] asks for the single-plane approximation.
//!
//! Conventions, from Lenstool's source (github.com/cerschae/Lenstool-HPC,
//! ChiBenchmark/lenstoolchi/src: `r_potentiel.c`, `set_potfile.c`, `o_print_res.c`,
//! `o_set_lens_bayes.c`):
//! - A `potfile` keyword with a mode flag (`sigma 3 100.1 18.7`) is read as `(mode, v1, v2)`
//!   and Lenstool evaluates the model at `v1`: mode 0 is a fixed value, 1 a uniform prior on
//!   `[v1, v2]` (starting at `v1`), 3 a Gaussian prior of mean `v1` and width `v2`. A
//!   `bestopt.par` from a Bayesian run (`inverse 3`) writes there the posterior median and
//!   `limit * stddev`; the best sample's own value is not written, so the median is used.
//! - Members (`filein 1` or `3`: rows `id x y a b theta mag lum`) are dPIEs of mass
//!   ellipticity `(a^2 - b^2)/(a^2 + b^2)` at angle `theta`, scaled from the `L*` galaxy of
//!   magnitude `mag0` with `L/L* = 10^(-0.4 (mag - mag0))`:
//!   `sigma = sigma* (L/L*)^(1/vdslope)`, `r_cut = r_cut* (L/L*)^(2/slope)`,
//!   `r_core = r_core* (L/L*)^(1/2)`.
//! - The k-th `limit` block belongs to the k-th `potentiel`, whatever number its header
//!   writes (Lenstool-HPC's `module_readParameters.cpp`); a line `v_disp 1 150 450 0.1` is a
//!   uniform prior on `[150, 450]` (mode 3: a normal of mean and width; 0: fixed).
//! - Radii in kpc become arcsec with the lens plane's `mpc_per_arcsec`; in a `potentiel`
//!   block the kpc value wins when both are given, in a `potfile` the arcsec one (as Lenstool).
//! - The shear `gamma` is at `D_ls/D_s = 1` like every Lenstool deflection; its `kappa`
//!   keyword is not read by Lenstool and must be 0 here.

use glam::DVec2;
use thiserror::Error;

use crate::catalog::{CatalogError, CatalogWarning, Member, MemberCatalog};
use crate::cosmology::{Cosmology, CosmologyError, LensPlane};
use crate::profiles::{Dpie, ExternalShear, Lens, MassComponent, ProfileError};
use crate::sky::SkyReference;

mod read;

pub use read::{parse_par, parse_par_with};

/// Redshifts of the potentials that differ by more than this make a multi-plane model.
pub(crate) const Z_MATCH_TOL: f64 = 1.0e-6;

/// What is wrong with a `.par` file or the model it describes; every variant names the file.
#[derive(Debug, Error)]
pub enum ParError {
    #[error("{file}: cannot read: {message}")]
    Io { file: String, message: String },
    #[error("{file}:{line}: {reason}")]
    Syntax {
        file: String,
        line: usize,
        reason: String,
    },
    #[error("{file}:{line}: `{keyword}` in block `{block}`: {reason} (got `{value}`)")]
    BadValue {
        file: String,
        line: usize,
        block: String,
        keyword: &'static str,
        value: String,
        reason: &'static str,
    },
    #[error("{file}:{line}: block `{block}`: {reason}")]
    Unsupported {
        file: String,
        line: usize,
        block: String,
        reason: String,
    },
    #[error("{file}:{line}: block `{block}` has no `{keyword}`")]
    Missing {
        file: String,
        line: usize,
        block: String,
        keyword: &'static str,
    },
    #[error("{file}: {reason}")]
    Model { file: String, reason: String },
    #[error("{file}:{line}: block `{block}`: {source}")]
    Profile {
        file: String,
        line: usize,
        block: String,
        #[source]
        source: ProfileError,
    },
    #[error("{file}: cosmologie: {source}")]
    Cosmology {
        file: String,
        #[source]
        source: CosmologyError,
    },
    #[error(transparent)]
    Catalog(Box<CatalogError>),
    #[error("{catalog}:{line}: member `{id}`: {reason}")]
    Member {
        catalog: String,
        line: usize,
        id: String,
        reason: String,
    },
}

/// How a `.par` file is read.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ParOptions {
    /// The single-plane approximation of a multi-plane model (default `false`: such a model is
    /// refused). Every `potentiel` / `potfile` block whose `z_lens` differs from the first
    /// block's is evaluated on the first block's plane, keeping its angular sizes (kpc radii
    /// converted on its own plane) and velocity dispersion, so its deflection scales with that
    /// plane's `D_ls/D_s`; the lensing of one plane by another is ignored. Each moved block is
    /// named in a [`ParWarning`].
    pub single_plane: bool,
}

impl ParOptions {
    /// How a `.par` is read for the galaxies it models on its own ([`LenstoolPar::galaxies`]):
    /// with the single-plane approximation, since only the galaxies at the first block's
    /// redshift are taken, so a model with a group at another redshift (Abell 370's CATS model
    /// has one at z = 1.05) gives its cluster galaxies without the setting.
    pub fn for_galaxies(self) -> Self {
        Self { single_plane: true }
    }
}

/// Something in a `.par` file that Lenstool accepts and the model is built without, or an
/// approximation asked for, worth telling the user.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParWarning {
    pub file: String,
    /// 1-based line.
    pub line: usize,
    pub message: String,
    /// The header of the block (e.g. `potfile1`) when the warning says that a block at another
    /// redshift was moved to the cluster's plane by the single-plane approximation
    /// ([`ParOptions::single_plane`]): a reader that takes only the galaxies at the cluster's
    /// redshift uses nothing of that block.
    pub moved_block: Option<String>,
}

impl std::fmt::Display for ParWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: {}", self.file, self.line, self.message)
    }
}

/// A radius as the file gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Radius {
    Arcsec(f64),
    Kpc(f64),
}

impl Radius {
    /// The radius in arcsec on `plane`.
    pub fn arcsec(self, plane: &LensPlane) -> f64 {
        match self {
            Radius::Arcsec(r) => r,
            Radius::Kpc(r) => r / (1.0e3 * plane.mpc_per_arcsec),
        }
    }
}

/// Largest core radius (kpc) of a `potentiel` that [`LenstoolPar::galaxies`] takes for a galaxy:
/// the CATS model of AS1063 gives its BCG (O3) 0.5 kpc and its north-east group (O4) 49 kpc.
pub const GALAXY_MAX_CORE_KPC: f64 = 5.0;

/// A `potentiel` on the lens plane with a core too wide for a galaxy (over
/// [`GALAXY_MAX_CORE_KPC`]; [`ParGalaxies::halos`]): a cluster's or a group's halo, or a
/// galaxy a set-up gives a wide core, whose mass the grid models.
#[derive(Debug, Clone, PartialEq)]
pub struct ParHalo {
    /// The block's name, e.g. `potentiel O1`.
    pub block: String,
    /// The block's first line (1-based).
    pub line: usize,
    /// Its core radius in kpc.
    pub core_kpc: f64,
}

/// The galaxies of a `.par` ([`LenstoolPar::galaxies`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ParGalaxies {
    /// Those with a `mag`, as member rows in the file's frame.
    pub members: Vec<Member>,
    /// Those without one, with what a member made of them needs instead (see
    /// [`GalaxyWithoutMag`]).
    pub without_mag: Vec<GalaxyWithoutMag>,
    /// Galaxies at another redshift than [`LenstoolPar::z_lens`] (read with the single-plane
    /// approximation), not the cluster's: each block's name, line and `z_lens`.
    pub other_plane: Vec<(String, usize, f64)>,
    /// The dPIEs on the lens plane with a core too wide for a galaxy (over
    /// [`GALAXY_MAX_CORE_KPC`]).
    pub halos: Vec<ParHalo>,
}

/// A galaxy of a `.par` with a velocity dispersion but no `mag` (a fitted `bestopt.par`
/// lists each galaxy it modelled so; a starting `.par` gives its BCG a dispersion to fit).
#[derive(Debug, Clone, PartialEq)]
pub struct GalaxyWithoutMag {
    /// The block's name, e.g. `potentiel 510`.
    pub block: String,
    /// Its last word, the id of a member made of it (`510`).
    pub id: String,
    /// The block's first line (1-based).
    pub line: usize,
    /// Its centre in arcsec, in the file's frame.
    pub centre: DVec2,
    /// The dPIE's total mass in Msun ([`Dpie::total_mass_msun`]), or `None` when the block's
    /// radii make no dPIE (a cut radius not above the core).
    pub mass_msun: Option<f64>,
    /// Axis ratio `b/a` from the mass ellipticity, as for the members with a `mag`.
    pub axis_ratio: f64,
    /// Position angle, degrees counter-clockwise from +x.
    pub pa_deg: f64,
    /// When its `limit` block leaves its mass free ([`FreeMass`]), `mass_msun` is the dPIE at
    /// the priors' low ends: that block's line and the dPIE's `[v_disp (km/s), core (kpc),
    /// cut (kpc)]`.
    pub at_prior_low_end: Option<(usize, [f64; 3])>,
}

/// One mass component of a `potentiel` block (positions in arcsec, angles in degrees
/// counter-clockwise from +x).
#[derive(Debug, Clone, PartialEq)]
pub enum ParComponent {
    /// Profile 81; `sigma_v_km_s` is Lenstool's `v_disp`, `ellipticity` its `ellipticite`.
    Dpie {
        center_arcsec: DVec2,
        sigma_v_km_s: f64,
        r_core: Radius,
        r_cut: Radius,
        ellipticity: f64,
        pa_deg: f64,
    },
    /// Profile 14.
    Shear {
        center_arcsec: DVec2,
        gamma: f64,
        pa_deg: f64,
    },
}

/// A `potentiel` block: its header (e.g. `potentiel O1`), line and component.
#[derive(Debug, Clone, PartialEq)]
pub struct ParPotential {
    pub block: String,
    pub line: usize,
    pub component: ParComponent,
    /// The block's `mag`, when it gives one (Lenstool scales a galaxy's dPIE with it; a BCG
    /// modelled on its own usually has it).
    pub mag: Option<f64>,
    /// The block's own `z_lens` (before a single-plane approximation moved it).
    pub z_lens: f64,
    /// The uniform priors its `limit` block puts on its mass (see [`FreeMass`]), when it puts
    /// any.
    pub free_mass: Option<FreeMass>,
}

/// The low ends of the uniform priors (`limit` lines of mode 1, `v_disp 1 150 450 0.1`) a
/// `.par`'s `limit` block puts on a dPIE's velocity dispersion and radii: in a starting
/// `.par` the `potentiel` block's values are where Lenstool's fit starts, not a mass it
/// measured (MACS J1149's CATS `m1149.par` writes the lens of SN Refsdal at 311 km/s with a
/// 206 kpc cut radius, outside its own prior of 30 - 70 kpc; the fit found 162 km/s and 55
/// kpc). A reconstruction takes such a galaxy at its least mass within the priors, the
/// written value where a prior starts at 0 ([`LenstoolPar::galaxies`]), in a layer of its
/// own: the grid adds what the images ask for, but cannot take mass away. The model itself
/// ([`LenstoolPar::build`]) is evaluated with the written values, as Lenstool evaluates it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeMass {
    /// The `limit` block's first line.
    pub line: usize,
    /// The low end of `v_disp`'s prior (km/s); `None` without a prior or when it starts at 0
    /// (no least mass: the written value stays).
    pub sigma_v_km_s: Option<f64>,
    /// The low end of the core radius's prior, likewise.
    pub r_core: Option<Radius>,
    /// The low end of the cut radius's prior, likewise.
    pub r_cut: Option<Radius>,
}

/// A `potfile` block: the member catalogue and the `L*` galaxy of the scaling relations.
#[derive(Debug, Clone, PartialEq)]
pub struct ParPotfile {
    pub block: String,
    pub line: usize,
    /// The `filein` path as written (relative to wherever Lenstool ran).
    pub filein: String,
    pub mag0: f64,
    pub sigma_km_s: f64,
    pub r_core: Radius,
    pub r_cut: Radius,
    pub slope: f64,
    pub vdslope: f64,
}

impl ParPotfile {
    /// Lenstool's scaling for a member of magnitude `mag`: `(sigma [km/s], r_core [arcsec],
    /// r_cut [arcsec])` with `L/L* = 10^(-0.4 (mag - mag0))` (see the module documentation).
    pub fn scaled(&self, mag: f64, plane: &LensPlane) -> (f64, f64, f64) {
        let lum = 10f64.powf(0.4 * (self.mag0 - mag));
        (
            self.sigma_km_s * lum.powf(1.0 / self.vdslope),
            self.r_core.arcsec(plane) * lum.sqrt(),
            self.r_cut.arcsec(plane) * lum.powf(2.0 / self.slope),
        )
    }

    /// The member `m` of `catalog` as a dPIE on `plane`.
    fn member(&self, m: &Member, catalog: &str, plane: &LensPlane) -> Result<Dpie, ParError> {
        let fail = |reason: String| ParError::Member {
            catalog: catalog.to_string(),
            line: m.line,
            id: m.id.clone(),
            reason,
        };
        let (a, b) = (m.a_arcsec, m.b_arcsec);
        if !(a >= b && a > 0.0) {
            return Err(fail(format!(
                "needs a >= b and a > 0 for the ellipticity (a = {a}, b = {b}; Lenstool refuses it too)"
            )));
        }
        if m.mag == 0.0 {
            return Err(fail("magnitude 0 (Lenstool would give it no mass)".into()));
        }
        let (sigma, core, cut) = self.scaled(m.mag, plane);
        // Far outside any galaxy, too heavy or (more than MAX_MAG_FROM_L_STAR magnitudes
        // fainter than L*) all but massless: the scaling's L* magnitude and the catalogue's
        // magnitudes disagree (another band, a typo). Blame both, not the row alone.
        if (m.mag - self.mag0).abs() > crate::inversion::MAX_MAG_FROM_L_STAR
            || crate::profiles::require_sigma_v("dpie", sigma).is_err()
        {
            return Err(fail(format!(
                "magnitude {} scaled from the L* galaxy of potfile `{}` (the block at line {}: \
                 mag0 = {}, sigma = {} km/s) gives a velocity dispersion of {:.2e} km/s; check \
                 that mag0 and the catalogue's magnitudes are in the same band",
                m.mag,
                self.block,
                self.line,
                crate::error::number(self.mag0),
                crate::error::number(self.sigma_km_s),
                sigma,
            )));
        }
        let e = (a * a - b * b) / (a * a + b * b);
        Dpie::new(m.position, sigma, core, cut, e, m.theta_deg)
            .map_err(|e| fail(format!("{e} (potfile `{}`)", self.block)))
    }
}

/// The model of a `.par` file, as written (no file read yet).
#[derive(Debug, Clone, PartialEq)]
pub struct LenstoolPar {
    pub source_name: String,
    /// `runmode reference 1|3 ra dec`; `None` without one.
    pub reference: Option<SkyReference>,
    pub cosmology: Cosmology,
    /// The redshift shared by every potential.
    pub z_lens: f64,
    pub potentials: Vec<ParPotential>,
    pub potfiles: Vec<ParPotfile>,
    /// The redshift priors of multiple-image systems, from the `image` block's `z_m_limit`
    /// lines, in the file's order.
    pub redshift_priors: Vec<ParRedshiftPrior>,
    /// The `source` block's redshift keywords, as written (read only when a catalogue row has
    /// no redshift: [`Self::unknown_source_z`]).
    pub source_z: ParSourceZ,
    /// What was skipped or approximated while reading (unknown blocks and keywords, blocks
    /// moved by the single-plane approximation).
    pub warnings: Vec<ParWarning>,
}

/// Lenstool's redshift for a source without one when the `.par` gives no `z_source`
/// (its manual, `source` section).
pub const LENSTOOL_DEFAULT_Z_SOURCE: f64 = 0.8;

/// The redshift keywords of a `.par`'s `source` block, as written: `z_source z` (the redshift
/// Lenstool gives sources without one, default [`LENSTOOL_DEFAULT_Z_SOURCE`]) and `dist_z kind
/// ...` (how it draws simulated sources' redshifts: 0 all at `z_source`, 1 uniform between two
/// redshifts, 2 the Smail et al. law of the `smail` keyword). Each is its values and line.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParSourceZ {
    pub z_source: Option<(Vec<String>, usize)>,
    pub dist_z: Option<(Vec<String>, usize)>,
}

/// The redshift a `.par` gives catalogue rows without one ([`LenstoolPar::unknown_source_z`]).
#[derive(Debug, Clone, PartialEq)]
pub struct UnknownSourceZ {
    pub z: f64,
    /// Where it comes from, for the reader's warning: "z_source 1.5 of x.par's `source`
    /// block (line 12)" or "Lenstool's default 0.8: x.par gives no z_source".
    pub origin: String,
}

/// One `z_m_limit` line: the prior a Lenstool model put on a system's redshift.
#[derive(Debug, Clone, PartialEq)]
pub struct ParRedshiftPrior {
    /// 1-based line.
    pub line: usize,
    /// The system's id as the line writes it (`6` or `6.0`).
    pub system: String,
    pub prior: crate::inversion::RedshiftPrior,
}

/// A model ready to evaluate: the lens (reference normalisation) and its plane.
#[derive(Debug)]
pub struct LenstoolModel {
    pub lens: Lens,
    pub plane: LensPlane,
    pub reference: Option<SkyReference>,
    /// Components from `potentiel` blocks, then members from the potfiles.
    pub potentials: usize,
    pub members: usize,
}

impl LenstoolPar {
    /// The redshift this `.par` gives sources without one, as Lenstool does: its `source`
    /// block's `z_source`, else Lenstool's default 0.8. Refused, with the reason, when the
    /// block draws redshifts from a distribution (`dist_z` 1 or 2: a catalogue row without a
    /// redshift then stands for many, which one redshift does not stand for) or when
    /// `z_source` is not a redshift.
    pub fn unknown_source_z(&self) -> Result<UnknownSourceZ, String> {
        let file = &self.source_name;
        if let Some((values, line)) = &self.source_z.dist_z {
            let kind = values.first().map(String::as_str).unwrap_or("");
            if kind.parse::<f64>() != Ok(0.0) {
                let law = match kind {
                    "1" => "uniform between two redshifts",
                    "2" => "the Smail et al. law of its `smail` line",
                    _ => "a law this tool does not know",
                };
                return Err(format!(
                    "{file} (line {line}: dist_z {}) draws the redshifts of sources without \
                     one from a distribution ({law}), which this tool does not model",
                    values.join(" ")
                ));
            }
        }
        let Some((values, line)) = &self.source_z.z_source else {
            return Ok(UnknownSourceZ {
                z: LENSTOOL_DEFAULT_Z_SOURCE,
                origin: format!(
                    "Lenstool's default {LENSTOOL_DEFAULT_Z_SOURCE}: {file} gives no z_source"
                ),
            });
        };
        let written = values.first().map(String::as_str).unwrap_or("");
        match written.parse::<f64>() {
            Ok(z) if z.is_finite() && z > 0.0 => Ok(UnknownSourceZ {
                z,
                origin: format!("z_source {written} of {file}'s `source` block (line {line})"),
            }),
            _ => Err(format!(
                "{file} (line {line}): z_source '{written}' is not a redshift (a number above 0)"
            )),
        }
    }

    /// The frame a member catalogue given with this `.par` is read in when it has no header:
    /// [`Self::reference`] when the `.par` has a `potfile` block (the catalogue is its potfile,
    /// whose positions Lenstool reads as arcsec from the reference), else `None`.
    pub fn potfile_reference(&self) -> Option<SkyReference> {
        self.reference.filter(|_| !self.potfiles.is_empty())
    }

    /// The lens plane at [`Self::z_lens`] in the file's cosmology.
    pub fn lens_plane(&self) -> Result<LensPlane, ParError> {
        LensPlane::new(self.cosmology, self.z_lens).map_err(|source| ParError::Cosmology {
            file: self.source_name.clone(),
            source,
        })
    }

    /// The galaxies the file models on their own: its dPIE `potentiel` blocks with a core of
    /// at most [`GALAXY_MAX_CORE_KPC`] (a BCG's is below a kpc; a group or cluster halo's tens
    /// of kpc), as member rows in the file's frame (id: the block's name, e.g. `O3`; a and b
    /// from the ellipticity `(a^2 - b^2)/(a^2 + b^2)`; line: the block's). Those without a
    /// `mag`, which a member needs, come second with their dPIE's mass ([`GalaxyWithoutMag`];
    /// a massless one, `v_disp 0`, is left out); those at another redshift (a single-plane
    /// read, [`ParOptions::for_galaxies`]) third; the wider ones on the lens plane last
    /// ([`ParGalaxies::halos`]).
    pub fn galaxies(&self) -> Result<ParGalaxies, ParError> {
        let plane = self.lens_plane()?;
        let (mut rows, mut without_mag, mut other_plane) = (Vec::new(), Vec::new(), Vec::new());
        let mut halos = Vec::new();
        for p in &self.potentials {
            let ParComponent::Dpie {
                center_arcsec,
                sigma_v_km_s,
                r_core,
                r_cut,
                ellipticity,
                pa_deg,
            } = p.component
            else {
                continue;
            };
            let core_kpc = r_core.arcsec(&plane) * plane.mpc_per_arcsec * 1.0e3;
            let same_plane = (p.z_lens - self.z_lens).abs() <= Z_MATCH_TOL;
            if core_kpc > GALAXY_MAX_CORE_KPC {
                if same_plane {
                    halos.push(ParHalo {
                        block: p.block.clone(),
                        line: p.line,
                        core_kpc,
                    });
                }
                continue;
            }
            if !same_plane {
                other_plane.push((p.block.clone(), p.line, p.z_lens));
                continue;
            }
            let id = p.block.split_whitespace().last().unwrap_or("potentiel");
            let e = ellipticity.clamp(0.0, 0.99);
            let axis_ratio = ((1.0 - e) / (1.0 + e)).sqrt();
            let Some(mag) = p.mag else {
                // A massless potential (a node of a grid model) is no galaxy to fit.
                if sigma_v_km_s > 0.0 {
                    // Where a `limit` block leaves the mass free, its least mass there.
                    let free = p.free_mass.as_ref();
                    let sigma = free.and_then(|f| f.sigma_v_km_s).unwrap_or(sigma_v_km_s);
                    let (core, cut) = (
                        free.and_then(|f| f.r_core).unwrap_or(r_core).arcsec(&plane),
                        free.and_then(|f| f.r_cut).unwrap_or(r_cut).arcsec(&plane),
                    );
                    let mass_msun = Dpie::new(center_arcsec, sigma, core, cut, e, pa_deg)
                        .ok()
                        .map(|d| d.total_mass_msun(&plane));
                    let kpc = 1.0e3 * plane.mpc_per_arcsec;
                    without_mag.push(GalaxyWithoutMag {
                        block: p.block.clone(),
                        id: id.to_string(),
                        line: p.line,
                        centre: center_arcsec,
                        mass_msun,
                        axis_ratio,
                        pa_deg,
                        at_prior_low_end: p
                            .free_mass
                            .map(|f| (f.line, [sigma, core * kpc, cut * kpc])),
                    });
                }
                continue;
            };
            rows.push(Member {
                id: id.to_string(),
                position: center_arcsec,
                a_arcsec: 1.0,
                b_arcsec: axis_ratio,
                theta_deg: pa_deg,
                mag,
                lum: 0.0,
                line: p.line,
            });
        }
        Ok(ParGalaxies {
            members: rows,
            without_mag,
            other_plane,
            halos,
        })
    }

    /// Where the member catalogues of the `potfile` blocks are when the `.par` file is
    /// `par_path`, one per block, each with a sentence when it is not where Lenstool run in the
    /// `.par`'s folder would look. The first of these that exists: the block's `filein`
    /// relative to the `.par`'s folder (as Lenstool reads it when run there); as written,
    /// relative to the working folder (as Lenstool reads it when run here); its file name
    /// alone in the `.par`'s folder (a package that keeps its files together, whose `.par`
    /// names a folder of the modeller's machine, e.g. `../model/a2390/cgalVzK.cat`). When none
    /// exists, the first, whose error then names it.
    pub fn potfile_paths(
        &self,
        par_path: &std::path::Path,
    ) -> Vec<(std::path::PathBuf, Option<String>)> {
        let dir = par_path.parent().unwrap_or(std::path::Path::new("."));
        self.potfiles
            .iter()
            .map(|p| {
                let beside_par = dir.join(&p.filein);
                if beside_par.exists() {
                    return (beside_par, None);
                }
                let written = std::path::PathBuf::from(&p.filein);
                let by_name = std::path::Path::new(&p.filein)
                    .file_name()
                    .map(|name| dir.join(name));
                let found = [Some(written), by_name]
                    .into_iter()
                    .flatten()
                    .find(|path| path.is_file());
                match found {
                    None => (beside_par, None),
                    Some(path) => {
                        let note = format!(
                            "{}: line {}: the potfile's `filein {}` is not in the .par's folder \
                             ({} does not exist): {} is read instead",
                            self.source_name,
                            p.line,
                            p.filein,
                            beside_par.display(),
                            path.display()
                        );
                        (path, Some(note))
                    }
                }
            })
            .collect()
    }

    /// [`Self::build`] from the texts of the member catalogues, `(name, text)` one per
    /// `potfile` block in order, each read in the frame of [`Self::reference`] as Lenstool
    /// does; also returns the catalogues' warnings.
    pub fn build_from_texts(
        &self,
        member_texts: &[(impl AsRef<str>, impl AsRef<str>)],
    ) -> Result<(LenstoolModel, Vec<CatalogWarning>), ParError> {
        let mut catalogs = Vec::with_capacity(member_texts.len());
        let mut warnings = Vec::new();
        for (name, text) in member_texts {
            let (catalog, w) =
                crate::catalog::parse_potfile_catalog(text.as_ref(), name.as_ref(), self.reference)
                    .map_err(|e| ParError::Catalog(Box::new(e)))?;
            warnings.extend(w);
            catalogs.push(catalog);
        }
        Ok((self.build(&catalogs)?, warnings))
    }

    /// Builds the lens: one component per `potentiel` block (but a dPIE with `v_disp 0`,
    /// which has no mass), then one dPIE per member of
    /// `member_catalogs[k]` for the `k`-th `potfile` block (read them with
    /// [`crate::catalog::parse_member_catalog`] in the frame of [`Self::reference`]).
    pub fn build(&self, member_catalogs: &[MemberCatalog]) -> Result<LenstoolModel, ParError> {
        if member_catalogs.len() != self.potfiles.len() {
            return Err(ParError::Model {
                file: self.source_name.clone(),
                reason: format!(
                    "{} potfile block(s) but {} member catalogue(s) given",
                    self.potfiles.len(),
                    member_catalogs.len()
                ),
            });
        }
        let plane = self.lens_plane()?;
        let mut components: Vec<Box<dyn MassComponent>> = Vec::new();
        for p in &self.potentials {
            let profile = |source| ParError::Profile {
                file: self.source_name.clone(),
                line: p.line,
                block: p.block.clone(),
                source,
            };
            match p.component {
                ParComponent::Dpie {
                    center_arcsec,
                    sigma_v_km_s,
                    r_core,
                    r_cut,
                    ellipticity,
                    pa_deg,
                } => {
                    // Massless, as Lenstool evaluates it: the nodes of a non-parametric grid
                    // (`nmsgrid`) start at zero.
                    if sigma_v_km_s == 0.0 {
                        continue;
                    }
                    let (core, cut) = (r_core.arcsec(&plane), r_cut.arcsec(&plane));
                    let d = Dpie::new(center_arcsec, sigma_v_km_s, core, cut, ellipticity, pa_deg);
                    components.push(Box::new(d.map_err(profile)?));
                }
                ParComponent::Shear {
                    center_arcsec,
                    gamma,
                    pa_deg,
                } => {
                    let s = ExternalShear::new(center_arcsec, gamma, pa_deg);
                    components.push(Box::new(s.map_err(profile)?));
                }
            }
        }
        let potentials = components.len();
        for (pf, cat) in self.potfiles.iter().zip(member_catalogs) {
            for m in &cat.members {
                components.push(Box::new(pf.member(m, &cat.source_name, &plane)?));
            }
        }
        let members = components.len() - potentials;
        Ok(LenstoolModel {
            lens: Lens::new(components),
            plane,
            reference: self.reference,
            potentials,
            members,
        })
    }
}

/// Reads `par_path` and its member catalogues and builds the model. `member_paths` gives one
/// catalogue per `potfile` block in order; when empty, each `filein` is found as
/// [`LenstoolPar::potfile_paths`] finds it.
#[cfg(not(target_arch = "wasm32"))]
pub fn load_lenstool_model(
    par_path: &std::path::Path,
    member_paths: &[&std::path::Path],
) -> Result<LenstoolModel, ParError> {
    let read = |path: &std::path::Path| {
        std::fs::read_to_string(path).map_err(|e| ParError::Io {
            file: path.display().to_string(),
            message: e.to_string(),
        })
    };
    let par = parse_par(&read(par_path)?, &par_path.display().to_string())?;
    let paths: Vec<std::path::PathBuf> = if member_paths.is_empty() {
        par.potfile_paths(par_path)
            .into_iter()
            .map(|(path, _)| path)
            .collect()
    } else {
        member_paths.iter().map(|p| p.to_path_buf()).collect()
    };
    let texts = paths
        .iter()
        .map(|path| Ok((path.display().to_string(), read(path)?)))
        .collect::<Result<Vec<_>, ParError>>()?;
    Ok(par.build_from_texts(&texts)?.0)
}
