//! WSLAP+ free-form strong-lensing mass reconstruction (Sendra, Diego, Broadhurst & Lazkoz).
//!
//! A cluster's mass is a grid of Gaussian cells plus its member galaxies (luminosity-scaled
//! halos rescaled by free factors `C`), constrained by multiply-lensed images: the lens
//! equation becomes a linear system, solved with non-negative quadratic programming. The
//! equations, frames, units and file conventions are in [`method`]. Angles are arcsec in the
//! tangent-plane frame of [method §1] (+x West, +y North); every stored deflection,
//! convergence and shear is for `D_ls/D_s = 1`.
//!
//! Everything a user of the library needs is here at the root, in the order of the pipeline:
//!
//! - cosmology and the sky frame: [`Cosmology`], [`LensPlane`], [`SkyReference`];
//! - mass components and their maps: [`MassComponent`], [`Lens`], [`LensMaps`],
//!   [`CriticalCurves`], [`Products`], [`find_images`];
//! - the inputs: [`parse_image_catalog`], [`parse_member_catalog`], [`parse_arcs`],
//!   [`arcs_from_regions`], [`parse_par`], [`read_image`], and [`Dataset`], which reads them
//!   into one frame the way the command line and the app both do;
//! - a reconstruction: [`reconstruct`] of [`Inputs`] with a [`ReconstructConfig`], giving a
//!   [`Reconstruction`]; [`cross_validate`] for held-out systems;
//! - the pieces under it: the cell grid ([`CellGrid`]), members ([`build_member_layers`]), the
//!   constraints ([`build_constraints`]), the [`LinearSystem`] and the solvers
//!   ([`minimise_exact`], [`QadpProblem`], [`accelerated_gradient`]);
//! - figures ([`render_kappa_png`], [`LinePlot`]) and simulated clusters ([`Simulation`]).
//!
//! Every out-of-range setting is reported as a [`BadFieldValue`] inside the error of the step
//! that checked it. Two shells sit on this library: the `wslap` command line (`main.rs`) and the
//! browser app, whose core is [`app`] (called from a web worker through the wasm boundary);
//! [`paper`] reproduces the paper's test; [`playground`] is the live lensing playground.
//!
//! [method §1]: crate::method#1-frames-and-units

pub mod app;
pub mod method;
pub mod paper;
pub mod playground;

mod arcs;
mod catalog;
mod coordinates;
mod cosmology;
mod curves;
mod demo;
mod ds9;
mod error;
mod fits;
mod image_search;
mod inversion;
mod lenstool_par;
mod limits;
mod map;
mod model;
mod potential;
mod products;
mod profiles;
mod radial;
mod reconstruct;
mod render;
mod simulate;
mod sky;
mod solver;
mod stats;
mod threads;
mod units;

#[cfg(target_arch = "wasm32")]
mod wasm;

// Cosmology, the sky frame and units.
pub use coordinates::{
    parse_position, sexagesimal_text, CoordinateError, PositionForm, TypedPosition, SKY_MATCH_DEG,
};
pub use cosmology::{Cosmology, CosmologyError, LensPlane, H0_MAX_KM_S_MPC};
pub use sky::{parse_sky_angle, SkyReference};

// Mass components and the maps of a lens.
pub use curves::{
    critical_curves, critical_curves_about, einstein_radius_for, zero_contours, Caustics,
    CriticalCurves, LensRegion, Polyline, OPEN_AREA_SHARE, TANGENTIAL_BORDER_SHARE,
};
pub use demo::{CLUSTER_MODEL_JSON, TEACHING_MODEL_JSON};
pub use image_search::{
    find_images, source_position, source_scatter, FoundImage, ImageError, ImageKind, ImageSearch,
    Parity, SearchGrid,
};
pub use map::{magnification_at_point, LensMaps, Map, MapGeometry, MapsError, MAGNIFICATION_CLAMP};
pub use model::{ComponentSpec, ModelError, ModelFile};
pub use potential::{
    arrival_time_days, potential_at, potential_difference, potential_map, time_delay_distance_mpc,
};
pub use products::{
    ProductOptions, Products, ProductsError, EINSTEIN_MAP_WIDENING, MAIN_CURVE_NOTE_SHARE,
};
pub use profiles::{
    add_pixelwise, cell_unit_deflection, dpie_b0_arcsec, gaussian_unit_deflection,
    gaussian_unit_hessian, kk_epsilon, nfw_deflection, nfw_hessian, nfw_mass_cylinder_msun,
    nfw_terms, sis_theta_e_arcsec, tnfw_far_field_coefficients, tnfw_mass_and_kappa_unit, Dpie,
    ExternalShear, Gaussian, Lens, MassComponent, MassSheet, Nfw, NfwEllipse, NfwTerms, PointMass,
    ProfileError, Sie, Sis, TruncatedNfw, CSE_TERMS, DPIE_CIRCULAR_EPSILON,
    DPIE_SINGULAR_CORE_ARCSEC, NFW_X_FLOOR,
};
pub use radial::{radial_profile, rect_disc_area, RadialBins, RadialError, RadialProfile};

// The inputs: catalogues, arcs, regions, Lenstool models, FITS.
pub use arcs::{arcs_from_regions, parse_arcs, ArcCatalog, ArcSystem, ArcsError};
pub use catalog::{
    arclet_ellipticity, galaxy_of_system, parse_arclet_catalog, parse_arclet_catalog_with,
    parse_image_catalog, parse_member_catalog, parse_potfile_catalog, system_of_image, Arclet,
    ArcletCatalog, ArcletUnknownZ, CatalogError, CatalogKind, CatalogRow, CommentedBcgs, Image,
    ImageCatalog, ImageSystem, Member, MemberCatalog, DEGREE_LOOKALIKE, FIELD_ERROR_DEG,
    FIELD_WARN_DEG, MAG_NO_MEASUREMENT, Z_AGREEMENT_TOL,
};
pub use ds9::{
    polyline_is_open, read_regions, write_marks, write_regions, Ds9Error, Ds9Frame, Mark, Region,
    Shape,
};
pub use fits::{
    read_image, write_image, Card, CardValue, FitsError, FitsImage, FitsWriteOptions, NoDataPixels,
};
#[cfg(not(target_arch = "wasm32"))]
pub use lenstool_par::load_lenstool_model;
pub use lenstool_par::{
    parse_par, parse_par_with, FreeMass, GalaxyWithoutMag, LenstoolModel, LenstoolPar,
    ParComponent, ParError, ParGalaxies, ParHalo, ParOptions, ParRedshiftPrior, ParSourceZ,
    ParWarning, Radius, UnknownSourceZ, GALAXY_MAX_CORE_KPC, LENSTOOL_DEFAULT_Z_SOURCE,
};
pub use limits::{
    with_line_feeds, InputKind, TooLarge, MAX_ARCS_BYTES, MAX_ARC_PIXELS, MAX_CATALOG_BYTES,
    MAX_CATALOG_ROWS, MAX_FITS_BYTES, MAX_FITS_PIXELS, MAX_JSON_BYTES,
};

// The WSLAP+ inversion: cells, members, constraints, the linear system.
pub use inversion::{
    build_constraints, build_member_layers, capped_inverse_jacobian, cell_penalty, ellipse_pixels,
    export_system, npy_header, write_f64s, write_npy, AutoWord, Cell, CellGrid, ColumnInfo,
    ConstraintConfig, ConstraintError, ConstraintMode, ConstraintPixel, ConstraintSet,
    ConstraintSource, ConstraintSystem, ExcludedSystem, Exclusion, GridConfig, GridError, GridMass,
    HaloProfile, Layer, LayerSplit, LinearSystem, MapPlan, MemberConfig, MemberHalo, MemberModel,
    MembersError, NpyError, ObjectiveConfig, ObjectiveTerms, RedshiftPrior, Regulariser, RowBlock,
    ScaledLens, Strength, SystemConfig, SystemError, Weighting, LAYER_SHARE_WARN,
    MAX_SINGLE_LAYERS, PRIOR_PULL_SIGMA,
};
pub use inversion::{
    kappa_gamma, with_ring, ShearConfig, ShearPoint, ShearSet, MIN_ONE_MINUS_KAPPA,
};
// The tidal field of mass beyond the grid.
pub use inversion::{
    external_shear_layers, external_shear_of, shear_strength_angle, ExternalShearFit, LayerKind,
    EXTERNAL_SHEAR_UNIT,
};

// Non-negative quadratic programming.
pub use solver::{
    accelerated_gradient, column_independence, gram_weighted, iterate_schedule, locality_order,
    minimise_exact, nnqp_exact, objective as quadratic_objective, Control, Iterate,
    NormalEquations, Progress, QadpProblem, SolveOutcome, SolveStatus, SolverError, SolverSettings,
    INDEPENDENCE_MAX_UNKNOWNS, MAX_ITERATIONS, MAX_KEPT_ITERATES, NNQP_EXACT_MAX_UNKNOWNS,
};

// A reconstruction: inputs, settings, the run, cross-validation.
pub use reconstruct::{
    avoid_crowded_map, check_ensemble_size, check_memory, cross_validate, estimate_redshift,
    fitted_system_ids, fold_groups, holdable_sources, holdable_system_ids, image_regions,
    layer_count, product_options, reconstruct, reconstruct_with_choice, refit_for_second_choice,
    run_ensemble, second_choice, second_round, strength_candidates, strength_folds, strength_trial,
    with_uncrowded_map, ArrivalTimes, Bytes, Calibration, Candidate, ConvergenceRecord,
    CrossValidation, CrossvalTotals, CrowdedMap, Dataset, DatasetError, Ensemble, EnsembleMaps,
    EnsembleMember, EnsemblePlan, EstimatedRedshifts, FoldRun, FreeZSummary, Heap, HoldoutSource,
    ImageReport, InputText, InputTexts, Inputs, InterpolatedLens, KappaSpread, LayerSource,
    LeftOutImage, MemberDraw, MemberRun, MemoryEstimate, MemoryLimit, PredictedImage,
    PredictedSystem, ProductConfig, ReconstructConfig, ReconstructError, ReconstructSummary,
    Reconstruction, RedshiftEstimate, RunSize, RunStatus, SecondRound, Solved, SolverConfig,
    SolverMethod, SourceReport, StrengthCandidate, StrengthChoice, SystemCheck, TooMuchMemory,
    Trust, Verdict, VerdictInputs, WeakLensingFit, CALIBRATION_MIN_IMAGES,
    CALIBRATION_MIN_PREDICTIONS, CHOICE_MAP_PIXELS, CROWDED_MAP_RETRIES, DEFAULT_FOLDS,
    FALLBACK_MEMORY_LIMIT_BYTES, FALLBACK_SIGMA_ARCSEC, MAX_ENSEMBLE_MEMBERS, PAR_GALAXY_MAX_LSTAR,
    SHOWN_MIN_MAGNIFICATION, WASM_MEMORY_LIMIT_BYTES,
};

// The verdict on a reconstruction and its thresholds.
pub use reconstruct::{
    members_with_own_curves, BcgFacts, Crowding, FAR_MORE_PREDICTED_FACTOR, FLAG_OFFSET_ARCSEC,
    GOOD_FIT_OFFSET_ARCSEC, GOOD_HOLDOUT_OFFSET_ARCSEC, LOST_IMAGE_ARCSEC, LOST_SYSTEMS_SHARE,
    MAIN_CURVE_MIN_SHARE, ON_CURVE_MAGNIFICATION, ON_CURVE_SHARE, SMALL_SCALE_OFFSET_ARCSEC,
    WORST_SHOWN,
};

// Figures.
pub use render::{
    color_limits, compose_grid, compose_png_grid, grid_offsets, kappa_figure_frame,
    kappa_figure_frame_for, render_colormap_rgba, render_kappa_png, value_rgb, Axis, AxisScale,
    ColorScale, Colormap, FigureFrame, GridLayout, KappaPlotOptions, LegendPlace, LinePlot,
    LineStyle, Marker, Overlay, OverlayLabel, OverlayPoints, PlotFrame, Reference, RenderError,
    Series, CAUSTIC_RGB, LOG_RANGE, MAX_COMPOSED_PIXELS, MAX_COMPOSED_SIDE_PX, MAX_LINE_WIDTH_PX,
    MIN_PIXEL_SIDE_PX, NO_DATA_RGB, PALETTE, PIXEL_ALPHA, PLOT_SIDE_PX, RADIAL_RGB, TANGENTIAL_RGB,
};

// Simulated clusters.
#[cfg(not(target_arch = "wasm32"))]
pub use simulate::write_simulation;
pub use simulate::{
    GalaxySet, SimulatedSource, Simulation, SimulationConfig, MAX_SYSTEM_AREA_ARCSEC2,
    MIN_SYSTEM_AREA_ARCSEC2, N_GALAXIES, RADIAL_ZONE_ARCSEC, SOFT_TO_GALAXY, SYSTEM_GAP_PIXELS,
    TOTAL_FIELD_MASS_MSUN,
};

// Errors shared by every settings check, and the run's threads.
pub use error::BadFieldValue;
pub use threads::{available as available_threads, with_limit as with_thread_limit};
