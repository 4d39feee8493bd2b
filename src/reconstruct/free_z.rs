//! Redshifts for systems that have none: estimated on the lens of the other systems, then
//! fitted at the estimate.
//!
//! Many multiple-image systems of a real catalogue have no spectroscopic redshift (AS1063
//! silver: 22 of 72 images). The redshift of a system enters the lens equation only through
//! `f = D_ls/D_s`, which scales the deflection: `beta = theta - f(z) alpha(theta)`. With the
//! lens known, the images of one source back-project onto one point only at the right `f`.
//!
//! The estimate, per system (its images `theta_k`, k = 1..N, on the lens `alpha` fitted to
//! the systems with a redshift, which never saw this one):
//!
//! 1. For each `z` on a fine grid over the prior range `[z_lo, z_hi]`
//!    (`constraints.free_z_prior`, default 0.5 to 8, the low end raised to just behind the
//!    lens), back-project: `beta_k(z) = theta_k - f(z) alpha(theta_k)`.
//! 2. Turn the source-plane scatter into image-plane offsets, as the fit does
//!    ([`crate::inversion::capped_inverse_jacobian`]): `d_k = M_k (beta_k - beta)` with
//!    `M_k` the inverse of the lens Jacobian `A_k = I - f(z) H(theta_k)`, its stretch capped at
//!    `objective.max_stretch`. The source `beta` that minimises `sum |d_k|^2` is the weighted
//!    mean `(sum M_k^T M_k)^-1 sum M_k^T M_k beta_k`.
//! 3. `chi2(z) = sum_k |d_k|^2 / (sigma^2 / 2)`, with `sigma` the model's own error for images
//!    it was not given: the held-out rms of the cross-validation that chose the regulariser's
//!    strength (an "auto" strength), else [`FALLBACK_SIGMA_ARCSEC`]. When the best `z` still
//!    leaves a reduced chi2 above 1 (`2N - 3` degrees of freedom), `sigma` is scaled up by its
//!    square root (the images disagree with the lens more than its typical error, so the
//!    interval must widen).
//! 4. The posterior `p(z) ~ exp(-chi2 / 2)` (a flat prior in `z` over the range, or the
//!    system's own prior when it has one, `constraints.z_priors`: a range narrows the range,
//!    a normal multiplies the posterior by its density; a `.par`'s `z_m_limit` lines give
//!    them, as the modeller set them for Lenstool):
//!    `z_estimate` is its peak (the smallest chi2), `z_interval` the narrowest interval that
//!    holds 68% of it. On the six synthetic clusters of `tests/data/fidelity`, a third of
//!    their systems blanked, the peak is closer to the truth than the posterior median
//!    (median |dz|/(1+z) 0.018 against 0.028): above z ~ 3 the posterior is broad and skewed
//!    towards high redshift, since `f` hardly changes there.
//!
//! **Over the ways of drawing the map.** A system whose images lie beyond those of the systems
//! with a redshift (as in real catalogues, where the redshifts measured are mostly of the
//! bright inner arcs) sees the lens where only the regulariser drew it: least mass lets the map
//! fall off there (the redshift estimated comes out too high, often at the top of the range),
//! the smoothest map keeps it level (too low), and the held-out systems of the cross-validation,
//! which lie among the others, cannot tell which is right. So with an "auto" strength the
//! posterior is the mean of those on the chosen map and on the maps of the same systems drawn
//! with the best candidate of each other regulariser tried (each normalised), and the interval
//! and the median are the mean's; the system is still fitted at the chosen map's most probable
//! `z`, since that map is drawn through it. Where the maps agree, among the systems with a
//! redshift, this changes little; where they part, the interval widens to hold them, and an
//! ensemble's members draw their redshifts from it. Measured on the synthetic clusters with
//! the outer third of their systems blanked (`benches/free_z.py --pick outer`): the truth
//! inside the interval for 52% of them on the chosen map alone, 74% over the maps.
//!
//! The systems are then fitted with the others, each at its `z_estimate`, with the settings
//! (and the regulariser's strength) of the first fit (an "auto" strength then chooses again
//! with them fitted in every fold, and refits at the same estimates when its choice changes:
//! `super::second_round`), and with the image-plane error its
//! redshift's uncertainty means added to the position error in quadrature
//! ([`RedshiftEstimate::position_error_arcsec`]: how far its images move on the first lens
//! between the estimate and the interval's ends), so that a redshift the images hardly fix
//! weighs little in the map. Fitted at full weight, a biased estimate bends the map towards
//! itself: on the ten synthetic clusters with only their five innermost systems' redshifts
//! kept (a real catalogue with few spectroscopic redshifts), the Einstein radius was off by
//! 13.9% (median) and the deflection by 3.91″, against 11.7% and 3.32″ with the error added
//! (6.9% and 3.57″ with the systems left out altogether; BENCHMARKS.md), and 5.6% and
//! 2.55″ once "auto" chose again with them fitted.
//!
//! **Made consistent with the map.** The estimates come from the lens of the systems with a
//! redshift, which only the regulariser drew where the others' images lie; the map fitted
//! to every system is drawn through them. So, at the end of the run (after the second round
//! of an "auto" choice, or after its only round when too few systems had a redshift for
//! folds), each system's redshift is estimated again on that map, and if any
//! moves by more than 0.01 (1 + z) every system is fitted again at the new estimates, at most
//! `constraints.free_z_passes` times (default 2; [`fit_consistently`]): the map and the
//! redshifts it is fitted at become a joint fit of both, as a parametric modeller's free
//! redshifts are. The interval and the position error stay those of the first estimate (the
//! map of every system has seen the system; the interval is widened to hold the new
//! estimate). On the ten synthetic clusters with five redshifts kept this took the median
//! Einstein-radius error from 5.6% to 2.4%, the deflection error from 2.55 to 2.44″ and the
//! fitted images from 0.75 to 0.48″ (BENCHMARKS.md). `sources.json`
//! gives the estimate, the interval and that error per system; `summary.json` the fitted
//! median offset of the systems with a redshift before and after they were added (adding
//! them must not spoil those). A cross-validation of the run and an ensemble fit them alike.
//!
//! **What estimated systems cannot tell: the mass sheet.** Scale the map by `lambda` and add a
//! uniform sheet of `1 - lambda`: `alpha' = lambda alpha + (1 - lambda) theta`. Then
//! `theta - f' alpha' = (lambda f' / f) (theta - f alpha)` for `f' = 1 / (1 - lambda + lambda /
//! f)`, so a system fitted at `f` on the map fits the transformed map exactly at `f'`, its
//! source scaled. Every system whose redshift is estimated follows any such `lambda` (within
//! the prior's range of `f`); only the systems with a known redshift hold it, by how their
//! `f` differ. A catalogue with few redshifts therefore fixes the overall scale of the map
//! (and the Einstein radius at a given `z_s`) from those few, however many systems are
//! estimated: on the synthetic clusters with five redshifts kept, the maps' `lambda` against
//! the truth spans 0.73 - 1.04 (BENCHMARKS.md). A redshift prior of the system's own (a
//! photometric redshift as a normal) is what adds information on it.
//!
//! What the interval does not include: the uncertainty of the lens itself beyond `sigma`,
//! and the estimate's effect back on the lens (the second fit takes `z_estimate` as known,
//! within the error above).
//! An ensemble carries the interval into the maps: each member fits these systems at a
//! redshift drawn from it ([`draw`]).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::sources::held_out_images;
use super::summary::{image_offsets_arcsec, median_arcsec};
use super::{
    reconstruct_limited, ConvergenceRecord, Inputs, ReconstructConfig, ReconstructError,
    Reconstruction,
};
use crate::cosmology::LensPlane;
use crate::inversion::{capped_inverse_jacobian, Exclusion, RedshiftPrior};
use crate::profiles::MassComponent;
use crate::solver::{Control, SolveStatus};

/// The image-plane error (arcsec, rms over both axes) assumed for a system's images on a lens
/// that was not fitted to them, when no cross-validation measured it: about what free-form
/// models of cluster catalogues predict held-out images to (1 - 2″ for AS1063 and the
/// synthetic clusters of `tests/data/fidelity`), at the better end.
pub const FALLBACK_SIGMA_ARCSEC: f64 = 1.0;

/// Redshifts tried over the prior range (evenly spaced in `z`).
const Z_GRID_POINTS: usize = 400;

/// How far behind the lens the lowest redshift tried lies.
const BEHIND_LENS: f64 = 0.02;

/// The redshift found for one system (`sources.json`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RedshiftEstimate {
    /// The most probable redshift (the smallest chi2): the one the system is fitted at.
    pub z: f64,
    /// The narrowest interval that holds 68% of the posterior (it contains `z`; at least the
    /// step of the grid of redshifts tried wide, 1/400 of the prior range).
    pub interval: [f64; 2],
    /// The posterior median, which a broad posterior at high redshift (where `f` hardly
    /// changes) pulls away from `z`.
    pub z_median: f64,
    /// The chi2 per degree of freedom at `z_best_fit` with the `sigma` assumed (before any
    /// scaling).
    pub reduced_chi2: f64,
    /// The image-plane error used (arcsec, rms over both axes), after any scaling.
    pub sigma_arcsec: f64,
    /// How far (arcsec, rms per image) the system's images would move on the first lens were
    /// it at an end of `interval` rather than at `z` (the mean of the two ends' squared
    /// misfits less the one at `z`): the image-plane error the redshift's uncertainty adds.
    /// The system is fitted with it added to `constraints.sigma_pos_arcsec` in quadrature.
    #[serde(default)]
    pub position_error_arcsec: f64,
}

/// `summary.json`'s `free_redshifts`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FreeZSummary {
    /// Per system estimated: its id and the estimate.
    pub systems: Vec<(String, RedshiftEstimate)>,
    /// Systems left out because no redshift could be estimated (fewer than two images with a
    /// position on the lens, or no redshift of the range behind the lens).
    pub not_estimated: Vec<String>,
    /// The image-plane error the estimates started from (arcsec; module documentation).
    pub sigma_arcsec: f64,
    /// Where `sigma_arcsec` came from, in words.
    pub sigma_from: String,
    /// How many maps the intervals were taken over (the chosen one and the best of each other
    /// regulariser tried; module documentation).
    #[serde(default = "one_map")]
    pub maps: usize,
    /// How many times the estimates were made again on the map fitted to every system and
    /// the systems fitted again at them (at most `constraints.free_z_passes`; 0: the first
    /// estimates stood).
    #[serde(default)]
    pub passes: usize,
    /// The fitted median image offset (arcsec) of the systems with a known redshift, in the
    /// fit without the estimated systems and in the final one with them.
    pub known_fit_median_without_arcsec: Option<f64>,
    pub known_fit_median_with_arcsec: Option<f64>,
}

fn one_map() -> usize {
    1
}

/// The final reconstruction from `first`, a fit that left out the systems whose redshift is to
/// be estimated: their redshifts estimated on its lens and on the lenses of the same systems
/// fitted with each of `others` (the best settings of the other regularisers an "auto"
/// strength tried; module documentation), then a fit of every system with the settings of
/// `first` (`config`, whose strength is a number). `sigma` is the held-out image error
/// measured by the cross-validation of an "auto" strength, if any. Returns `first` when there
/// is no such system, or when `first` or another fit was cancelled.
pub(super) fn add_free_systems(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    first: Reconstruction,
    sigma: Option<f64>,
    others: &[ReconstructConfig],
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Reconstruction, ReconstructError> {
    let free: Vec<String> = first
        .system
        .constraints
        .excluded
        .iter()
        .filter(|e| e.reason == Exclusion::FreeRedshift)
        .map(|e| e.id.clone())
        .collect();
    let prior = config.constraints.free_z_prior.unwrap_or(OPEN_RANGE);
    if free.is_empty() || first.status == SolveStatus::Cancelled {
        return Ok(first);
    }
    let (sigma_arcsec, sigma_from) = match sigma {
        Some(s) if s.is_finite() && s > 0.0 => (
            s,
            "the held-out images of the cross-validation that chose the strength".to_string(),
        ),
        _ => (
            FALLBACK_SIGMA_ARCSEC,
            "no cross-validation measured it: the fallback".to_string(),
        ),
    };
    let mut other_lenses = Vec::with_capacity(others.len());
    for other in others {
        let r = reconstruct_limited(inputs, other, progress)?;
        if r.status == SolveStatus::Cancelled {
            return Ok(first);
        }
        other_lenses.push(r.lens);
    }
    let lenses: Vec<&dyn MassComponent> = std::iter::once(&first.lens)
        .chain(&other_lenses)
        .map(|l| l as &dyn MassComponent)
        .collect();
    let mut estimates = Vec::new();
    let mut not_estimated = Vec::new();
    for id in &free {
        match estimate_redshift_over(
            &lenses,
            &inputs.plane,
            &observed_images(inputs, id),
            prior,
            config.constraints.z_priors.get(id).copied(),
            sigma_arcsec,
            config.objective.max_stretch,
        ) {
            Some(e) => estimates.push((id.clone(), e)),
            None => not_estimated.push(id.clone()),
        }
    }
    if estimates.is_empty() {
        let mut first = first;
        first.warnings.extend(not_estimated_note(&not_estimated));
        return Ok(first);
    }
    let free = FreeZSummary {
        systems: estimates,
        not_estimated,
        sigma_arcsec,
        sigma_from,
        maps: lenses.len(),
        passes: 0,
        known_fit_median_without_arcsec: first.image_offset_median_arcsec(false),
        known_fit_median_with_arcsec: None,
    };
    fit_at_estimates(inputs, config, free, progress)
}

/// The fit of every system, those of `free` each at its estimated redshift with the error its
/// uncertainty adds, with `config` (whose strength is a number); the result's `free_z` is
/// `free` with the fitted median of the systems with a known redshift, and its warnings say
/// what was estimated. [`add_free_systems`] ends with it, and an "auto" strength chosen again
/// with the estimates in (`super::refit_with_choice`) fits the same estimates with it.
pub(super) fn fit_at_estimates(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    mut free: FreeZSummary,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Reconstruction, ReconstructError> {
    let estimates = &free.systems;
    let mut second = config.clone();
    second.constraints.z_estimates = estimates.iter().map(|(id, e)| (id.clone(), e.z)).collect();
    second.constraints.z_estimate_errors = estimates
        .iter()
        .map(|(id, e)| (id.clone(), e.position_error_arcsec))
        .collect();
    let mut r = reconstruct_limited(inputs, &second, progress)?;
    // An interval that ends at the top of the range searched is not bounded by the images
    // there: the top is the setting's (or the system's own prior's), and the note says so.
    // Per estimate, that top when its interval reaches it.
    let open_above: Vec<Option<f64>> = estimates
        .iter()
        .map(|(id, e)| {
            let top = search_range(config, id)[1];
            (e.interval[1] >= top - AT_RANGE_TOP).then_some(top)
        })
        .collect();
    for s in r.sources.iter_mut() {
        if let Some(k) = estimates.iter().position(|(id, _)| *id == s.id) {
            let e = &estimates[k].1;
            s.z_estimate = Some(e.z);
            s.z_interval = Some(e.interval);
            s.z_position_error_arcsec = Some(e.position_error_arcsec);
            s.z_open_above = open_above[k].is_some();
        }
    }
    let estimated = |id: &str| estimates.iter().any(|(e, _)| e == id);
    free.known_fit_median_with_arcsec = median_arcsec(image_offsets_arcsec(
        r.sources
            .iter()
            .filter(|s| !s.held_out && !estimated(&s.id)),
    ));
    let own_prior = |id: &str| match config.constraints.z_priors.get(id) {
        Some(p) => format!(" under its own prior ({})", p.describe()),
        None => String::new(),
    };
    // How the estimates were made: said once.
    let how = format!(
        "on the lens of the systems with a known one{}",
        match free.maps {
            0 | 1 => String::new(),
            n => format!(" (the interval over the maps of {n} regularisers)"),
        },
    );
    let again = match free.passes {
        0 => String::new(),
        1 => " and again on the map of every system".to_string(),
        n => format!(" and again, {n} times, on the map of every system"),
    };
    let mut notes: Vec<String> = match &estimates[..] {
        [] => Vec::new(),
        [(id, e)] => {
            let open = match open_above[0] {
                Some(top) => format!(", open above: {top:.2} is the top of the range searched"),
                None => String::new(),
            };
            vec![format!(
                "system {id}: redshift estimated z = {:.2} (68%: {:.2} - {:.2}{open}){} {how}{again}, \
                 and fitted at it",
                e.z,
                e.interval[0],
                e.interval[1],
                own_prior(id),
            )]
        }
        // One line for them all (27 lines for one catalogue said less than this one); the
        // systems table and sources.json have each again.
        many => {
            let each: Vec<String> = many
                .iter()
                .zip(&open_above)
                .map(|((id, e), &open)| {
                    format!(
                        "system {id} at z = {:.2} ({:.2} - {:.2}{}){}",
                        e.z,
                        e.interval[0],
                        e.interval[1],
                        if open.is_some() { ", open above" } else { "" },
                        own_prior(id),
                    )
                })
                .collect();
            let open = match open_above.iter().any(Option::is_some) {
                true => "; \"open above\": the interval ends at the top of the range searched, \
                         where the images no longer bound it"
                    .to_string(),
                false => String::new(),
            };
            vec![format!(
                "redshifts estimated for {} systems {how}{again}, and fitted at them (68% \
                 intervals): {}{open}",
                many.len(),
                each.join(", "),
            )]
        }
    };
    notes.extend(not_estimated_note(&free.not_estimated));
    r.warnings.extend(notes);
    r.free_z = Some(free);
    Ok(r)
}

/// How far an estimate must move (`|dz| / (1 + z)`) for [`fit_consistently`] to fit the
/// systems again: the step of the redshifts tried over the default range is about 0.02.
const SETTLED_DZ: f64 = 0.01;

/// The estimated systems' redshifts and the map made consistent: each system's redshift
/// estimated again on the map fitted to every system (`current`, else `r`), and every system
/// fitted again at the new estimates with `config` (whose strength is a number), until no
/// estimate moves by more than [`SETTLED_DZ`]` (1 + z)` or `constraints.free_z_passes` fits
/// were made. Returns the last fit, `current` itself when no estimate moved, or `None` when
/// nothing was fitted (no estimated system, or a cancelled map). Module documentation: why.
pub(super) fn fit_consistently(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    r: &Reconstruction,
    mut current: Option<Reconstruction>,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Option<Reconstruction>, ReconstructError> {
    for _ in 0..config.constraints.free_z_passes {
        let on = current.as_ref().unwrap_or(r);
        match estimate_again(inputs, config, on, progress)? {
            Some(next) => current = Some(next),
            None => break,
        }
    }
    Ok(current)
}

/// One pass of [`fit_consistently`]: `None` when no estimate moves (or `on` has none, or
/// was cancelled). A moved estimate keeps its interval, widened to hold it, and its position
/// error (both from the lens of the systems with a known redshift, which never saw it).
fn estimate_again(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    on: &Reconstruction,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Option<Reconstruction>, ReconstructError> {
    let Some(mut free) = on.free_z.clone() else {
        return Ok(None);
    };
    if on.status == SolveStatus::Cancelled {
        return Ok(None);
    }
    let prior = config.constraints.free_z_prior.unwrap_or(OPEN_RANGE);
    let mut moved = false;
    for (id, e) in free.systems.iter_mut() {
        let again = estimate_redshift_over(
            &[&on.lens as &dyn MassComponent],
            &inputs.plane,
            &observed_images(inputs, id),
            prior,
            config.constraints.z_priors.get(id).copied(),
            free.sigma_arcsec,
            config.objective.max_stretch,
        );
        if let Some(z) = again
            .map(|a| a.z)
            .filter(|z| (z - e.z).abs() > SETTLED_DZ * (1.0 + e.z))
        {
            e.z = z;
            e.interval = [e.interval[0].min(z), e.interval[1].max(z)];
            moved = true;
        }
    }
    if !moved {
        return Ok(None);
    }
    free.passes += 1;
    let mut next = fit_at_estimates(inputs, config, free, progress)?;
    next.config = on.config.clone();
    next.strength_choice = on.strength_choice.clone();
    Ok(Some(next))
}

/// The observed positions (arcsec) of system `id`'s images, whether or not a fit used them.
fn observed_images(inputs: &Inputs<'_>, id: &str) -> Vec<DVec2> {
    held_out_images(inputs, id)
        .map(|(_, observed)| observed.into_iter().map(|(_, p)| p).collect())
        .unwrap_or_default()
}

/// The warning for the systems no redshift could be estimated for, if any.
fn not_estimated_note(ids: &[String]) -> Option<String> {
    (!ids.is_empty()).then(|| {
        format!(
            "no redshift could be estimated for system(s) {}: not used",
            ids.join(", ")
        )
    })
}

/// The systems of `sources` whose redshift was estimated: id, most probable redshift and 68%
/// interval.
pub(super) fn estimates_of(sources: &[super::SourceReport]) -> Vec<(String, f64, [f64; 2])> {
    sources
        .iter()
        .filter_map(|s| Some((s.id.clone(), s.z_estimate?, s.z_interval?)))
        .collect()
}

/// The redshifts a run estimated, as a later fit takes them (`constraints.z_estimates` and
/// `constraints.z_estimate_errors`, by system id): e.g. the second round of an "auto" choice
/// run in other workers, which do not have the run.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct EstimatedRedshifts {
    pub z_estimates: Vec<(String, f64)>,
    pub z_estimate_errors: Vec<(String, f64)>,
}

impl EstimatedRedshifts {
    /// The systems of `sources` whose redshift was estimated: at their estimates, with the
    /// image-plane error their redshifts' uncertainty adds.
    pub fn of(sources: &[super::SourceReport]) -> Self {
        Self {
            z_estimates: most_probable_of(&estimates_of(sources)),
            z_estimate_errors: position_errors_of(sources),
        }
    }

    /// Sets `constraints` to fit these systems so.
    pub fn fit_in(&self, constraints: &mut crate::inversion::ConstraintConfig) {
        constraints.z_estimates = self.z_estimates.clone();
        constraints.z_estimate_errors = self.z_estimate_errors.clone();
    }

    /// `config` fitting these systems so (as a second round's trials run it).
    pub fn fitted_by(&self, config: &ReconstructConfig) -> ReconstructConfig {
        let mut c = config.clone();
        self.fit_in(&mut c.constraints);
        c
    }
}

/// Sets `constraints` to fit the systems of `sources` whose redshift was estimated as the run
/// that reported them did ([`EstimatedRedshifts::of`]).
pub(crate) fn fit_estimates_in(
    sources: &[super::SourceReport],
    constraints: &mut crate::inversion::ConstraintConfig,
) {
    EstimatedRedshifts::of(sources).fit_in(constraints);
}

/// The image-plane error each estimated system of `sources` is fitted with, as
/// `constraints.z_estimate_errors` takes them.
pub(super) fn position_errors_of(sources: &[super::SourceReport]) -> Vec<(String, f64)> {
    sources
        .iter()
        .filter_map(|s| Some((s.id.clone(), s.z_position_error_arcsec?)))
        .collect()
}

/// The most probable redshift of each of `estimated`, as `z_estimates` takes them.
pub(super) fn most_probable_of(estimated: &[(String, f64, [f64; 2])]) -> Vec<(String, f64)> {
    estimated
        .iter()
        .map(|(id, z, _)| (id.clone(), *z))
        .collect()
}

/// A redshift for each of `estimated` drawn from its estimate: a normal on each side of the
/// most probable `z` whose width is the interval's on that side (a split normal holding 68%
/// inside the interval), kept within `[z_lo, 2 z_hi - z]` (not below the interval, whose low
/// end lies inside the prior and behind the lens) and within the range the system's redshift
/// was searched in, `range(id)` (the prior range, narrowed by a system's own).
pub(super) fn draw(
    estimated: &[(String, f64, [f64; 2])],
    range: impl Fn(&str) -> [f64; 2],
    rng: &mut crate::simulate::rng::Rng,
) -> Vec<(String, f64)> {
    estimated
        .iter()
        .map(|(id, z, [lo, hi])| {
            let n = rng.normal();
            let width = if n < 0.0 { z - lo } else { hi - z };
            let top = (2.0 * hi - z).min(range(id)[1]).max(*lo);
            (id.clone(), (z + n * width).clamp(*lo, top))
        })
        .collect()
}

/// How close to the top of the range searched an interval's end is taken to reach it: half
/// the last digit the note prints, so that an end printed as the top is said to be it.
const AT_RANGE_TOP: f64 = 0.005;

/// The range searched when `constraints.free_z_prior` is off (then only systems with a prior
/// of their own are estimated, within it): every redshift a setting allows (the low end is
/// raised to just behind the lens like any other).
const OPEN_RANGE: [f64; 2] = [0.0, 20.0];

/// The range the redshift of system `id` is searched in: `constraints.free_z_prior` (or
/// [`OPEN_RANGE`] when it is off), narrowed by the system's own range if it has one.
pub(super) fn search_range(config: &ReconstructConfig, id: &str) -> [f64; 2] {
    let prior = config.constraints.free_z_prior.unwrap_or(OPEN_RANGE);
    narrowed(prior, config.constraints.z_priors.get(id).copied())
}

/// `prior` narrowed by a system's own range, if `own` is one.
fn narrowed(prior: [f64; 2], own: Option<RedshiftPrior>) -> [f64; 2] {
    match own {
        Some(RedshiftPrior::Range([lo, hi])) => [prior[0].max(lo), prior[1].min(hi)],
        _ => prior,
    }
}

/// The estimate of the redshift of the source of `images` (arcsec) on `lens` (deflection at
/// `D_ls/D_s = 1`) within `prior` (see the module documentation); `None` with fewer than two
/// images or when no redshift of the range lies behind the lens.
pub fn estimate_redshift(
    lens: &dyn MassComponent,
    plane: &LensPlane,
    images: &[DVec2],
    prior: [f64; 2],
    sigma_arcsec: f64,
    max_stretch: f64,
) -> Option<RedshiftEstimate> {
    estimate_redshift_over(
        &[lens],
        plane,
        images,
        prior,
        None,
        sigma_arcsec,
        max_stretch,
    )
}

/// [`estimate_redshift`] on several lenses at once (the maps of the same systems drawn with
/// different regularisers, the one the system will be fitted with first): `z`, the most
/// probable redshift, is the first lens's (that map is drawn through the system at it); the
/// interval and the median are those of the mean of the lenses' posteriors, each normalised
/// (how far the maps part where the images lie), the interval widened to hold `z`.
/// `reduced_chi2` and `sigma_arcsec` are the first lens's. `None` as for one lens, or when
/// the first lens gives no finite misfit.
///
/// `own` is the system's own prior, if it has one (`constraints.z_priors`): a range narrows
/// `prior`'s, a normal multiplies the posterior (of each lens) by its density.
pub fn estimate_redshift_over(
    lenses: &[&dyn MassComponent],
    plane: &LensPlane,
    images: &[DVec2],
    prior: [f64; 2],
    own: Option<RedshiftPrior>,
    sigma_arcsec: f64,
    max_stretch: f64,
) -> Option<RedshiftEstimate> {
    let [low, high] = narrowed(prior, own);
    let low = low.max(plane.z_lens + BEHIND_LENS);
    let usable = high > low && sigma_arcsec > 0.0;
    if images.len() < 2 || !usable {
        return None;
    }
    let zs: Vec<f64> = (0..Z_GRID_POINTS)
        .map(|i| low + (high - low) * i as f64 / (Z_GRID_POINTS - 1) as f64)
        .collect();
    // The system's own prior's -ln density on the grid (a constant but for a normal).
    let minus_log_prior: Vec<f64> = zs
        .iter()
        .map(|&z| match own {
            Some(RedshiftPrior::Normal([mean, sigma])) => 0.5 * ((z - mean) / sigma).powi(2),
            _ => 0.0,
        })
        .collect();
    let search = Search {
        plane,
        images,
        zs: &zs,
        minus_log_prior: &minus_log_prior,
        sigma_arcsec,
        max_stretch,
    };
    let (&chosen, others) = lenses.split_first()?;
    let first = search.posterior(chosen)?;
    let rest: Vec<Posterior> = others
        .iter()
        .filter_map(|&lens| search.posterior(lens))
        .collect();
    let (reduced, scale) = (first.reduced_chi2, first.scale);
    let count = (1 + rest.len()) as f64;
    let weights: Vec<f64> = (0..zs.len())
        .map(|i| (first.weights[i] + rest.iter().map(|p| p.weights[i]).sum::<f64>()) / count)
        .collect();
    let median = quantiles(&zs, &weights)(0.5);
    // The peak of the first lens's posterior, refined on its logarithm (a parabola through
    // the misfit's smallest sample and its neighbours).
    let best = (0..zs.len()).max_by(|&a, &b| first.weights[a].total_cmp(&first.weights[b]))?;
    let minus_log: Vec<f64> = first.weights.iter().map(|w| -w.ln()).collect();
    let z = most_probable(&zs, &minus_log, best);
    // Each grid point stands for the half step on either side of it (a posterior narrower
    // than the step gives an interval one step wide around z).
    let [lo, hi] = densest_interval(&zs, &weights, 0.68);
    let half = 0.5 * (zs[1] - zs[0]);
    let interval = [(lo - half).max(low).min(z), (hi + half).min(high).max(z)];
    Some(RedshiftEstimate {
        z,
        interval,
        z_median: median,
        reduced_chi2: reduced,
        sigma_arcsec: sigma_arcsec * scale.sqrt(),
        position_error_arcsec: search.position_error(chosen, z, interval),
    })
}

/// One lens's posterior of a system's redshift on the grid `zs` (module documentation, steps
/// 1 - 4), its weights summing to 1.
struct Posterior {
    weights: Vec<f64>,
    /// The chi2 per degree of freedom at the best `z` with the `sigma` given.
    reduced_chi2: f64,
    /// What the variance was scaled by (at least 1).
    scale: f64,
}

/// What a system's posterior is computed from, whatever the lens.
struct Search<'a> {
    plane: &'a LensPlane,
    images: &'a [DVec2],
    /// The redshifts tried.
    zs: &'a [f64],
    /// The prior's -ln density at each of `zs`, up to a constant.
    minus_log_prior: &'a [f64],
    sigma_arcsec: f64,
    max_stretch: f64,
}

impl Search<'_> {
    /// [`RedshiftEstimate::position_error_arcsec`] of the system on `lens` at `z` for
    /// `interval`.
    fn position_error(&self, lens: &dyn MassComponent, z: f64, interval: [f64; 2]) -> f64 {
        let lensing = self.lensing(lens);
        let misfit = |z: f64| {
            self.plane
                .distance_ratio(z)
                .map_or(f64::NAN, |f| image_offsets2(&lensing, f, self.max_stretch))
        };
        let ends = 0.5 * (misfit(interval[0]) + misfit(interval[1]));
        let added = (ends - misfit(z)) / self.images.len() as f64;
        if added.is_finite() {
            added.max(0.0).sqrt()
        } else {
            0.0
        }
    }

    /// Each image's position, deflection and Hessian on `lens`.
    fn lensing(&self, lens: &dyn MassComponent) -> Vec<(DVec2, DVec2, [f64; 3])> {
        self.images
            .iter()
            .map(|&theta| {
                let (alpha, h) = lens.deflection_hessian(theta);
                (theta, alpha, h)
            })
            .collect()
    }

    fn posterior(&self, lens: &dyn MassComponent) -> Option<Posterior> {
        let lensing = self.lensing(lens);
        // Sum of |d_k|^2 (arcsec^2) at each z.
        let offsets2: Vec<f64> = self
            .zs
            .iter()
            .map(|&z| {
                self.plane.distance_ratio(z).map_or(f64::INFINITY, |f| {
                    image_offsets2(&lensing, f, self.max_stretch)
                })
            })
            .collect();
        let least = offsets2.iter().copied().fold(f64::INFINITY, f64::min);
        if !least.is_finite() {
            return None;
        }
        let dof = (2 * self.images.len()).saturating_sub(3).max(1) as f64;
        let axis_var = 0.5 * self.sigma_arcsec * self.sigma_arcsec;
        let reduced_chi2 = least / axis_var / dof;
        let scale = reduced_chi2.max(1.0);
        let var = axis_var * scale;
        // -ln of the posterior up to a constant, shifted so that its peak weighs 1.
        let minus_log: Vec<f64> = offsets2
            .iter()
            .zip(self.minus_log_prior)
            .map(|(&o, &p)| (o - least) / (2.0 * var) + p)
            .collect();
        let lowest = minus_log.iter().copied().fold(f64::INFINITY, f64::min);
        let mut weights: Vec<f64> = minus_log.iter().map(|&m| (lowest - m).exp()).collect();
        let total: f64 = weights.iter().sum();
        weights.iter_mut().for_each(|w| *w /= total);
        Some(Posterior {
            weights,
            reduced_chi2,
            scale,
        })
    }
}

/// The minimum of `values` on the even grid `zs` near its smallest sample `best`, from the
/// parabola through it and its neighbours (the sample itself at the ends of the range).
fn most_probable(zs: &[f64], values: &[f64], best: usize) -> f64 {
    if best == 0 || best + 1 >= zs.len() {
        return zs[best];
    }
    let (a, b, c) = (values[best - 1], values[best], values[best + 1]);
    let curvature = a - 2.0 * b + c;
    if !curvature.is_finite() || curvature <= 0.0 {
        return zs[best];
    }
    let step = zs[1] - zs[0];
    zs[best] + 0.5 * step * (a - c) / curvature
}

/// The narrowest interval of the grid `zs` holding the share `mass` of the density `weights`:
/// the grid points of highest density taken in turn until they hold it (for a density with
/// one peak, an interval that contains the peak).
fn densest_interval(zs: &[f64], weights: &[f64], mass: f64) -> [f64; 2] {
    let total: f64 = weights.iter().sum();
    let mut order: Vec<usize> = (0..zs.len()).collect();
    order.sort_by(|&a, &b| weights[b].total_cmp(&weights[a]));
    let (mut held, mut low, mut high) = (0.0, f64::INFINITY, f64::NEG_INFINITY);
    for i in order {
        held += weights[i];
        low = low.min(zs[i]);
        high = high.max(zs[i]);
        if held >= mass * total {
            break;
        }
    }
    [low, high]
}

/// `sum_k |M_k (beta_k - beta)|^2` at `f` with the best `beta` (module documentation, step 2).
fn image_offsets2(lensing: &[(DVec2, DVec2, [f64; 3])], f: f64, max_stretch: f64) -> f64 {
    let terms: Vec<(DVec2, [f64; 4])> = lensing
        .iter()
        .map(|&(theta, alpha, h)| {
            (
                theta - f * alpha,
                capped_inverse_jacobian(h, f, max_stretch),
            )
        })
        .collect();
    let beta = super::sources::image_plane_source(&terms);
    super::sources::image_plane_offsets2(&terms, beta)
}

/// The quantiles of the distribution with density `weights` on the even grid `zs` (linear
/// between grid points).
fn quantiles<'a>(zs: &'a [f64], weights: &[f64]) -> impl Fn(f64) -> f64 + 'a {
    let mut cdf = vec![0.0; zs.len()];
    for i in 1..zs.len() {
        cdf[i] = cdf[i - 1] + 0.5 * (weights[i - 1] + weights[i]);
    }
    let total = cdf[zs.len() - 1];
    move |q: f64| {
        if total <= 0.0 {
            return zs[0];
        }
        let target = q * total;
        let i = cdf.partition_point(|&c| c < target).clamp(1, zs.len() - 1);
        let (c0, c1) = (cdf[i - 1], cdf[i]);
        let t = if c1 > c0 {
            (target - c0) / (c1 - c0)
        } else {
            0.0
        };
        zs[i - 1] + t * (zs[i] - zs[i - 1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cosmology::Cosmology;
    use crate::profiles::{Lens, Sis};

    #[test]
    fn densest_interval_holds_the_peak() {
        let zs: Vec<f64> = (0..101).map(|i| i as f64 * 0.1).collect();
        // A skewed density: peak at 2, a long tail to high z.
        let w: Vec<f64> = zs
            .iter()
            .map(|&z| {
                if z < 2.0 {
                    (-(z - 2.0).powi(2) / 0.1).exp()
                } else {
                    (-(z - 2.0) / 3.0).exp()
                }
            })
            .collect();
        let [lo, hi] = densest_interval(&zs, &w, 0.68);
        assert!(lo <= 2.0 && 2.0 <= hi && lo > 1.0 && hi > 4.0, "{lo} {hi}");
        let chi2: Vec<f64> = zs.iter().map(|&z| (z - 3.33).powi(2)).collect();
        assert!((most_probable(&zs, &chi2, 33) - 3.33).abs() < 1e-9);
    }

    #[test]
    fn drawn_redshifts_follow_the_interval() {
        let mut rng = crate::simulate::rng::Rng::stream(7, 1);
        let estimated = [("1".to_string(), 3.0, [2.5, 4.0])];
        let draws: Vec<f64> = (0..4000)
            .map(|_| draw(&estimated, |_| [0.5, 8.0], &mut rng)[0].1)
            .collect();
        assert!(draws.iter().all(|&z| (2.5..=5.0).contains(&z)));
        // Never beyond the range searched (a system's own prior up to 4.5, say).
        let capped: Vec<f64> = (0..4000)
            .map(|_| draw(&estimated, |_| [0.5, 4.5], &mut rng)[0].1)
            .collect();
        assert!(capped.iter().all(|&z| (2.5..=4.5).contains(&z)));
        assert!(capped.iter().any(|&z| z > 4.4), "the cap is reached");
        let inside = draws.iter().filter(|&&z| z > 2.5 && z < 4.0).count() as f64 / 4000.0;
        assert!((inside - 0.68).abs() < 0.1, "{inside}");
        let above = draws.iter().filter(|&&z| z > 3.0).count() as f64 / 4000.0;
        assert!((above - 0.5).abs() < 0.05, "{above}");
    }

    #[test]
    fn quantiles_of_a_flat_density_are_linear() {
        let zs: Vec<f64> = (0..11).map(|i| i as f64).collect();
        let q = quantiles(&zs, &[1.0; 11]);
        assert!((q(0.5) - 5.0).abs() < 1e-12);
        assert!((q(0.16) - 1.6).abs() < 1e-12);
    }

    #[test]
    fn the_position_error_is_how_far_the_interval_moves_the_images() {
        // On an SIS the images of a source at beta on the x axis lie at beta +- theta_E f;
        // fitted at f' they are predicted at beta +- theta_E f', each moved by
        // theta_E |f' - f| (radially, where an SIS does not stretch). So the ends of the
        // interval add theta_E^2 ((f_lo - f)^2 + (f_hi - f)^2) / 2 to each image's squared
        // misfit, less the estimate's own theta_E^2 (f_z - f)^2.
        let theta_e = 20.0;
        let lens = Lens::new(vec![Box::new(
            Sis::from_theta_e(DVec2::ZERO, theta_e).unwrap(),
        )]);
        let plane = LensPlane::new(Cosmology::default(), 0.3).unwrap();
        let ratio = |z: f64| plane.distance_ratio(z).unwrap();
        let f = ratio(2.5);
        let images = [
            DVec2::new(3.0 + theta_e * f, 0.0),
            DVec2::new(3.0 - theta_e * f, 0.0),
        ];
        for sigma in [0.3, 1.0] {
            let e = estimate_redshift(&lens, &plane, &images, [0.5, 8.0], sigma, 10.0)
                .expect("estimate");
            let [lo, hi] = e.interval;
            let moved = |z: f64| (ratio(z) - f).powi(2);
            let want = theta_e * (0.5 * (moved(lo) + moved(hi)) - moved(e.z)).sqrt();
            assert!(want > 0.05, "a real interval: {e:?}");
            assert!(
                (e.position_error_arcsec - want).abs() <= 1e-9 * want,
                "{} against {want}: {e:?}",
                e.position_error_arcsec
            );
        }
    }

    /// Two maps of one lens that part where a system's images lie (one 15% more massive): the
    /// estimate over both is the first map's, its interval holding each map's own; over two
    /// copies of one map it is that map's estimate.
    #[test]
    fn the_estimate_over_two_maps_holds_both() {
        let sis = |theta_e: f64| {
            Lens::new(vec![Box::new(
                Sis::from_theta_e(DVec2::ZERO, theta_e).unwrap(),
            )])
        };
        let (light, heavy) = (sis(20.0), sis(23.0));
        let plane = LensPlane::new(Cosmology::default(), 0.3).unwrap();
        let f = plane.distance_ratio(2.5).unwrap();
        // The images of a source 3" off the centre behind the light map at z = 2.5.
        let images = [
            DVec2::new(3.0 + 20.0 * f, 0.0),
            DVec2::new(3.0 - 20.0 * f, 0.0),
        ];
        let one = |lens: &Lens| {
            estimate_redshift(lens, &plane, &images, [0.5, 8.0], 0.3, 10.0).expect("estimate")
        };
        let (on_light, on_heavy) = (one(&light), one(&heavy));
        assert!((on_light.z - 2.5).abs() < 0.02, "{on_light:?}");
        assert!(
            on_heavy.z < 1.8,
            "the heavier map needs a nearer source: {on_heavy:?}"
        );
        assert!(
            on_light.interval[0] > on_heavy.interval[1],
            "the two do not overlap"
        );
        let over = |lenses: &[&dyn MassComponent]| {
            estimate_redshift_over(lenses, &plane, &images, [0.5, 8.0], None, 0.3, 10.0)
                .expect("estimate")
        };
        let both = over(&[&light, &heavy]);
        assert!(
            both.interval[0] <= on_heavy.z && both.interval[1] >= on_light.z,
            "{both:?}"
        );
        assert!(
            (both.z - on_light.z).abs() < 1e-9,
            "the first map's estimate: {both:?}"
        );
        let same = over(&[&light, &light]);
        assert!((same.z - on_light.z).abs() < 1e-9, "{same:?} {on_light:?}");
        assert_eq!(same.interval, on_light.interval);
    }

    /// A system's own prior: a range the truth lies outside pins the estimate to the range's
    /// nearer end and keeps the interval inside it; a normal about the truth leaves the
    /// estimate there and narrows the interval; a wide normal elsewhere does not move a
    /// well-measured estimate far, a narrow one does.
    #[test]
    fn a_system_s_own_prior_bounds_and_weighs_the_estimate() {
        let lens = Lens::new(vec![Box::new(
            Sis::from_theta_e(DVec2::ZERO, 20.0).unwrap(),
        )]);
        let plane = LensPlane::new(Cosmology::default(), 0.3).unwrap();
        let f = plane.distance_ratio(2.5).unwrap();
        let images = [
            DVec2::new(3.0 + 20.0 * f, 0.0),
            DVec2::new(3.0 - 20.0 * f, 0.0),
        ];
        let with = |own: Option<RedshiftPrior>| {
            estimate_redshift_over(&[&lens], &plane, &images, [0.5, 8.0], own, 0.3, 10.0)
                .expect("estimate")
        };
        let flat = with(None);
        assert!((flat.z - 2.5).abs() < 0.02, "{flat:?}");
        let above = with(Some(RedshiftPrior::Range([3.0, 5.0])));
        assert!((above.z - 3.0).abs() < 0.01, "{above:?}");
        assert!(
            above.interval[0] >= 3.0 && above.interval[1] <= 5.0,
            "{above:?}"
        );
        let about = with(Some(RedshiftPrior::Normal([2.5, 0.05])));
        assert!((about.z - 2.5).abs() < 0.02, "{about:?}");
        let width = |e: &RedshiftEstimate| e.interval[1] - e.interval[0];
        assert!(width(&about) < width(&flat), "{about:?} {flat:?}");
        let wide = with(Some(RedshiftPrior::Normal([4.0, 3.0])));
        assert!((wide.z - 2.5).abs() < 0.1, "{wide:?}");
        let narrow = with(Some(RedshiftPrior::Normal([4.0, 0.01])));
        assert!((narrow.z - 4.0).abs() < 0.05, "{narrow:?}");
        // A range wholly in front of the lens leaves nothing to estimate.
        let lens_z = estimate_redshift_over(
            &[&lens],
            &plane,
            &images,
            [0.5, 8.0],
            Some(RedshiftPrior::Range([0.1, 0.25])),
            0.3,
            10.0,
        );
        assert!(lens_z.is_none());
    }

    /// The mass-sheet degeneracy with free redshifts, exactly: the lens `lambda alpha + (1 -
    /// lambda) theta` (the map scaled by `lambda` plus a uniform sheet of `1 - lambda`) puts
    /// the images of a source at `f = D_ls/D_s` where the original lens does for the source at
    /// `f' = 1 / (1 - lambda + lambda / f)` (the source plane scaled by `lambda f' / f`). So an
    /// estimated system fits a sheet-transformed map as well as the true one, at another
    /// redshift, and only the systems whose redshift is known hold `lambda`
    /// (BENCHMARKS.md, "Few redshifts").
    #[test]
    fn a_mass_sheet_moves_an_estimate_to_the_redshift_the_degeneracy_gives() {
        let theta_e = 20.0;
        let plane = LensPlane::new(Cosmology::default(), 0.3).unwrap();
        let f = plane.distance_ratio(2.5).unwrap();
        // The images of a source 3" off the centre behind the SIS at z = 2.5.
        let images = [
            DVec2::new(3.0 + theta_e * f, 0.0),
            DVec2::new(3.0 - theta_e * f, 0.0),
        ];
        for lambda in [0.8, 1.15] {
            let transformed = Lens::new(vec![
                Box::new(Sis::from_theta_e(DVec2::ZERO, lambda * theta_e).unwrap()),
                Box::new(crate::profiles::MassSheet::new(1.0 - lambda).unwrap()),
            ]);
            let e = estimate_redshift(&transformed, &plane, &images, [0.5, 8.0], 0.3, 10.0)
                .expect("estimate");
            let want = 1.0 / (1.0 - lambda + lambda / f);
            let got = plane.distance_ratio(e.z).unwrap();
            assert!(
                (got - want).abs() < 2e-3,
                "lambda {lambda}: f {got} against {want}: {e:?}"
            );
            assert!((e.z - 2.5).abs() > 0.3, "the sheet moves it: {e:?}");
            assert!(e.reduced_chi2 < 1e-2, "and it fits as well: {e:?}");
        }
    }

    #[test]
    fn offsets_vanish_at_the_true_distance_ratio() {
        // An SIS: images at +-(beta + theta_E f) on the x axis for a source at beta.
        let lens = Lens::new(vec![Box::new(
            Sis::from_theta_e(DVec2::ZERO, 20.0).unwrap(),
        )]);
        let f = 0.7;
        let images = [DVec2::new(3.0 + 14.0, 0.0), DVec2::new(3.0 - 14.0, 0.0)];
        let lensing: Vec<_> = images
            .iter()
            .map(|&t| {
                let (a, h) = lens.deflection_hessian(t);
                (t, a, h)
            })
            .collect();
        assert!(image_offsets2(&lensing, f, 10.0) < 1e-20);
        assert!(image_offsets2(&lensing, 0.6, 10.0) > 1.0);
        let plane = LensPlane::new(Cosmology::default(), 0.3).unwrap();
        assert!(estimate_redshift(&lens, &plane, &images[..1], [0.5, 8.0], 1.0, 10.0).is_none());
    }
}
