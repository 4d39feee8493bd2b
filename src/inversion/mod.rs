//! The WSLAP+ inversion between the catalogues and the solver ([method §3] and [§4]):
//! the cell grid, the member-galaxy layers, the constraint pixels, the weak-lensing rows and
//! the linear system
//! `Theta = Gamma X` with its normal equations.
//!
//! [method §3]: crate::method#3-the-linear-system
//! [§4]: crate::method#4-member-galaxies

mod cells;
mod cells_fft;
mod constraints;
mod external_shear;
mod members;
mod npy;
mod regularise;
mod shear;
mod system;

pub use cells::{Cell, CellGrid, GridConfig, GridError, GridMass};
pub use cells_fft::MapPlan;
pub use constraints::{
    build_constraints, ellipse_pixels, ConstraintConfig, ConstraintError, ConstraintMode,
    ConstraintPixel, ConstraintSet, ConstraintSource, ConstraintSystem, ExcludedSystem, Exclusion,
    RedshiftPrior, Weighting,
};
pub use external_shear::{
    external_shear_layers, external_shear_of, shear_strength_angle, ExternalShearFit,
    EXTERNAL_SHEAR_UNIT,
};
pub(crate) use members::member_halo;
pub(crate) use members::BCG_MIN_LSTAR;
pub(crate) use members::MAX_MAG_FROM_L_STAR;
pub(crate) use members::MAX_MASS_TO_LIGHT;
pub use members::{
    build_member_layers, member_layers_with, missing_bcg_warning, HaloProfile, Layer, LayerKind,
    LayerSplit, MemberConfig, MemberHalo, MemberModel, MembersError, MAX_SINGLE_LAYERS,
};
pub use npy::{export_system, npy_header, write_f64s, write_npy, NpyError};
pub use regularise::{
    capped_inverse_jacobian, cell_penalty, AutoWord, ObjectiveConfig, Regulariser, Strength,
};
pub use shear::{kappa_gamma, with_ring, ShearConfig, ShearPoint, ShearSet, MIN_ONE_MINUS_KAPPA};
pub use system::{
    ColumnInfo, LinearSystem, ObjectiveTerms, RowBlock, ScaledLens, SystemConfig, SystemError,
    LAYER_SHARE_WARN, PRIOR_PULL_SIGMA,
};
