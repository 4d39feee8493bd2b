//! The lensing physics, each part against an independent reference: cosmology and the mass
//! profiles (against astropy, lenstronomy and 1-D integrals), the model file, the image finder,
//! grid-mass maps by FFT, and the map products (curves, Einstein radius, profiles) and the
//! forward path the app's worker runs. Runs natively and in a dedicated browser worker.

#[path = "../common/mod.rs"]
mod common;

mod dpie;
mod forward;
mod grid_maps;
mod images;
mod model_file;
mod nfw;
mod physics;
mod playground;
mod products;
mod sie_shear_sheet;
mod time_delays;
