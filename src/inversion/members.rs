//! Member galaxies: the WSLAP+ prior ([method §4], paper section 3).
//!
//! Each member gets a luminosity `L/L* = 10^(-0.4 (mag - mag*))` and a halo mass
//! `M = Upsilon L = Upsilon L* (L/L*)`. Defaults: `Upsilon = 20 Msun/Lsun` (the paper's
//! "ratio ~20") and `L* = 5e10 Lsun`, so an `L*` galaxy has `M* = 1e12 Msun`, a typical
//! total halo mass of an `L*` galaxy. `mag*` is the apparent magnitude of `L*`: given, or
//! `M*_abs + 5 log10(D_L / 10 pc)` with `M*_abs = -21.5` (about `L*` in the r/i bands for
//! H0 = 70, no K-correction) and `D_L = (1 + z_l)^2 D_l`.
//!
//! The halo is a truncated NFW (Baltz, Marshall & Oguri 2009) whose total mass is `M`
//! (or, with `profile = "nfw"`, an NFW with `M200 = M`). Its scale and truncation radii grow
//! self-similarly, `r_s = r_s* (M / M*)^e`, `r_t = r_t* (M / M*)^e` with `e = 1/3` (fixed mean
//! density; tidal truncation at a given cluster-centric distance also gives `r_t ∝ M^(1/3)`).
//! `r_t* = 40 kpc`: a truncated isothermal halo of `1e12 Msun` inside 40 kpc has
//! `sigma ~ 210 km/s`, as an `L*` elliptical, and galaxy-galaxy lensing in cluster cores finds
//! `r_t*` of 20-60 kpc (Limousin et al. 2007, Natarajan et al. 2009). `r_s* = 10 kpc`: then an
//! `L*` halo deflects by 1.1 arcsec at 5 kpc (`D_ls/D_s = 1`), as an SIS of 200 km/s
//! (1.15 arcsec) does; a field concentration (`c200 ~ 5`, `r_s ~ 70 kpc`) would give 0.3
//! arcsec, far too little for a galaxy whose centre is dominated by its stars. The parent NFW's
//! `rho_s` follows from `M = 4 pi rho_s r_s^3 m_tot(r_t / r_s)` and its `c200` from
//! `rho_s = (200/3) rho_crit c^3 / (ln(1 + c) - c/(1 + c))`.
//!
//! Members are grouped into layers, each one column `C_l` of the linear system whose fiducial
//! deflection is the sum of its galaxies' (`C_l = 1`: the catalogue masses are right).
//!
//! [method §4]: crate::method#4-member-galaxies

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::cells::CellGrid;
use crate::catalog::{CatalogRow, CommentedBcgs, Member, MemberCatalog};
use crate::cosmology::LensPlane;
use crate::error::{and_list, line_list};
use crate::profiles::{tnfw_total_mass_unit, Lens, MassComponent, Nfw, ProfileError, TruncatedNfw};

/// What can be wrong with member settings or a member galaxy.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MembersError {
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    #[error("members: layers = \"{value}\" is not one of none, single, bcg, brightest:N (N from 1 to {MAX_SINGLE_LAYERS})")]
    BadLayers { value: String },
    #[error(
        "{source_name}: line {line}: member {id}: {field} = {} is not allowed ({reason})", crate::error::number(*.value)
    )]
    BadMember {
        source_name: String,
        line: usize,
        id: String,
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
    #[error("{source_name}: line {line}: member {id}: its halo cannot be built: {source}")]
    Halo {
        source_name: String,
        line: usize,
        id: String,
        #[source]
        source: ProfileError,
    },
}

/// How members are grouped into layers (one `C_l` column each). In JSON a string:
/// `"none"`, `"single"`, `"bcg"` or `"brightest:N"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum LayerSplit {
    /// No member layer (the original WSLAP; the paper's case i).
    None,
    /// All members in one layer (the paper).
    Single,
    /// The brightest member alone, the rest in a second layer.
    Bcg,
    /// Each of the N brightest alone, the rest in one more layer (N from 1 to
    /// [`MAX_SINGLE_LAYERS`]).
    Brightest(usize),
}

/// Most members with a layer of their own (`brightest:N`): each is an unknown `C` that the
/// images must measure, which a few tens of them already hardly do.
pub const MAX_SINGLE_LAYERS: usize = 1000;

impl FromStr for LayerSplit {
    type Err = MembersError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || MembersError::BadLayers {
            value: s.to_string(),
        };
        match s.trim() {
            "none" => Ok(Self::None),
            "single" => Ok(Self::Single),
            "bcg" => Ok(Self::Bcg),
            t => match t
                .strip_prefix("brightest:")
                .map(|n| n.trim().parse::<usize>())
            {
                Some(Ok(n)) if (1..=MAX_SINGLE_LAYERS).contains(&n) => Ok(Self::Brightest(n)),
                _ => Err(bad()),
            },
        }
    }
}

impl fmt::Display for LayerSplit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::None => write!(f, "none"),
            Self::Single => write!(f, "single"),
            Self::Bcg => write!(f, "bcg"),
            Self::Brightest(n) => write!(f, "brightest:{n}"),
        }
    }
}

impl TryFrom<String> for LayerSplit {
    type Error = MembersError;
    fn try_from(s: String) -> Result<Self, Self::Error> {
        s.parse()
    }
}

impl From<LayerSplit> for String {
    fn from(l: LayerSplit) -> String {
        l.to_string()
    }
}

/// The halo profile given to each member.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HaloProfile {
    /// Truncated NFW whose total mass is the catalogue mass (default).
    Tnfw,
    /// Untruncated NFW with `M200` = the catalogue mass.
    Nfw,
}

/// Member-galaxy settings (the `members` block of an inversion configuration).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MemberConfig {
    /// Layer split: "none", "single" (default, the paper), "bcg" or "brightest:N".
    pub layers: LayerSplit,
    /// Apparent magnitude of an `L*` galaxy (default: from `abs_mag_star` and `D_L(z_l)`).
    pub mag_star: Option<f64>,
    /// Absolute magnitude of `L*` (default -21.5), used when `mag_star` is not given.
    pub abs_mag_star: f64,
    /// Mass-to-light ratio `Upsilon` in Msun/Lsun (default 20, the paper). Allowed (0, 1e4].
    pub mass_to_light: f64,
    /// `L*` in Lsun (default 5e10). Allowed (0, 1e13].
    pub l_star_lsun: f64,
    /// Halo profile (default "tnfw").
    pub profile: HaloProfile,
    /// Truncation radius of an `M*` halo in kpc (default 40). Allowed (0, 1e4].
    pub r_trunc_lstar_kpc: f64,
    /// Scale radius of an `M*` halo in kpc (default 10). Allowed (0, 1e4].
    pub r_s_lstar_kpc: f64,
    /// `r_s, r_t ∝ M^size_exponent` (default 1/3: self-similar). Allowed [0, 2].
    pub size_exponent: f64,
    /// Members farther than this fraction of the field width outside the grid are dropped
    /// with a warning (default 0.1). Allowed [0, 10].
    pub outside_margin_fraction: f64,
    /// Width of a Gaussian prior on every layer factor `C_l` around 1 (the M/L law as set):
    /// each layer adds the row `(C_l - 1) / c_prior_sigma = 0` to the system. Default none:
    /// `C_l` is free, as in the paper. Worth setting when the constraints are few (a catalogue
    /// of point images), which leave `C_l` to the start of QADP. Allowed (0, 100].
    pub c_prior_sigma: Option<f64>,
    /// The prior's width given to a layer that has none when the data hardly measure its
    /// factor (its independent share is below [`super::LAYER_SHARE_WARN`]: any change of
    /// `C_l` can be undone by the grid, so without it the regulariser, which costs the cells
    /// and not the members, would let `C_l` grow until the members are supercritical
    /// islands). Default 0.1: `C_l` stays at the luminosity scaling the catalogue implies.
    /// `null`: leave such a factor free. Allowed (0, 100].
    pub c_prior_sigma_unmeasured: Option<f64>,
    /// How uncertain the law's normalisation (`mass_to_light`) is, in dex (1 sigma of a
    /// log-normal; default 0.3, a factor 2). A reconstruction uses `mass_to_light` as set;
    /// each member of an ensemble draws its own from this scatter, so that the spread holds
    /// the members' mass where the images do not measure it (point images leave `C_l` at its
    /// prior). Published fits put the L* galaxy of a cluster far from any one law: the CATS
    /// Lenstool model of AS1063 fits 100 km/s, where its prior was 158 +- 27 km/s and this
    /// law's L* is about 200 km/s (mass ∝ sigma^2: 0.6 dex below the law). Allowed [0, 2].
    pub mass_to_light_scatter_dex: f64,
    /// When no member near the multiple images is as bright as a brightest cluster galaxy
    /// and commented-out rows of the catalogue there are, those rows are fitted as BCGs (one
    /// per core; default `true`): Lenstool set-ups model the BCGs in the `.par` and comment
    /// their rows out of the potfile catalogue, and without them the grid cannot hold their
    /// mass. `false`: the rows stay out and the run warns instead.
    pub fit_commented_bcg: bool,
}

/// Largest `MemberConfig::mass_to_light` a run accepts (Msun/Lsun).
pub(crate) const MAX_MASS_TO_LIGHT: f64 = 1e4;

/// Bisection steps for the parent concentration (`log c` over [1e-3, 1e3]: 2^-100 of that
/// interval is far below double precision).
const C200_BISECTIONS: usize = 100;
/// Concentrations the NFW profiles accept.
const C200_RANGE: (f64, f64) = (1.0e-3, 1.0e3);

impl Default for MemberConfig {
    fn default() -> Self {
        Self {
            layers: LayerSplit::Single,
            mag_star: None,
            abs_mag_star: -21.5,
            mass_to_light: 20.0,
            l_star_lsun: 5.0e10,
            profile: HaloProfile::Tnfw,
            r_trunc_lstar_kpc: 40.0,
            r_s_lstar_kpc: 10.0,
            size_exponent: 1.0 / 3.0,
            outside_margin_fraction: 0.1,
            c_prior_sigma: None,
            c_prior_sigma_unmeasured: Some(0.1),
            mass_to_light_scatter_dex: 0.3,
            fit_commented_bcg: true,
        }
    }
}

fn check(field: &'static str, v: f64, lo: f64, hi: f64, lo_open: bool) -> Result<(), MembersError> {
    let ok = v.is_finite() && v <= hi && if lo_open { v > lo } else { v >= lo };
    if ok {
        Ok(())
    } else {
        Err(crate::error::BadFieldValue::new(
            format!("members.{field}"),
            v,
            crate::error::range_reason(lo, hi, lo_open),
        )
        .into())
    }
}

impl MemberConfig {
    /// Checks every field against the range in its documentation.
    pub fn validate(&self) -> Result<(), MembersError> {
        if let Some(m) = self.mag_star {
            check("mag_star", m, -50.0, 50.0, false)?;
        }
        check("abs_mag_star", self.abs_mag_star, -50.0, 50.0, false)?;
        check(
            "mass_to_light",
            self.mass_to_light,
            0.0,
            MAX_MASS_TO_LIGHT,
            true,
        )?;
        check(
            "mass_to_light_scatter_dex",
            self.mass_to_light_scatter_dex,
            0.0,
            2.0,
            false,
        )?;
        check("l_star_lsun", self.l_star_lsun, 0.0, 1e13, true)?;
        check("r_trunc_lstar_kpc", self.r_trunc_lstar_kpc, 0.0, 1e4, true)?;
        check("r_s_lstar_kpc", self.r_s_lstar_kpc, 0.0, 1e4, true)?;
        check("size_exponent", self.size_exponent, 0.0, 2.0, false)?;
        if let Some(sigma) = self.c_prior_sigma {
            check("c_prior_sigma", sigma, 0.0, 100.0, true)?;
        }
        if let Some(sigma) = self.c_prior_sigma_unmeasured {
            check("c_prior_sigma_unmeasured", sigma, 0.0, 100.0, true)?;
        }
        check(
            "outside_margin_fraction",
            self.outside_margin_fraction,
            0.0,
            10.0,
            false,
        )?;
        if matches!(self.layers, LayerSplit::Brightest(n) if !(1..=MAX_SINGLE_LAYERS).contains(&n))
        {
            return Err(MembersError::BadLayers {
                value: self.layers.to_string(),
            });
        }
        Ok(())
    }

    /// Apparent magnitude of `L*` on `plane`: `mag_star`, or
    /// `abs_mag_star + 5 log10(D_L / Mpc) + 25` with `D_L = (1 + z_l)^2 D_l`.
    pub fn mag_star_on(&self, plane: &LensPlane) -> f64 {
        self.mag_star.unwrap_or_else(|| {
            let d_lum_mpc = (1.0 + plane.z_lens).powi(2) * plane.d_l_mpc;
            self.abs_mag_star + 5.0 * d_lum_mpc.log10() + 25.0
        })
    }

    /// Halo mass in Msun of a galaxy of apparent magnitude `mag`:
    /// `Upsilon L* 10^(-0.4 (mag - mag*))`.
    pub fn mass_msun(&self, mag: f64, mag_star: f64) -> f64 {
        self.mass_to_light * self.l_star_lsun * 10f64.powf(-0.4 * (mag - mag_star))
    }

    /// The apparent magnitude whose halo mass ([`Self::mass_msun`]) is `mass_msun`:
    /// `mag* - 2.5 log10(M / (Upsilon L*))`. A galaxy a Lenstool `.par` gives a mass but no
    /// magnitude becomes a member so.
    pub fn mag_of_mass(&self, mass_msun: f64, mag_star: f64) -> f64 {
        mag_star - 2.5 * (mass_msun / (self.mass_to_light * self.l_star_lsun)).log10()
    }

    /// Luminosity in `L*` of a galaxy of apparent magnitude `mag`: its halo mass
    /// ([`Self::mass_msun`]) over that of an `L*` galaxy.
    pub fn luminosity_lstar(&self, mag: f64, mag_star: f64) -> f64 {
        self.mass_msun(mag, mag_star) / (self.mass_to_light * self.l_star_lsun)
    }

    /// Truncation radius in kpc of a halo of mass `mass_msun`: `r_t* (M / M*)^e`.
    pub fn r_trunc_kpc(&self, mass_msun: f64) -> f64 {
        self.r_trunc_lstar_kpc * self.size_scale(mass_msun)
    }

    /// Scale radius in kpc of a halo of mass `mass_msun`: `r_s* (M / M*)^e`.
    pub fn r_s_kpc(&self, mass_msun: f64) -> f64 {
        self.r_s_lstar_kpc * self.size_scale(mass_msun)
    }

    /// `(M / M*)^e` with `M* = Upsilon L*`.
    fn size_scale(&self, mass_msun: f64) -> f64 {
        (mass_msun / (self.mass_to_light * self.l_star_lsun)).powf(self.size_exponent)
    }
}

/// One member's halo as built.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MemberHalo {
    /// Index into the member catalogue.
    pub member: usize,
    pub id: String,
    /// Position in arcsec.
    pub position: DVec2,
    pub mag: f64,
    /// `L / L*`.
    pub luminosity_lstar: f64,
    /// Catalogue mass `Upsilon L` in Msun (total mass of a truncated halo, M200 of an NFW).
    pub mass_msun: f64,
    /// M200 of the (parent) NFW in Msun.
    pub m200_msun: f64,
    /// Concentration of the (parent) NFW.
    pub c200: f64,
    /// Scale radius in arcsec.
    pub r_s_arcsec: f64,
    /// Truncation radius in arcsec (`None` for an untruncated NFW).
    pub r_trunc_arcsec: Option<f64>,
}

/// One galaxy layer: a fiducial deflection field with its own `C_l`.
#[derive(Debug, Clone)]
pub struct Layer {
    /// E.g. "members", "bcg", "member 12", "rest", or a name given to a true layer.
    pub name: String,
    /// Indices into the member catalogue (empty for a layer built from components).
    pub members: Vec<usize>,
    /// The summed halos at `D_ls/D_s = 1`, shared with reconstructed lenses.
    pub lens: Arc<Lens>,
    /// Width of the Gaussian prior on this layer's factor `C_l` around 1, if any
    /// ([`MemberConfig::c_prior_sigma`]).
    pub prior_sigma: Option<f64>,
    /// What `C_l` scales: galaxies, or one half of an external shear's component.
    pub kind: LayerKind,
}

/// What a layer's factor `C_l` scales.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LayerKind {
    /// Galaxies: `C_l` rescales their masses from the luminosity law (members, or a test's
    /// true galaxies).
    #[default]
    Galaxies,
    /// One signed half of an external shear's component `gamma1` or `gamma2`
    /// ([`super::external_shear_layers`]): no mass, no galaxy.
    ExternalShear {
        /// 1 or 2.
        component: u8,
        /// The `-gamma` half.
        negative: bool,
    },
}

impl LayerKind {
    /// Whether the layer is galaxies (its factor is a member factor `C`).
    pub fn is_galaxies(self) -> bool {
        self == Self::Galaxies
    }
}

/// Pairs each member layer of `layers` (galaxies, not an external shear's) with its value
/// in `per_layer` (one value per layer, in order): the one filter behind every "C" a user
/// reads (the summary's factors and their measurability, the convergence record, the
/// warnings).
pub fn member_layers_with<T>(
    layers: &[Layer],
    per_layer: impl IntoIterator<Item = T>,
) -> impl Iterator<Item = (&Layer, T)> {
    layers
        .iter()
        .zip(per_layer)
        .filter(|(layer, _)| layer.kind.is_galaxies())
}

impl Layer {
    /// A layer made directly from mass components (e.g. the true galaxies of a test).
    pub fn from_components(name: &str, components: Vec<Box<dyn MassComponent>>) -> Self {
        Self {
            name: name.to_string(),
            members: Vec::new(),
            lens: Arc::new(Lens::new(components)),
            prior_sigma: None,
            kind: LayerKind::Galaxies,
        }
    }

    /// Fiducial deflection `alpha_l` at `p` (arcsec), in arcsec, for `D_ls/D_s = 1`.
    pub fn deflection(&self, p: DVec2) -> DVec2 {
        self.lens.deflection(p)
    }
}

/// The members' halos and layers, with warnings about members left out.
#[derive(Debug, Clone)]
pub struct MemberModel {
    /// Halos of the members used, in catalogue order.
    pub halos: Vec<MemberHalo>,
    pub layers: Vec<Layer>,
    pub warnings: Vec<String>,
}

/// How far (in magnitudes) a member may lie from the L* magnitude it is scaled from: `10^8`
/// times brighter or fainter. Beyond, the catalogue's magnitudes and the L* magnitude are in
/// different bands (or one is a typo), and a member would weigh far more than a cluster or
/// next to nothing. Used for `mag_star` here and for a Lenstool potfile's `mag0`.
pub(crate) const MAX_MAG_FROM_L_STAR: f64 = 20.0;

/// `mu(c) = ln(1 + c) - c/(1 + c)` (dimensionless).
fn nfw_mu(c: f64) -> f64 {
    c.ln_1p() - c / (1.0 + c)
}

/// The `c200` whose NFW has characteristic density `rho_s` (Msun/Mpc^3) on `plane`:
/// `(200/3) rho_crit c^3 / mu(c) = rho_s`, by bisection in `log c` (the left side grows with
/// `c`); `None` outside [`C200_RANGE`].
fn c200_for_rho_s(rho_s: f64, plane: &LensPlane) -> Option<f64> {
    let g = |c: f64| 200.0 / 3.0 * plane.rho_crit_msun_per_mpc3 * c * c * c / nfw_mu(c) - rho_s;
    let (mut lo, mut hi) = C200_RANGE;
    if !(g(lo) <= 0.0 && g(hi) >= 0.0) {
        return None;
    }
    for _ in 0..C200_BISECTIONS {
        let mid = (lo * hi).sqrt();
        if g(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some((lo * hi).sqrt())
}

/// One member's halo component with its parent-NFW M200 (Msun), c200 and truncation radius
/// (arcsec).
pub(crate) type BuiltHalo = (Box<dyn MassComponent>, f64, f64, Option<f64>);

/// Builds the halo of one member of catalogue mass `mass_msun` at `position` (module
/// documentation): a truncated NFW of total mass `M`, or an NFW of `M200 = M`.
pub(crate) fn member_halo(
    config: &MemberConfig,
    position: DVec2,
    mass_msun: f64,
    plane: &LensPlane,
) -> Result<BuiltHalo, ProfileError> {
    let r_s_mpc = config.r_s_kpc(mass_msun) * 1e-3;
    let no_c200 = ProfileError::BadParameter {
        component: "member halo",
        field: "r_s",
        value: r_s_mpc * 1e3,
        reason: "r_s in kpc needs a concentration outside [1e-3, 1e3] for this mass",
    };
    match config.profile {
        HaloProfile::Nfw => {
            let r200_mpc = (3.0 * mass_msun
                / (800.0 * std::f64::consts::PI * plane.rho_crit_msun_per_mpc3))
                .cbrt();
            let c = r200_mpc / r_s_mpc;
            if !(C200_RANGE.0..=C200_RANGE.1).contains(&c) {
                return Err(no_c200);
            }
            let nfw = Nfw::new(position, mass_msun, c, plane)?;
            Ok((Box::new(nfw), mass_msun, c, None))
        }
        HaloProfile::Tnfw => {
            let r_t_mpc = config.r_trunc_kpc(mass_msun) * 1e-3;
            let tau = r_t_mpc / r_s_mpc;
            let rho_s = mass_msun
                / (4.0 * std::f64::consts::PI * r_s_mpc.powi(3) * tnfw_total_mass_unit(tau));
            let c = c200_for_rho_s(rho_s, plane).ok_or(no_c200)?;
            let m200 = 4.0 * std::f64::consts::PI * rho_s * r_s_mpc.powi(3) * nfw_mu(c);
            let r_t_arcsec = r_t_mpc / plane.mpc_per_arcsec;
            let tnfw = TruncatedNfw::new(position, m200, c, r_t_arcsec, plane)?;
            Ok((Box::new(tnfw), m200, c, Some(r_t_arcsec)))
        }
    }
}

/// Halos ([method §4]) and layers of the members of `catalog` that lie inside the
/// field of `grid` grown by `outside_margin_fraction` of its width; the others are left out
/// with a warning each. Layers are split by brightness (lowest magnitude first, ties by
/// catalogue order); empty layers are not made.
///
/// One warning for the members `outside` the field (none when there are none): a lone member
/// by line, id and position; several by their lines, so that a catalogue of the whole cluster
/// (AS1063's has 99 beyond its 108 arcsec field) gives one line, not 99.
fn outside_warning(
    catalog: &MemberCatalog,
    outside: &[&Member],
    width_arcsec: f64,
    margin_arcsec: f64,
) -> Option<String> {
    let field = format!("(grid of {width_arcsec:.1} arcsec plus {margin_arcsec:.1} arcsec margin)");
    match outside {
        [] => None,
        [m] => Some(format!(
            "{}: line {}: member {} at ({:.2}, {:.2}) arcsec lies outside the field {field}: \
             not used",
            catalog.source_name, m.line, m.id, m.position.x, m.position.y
        )),
        many => Some(format!(
            "{}: {} members lie outside the field {field} and are not used: lines {}",
            catalog.source_name,
            many.len(),
            line_list(many.iter().map(|m| m.line))
        )),
    }
}

/// [method §4]: crate::method#4-member-galaxies
pub fn build_member_layers(
    catalog: &MemberCatalog,
    config: &MemberConfig,
    plane: &LensPlane,
    grid: &CellGrid,
) -> Result<MemberModel, MembersError> {
    config.validate()?;
    let mag_star = config.mag_star_on(plane);
    let margin = config.outside_margin_fraction * grid.width_arcsec;
    let mut outside = Vec::new();
    let mut halos = Vec::new();
    let mut components: Vec<Box<dyn MassComponent>> = Vec::new();
    for (index, m) in catalog.members.iter().enumerate() {
        let bad_member =
            |field: &'static str, value: f64, reason: &'static str| MembersError::BadMember {
                source_name: catalog.source_name.clone(),
                line: m.line,
                id: m.id.clone(),
                field,
                value,
                reason,
            };
        for (field, v) in [("x", m.position.x), ("y", m.position.y)] {
            if !v.is_finite() {
                return Err(bad_member(field, v, "a position in arcsec must be finite"));
            }
        }
        if !(m.mag.is_finite() && (m.mag - mag_star).abs() <= MAX_MAG_FROM_L_STAR) {
            return Err(bad_member(
                "mag",
                m.mag,
                "must be within 20 magnitudes of mag_star",
            ));
        }
        if !grid.contains(m.position, margin) {
            outside.push(m);
            continue;
        }
        let mass_msun = config.mass_msun(m.mag, mag_star);
        let (component, m200_msun, c200, r_trunc_arcsec) =
            member_halo(config, m.position, mass_msun, plane).map_err(|source| {
                MembersError::Halo {
                    source_name: catalog.source_name.clone(),
                    line: m.line,
                    id: m.id.clone(),
                    source,
                }
            })?;
        components.push(component);
        halos.push(MemberHalo {
            member: index,
            id: m.id.clone(),
            position: m.position,
            mag: m.mag,
            luminosity_lstar: config.luminosity_lstar(m.mag, mag_star),
            mass_msun,
            m200_msun,
            c200,
            r_s_arcsec: config.r_s_kpc(mass_msun) * 1e-3 / plane.mpc_per_arcsec,
            r_trunc_arcsec,
        });
    }
    let warnings = outside_warning(catalog, &outside, grid.width_arcsec, margin)
        .into_iter()
        .collect();
    let layers = split_layers(
        config.layers,
        &halos,
        components,
        config.c_prior_sigma,
        &catalog.free_mass_galaxies,
    );
    Ok(MemberModel {
        halos,
        layers,
        warnings,
    })
}

/// Groups the halos (with their components, in the same order) into layers, each with the
/// prior `prior_sigma` on its factor. The members at the indices `free_mass` (the `.par`
/// galaxies whose mass it leaves free: [`MemberCatalog::free_mass_galaxies`]) come first, one
/// layer each; then `split` groups the others.
fn split_layers(
    split: LayerSplit,
    halos: &[MemberHalo],
    components: Vec<Box<dyn MassComponent>>,
    prior_sigma: Option<f64>,
    free_mass: &[usize],
) -> Vec<Layer> {
    if split == LayerSplit::None {
        return Vec::new();
    }
    let mut slots: Vec<Option<Box<dyn MassComponent>>> = components.into_iter().map(Some).collect();
    let mut layers = Vec::new();
    let (free, bound): (Vec<usize>, Vec<usize>) =
        (0..halos.len()).partition(|&k| free_mass.contains(&halos[k].member));
    for k in free {
        layers.push(Layer {
            name: format!("galaxy {} (mass free in the .par)", halos[k].id),
            members: vec![halos[k].member],
            lens: Arc::new(Lens::new(slots[k].take().into_iter().collect())),
            prior_sigma,
            kind: LayerKind::Galaxies,
        });
    }
    let n_alone = match split {
        LayerSplit::None | LayerSplit::Single => 0,
        LayerSplit::Bcg => 1,
        LayerSplit::Brightest(n) => n,
    }
    .min(bound.len());
    let mut order = bound;
    order.sort_by(|&i, &j| halos[i].mag.total_cmp(&halos[j].mag).then(i.cmp(&j)));
    for (rank, &k) in order[..n_alone].iter().enumerate() {
        let name = if split == LayerSplit::Bcg {
            "bcg".to_string()
        } else {
            format!("member {} (rank {})", halos[k].id, rank + 1)
        };
        layers.push(Layer {
            name,
            members: vec![halos[k].member],
            lens: Arc::new(Lens::new(slots[k].take().into_iter().collect())),
            prior_sigma,
            kind: LayerKind::Galaxies,
        });
    }
    let mut rest: Vec<usize> = order[n_alone..].to_vec();
    rest.sort_unstable();
    if !rest.is_empty() {
        let name = if n_alone == 0 { "members" } else { "rest" };
        layers.push(Layer {
            name: name.to_string(),
            members: rest.iter().map(|&k| halos[k].member).collect(),
            lens: Arc::new(Lens::new(
                rest.iter().filter_map(|&k| slots[k].take()).collect(),
            )),
            prior_sigma,
            kind: LayerKind::Galaxies,
        });
    }
    layers
}

/// Luminosity (in `L*`) that the brightest galaxy of a cluster core at least has: a brightest
/// cluster galaxy (BCG) is typically 2 to 3 magnitudes brighter than `L*` (5 to 15 `L*`), so a
/// core whose brightest member stays below 4 `L*` (1.5 magnitudes) has most likely lost it.
pub const BCG_MIN_LSTAR: f64 = 4.0;

/// Luminosity (in `L*`) above which a commented-out row is not taken for the brightest cluster
/// galaxy: the most luminous BCGs reach about 25 `L*` (absolute magnitude -25 against `L*`'s
/// -21.5), so a brighter row is more likely a star or a foreground galaxy the catalogue
/// commented out for that reason.
pub const BCG_MAX_LSTAR: f64 = 50.0;

/// A warning when no member near the multiple images is as bright as a brightest cluster
/// galaxy ([`BCG_MIN_LSTAR`]), `None` otherwise (or without members or images).
///
/// `members` and `commented` are the catalogue's rows and its commented-out rows
/// ([`MemberCatalog::commented`]), each with its luminosity in `L*`
/// ([`MemberConfig::luminosity_lstar`]). "Near" is within the median distance of the images
/// (`images`, arcsec) from their centroid. Lenstool set-ups often model the BCG as its own
/// `potentiel` in the `.par` and leave it out of the potfile catalogue (both real catalogues
/// this crate is measured on do), and a grid whose cells are several arcsec wide cannot hold
/// that much mass in so small a place: on MACS1931 the held-out images move from 1.78 to 1.41
/// arcsec when the catalogue's commented BCG row is fitted (BENCHMARKS.md).
///
/// Every commented-out row near the images that is bright enough (and not too bright:
/// [`BCG_MAX_LSTAR`]) is named ([`MissingBcg::commented`], in the file's order): a set-up that
/// models the BCG in the `.par` often keeps its row commented out in the catalogue, one row
/// for each core of a cluster with several, and a run fits them by default
/// ([`MemberConfig::fit_commented_bcg`], `Dataset::fit_commented_bcgs`).
///
/// `par` names the `.par` whose galaxies were added to the members, if one was given: with no
/// commented row to offer, the warning then says that file models none there, instead of
/// asking for a `.par`.
pub fn missing_bcg_warning(
    catalog_name: &str,
    par: Option<&str>,
    members: &[(&Member, f64)],
    images: &[DVec2],
    commented: &[(&Member, f64)],
) -> Option<MissingBcg> {
    if members.is_empty() || images.is_empty() {
        return None;
    }
    let centre = images.iter().copied().sum::<DVec2>() / images.len() as f64;
    let mut distances: Vec<f64> = images.iter().map(|p| p.distance(centre)).collect();
    distances.sort_by(f64::total_cmp);
    let radius = crate::stats::quantile(&distances, 0.5).max(1.0);
    // Members nowhere near the images (SGAS J1152's catalogue rows all lie 3.5' from its
    // arcs): a missing BCG is the wrong thing to suggest; the catalogue's frame or cluster is
    // what to check.
    let reach = distances.last().copied().unwrap_or(0.0).max(radius);
    let nearest = members
        .iter()
        .map(|(m, _)| (m, m.position.distance(centre)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    if let Some((m, d)) = nearest.filter(|(_, d)| *d > 2.0 * reach) {
        return Some(MissingBcg {
            warning: format!(
                "{catalog_name}: no member lies near the multiple images: the nearest, {} (line \
                 {}), is {d:.0} arcsec from their centre, and the farthest image {reach:.0} \
                 arcsec. Is the member catalogue of this cluster, and in the images' frame (its \
                 #REFERENCE header)?",
                m.id, m.line
            ),
            commented: None,
            members_far: true,
        });
    }
    let brightest = members
        .iter()
        .filter(|(m, _)| m.position.distance(centre) <= radius)
        .max_by(|a, b| a.1.total_cmp(&b.1));
    if brightest.is_some_and(|b| b.1 >= BCG_MIN_LSTAR) {
        return None;
    }
    let there = match brightest {
        Some((m, lstar)) => format!(
            "the brightest there is member {} at mag {:.2} ({lstar:.1} L*)",
            m.id, m.mag
        ),
        None => "there is none there".to_string(),
    };
    let finding = format!(
        "{catalog_name}: no member within {radius:.0} arcsec of the multiple images' centre \
         is as bright as a brightest cluster galaxy ({BCG_MIN_LSTAR} L* or more): {there}"
    );
    // Every commented row of a BCG's luminosity near the images, in the file's order: a
    // cluster with two cores has two BCGs, and a set-up that models them in the .par comments
    // out both.
    let mut rows: Vec<(&Member, f64)> = commented
        .iter()
        .copied()
        .filter(|(m, lstar)| {
            (BCG_MIN_LSTAR..=BCG_MAX_LSTAR).contains(lstar) && m.position.distance(centre) <= radius
        })
        .collect();
    rows.sort_by_key(|(m, _)| m.line);
    let described = |(m, lstar): &(&Member, f64)| {
        format!(
            "{} ({:.0} arcsec from that centre, mag {:.2}, {lstar:.1} L*)",
            m.id,
            m.position.distance(centre),
            m.mag
        )
    };
    let lines = and_list(rows.iter().map(|(m, _)| m.line.to_string()));
    let ids = and_list(rows.iter().map(described));
    // The words that agree with the number of rows, in one place.
    let (line_s, member_s, comment_s, it, they_are_fitted, if_that) = if rows.len() == 1 {
        let fitted = "it is fitted as the BCG";
        (
            "line",
            "member",
            "comments",
            "it",
            fitted,
            "that is the BCG",
        )
    } else {
        let fitted = "they are fitted as BCGs";
        (
            "lines",
            "members",
            "comment",
            "them",
            fitted,
            "those are the BCGs",
        )
    };
    let cure = match (rows.is_empty(), par) {
        (true, None) => "If the cluster has one, add its row (id x y a b theta mag lum) to the \
                         member catalogue, or give the .par that models it (wslap reconstruct \
                         --par; in the app, load it as the model file with \"Galaxies and \
                         redshift priors from the .par\" on)"
            .to_string(),
        (true, Some(par)) => format!(
            "The .par given ({par}) models no galaxy near the images either: if the cluster has a \
             BCG there, add its row (id x y a b theta mag lum) to the member catalogue"
        ),
        (false, _) => {
            let mut said = format!(
            "{line_s} {lines} {comment_s} out {member_s} {ids}: if {if_that}, remove the '#' to \
             fit {it}"
        );
            said[..1].make_ascii_uppercase();
            said
        }
    };
    let warning = format!(
        "{finding}. Lenstool set-ups often model the BCG as its own `potentiel` in the .par and \
         leave it out of the potfile catalogue (sometimes as a commented row); the grid cannot \
         hold that much mass in so small a place. {cure}"
    );
    let commented = (!rows.is_empty()).then(|| CommentedBcgs {
        rows: rows
            .iter()
            .map(|(m, _)| CatalogRow {
                line: m.line,
                id: m.id.clone(),
            })
            .collect(),
        note: format!(
            "{finding}, but {line_s} {lines} {comment_s} out {member_s} {ids}: \
             {they_are_fitted}, which Lenstool set-ups model in the .par and comment out of the \
             potfile catalogue. To leave {it} out, set members.fit_commented_bcg to false (in \
             the app: \"Fit commented-out BCG rows\")"
        ),
    });
    Some(MissingBcg {
        warning,
        commented,
        members_far: false,
    })
}

/// What [`missing_bcg_warning`] found: its warning and the commented-out rows that could be
/// the cluster's BCGs, if any.
#[derive(Debug, Clone, PartialEq)]
pub struct MissingBcg {
    pub warning: String,
    pub commented: Option<CommentedBcgs>,
    /// No member lies near the images at all (the catalogue is of another field, or in
    /// another frame): the warning asks about that, not about a BCG.
    pub members_far: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only the galaxies' layers keep their values, in order; an external shear's do not.
    #[test]
    fn member_layers_with_skips_the_shear_layers() {
        let mut shear = Layer::from_components("shear", Vec::new());
        shear.kind = LayerKind::ExternalShear {
            component: 1,
            negative: false,
        };
        let layers = [
            Layer::from_components("members", Vec::new()),
            shear,
            Layer::from_components("bcg", Vec::new()),
        ];
        let kept: Vec<(&str, f64)> = member_layers_with(&layers, [1.0, 2.0, 3.0])
            .map(|(l, c)| (l.name.as_str(), c))
            .collect();
        assert_eq!(kept, [("members", 1.0), ("bcg", 3.0)]);
    }

    /// A member of `luminosity_lstar` with `L*` at mag 20.
    fn halo(id: &str, x: f64, y: f64, luminosity_lstar: f64) -> Member {
        commented(id, 1, x, y, 20.0 - 2.5 * luminosity_lstar.log10())
    }

    /// `members` with their luminosity, `L*` at mag 20.
    fn lum(members: &[Member]) -> Vec<(&Member, f64)> {
        let lstar = |m: &Member| 10f64.powf(-0.4 * (m.mag - 20.0));
        members.iter().map(|m| (m, lstar(m))).collect()
    }

    /// Four images on a ring of 20 arcsec about (10, -5).
    fn ring() -> Vec<DVec2> {
        [(30.0, -5.0), (-10.0, -5.0), (10.0, 15.0), (10.0, -25.0)]
            .map(|(x, y)| DVec2::new(x, y))
            .to_vec()
    }

    #[test]
    fn a_par_already_given_is_not_asked_for() {
        let halos = [halo("7", 12.0, -3.0, 1.0)];
        let asks = missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &[])
            .expect("a warning")
            .warning;
        assert!(asks.contains("or give the .par that models it"), "{asks}");
        let given = missing_bcg_warning("m.cat", Some("best.par"), &lum(&halos), &ring(), &[])
            .expect("a warning")
            .warning;
        assert!(!given.contains("give the .par"), "{given}");
        assert!(
            given.ends_with(
                "The .par given (best.par) models no galaxy near the images either: if the \
                 cluster has a BCG there, add its row (id x y a b theta mag lum) to the member \
                 catalogue"
            ),
            "{given}"
        );
    }

    #[test]
    fn a_core_without_a_bright_member_is_named() {
        // The brightest member of the catalogue lies far outside the images; inside, an L*.
        let halos = [halo("far", 150.0, 0.0, 20.0), halo("7", 12.0, -3.0, 1.0)];
        let w = missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &[])
            .expect("a warning")
            .warning;
        assert!(w.starts_with("m.cat: no member within 20 arcsec of the multiple images' centre is as bright as a brightest cluster galaxy (4 L* or more)"), "{w}");
        assert!(w.contains("member 7 at mag 20.00 (1.0 L*)"), "{w}");
        // The centre is (10, -5): a bright member 20.1 arcsec from it is not counted, and
        // alone it leaves no member there at all.
        let halos = [halo("edge", 10.0, 15.1, 8.0), halo("7", 12.0, -3.0, 1.0)];
        assert!(missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &[]).is_some());
        let w = missing_bcg_warning("m.cat", None, &lum(&halos[..1]), &ring(), &[])
            .expect("a warning")
            .warning;
        assert!(w.contains("there is none there"), "{w}");
    }

    #[test]
    fn members_nowhere_near_the_images_ask_for_the_frame_not_a_bcg() {
        // Every row far beyond the images (ring of 20 arcsec about (10, -5)), as when the
        // catalogue is of another field or frame: no BCG is asked for.
        let halos = [halo("a", 210.0, -5.0, 8.0), halo("b", 10.0, 240.0, 1.0)];
        let missing = missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &[]).unwrap();
        assert_eq!(
            missing.warning,
            "m.cat: no member lies near the multiple images: the nearest, a (line 1), is 200 \
             arcsec from their centre, and the farthest image 20 arcsec. Is the member \
             catalogue of this cluster, and in the images' frame (its #REFERENCE header)?"
        );
        assert!(missing.commented.is_none() && missing.members_far);
        // One member among the images is enough for the usual search.
        let halos = [halos[0].clone(), halo("7", 12.0, -3.0, 1.0)];
        let w = missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &[]).unwrap();
        assert!(w.warning.contains("member 7 at mag 20.00"), "{}", w.warning);
        assert!(!w.members_far);
    }

    fn commented(id: &str, line: usize, x: f64, y: f64, mag: f64) -> Member {
        Member {
            id: id.to_string(),
            position: DVec2::new(x, y),
            a_arcsec: 1.0,
            b_arcsec: 1.0,
            theta_deg: 0.0,
            mag,
            lum: 0.0,
            line,
        }
    }

    #[test]
    fn a_commented_bcg_row_near_the_images_is_named_with_its_line() {
        let halos = [halo("7", 12.0, -3.0, 1.0)];
        let (bcg, faint) = (
            commented("1009", 10, 10.0, -3.0, 17.3),
            commented("1186", 19, 11.0, -6.0, 24.7),
        );
        let far = commented("far", 30, 150.0, 0.0, 16.0);
        let rows = [(&faint, 0.02), (&bcg, 9.5), (&far, 20.0)];
        let found =
            missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &rows).expect("a warning");
        let row = CatalogRow {
            line: 10,
            id: "1009".to_string(),
        };
        let named = found.commented.expect("the row is named");
        assert_eq!(named.rows, [row]);
        // The note a run that fits it carries says what was found and how to leave it out.
        assert!(
            named.note.starts_with(
                "m.cat: no member within 20 arcsec of the multiple images' centre is as \
                 bright as a brightest cluster galaxy (4 L* or more): the brightest there is \
                 member 7 at mag 20.00 (1.0 L*), but line 10 comments out member 1009 (2 \
                 arcsec from that centre, mag 17.30, 9.5 L*): it is fitted as the BCG"
            ),
            "{}",
            named.note
        );
        assert!(named.note.ends_with(
            "set members.fit_commented_bcg to false (in the app: \"Fit commented-out BCG rows\")"
        ));
        let w = found.warning;
        assert!(
            w.ends_with(
                "Line 10 comments out member 1009 (2 arcsec from that centre, mag 17.30, 9.5 \
                 L*): if that is the BCG, remove the '#' to fit it"
            ),
            "{w}"
        );
        // Too bright to be a galaxy of the cluster: a star, say, is passed over for the BCG.
        let star = commented("star", 5, 9.0, -4.0, 12.0);
        let with_star = [rows[0], (&star, 400.0), rows[1], rows[2]];
        let found = missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &with_star).unwrap();
        assert_eq!(found.commented.map(|c| c.rows[0].line), Some(10));
        let found =
            missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &with_star[..2]).unwrap();
        assert_eq!(found.commented, None);
        // Faint or far commented rows are not offered: the generic advice stays.
        let found =
            missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &[rows[0], rows[2]]).unwrap();
        assert_eq!(found.commented, None);
        let w = found.warning;
        assert!(w.ends_with(
            "add its row (id x y a b theta mag lum) to the member catalogue, or give the .par \
             that models it (wslap reconstruct --par; in the app, load it as the model file \
             with \"Galaxies and redshift priors from the .par\" on)"
        ));
    }

    #[test]
    fn every_commented_bcg_row_of_a_cluster_with_two_cores_is_named() {
        // Two cores, each BCG commented out (the synthetic bimodal clusters of BENCHMARKS.md);
        // the list is in the file's order, not by brightness.
        let halos = [halo("7", 12.0, -3.0, 1.0)];
        let east = commented("1", 72, 0.0, -8.0, 18.1);
        let west = commented("2", 73, 24.0, 0.0, 17.9);
        let far = commented("far", 80, 150.0, 0.0, 17.0);
        let rows = [(&west, 7.0), (&far, 9.0), (&east, 6.0)];
        let found =
            missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &rows).expect("a warning");
        let named = found.commented.expect("the rows are named");
        let lines: Vec<(usize, &str)> =
            named.rows.iter().map(|r| (r.line, r.id.as_str())).collect();
        assert_eq!(lines, [(72, "1"), (73, "2")]);
        assert!(
            named.note.contains(
                "but lines 72 and 73 comment out members 1 (10 arcsec from that centre, mag \
                 18.10, 6.0 L*) and 2 (15 arcsec from that centre, mag 17.90, 7.0 L*): they \
                 are fitted as BCGs, "
            ),
            "{}",
            named.note
        );
        assert!(named
            .note
            .contains("To leave them out, set members.fit_commented_bcg"));
        assert!(
            found.warning.ends_with(
                "Lines 72 and 73 comment out members 1 (10 arcsec from that centre, mag 18.10, \
                 6.0 L*) and 2 (15 arcsec from that centre, mag 17.90, 7.0 L*): if those are \
                 the BCGs, remove the '#' to fit them"
            ),
            "{}",
            found.warning
        );
    }

    #[test]
    fn a_bright_central_member_or_no_members_need_no_warning() {
        let halos = [halo("far", 150.0, 0.0, 20.0), halo("bcg", 9.0, -4.0, 8.0)];
        assert_eq!(
            missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &[]),
            None
        );
        // Just at the threshold, and just inside the radius.
        let halos = [halo("bcg", 10.0, 14.9, BCG_MIN_LSTAR)];
        assert_eq!(
            missing_bcg_warning("m.cat", None, &lum(&halos), &ring(), &[]),
            None
        );
        assert_eq!(missing_bcg_warning("m.cat", None, &[], &ring(), &[]), None);
        assert_eq!(
            missing_bcg_warning("m.cat", None, &lum(&halos), &[], &[]),
            None
        );
    }
}
