//! Physical constants and unit conversions (CODATA 2018 / IAU 2015, as astropy uses them).

/// Arcseconds in one radian.
pub const ARCSEC_PER_RAD: f64 = 206_264.806_247_096_36;
/// Speed of light in km/s.
pub const C_KM_S: f64 = 299_792.458;
/// Speed of light in m/s.
pub const C_M_S: f64 = 299_792_458.0;
/// Newton's constant in m^3 kg^-1 s^-2 (CODATA 2018).
pub const G_SI: f64 = 6.674_30e-11;
/// Solar mass in kg (IAU 2015 nominal G M_sun / G, as in astropy).
pub const MSUN_KG: f64 = 1.988_409_870_698_051e30;
/// One megaparsec in metres.
pub const MPC_M: f64 = 3.085_677_581_491_367e22;

/// `c^2 / (4 pi G)` in Msun/Mpc ([method §1] quotes 1.66292e18).
///
/// [method §1]: crate::method#1-frames-and-units
pub fn c2_over_4pi_g_msun_per_mpc() -> f64 {
    C_M_S * C_M_S / (4.0 * std::f64::consts::PI * G_SI) * MPC_M / MSUN_KG
}

/// `4 G Msun / (c^2 * 1 Mpc)` in arcsec^2: a point mass `m` (Msun) at `D_l` (Mpc) deflects by
/// `K * m / D_l / r` arcsec for `D_ls/D_s = 1` ([method §1]: 8.14385e-9).
pub fn point_mass_deflection_arcsec2() -> f64 {
    4.0 * G_SI * MSUN_KG / (C_M_S * C_M_S * MPC_M) * ARCSEC_PER_RAD * ARCSEC_PER_RAD
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constants_match_method_md() {
        let sigma = c2_over_4pi_g_msun_per_mpc();
        assert!((sigma / 1.66292e18 - 1.0).abs() < 1e-5, "{sigma}");
        let k = point_mass_deflection_arcsec2();
        assert!((k / 8.14385e-9 - 1.0).abs() < 1e-5, "{k}");
    }
}
