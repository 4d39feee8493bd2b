//! The simulated A1689-like cluster of the WSLAP+ paper (section 4; [method §8]): the
//! data set on which the three reconstruction cases are run, and the app's built-in example.
//!
//! A cluster at `z_l = 0.185` made of 94 elliptical NFW galaxy halos ("galaxy-true") and a
//! smooth three-component halo ("soft") with three times their projected mass inside the
//! 198 arcsec field, 2.58e14 Msun/h in total (`cluster`); a perturbed copy of the galaxies
//! ("galaxy-model", ~20% in mass and scale radius); and 30 elliptical Sérsic sources at
//! A1689-like redshifts ray-traced through the truth lens on a 0.5 arcsec pixel grid, every
//! pixel above 1% of its source's peak brightness being one constraint (`raytrace`,
//! `sources`). Everything is deterministic for a seed (own SplitMix64 generator) and runs
//! without threads or files, so the same simulation is made in the browser.
//!
//! [method §8]: crate::method#8-the-papers-test

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

mod cluster;
mod raytrace;
pub(crate) mod rng;
mod sources;
mod write;

pub use cluster::{N_GALAXIES, SOFT_TO_GALAXY, TOTAL_FIELD_MASS_MSUN};
pub use raytrace::THRESHOLD_FRACTION;
pub use sources::{
    MAX_SYSTEM_AREA_ARCSEC2, MIN_SYSTEM_AREA_ARCSEC2, RADIAL_ZONE_ARCSEC, SOURCE_REDSHIFTS,
    SYSTEM_GAP_PIXELS,
};
#[cfg(not(target_arch = "wasm32"))]
pub use write::write_simulation;

use crate::arcs::{ArcCatalog, ArcSystem};
use crate::cosmology::{Cosmology, CosmologyError, LensPlane};
use crate::curves::critical_curves;
use crate::inversion::Layer;
use crate::map::LensMaps;
use crate::map::{Map, MapGeometry};
use crate::model::{ComponentSpec, ModelError, ModelFile};
use crate::products::ProductsError;
use crate::profiles::{MassComponent, ProfileError};
use crate::sky::SkyReference;

/// Sky position of the frame origin (the BCG of A1689, J2000 13:11:29.5 -01:20:28), degrees.
pub const REFERENCE_RA_DEG: f64 = 197.872_917;
pub const REFERENCE_DEC_DEG: f64 = -1.341_111;
/// Source redshift of the reported Einstein radius and of the written truth products.
pub const SUMMARY_Z_SOURCE: f64 = 3.0;

/// What can go wrong while simulating or writing the simulation.
#[derive(Debug, Error)]
pub enum SimulateError {
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    #[error(transparent)]
    Cosmology(#[from] CosmologyError),
    #[error("simulated truth model: {0}")]
    Model(#[from] ModelError),
    #[error("simulated halo {index}: {source}")]
    Halo {
        index: usize,
        #[source]
        source: ProfileError,
    },
    #[error("simulation: {what} cannot be normalised (value {value})")]
    Normalisation { what: &'static str, value: f64 },
    #[error("simulation: could not place {what} after {attempts} attempts")]
    Placement { what: String, attempts: usize },
    #[error("simulation: source {system} at z = {z} has no caustic to be placed on")]
    NoCaustic { system: String, z: f64 },
    #[error("simulation: PNG encoding failed: {0}")]
    Png(String),
    #[error("simulation products: {0}")]
    Products(#[from] ProductsError),
    #[error("{path}: {message}")]
    Io { path: String, message: String },
}

/// Settings of the simulation; every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimulationConfig {
    /// Seed of every random draw (default 1).
    pub seed: u64,
    /// Pixel of the ray-traced image, arcsec (default 0.5). Allowed [0.2, 1]: the sources are
    /// 0.1-0.6 arcsec across, coarser pixels do not resolve their arcs.
    pub pixel_arcsec: f64,
    /// Side of the square field centred on the BCG, arcsec (default 198 = 3.3 arcmin).
    /// Allowed [100, 600].
    pub field_arcsec: f64,
    /// Lens redshift (default 0.185, A1689). Allowed [0.05, 1].
    pub z_lens: f64,
    /// Number of sources (default 30). Allowed 1 to 30.
    pub n_sources: usize,
    /// Log-normal scatter of the galaxy-model masses and scale radii (default 0.2). Allowed [0, 1].
    pub model_scatter: f64,
}

impl Default for SimulationConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            pixel_arcsec: 0.5,
            field_arcsec: 198.0,
            z_lens: 0.185,
            n_sources: 30,
            model_scatter: 0.2,
        }
    }
}

impl SimulationConfig {
    /// Checks every field against the range in its documentation.
    pub fn validate(&self) -> Result<(), SimulateError> {
        let checks = [
            ("pixel_arcsec", self.pixel_arcsec, 0.2, 1.0),
            ("field_arcsec", self.field_arcsec, 100.0, 600.0),
            ("z_lens", self.z_lens, 0.05, 1.0),
            (
                "n_sources",
                self.n_sources as f64,
                1.0,
                SOURCE_REDSHIFTS.len() as f64,
            ),
            ("model_scatter", self.model_scatter, 0.0, 1.0),
        ];
        for (field, value, lo, hi) in checks {
            if !(value.is_finite() && (lo..=hi).contains(&value)) {
                return Err(crate::error::BadFieldValue::new(
                    format!("simulation.{field}"),
                    value,
                    crate::error::range_reason(lo, hi, false),
                )
                .into());
            }
        }
        Ok(())
    }
}

/// Which galaxy set: the truth, or the perturbed model used as the reconstruction prior.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GalaxySet {
    True,
    Model,
}

/// One simulated source and what it produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimulatedSource {
    /// System id ("1" to "30"), also the id in the arc and image catalogues.
    pub id: String,
    pub z: f64,
    /// True source position, arcsec.
    pub beta_arcsec: DVec2,
    /// Half-light radius of the Sérsic profile, arcsec (and in physical kpc).
    pub r_half_arcsec: f64,
    pub r_half_kpc: f64,
    /// Axis ratio and position angle (degrees CCW from +x) of the source.
    pub q: f64,
    pub pa_deg: f64,
    pub sersic_n: f64,
    /// Elliptical radius of the constraint threshold, arcsec: every arc pixel maps inside it.
    pub threshold_radius_arcsec: f64,
    /// `D_ls/D_s` of the source.
    pub distance_ratio: f64,
    pub n_images: usize,
    pub n_pixels: usize,
    /// Whether one image crosses the central radial critical curve (see `sources`).
    pub radial_arc: bool,
}

/// The simulated data set (units in the field names; masses in Msun).
#[derive(Debug, Clone)]
pub struct Simulation {
    pub config: SimulationConfig,
    pub plane: LensPlane,
    pub reference: SkyReference,
    pub soft: Vec<ComponentSpec>,
    pub galaxies_true: Vec<ComponentSpec>,
    pub galaxies_model: Vec<ComponentSpec>,
    pub sources: Vec<SimulatedSource>,
    /// System ids = source ids, z set, images = 8-connected pixel groups (pixel centres).
    pub arcs: ArcCatalog,
    /// Lensed surface brightness of all sources on the `pixel_arcsec` grid of the field.
    pub image: Map,
    /// The truth's lens maps on the same grid (`D_ls/D_s = 1`): what the sources were
    /// ray-shot through, reused for the written truth products.
    pub truth_maps: LensMaps,
    /// Soft halo, projected inside the field square.
    pub soft_mass_msun: f64,
    /// Galaxy-true, projected inside the field square.
    pub galaxy_mass_msun: f64,
    /// Factors applied to `rho_s` of the drawn galaxies and soft components to meet the masses.
    pub galaxy_normalisation: f64,
    pub soft_normalisation: f64,
    /// Effective Einstein radius of the truth at `z_s = 3`, arcsec.
    pub theta_e_z3_arcsec: f64,
    /// Wall-clock time of [`Simulation::new`], ms.
    pub elapsed_ms: f64,
}

/// The short account written as `simulation.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimulationSummary {
    pub seed: u64,
    pub pixel_arcsec: f64,
    pub field_arcsec: f64,
    pub z_lens: f64,
    pub reference_ra_deg: f64,
    pub reference_dec_deg: f64,
    pub n_galaxies: usize,
    pub soft_mass_msun: f64,
    pub galaxy_mass_msun: f64,
    pub total_mass_msun: f64,
    /// The total in Msun/h with h = H0/100.
    pub total_mass_msun_per_h: f64,
    pub soft_to_galaxy: f64,
    pub galaxy_normalisation: f64,
    pub soft_normalisation: f64,
    pub theta_e_z3_arcsec: f64,
    pub threshold_fraction: f64,
    pub n_systems: usize,
    pub n_images: usize,
    pub n_pixels: usize,
    pub n_radial_arc_systems: usize,
    pub elapsed_ms: f64,
    pub sources: Vec<SimulatedSource>,
}

impl Simulation {
    /// Simulates the cluster, the sources and their arcs for `config` (module documentation).
    pub fn new(config: &SimulationConfig) -> Result<Self, SimulateError> {
        let clock = crate::products::Clock::start();
        config.validate()?;
        let plane = LensPlane::new(Cosmology::default(), config.z_lens)?;
        let cl = cluster::build_cluster(config, &plane)?;
        let specs = |h: &[cluster::Halo]| h.iter().map(cluster::Halo::spec).collect::<Vec<_>>();
        let mut sim = Self {
            config: *config,
            plane,
            reference: reference(),
            soft: specs(&cl.soft),
            galaxies_true: specs(&cl.galaxies_true),
            galaxies_model: specs(&cl.galaxies_model),
            sources: Vec::new(),
            arcs: ArcCatalog {
                source_name: "simulation".into(),
                systems: Vec::new(),
            },
            image: Map {
                geometry: MapGeometry::centered(config.field_arcsec, 1),
                data: vec![0.0],
            },
            truth_maps: LensMaps::zeros(MapGeometry::centered(config.field_arcsec, 1)),
            soft_mass_msun: cl.soft_mass_msun,
            galaxy_mass_msun: cl.galaxy_mass_msun,
            galaxy_normalisation: cl.galaxy_norm,
            soft_normalisation: cl.soft_norm,
            theta_e_z3_arcsec: 0.0,
            elapsed_ms: 0.0,
        };
        let lens = sim.truth_model().build_lens()?;
        let pixels = (config.field_arcsec / config.pixel_arcsec)
            .round()
            .max(16.0) as usize;
        let geometry = MapGeometry::centered(config.field_arcsec, pixels);
        let maps = LensMaps::from_lens(&lens, geometry);
        let f3 = plane.distance_ratio(SUMMARY_Z_SOURCE)?;
        sim.theta_e_z3_arcsec =
            critical_curves(&maps, f3, SUMMARY_Z_SOURCE, None).einstein_radius_arcsec;
        let grid = raytrace::RayGrid::new(&maps);
        let placed = sources::place_sources(config.seed, config.n_sources, &plane, &maps, &grid)?;
        let mut image = vec![0.0; pixels * pixels];
        for p in &placed {
            grid.add_brightness(p.f, &p.shape, &mut image);
        }
        sim.image = Map {
            geometry,
            data: image,
        };
        sim.arcs.systems = placed
            .iter()
            .map(|p| ArcSystem {
                id: p.source.id.clone(),
                z: Some(p.source.z),
                images: p
                    .images
                    .iter()
                    .map(|im| im.iter().map(|&k| grid.position(k)).collect())
                    .collect(),
                image_ids: Vec::new(),
                line: 0,
            })
            .collect();
        sim.sources = placed.into_iter().map(|p| p.source).collect();
        sim.truth_maps = maps;
        sim.elapsed_ms = clock.ms();
        Ok(sim)
    }

    fn model_file(&self, components: Vec<ComponentSpec>, name: &str) -> ModelFile {
        ModelFile {
            cosmology: self.plane.cosmology,
            z_lens: self.plane.z_lens,
            reference: Some(self.reference),
            components,
            source_name: name.to_string(),
        }
    }

    /// The truth: soft halo and galaxy-true.
    pub fn truth_model(&self) -> ModelFile {
        let mut c = self.soft.clone();
        c.extend_from_slice(&self.galaxies_true);
        self.model_file(c, "simulation truth")
    }

    /// The soft (cluster) halo alone.
    pub fn soft_model(&self) -> ModelFile {
        self.model_file(self.soft.clone(), "simulation soft halo")
    }

    /// The galaxies of `set` alone.
    pub fn galaxies_model_file(&self, set: GalaxySet) -> ModelFile {
        match set {
            GalaxySet::True => self.model_file(self.galaxies_true.clone(), "galaxy-true"),
            GalaxySet::Model => self.model_file(self.galaxies_model.clone(), "galaxy-model"),
        }
    }

    /// The galaxies of `set` as one fiducial-deflection layer named "galaxy-true" or
    /// "galaxy-model" (deflections in arcsec at `D_ls/D_s = 1`).
    pub fn layer(&self, set: GalaxySet) -> Result<Layer, SimulateError> {
        let (name, specs) = match set {
            GalaxySet::True => ("galaxy-true", &self.galaxies_true),
            GalaxySet::Model => ("galaxy-model", &self.galaxies_model),
        };
        let components = specs
            .iter()
            .enumerate()
            .map(|(index, s)| {
                s.build(&self.plane)
                    .map_err(|source| SimulateError::Halo { index, source })
            })
            .collect::<Result<Vec<Box<dyn MassComponent>>, _>>()?;
        Ok(Layer::from_components(name, components))
    }

    /// The summary written as `simulation.json`.
    pub fn summary(&self) -> SimulationSummary {
        let total = self.soft_mass_msun + self.galaxy_mass_msun;
        SimulationSummary {
            seed: self.config.seed,
            pixel_arcsec: self.image.geometry.pixel_arcsec(),
            field_arcsec: self.config.field_arcsec,
            z_lens: self.plane.z_lens,
            reference_ra_deg: self.reference.ra_deg,
            reference_dec_deg: self.reference.dec_deg,
            n_galaxies: self.galaxies_true.len(),
            soft_mass_msun: self.soft_mass_msun,
            galaxy_mass_msun: self.galaxy_mass_msun,
            total_mass_msun: total,
            total_mass_msun_per_h: total * self.plane.cosmology.h0 / 100.0,
            soft_to_galaxy: self.soft_mass_msun / self.galaxy_mass_msun,
            galaxy_normalisation: self.galaxy_normalisation,
            soft_normalisation: self.soft_normalisation,
            theta_e_z3_arcsec: self.theta_e_z3_arcsec,
            threshold_fraction: THRESHOLD_FRACTION,
            n_systems: self.sources.len(),
            n_images: self.sources.iter().map(|s| s.n_images).sum(),
            n_pixels: self.sources.iter().map(|s| s.n_pixels).sum(),
            n_radial_arc_systems: self.sources.iter().filter(|s| s.radial_arc).count(),
            elapsed_ms: self.elapsed_ms,
            sources: self.sources.clone(),
        }
    }
}

/// The sky reference of the frame (A1689's BCG).
fn reference() -> SkyReference {
    SkyReference {
        ra_deg: REFERENCE_RA_DEG,
        dec_deg: REFERENCE_DEC_DEG,
    }
}

/// Total flux of a pixel set of the brightness map (value times pixel area, arcsec^2).
pub(crate) fn flux(image: &Map, points: &[DVec2]) -> f64 {
    let g = image.geometry;
    let n = g.pixels;
    let area = g.pixel_arcsec() * g.pixel_arcsec();
    points
        .iter()
        .map(|&p| {
            let q = g.arcsec_to_pixel(p).round();
            let (i, j) = (
                q.x.clamp(0.0, (n - 1) as f64),
                q.y.clamp(0.0, (n - 1) as f64),
            );
            image.at(i as usize, j as usize) * area
        })
        .sum()
}
