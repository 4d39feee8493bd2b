//! `wslap reconstruct`: the WSLAP+ inversion of a Lenstool image catalogue.

use std::fs;
use std::path::{Path, PathBuf};

use clap::Args;
use serde::Serialize;
use wslap::{
    check_ensemble_size, check_memory, cross_validate, export_system, fold_groups,
    holdable_sources, image_regions, parse_par_with, reconstruct, run_ensemble,
    strength_candidates, ColorScale, Control, ConvergenceRecord, Cosmology, CosmologyError,
    CrossValidation, Dataset, InputKind, InputText, InputTexts, Inputs, LensPlane, LenstoolPar,
    ParOptions, ReconstructConfig, ReconstructError, Reconstruction, SolverMethod,
};

use super::input::read_text;
use super::maps::write_products;

/// Free-form mass reconstruction (WSLAP+) from multiple images and member galaxies.
///
/// Writes into DIR the map files of `wslap maps` (kappa.fits, ..., kappa.png) for the
/// reconstructed lens, plus sources.json (per system: z, beta, scatter, observed and predicted
/// images, offsets; held-out systems marked), images.reg (DS9 circles: observed images green,
/// predicted ones magenta), convergence.json (objective, grid mass and C per report) and
/// summary.json (settings, C per layer, grid mass, enclosed masses, Einstein
/// radius, image-plane rms, the weak-lensing fit with --shear, timings); with --folds also crossval.json and the folds' convergence
/// (crossval-kappa-mean.fits, crossval-kappa-spread.fits, crossval-kappa-spread.png).
#[derive(Debug, Args)]
#[command(group(
    clap::ArgGroup::new("constraints")
        .required(true)
        .multiple(true)
        .args(["images", "arcs"])
))]
pub struct ReconstructArgs {
    /// Lenstool multiple-image catalogue (id x y a b theta z mag).
    #[arg(long, value_name = "IMAGES.cat")]
    images: Option<PathBuf>,
    /// Arc pixels. Alone they are fitted as arcs; with --images, constraints.mode "arcs" fits
    /// them and the catalogue gives the frame and the redshifts of regions without one. Either JSON
    /// ({"systems": [{"id", "z", "images": [[[x, y], ...], ...]}]}, arcsec) or a DS9 region file
    /// in fk5: one region per image (polygon, circle, ellipse, box or point) labelled
    /// text={1.1 z=2.5}, sampled at constraints.pixel_arcsec; '-' regions cut pixels out.
    #[arg(long, value_name = "ARCS.json|ARCS.reg")]
    arcs: Option<PathBuf>,
    /// Lenstool member catalogue (potfile: id x y a b theta mag lum). When no member near the
    /// multiple images is as bright as a BCG (4 L*) and commented-out rows there are (one per
    /// core), they are fitted as BCGs and a warning names their lines
    /// (`members.fit_commented_bcg` in the --config file: false leaves them out).
    #[arg(long, value_name = "MEMBERS.cat")]
    members: Option<PathBuf>,
    /// A Lenstool .par of the same cluster (e.g. the published model's bestopt.par): the
    /// galaxies it models on its own, dPIE potentials with a core of at most 5 kpc and a `mag`
    /// (typically the BCG, which the member catalogue then leaves out), are fitted as members,
    /// and the `z_m_limit` lines of its image block set the redshift priors of the systems they
    /// name (flag 0 fixed, 1 uniform, 3 normal; over the catalogue's redshift, as in Lenstool).
    /// Its cluster-scale potentials are not used.
    #[arg(long, value_name = "MODEL.par")]
    par: Option<PathBuf>,
    /// Lenstool arclet catalogue (id x y a b theta z) of weakly lensed background galaxies:
    /// each galaxy's ellipticity (a - b)/(a + b) exp(2i theta) adds two reduced-shear rows,
    /// and a ring of coarser cells around the grid reaches the median galaxy (the outer half,
    /// beyond the grid, weigh the mass inside it).
    #[arg(long, value_name = "ARCLETS.cat")]
    shear: Option<PathBuf>,
    /// Shape noise of the arclets: the scatter of each ellipticity component (default 0.3;
    /// overrides shear.shape_noise of the configuration).
    #[arg(
        long,
        value_name = "SIGMA",
        requires = "shear",
        allow_negative_numbers = true
    )]
    shape_noise: Option<f64>,
    /// Lens redshift.
    #[arg(long, allow_negative_numbers = true)]
    z_lens: f64,
    /// Settings (JSON); every field is optional. `wslap config` prints them all with their
    /// defaults.
    #[arg(long, value_name = "CONFIG.json")]
    config: Option<PathBuf>,
    /// Systems to leave out of the fit and predict, e.g. 3,7.
    #[arg(long, value_delimiter = ',', value_name = "IDS")]
    holdout: Vec<String>,
    /// Redshift for systems whose catalogue redshift is 0 (unknown); without it their redshift
    /// is estimated (see --free-z).
    #[arg(long, allow_negative_numbers = true)]
    default_z: Option<f64>,
    /// Systems whose redshift is estimated although the catalogue gives one, e.g. 3,7 (systems
    /// with z = 0 are estimated anyway). Each is left out of a first fit, its redshift found on
    /// that lens (sources.json: z_estimate and its 68% z_interval), then fitted at it.
    #[arg(long, value_delimiter = ',', value_name = "IDS")]
    free_z: Vec<String>,
    /// The range an estimated redshift lies in, LOW,HIGH (default 0.5,8).
    #[arg(
        long,
        value_delimiter = ',',
        num_args = 1..=2,
        value_name = "LOW,HIGH",
        allow_negative_numbers = true
    )]
    z_prior: Option<Vec<f64>>,
    /// QADP iterations (overrides the configuration).
    #[arg(long)]
    iterations: Option<usize>,
    /// H0 in km/s/Mpc.
    #[arg(long, allow_negative_numbers = true, default_value_t = 70.0)]
    h0: f64,
    /// Omega_m of flat LCDM.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.3)]
    omega_m: f64,
    /// Also cross-validate (default 5 folds): reconstruct K more times, each time holding out
    /// one group of the fitted systems (every K-th in catalogue order) and predicting its
    /// images; writes crossval.json (per fold and per predicted system; the held-out images'
    /// median and rms offsets against the fitted ones'). How well the settings predict images
    /// the model was not given. Also the mean and standard deviation of the folds' convergence
    /// on the maps of kappa.fits (crossval-kappa-mean.fits, crossval-kappa-spread.fits and a
    /// PNG): where the mass map depends on which systems are fitted. With fewer systems that
    /// can be held out than K, one fold per system.
    #[arg(long, value_name = "K", num_args = 0..=1, default_missing_value = "5")]
    folds: Option<usize>,
    /// Also run an ensemble of N more reconstructions (2 to 200) that differ in the systems
    /// fitted (bootstrap over systems) and the grid's placement (up to half a cell), with this
    /// run's settings: writes kappa-mean.fits, kappa-std.fits, magnif-p16/p50/p84.fits, each
    /// member's maps in range/, ensemble.json, kappa-std.png, and the 16th - 84th percentile
    /// ranges of the Einstein radius and enclosed masses in summary.json.
    #[arg(long, value_name = "N")]
    ensemble: Option<usize>,
    /// Seed of the ensemble's draws (the same seed gives the same members).
    #[arg(long, default_value_t = 1, requires = "ensemble")]
    seed: u64,
    /// Also write the linear system (gamma.npy, theta.npy, weights.npy, columns.json) here.
    #[arg(long, value_name = "DIR")]
    export_system: Option<PathBuf>,
    /// Output folder (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// Prints every setting of `wslap reconstruct --config` with its default value.
///
/// The output is a complete CONFIG.json: save it, change what you need and pass it back with
/// `--config` (fields left out keep these defaults; `null` means "not set", e.g. an automatic
/// field width or no prior on C). What each field means and its allowed range: README.md. A
/// run's `summary.json` repeats these settings as given (`settings`); with the strength "auto",
/// what the choice used is in `strength_choice` (`chosen`, `chosen_regulariser`,
/// `chosen_cells`).
#[derive(Debug, Args)]
pub struct ConfigArgs {}

pub fn print_config() -> Result<(), String> {
    let json = serde_json::to_string_pretty(&ReconstructConfig::default())
        .map_err(|e| format!("writing the default settings: {e}"))?;
    println!("{json}");
    Ok(())
}

pub fn run(args: &ReconstructArgs) -> Result<(), String> {
    super::input::check_out_dir(&args.out)?;
    let mut config = match &args.config {
        Some(path) => ReconstructConfig::from_json_str(
            &read_text(path, InputKind::Config)?,
            &path.display().to_string(),
        )
        .map_err(|e| e.to_string())?,
        None => ReconstructConfig::default(),
    };
    // Where the settings came from, for messages: the file, with the options over it.
    let settings_name = match &args.config {
        Some(path) => path.display().to_string(),
        None => "the default settings".to_string(),
    };
    if let Some(n) = args.iterations {
        config.solver.iterations = n;
    }
    if !args.free_z.is_empty() {
        config.constraints.free_z_systems.clone_from(&args.free_z);
    }
    if let Some(prior) = &args.z_prior {
        let &[low, high] = prior.as_slice() else {
            return Err(format!(
                "--z-prior needs two redshifts, LOW,HIGH (e.g. --z-prior 0.5,8); {} given",
                prior.len()
            ));
        };
        config.constraints.free_z_prior = Some([low, high]);
    }
    if args.default_z.is_some() {
        config.constraints.default_z = args.default_z;
    }
    if let Some(sigma) = args.shape_noise {
        config.shear.shape_noise = sigma;
    }
    let option = |flag: &str, e: &dyn std::fmt::Display| format!("{flag}: {e}");
    config
        .solver_settings()
        .validate()
        .map_err(|e| option("--iterations", &e))?;
    config
        .shear
        .validate()
        .map_err(|e| option("--shape-noise", &e))?;
    config.constraints.validate().map_err(|e| {
        match e.to_string().contains("free_z_prior") && args.z_prior.is_some() {
            true => option("--z-prior", &e),
            false => option("--default-z", &e),
        }
    })?;
    // A value refused by the distances is named by the option that gave it.
    let by_flag = |e: CosmologyError| match &e {
        CosmologyError::BadFieldValue(bad) => option(
            match bad.field.as_str() {
                "cosmology.h0" => "--h0",
                "cosmology.omega_m" => "--omega-m",
                _ => "--z-lens",
            },
            &e,
        ),
        CosmologyError::SourceNotBehindLens { .. } => option("--z-lens", &e),
    };
    let cosmology = Cosmology::new(args.h0, args.omega_m).map_err(by_flag)?;
    let plane = LensPlane::new(cosmology, args.z_lens).map_err(by_flag)?;
    // Known before any data is read: a source in front of the lens is refused at once.
    if let Err(e) = config.check_behind_lens(args.z_lens) {
        return Err(
            if e.field == "constraints.default_z" && args.default_z.is_some() {
                option("--default-z", &e)
            } else if e.field.starts_with("constraints.free_z_prior") && args.z_prior.is_some() {
                option("--z-prior", &e)
            } else if args.config.is_none() {
                // The lens put behind a redshift the default settings use (the maps' z_s = 2):
                // the option is what to change.
                format!("--z-lens {}: {settings_name}: {e}", args.z_lens)
            } else {
                format!("{settings_name}: {e}")
            },
        );
    }
    let texts = [&args.images, &args.members, &args.arcs, &args.shear].map(|path| {
        let kind = if path == &args.arcs {
            InputKind::Arcs
        } else {
            InputKind::Catalog
        };
        path.as_ref()
            .map(|p| Ok::<_, String>((name(p), read_text(p, kind)?)))
            .transpose()
    });
    let [images, members, arcs, shear] = texts;
    let (images, members, arcs, shear) = (images?, members?, arcs?, shear?);
    fn text(f: &Option<(String, String)>) -> Option<InputText<'_>> {
        f.as_ref().map(|(name, text)| InputText { name, text })
    }
    let par = match &args.par {
        Some(path) => {
            let text = read_text(path, InputKind::Model)?;
            let options = ParOptions::default().for_galaxies();
            Some(parse_par_with(&text, &name(path), &options).map_err(|e| e.to_string())?)
        }
        None => None,
    };
    let unknown_source_z = par.as_ref().map(LenstoolPar::unknown_source_z);
    let files = InputTexts {
        images: text(&images),
        members: text(&members),
        arcs: text(&arcs),
        shear: text(&shear),
        potfile_reference: par.as_ref().and_then(LenstoolPar::potfile_reference),
        unknown_source_z: unknown_source_z.as_ref(),
    };
    let mut data =
        Dataset::read(&files, config.constraints.pixel_arcsec).map_err(|e| e.to_string())?;
    if let Some(par) = &par {
        for w in &par.warnings {
            if let Some(block) = &w.moved_block {
                // Read for its galaxies, a multi-plane .par is moved to one plane only to be
                // read: nothing of a block at another redshift is used.
                eprintln!(
                    "note: {}:{}: block `{block}` lies at another redshift than z_lens = {}: \
                     not used (a reconstruction takes from a .par its galaxies at z_lens and \
                     its redshift priors; members come from --members)",
                    w.file, w.line, par.z_lens
                );
            } else {
                eprintln!("warning: {w}");
            }
        }
        for note in data
            .add_par(par, &plane, &config)
            .map_err(|e| e.to_string())?
        {
            eprintln!("note: {note}");
        }
    }
    // The run's warnings say so when it fits a commented-out BCG row.
    data.fit_commented_bcgs(&plane, &config);
    let unfitted = data.unfitted_arcs(config.constraints.mode);
    for w in data.warnings.iter().chain(&unfitted) {
        eprintln!("warning: {w}");
    }
    let inputs = data
        .inputs(plane, &args.holdout, &mut config)
        .map_err(|e| e.to_string())?;
    let folds = match args.folds {
        Some(asked) => Some(usable_folds(&inputs, &config, asked)?),
        None => None,
    };
    if let Some(n) = args.ensemble {
        check_ensemble_size(n).map_err(|e| format!("--ensemble: {e}"))?;
    }
    // So is a run larger than the machine's memory (`reconstruct` checks it again).
    // Only a size the settings ask for is theirs to blame; a bad hold-out or an empty
    // system names its own file or option.
    check_memory(&inputs, &config).map_err(|e| match e {
        ReconstructError::Memory(_) | ReconstructError::BadFieldValue(_) => {
            format!("{settings_name}: {e}")
        }
        // A system the options name that the catalogue lacks: the option that named it.
        ReconstructError::Constraints(_)
            if !args.free_z.is_empty() && e.to_string().contains("free_z_systems") =>
        {
            format!("--free-z: {e}")
        }
        ReconstructError::Constraints(_)
            if !args.holdout.is_empty() && e.to_string().contains("hold-out") =>
        {
            format!("--holdout: {e}")
        }
        other => other.to_string(),
    })?;
    let total = config.solver.iterations;
    let exact = config.solver.method == SolverMethod::Exact;
    let mut progress = |r: &ConvergenceRecord| {
        if exact {
            // One line per exchange of the free set (the start, X = 0, says nothing).
            if r.iteration > 0 {
                eprintln!(
                    "pass {} exchange {:>3}: objective {:.6e}, grid mass {:.4e} Msun{}",
                    r.level,
                    r.iteration,
                    r.objective,
                    r.grid_mass_msun,
                    c_text(", ", &r.c)
                );
            }
        } else if r.iteration % 1000 == 0 || r.iteration == total {
            eprintln!(
                "level {} iteration {:>6}/{total}: objective {:.6e}, grid mass {:.4e} Msun{}",
                r.level,
                r.iteration,
                r.objective,
                r.grid_mass_msun,
                c_text(", ", &r.c)
            );
        }
        Control::Continue
    };
    // The choice's trials run side by side and report nothing until it is made.
    if config.objective.strength.value().is_none() {
        eprintln!(
            "choosing the regulariser, its strength and the grid: {} candidates, each \
             cross-validated over up to {} folds, side by side on the cores (AS1063's 50 images: \
             about a minute); then the chosen map's passes",
            strength_candidates(&config).len(),
            config.objective.folds
        );
    }
    let result = reconstruct(&inputs, &config, &mut progress).map_err(|e| e.to_string())?;
    for w in &result.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(dir) = &args.export_system {
        export_system(&result.system, dir).map_err(|e| e.to_string())?;
    }
    write_reconstruction(&result, &args.out)?;
    println!("{}", one_line(&result, &args.out));
    let cv = match folds {
        Some(folds) => Some(run_crossval(&inputs, &config, folds, &result, &args.out)?),
        None => None,
    };
    if let Some(n) = args.ensemble {
        write_ensemble(
            &inputs,
            &config,
            n,
            args.seed,
            &result,
            cv.as_ref(),
            &args.out,
        )?;
    }
    Ok(())
}

/// `--ensemble`: `members` more reconstructions ([`run_ensemble`]), their files written to
/// `out` and their ranges added to its summary.json (which keeps the cross-validation `cv`'s
/// totals, with `--folds`), with a line on stdout.
fn write_ensemble(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    members: usize,
    seed: u64,
    result: &Reconstruction,
    cv: Option<&CrossValidation>,
    out: &Path,
) -> Result<(), String> {
    // Members run side by side, their reports interleaved: a line when each starts.
    let mut started = vec![false; members + 1];
    let mut progress = |member: usize, _: &ConvergenceRecord| {
        if let Some(seen @ false) = started.get_mut(member) {
            *seen = true;
            eprintln!("ensemble member {member}/{members}");
        }
        Control::Continue
    };
    let ensemble = run_ensemble(inputs, config, result, members, seed, &mut progress)
        .map_err(|e| e.to_string())?;
    let p = &result.products;
    let files = ensemble
        .files(p.reference, p.plane.z_lens, Some(&p.curves))
        .map_err(|e| e.to_string())?;
    let range = out.join("range");
    fs::create_dir_all(&range).map_err(|e| format!("{}: {e}", range.display()))?;
    let write = |file: &str, bytes: &[u8]| -> Result<(), String> {
        let path = out.join(file);
        fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))
    };
    for (file, bytes) in &files {
        write(file, bytes)?;
    }
    write("ensemble.json", json(&ensemble)?.as_bytes())?;
    // The ranges join the main run's summary.json.
    let mut summary = serde_json::to_value(result.summary_after(cv)).map_err(|e| e.to_string())?;
    ensemble.add_to_summary(&mut summary);
    write("summary.json", json(&summary)?.as_bytes())?;
    let radius = ensemble
        .einstein_radius_interval_arcsec
        .map_or("n/a".to_string(), |[a, b]| {
            format!("{a:.2} - {b:.2} arcsec")
        });
    // Members whose first map was crowded and who fitted their draw's next candidates.
    let moved = ensemble
        .members
        .iter()
        .filter(|m| !m.crowded_maps.is_empty())
        .count();
    let moved = match moved {
        0 => String::new(),
        k => format!("; {k} passed over crowded maps for their next candidates"),
    };
    println!(
        "wrote {} ({} members: Einstein radius (16th - 84th percentile) {radius}{moved}; \
         kappa-mean.fits, kappa-std.fits, magnif-p16/p50/p84.fits, range/)",
        out.join("ensemble.json").display(),
        ensemble.members.len()
    );
    Ok(())
}

/// The folds `--folds asked` runs: `asked`, or one per system a fold can hold out when there
/// are fewer (as the app's Cross-validate takes them), said on stderr; a number that cannot
/// work even so (below 2 folds or 2 such systems) is refused before the first run.
fn usable_folds(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    asked: usize,
) -> Result<usize, String> {
    let holdable = holdable_sources(inputs, config)
        .map_err(|e| e.to_string())?
        .len();
    let folds = match asked > holdable && holdable >= 2 {
        true => {
            eprintln!(
                "note: --folds {asked}: {holdable} systems can be held out (those fitted at a \
                 redshift of their own, the knots of one galaxy counted once), so {holdable} \
                 folds, one system each"
            );
            holdable
        }
        false => asked,
    };
    fold_groups(inputs, config, folds).map_err(|e| e.to_string())?;
    Ok(folds)
}

/// `--folds`: the cross-validation of `result`'s inputs and settings over `folds` folds, written
/// to `out` (crossval.json and the folds' convergence maps; summary.json again, with its totals
/// and the verdict they inform) with a line on stdout.
fn run_crossval(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    folds: usize,
    result: &Reconstruction,
    out: &Path,
) -> Result<CrossValidation, String> {
    // A fold's first report says it fits (after its own choice of the settings, which reports
    // nothing); QADP's last one too.
    let total = config.solver.iterations;
    let qadp = config.solver.method != SolverMethod::Exact;
    eprintln!(
        "cross-validating over {folds} folds{}",
        match config.objective.strength.value() {
            None => ", side by side; each chooses its settings again (as above) before it fits",
            Some(_) => ", side by side",
        }
    );
    let mut started = vec![false; folds + 1];
    let mut progress = |fold: usize, r: &ConvergenceRecord| {
        if let Some(seen @ false) = started.get_mut(fold) {
            *seen = true;
            eprintln!("fold {fold}/{folds}: fitting");
        }
        if qadp && r.iteration == total {
            eprintln!("fold {fold}/{folds}: {total} iterations");
        }
        Control::Continue
    };
    let geometry = result.products.maps.geometry();
    // Systems whose redshift the run estimated are fitted in every fold at it.
    let mut config = config.clone();
    result.fit_estimates_in(&mut config.constraints);
    let cv = cross_validate(inputs, &config, folds, Some(geometry), &mut progress)
        .map_err(|e| e.to_string())?;
    let write = |file: &str, bytes: &[u8]| -> Result<(), String> {
        let path = out.join(file);
        fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))
    };
    write("crossval.json", json(&cv)?.as_bytes())?;
    write(
        "summary.json",
        json(&result.summary_after(Some(&cv)))?.as_bytes(),
    )?;
    if let Some(kappa) = &cv.kappa {
        let p = &result.products;
        let files = kappa
            .files(p.reference, p.plane.z_lens, Some(&p.curves), cv.runs.len())
            .map_err(|e| e.to_string())?;
        for (file, bytes) in files {
            write(file, &bytes)?;
        }
    }
    println!("{}", crossval_line(&cv, &out.join("crossval.json")));
    Ok(cv)
}

fn crossval_line(cv: &CrossValidation, path: &Path) -> String {
    let arcsec = |v: Option<f64>| v.map_or("n/a".to_string(), |v| format!("{v:.2} arcsec"));
    let spread = cv.kappa.as_ref().map_or(String::new(), |k| {
        let mut values = k.spread.data.clone();
        values.sort_by(f64::total_cmp);
        format!(
            "; the folds' kappa spread: median {:.3}, largest {:.3} (crossval-kappa-spread.fits)",
            values[values.len() / 2],
            values.last().copied().unwrap_or(f64::NAN)
        )
    });
    let always = match cv.always_fitted.as_slice() {
        [] => String::new(),
        ids => format!(
            "; fitted in every fold at their estimated redshift: {}",
            ids.join(", ")
        ),
    };
    format!(
        "wrote {} ({} folds: held-out images median {}, rms {}, {} of {} without a predicted image; fitted images median {}{spread}{always})",
        path.display(),
        cv.totals.folds,
        arcsec(cv.totals.holdout_image_offset_median_arcsec),
        arcsec(cv.totals.holdout_image_plane_rms_arcsec),
        cv.totals.holdout_images_unmatched,
        cv.totals.holdout_images,
        arcsec(cv.totals.fit_image_offset_median_arcsec),
    )
}

fn name(path: &Path) -> String {
    path.display().to_string()
}

/// Writes the map files, sources.json, images.reg (DS9), convergence.json and summary.json
/// into `dir`.
pub(super) fn write_reconstruction(r: &Reconstruction, dir: &Path) -> Result<(), String> {
    write_products(&r.products, ColorScale::Log, dir)?;
    let write = |file: &str, text: String| -> Result<(), String> {
        let path = dir.join(file);
        fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
    };
    write("sources.json", json(&r.sources)?)?;
    write("images.reg", image_regions(&r.sources, &r.products))?;
    write("convergence.json", json(&r.convergence)?)?;
    write("summary.json", json(&r.summary())?)?;
    Ok(())
}

/// `"{sep}C = 1.004"` (several layers: `"C = 1.004, 0.982"`), nothing without member layers.
fn c_text(sep: &str, c: &[f64]) -> String {
    if c.is_empty() {
        return String::new();
    }
    let values: Vec<String> = c.iter().map(|v| format!("{v:.3}")).collect();
    format!("{sep}C = {}", values.join(", "))
}

fn one_line(r: &Reconstruction, out: &Path) -> String {
    let choice = r
        .strength_choice
        .as_ref()
        .map_or(String::new(), |c| format!("; regulariser {}", c.describe()));
    let shear = match r.external_shear() {
        Some(g) => format!(
            "; external shear {:.3} along {:.0} deg",
            g.gamma, g.angle_deg
        ),
        None => r
            .external_shear_left_out()
            .map_or(String::new(), |why| format!("; no external shear ({why})")),
    };
    format!(
        "wrote {} ({} systems, {} constraint pixels, {} iterations{}{shear}; grid mass {:.3e} Msun; Einstein radius at z_s = {}: {}; image offsets: rms {}, median {}{choice})",
        out.display(),
        r.system.constraints.systems.len(),
        r.system.constraints.pixels.len(),
        r.iterations,
        c_text("; ", &r.member_factors()),
        r.grid_mass_msun(),
        r.config.products.z_source,
        r.products.summary().einstein_radius_text(),
        r.image_plane_rms_arcsec(false).map_or("n/a".to_string(), |v| format!("{v:.2} arcsec")),
        r.image_offset_median_arcsec(false).map_or("n/a".to_string(), |v| format!("{v:.2} arcsec")),
    )
}

/// Pretty JSON of a result file.
fn json<T: Serialize>(value: &T) -> Result<String, String> {
    serde_json::to_string_pretty(value).map_err(|e| e.to_string())
}
