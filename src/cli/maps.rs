//! `wslap maps`: the map products of a model file, of a published Lenstool model (`.par` and
//! its member catalogues), or of published HFF deflection maps.

use std::fs;
use std::path::{Path, PathBuf};

use super::input::{read_bytes, read_text};

use clap::Args;
use wslap::read_image;
use wslap::ColorScale;
use wslap::InputKind;
use wslap::LenstoolModel;
use wslap::ModelFile;
use wslap::{parse_par_with, ParOptions};
use wslap::{Cosmology, LensPlane};
use wslap::{ProductOptions, Products, ProductsError};

/// Maps, critical curves, caustics and figures of a lens.
///
/// Writes into DIR: kappa.fits, gamma1.fits, gamma2.fits, x-arcsec-deflect.fits,
/// y-arcsec-deflect.fits, psi.fits (all for D_ls/D_s = 1), magnif.fits (at --z-source, header ZSOURCE),
/// critical-curves.json, critical-curves.reg (DS9), kappa.png and summary.json.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("lens").required(true).args(["model", "lenstool", "deflection"])))]
pub struct MapsArgs {
    /// Model file (JSON) of a parametric lens.
    #[arg(long, value_name = "MODEL.json")]
    model: Option<PathBuf>,
    /// A Lenstool parametric model (e.g. a published bestopt.par): its dPIE and shear
    /// potentials, and its potfile members (see --potfile), evaluated as written.
    #[arg(long, value_name = "MODEL.par")]
    lenstool: Option<PathBuf>,
    /// Member catalogue of the --lenstool model's potfile blocks, one per block in order
    /// (repeat the option); without it, each block's `filein` relative to the .par's folder,
    /// else relative to the working folder, else its file name beside the .par (with a
    /// warning).
    #[arg(long, value_name = "MEMBERS.cat", conflicts_with_all = ["model", "deflection"])]
    potfile: Vec<PathBuf>,
    /// Evaluate a --lenstool model with potentials at several redshifts (a foreground or
    /// background group) in the single-plane approximation: every potential at the first
    /// one's z_lens, keeping its angular sizes and velocity dispersion (a warning names each
    /// block moved). Without it such a model is refused.
    #[arg(long, requires = "lenstool")]
    single_plane: bool,
    /// Published deflection maps (HFF x- and y-arcsec-deflect FITS, D_ls/D_s = 1).
    #[arg(long, num_args = 2, value_names = ["X.fits", "Y.fits"])]
    deflection: Option<Vec<PathBuf>>,
    /// Lens redshift (with --deflection, default the maps' ZLENS card; a model file has its own).
    #[arg(long, allow_negative_numbers = true)]
    z_lens: Option<f64>,
    /// H0 in km/s/Mpc (with --deflection; default 70).
    #[arg(long, allow_negative_numbers = true)]
    h0: Option<f64>,
    /// Omega_m of flat LCDM (with --deflection; default 0.3).
    #[arg(long, allow_negative_numbers = true)]
    omega_m: Option<f64>,
    /// Output folder (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Source redshift of the magnification map and the critical curves.
    #[arg(long, allow_negative_numbers = true, default_value_t = 2.0)]
    z_source: f64,
    /// Map width in arcsec, centred on (0, 0) (model files and Lenstool models).
    #[arg(long, allow_negative_numbers = true, default_value_t = 200.0)]
    size: f64,
    /// Pixels on a side (model files and Lenstool models).
    #[arg(long, default_value_t = 512)]
    pixels: usize,
    /// Colour scale of kappa.png.
    #[arg(long, value_enum, default_value_t = Scale::Log)]
    scale: Scale,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Scale {
    Log,
    Linear,
}

impl From<Scale> for ColorScale {
    fn from(s: Scale) -> Self {
        match s {
            Scale::Log => ColorScale::Log,
            Scale::Linear => ColorScale::Linear,
        }
    }
}

pub fn run(args: &MapsArgs) -> Result<(), String> {
    super::input::check_out_dir(&args.out)?;
    // A model file and a .par carry their own distances: an option that would not be used is
    // refused, not ignored.
    if args.deflection.is_none() {
        let given = [
            ("--z-lens", args.z_lens.is_some()),
            ("--h0", args.h0.is_some()),
            ("--omega-m", args.omega_m.is_some()),
        ];
        if let Some((flag, _)) = given.iter().find(|(_, set)| *set) {
            return Err(format!(
                "{flag} is for --deflection maps only: a model file or a .par gives its own \
                 lens redshift and cosmology"
            ));
        }
    }
    let opts = ProductOptions {
        z_source: args.z_source,
        size_arcsec: args.size,
        pixels: args.pixels,
        scale: args.scale.into(),
        maps_only: false,
    };
    // Checked before any file is read, and blamed on the option that set it (the settings'
    // names, `products.pixels`, are not what the user typed here).
    if let (None, Err(ProductsError::BadFieldValue(mut e))) = (&args.deflection, opts.validate()) {
        e.field = match e.field.as_str() {
            "products.size" => "--size",
            "products.pixels" => "--pixels",
            "products.z_source" => "--z-source",
            other => other,
        }
        .to_string();
        return Err(e.to_string());
    }
    let products = if let Some(path) = &args.model {
        let text = read_text(path, InputKind::Model)?;
        let model = ModelFile::from_json_str(&text, &path.display().to_string())
            .map_err(|e| e.to_string())?;
        Products::from_model(&model, &opts).map_err(|e| e.to_string())?
    } else if let Some(path) = &args.lenstool {
        let par_options = ParOptions {
            single_plane: args.single_plane,
        };
        lenstool_products(path, &args.potfile, &par_options, &opts)?
    } else {
        let paths = args.deflection.as_deref().unwrap_or_default();
        let (ax, ay) = (read_map(&paths[0])?, read_map(&paths[1])?);
        let z_lens = match args.z_lens {
            Some(z) => z,
            None => ax
                .2?
                .ok_or("--deflection needs --z-lens (the maps have no ZLENS card)")?,
        };
        let cosmology = Cosmology::new(args.h0.unwrap_or(70.0), args.omega_m.unwrap_or(0.3))
            .map_err(|e| e.to_string())?;
        let plane = LensPlane::new(cosmology, z_lens).map_err(|e| match args.z_lens {
            Some(_) => e.to_string(),
            None => format!("{}: its ZLENS card: {e}", paths[0].display()),
        })?;
        Products::from_deflection(ax.0, ay.0, plane, ax.1, args.z_source)
            .map_err(|e| e.to_string())?
    };
    write_products(&products, args.scale.into(), &args.out)?;
    let s = products.summary();
    println!(
        "wrote {} (Einstein radius at z_s = {}: {}; {} tangential, {} radial critical curves)",
        args.out.display(),
        s.z_source,
        s.einstein_radius_text(),
        s.tangential_curves,
        s.radial_curves
    );
    Ok(())
}

/// The products of the Lenstool model of [`load_lenstool`] on the map of `opts` centred on the
/// model's reference point.
fn lenstool_products(
    par_path: &Path,
    potfiles: &[PathBuf],
    par_options: &ParOptions,
    opts: &ProductOptions,
) -> Result<Products, String> {
    let model = load_lenstool(par_path, potfiles, par_options)?;
    Products::from_lens(&model.lens, model.plane, model.reference, opts).map_err(|e| e.to_string())
}

/// The Lenstool model `par_path` with the member catalogues `potfiles` (one per potfile block;
/// when empty, each block's `filein` as [`wslap::LenstoolPar::potfile_paths`] finds it), read
/// with `par_options`;
/// warnings go to stderr.
pub(super) fn load_lenstool(
    par_path: &Path,
    potfiles: &[PathBuf],
    par_options: &ParOptions,
) -> Result<LenstoolModel, String> {
    let name = par_path.display().to_string();
    let text = read_text(par_path, InputKind::Model)?;
    let par = parse_par_with(&text, &name, par_options).map_err(|e| e.to_string())?;
    for w in &par.warnings {
        eprintln!("warning: {w}");
    }
    let paths: Vec<PathBuf> = if potfiles.is_empty() {
        let found = par.potfile_paths(par_path);
        for note in found.iter().filter_map(|(_, note)| note.as_ref()) {
            eprintln!("warning: {note}");
        }
        found.into_iter().map(|(path, _)| path).collect()
    } else {
        potfiles.to_vec()
    };
    let mut texts = Vec::with_capacity(paths.len());
    for path in &paths {
        let text = read_text(path, InputKind::Catalog).map_err(|e| {
            format!("{e} (a potfile of {name}; give its member catalogue with --potfile)")
        })?;
        texts.push((path.display().to_string(), text));
    }
    let (model, warnings) = par.build_from_texts(&texts).map_err(|e| e.to_string())?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    Ok(model)
}

/// A FITS map, its sky reference and its `ZLENS` card (the lens redshift the project writes).
/// The redshift is `Ok(None)` without a card, an error naming the file when the card is there
/// but is not a redshift (the caller needs it only when no `--z-lens` is given).
#[allow(clippy::type_complexity)]
pub(super) fn read_map(
    path: &Path,
) -> Result<
    (
        wslap::Map,
        Option<wslap::SkyReference>,
        Result<Option<f64>, String>,
    ),
    String,
> {
    let bytes = read_bytes(path, InputKind::Fits)?;
    let image = read_image(&bytes, &path.display().to_string()).map_err(|e| e.to_string())?;
    let (_, reference) = image.geometry().map_err(|e| e.to_string())?;
    let (map, no_data) = image.to_map_no_data().map_err(|e| e.to_string())?;
    if no_data.total() > 0 {
        eprintln!(
            "warning: {}: {} pixels have no data ({} NaN or blank, {} in borders of zeros): \
             NaN in the maps written, left out of the curves and the profile",
            path.display(),
            no_data.total(),
            no_data.blank,
            no_data.zero_border
        );
    }
    let z_lens = match image.card("ZLENS") {
        None => Ok(None),
        Some(card) => match card.as_f64().filter(|z| z.is_finite() && *z > 0.0) {
            Some(z) => Ok(Some(z)),
            None => Err(format!(
                "{}: the ZLENS card ({}) is not a lens redshift (a number above 0); give \
                 --z-lens",
                path.display(),
                wslap::CardValue::shown(card.value.as_ref())
            )),
        },
    };
    Ok((map, reference, z_lens))
}

/// Writes every product file into `dir`.
pub fn write_products(products: &Products, scale: ColorScale, dir: &Path) -> Result<(), String> {
    fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let write = |name: &str, bytes: &[u8]| -> Result<(), String> {
        let path = dir.join(name);
        fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))
    };
    for (name, bytes) in products.fits_files().map_err(|e| e.to_string())? {
        write(name, &bytes)?;
    }
    write("critical-curves.json", products.curves_json().as_bytes())?;
    write("critical-curves.reg", products.regions().as_bytes())?;
    write(
        "kappa.png",
        &products.kappa_png(scale).map_err(|e| e.to_string())?,
    )?;
    let summary = serde_json::to_string_pretty(&products.summary()).map_err(|e| e.to_string())?;
    write("summary.json", summary.as_bytes())?;
    Ok(())
}
