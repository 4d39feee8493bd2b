//! Ensembles in the app: the setting, the members run apart (as the web workers run them) and
//! combined, the same ensemble as `wslap reconstruct --ensemble` with the same seed, and what
//! the app shows of it (summary, files, spread view, read-out).

use crate::fixtures::teaching_session;
use serde_json::json;
use wslap::app::{RunKind, Session, ViewOptions};
use wslap::{reconstruct, run_ensemble, Control, EnsembleMember, MAX_ENSEMBLE_MEMBERS};

const PNG_MAGIC: &[u8] = b"\x89PNG\r\n\x1a\n";

/// The teaching session with an ensemble of `members` from `seed`, reconstructed.
fn with_ensemble_setting(members: usize, seed: u64) -> Session {
    let mut s = teaching_session();
    s.set_field("ensemble.members", json!(members)).unwrap();
    s.set_field("ensemble.seed", json!(seed)).unwrap();
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    s
}

/// A member's record without its time, which differs from run to run.
fn untimed(m: &EnsembleMember) -> EnsembleMember {
    EnsembleMember {
        elapsed_ms: 0.0,
        ..m.clone()
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_ensemble_setting_is_off_by_default_and_bounded() {
    let mut s = teaching_session();
    assert_eq!(s.settings.ensemble.members, 0);
    assert_eq!(s.settings.ensemble.seed, 1);
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    assert!(s.ensemble_plan().unwrap().is_none());
    for bad in [1, MAX_ENSEMBLE_MEMBERS + 1] {
        let err = s
            .set_field("ensemble.members", json!(bad))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("ensemble.members") && err.contains("2 to 200"),
            "{err}"
        );
    }
    s.set_field("ensemble.members", json!(MAX_ENSEMBLE_MEMBERS))
        .unwrap();
    // Members' maps that would not fit in a browser tab are refused when set.
    let err = s
        .set_field("reconstruct.products.pixels", json!(2048))
        .unwrap_err()
        .to_string();
    assert!(err.contains("ensemble.members"), "{err}");
    // A spread view and the files without an ensemble say how to get one.
    let err = s.spread_view(&ViewOptions::default()).unwrap_err();
    assert!(err.to_string().contains("Ensemble members"), "{err}");
}

/// The members run in another session (a web worker opens the same project), in reverse
/// order, and combined in the first: the same members and maps as `run_ensemble` with the
/// same seed on the same inputs (`wslap reconstruct --ensemble 3 --seed 7`).
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn members_run_apart_give_the_ensemble_of_the_cli() {
    let mut s = with_ensemble_setting(3, 7);
    let plan = s.ensemble_plan().unwrap().expect("a plan");
    assert_eq!(plan.members(), 3);
    let worker = teaching_session();
    let mut seen = 0;
    let runs: Vec<_> = (1..=3)
        .rev()
        .map(|k| {
            worker
                .ensemble_member(&plan, k, &mut |_| {
                    seen += 1;
                    Control::Continue
                })
                .unwrap()
        })
        .collect();
    assert!(seen > 0);
    assert!(worker
        .ensemble_member(&plan, 4, &mut |_| Control::Continue)
        .is_err());
    s.set_ensemble(&plan, runs, true).unwrap();
    let app = s.ensemble().expect("the result's ensemble");

    // The CLI's path on the same data and settings.
    let data = s.parsed().unwrap();
    let mut config = s.settings.reconstruct.clone();
    let plane = s.settings.lens_plane().unwrap();
    let inputs = data
        .inputs(plane, &s.settings.holdout, &mut config)
        .unwrap();
    let main = reconstruct(&inputs, &config, &mut |_| Control::Continue).unwrap();
    let native =
        run_ensemble(&inputs, &config, &main, 3, 7, &mut |_, _| Control::Continue).unwrap();
    assert_eq!(app.status, "Completed");
    assert_eq!(
        app.members.iter().map(untimed).collect::<Vec<_>>(),
        native.members.iter().map(untimed).collect::<Vec<_>>()
    );
    assert_eq!(
        app.einstein_radius_interval_arcsec,
        native.einstein_radius_interval_arcsec
    );
    assert_eq!(
        app.mass_within_interval_msun,
        native.mass_within_interval_msun
    );
    let (a, n) = (app.maps.as_ref().unwrap(), native.maps.as_ref().unwrap());
    assert_eq!(a.kappa_mean, n.kappa_mean);
    assert_eq!(a.kappa_std, n.kappa_std);
    assert_eq!(a.magnif_p16, n.magnif_p16);
    assert_eq!(a.magnif_p84, n.magnif_p84);
    // The app keeps the statistics, not the members' own maps.
    assert!(a.member_kappa.is_empty() && a.member_magnif.is_empty());
    assert!(
        a.kappa_std.data.iter().any(|&v| v > 0.0),
        "the members differ"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_ensemble_shows_in_the_summary_files_view_and_read_out() {
    let mut s = with_ensemble_setting(2, 1);
    let plan = s.ensemble_plan().unwrap().unwrap();
    // A member twice, or one of another plan's map, is refused.
    let run = |k| {
        s.ensemble_member(&plan, k, &mut |_| Control::Continue)
            .unwrap()
    };
    let (one, two) = (run(1), run(2));
    let mut small = plan.clone();
    small.geometry.pixels = 8;
    assert!(s
        .set_ensemble(&plan, vec![one.clone(), one.clone()], true)
        .is_err());
    assert!(s
        .set_ensemble(&small, vec![one.clone(), two.clone()], true)
        .is_err());
    assert!(s.ensemble().is_none());
    s.set_ensemble(&plan, vec![one, two], true).unwrap();

    let summary: serde_json::Value =
        serde_json::from_str(&s.result().unwrap().summary_json().unwrap()).unwrap();
    assert_eq!(summary["ensemble_members"], 2);
    let [lo, hi] = [0, 1].map(|k| {
        summary["einstein_radius_interval_arcsec"][k]
            .as_f64()
            .unwrap()
    });
    assert!(lo <= hi, "{summary}");
    assert_eq!(
        summary["mass_within_interval_msun"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
    let json: serde_json::Value = serde_json::from_str(&s.ensemble_json().unwrap()).unwrap();
    assert_eq!(json["members"].as_array().unwrap().len(), 2);

    let files = s.ensemble_files().unwrap();
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "kappa-mean.fits",
            "kappa-std.fits",
            "magnif-p16.fits",
            "magnif-p50.fits",
            "magnif-p84.fits",
            "kappa-std.png"
        ]
    );
    let std = wslap::read_image(&files[1].1, "kappa-std.fits")
        .unwrap()
        .to_map()
        .unwrap();
    assert_eq!(std.geometry.pixels, plan.geometry.pixels);

    let view = s.spread_view(&ViewOptions::default()).unwrap();
    assert!(view.png.starts_with(PNG_MAGIC));
    // The read-out under the map's centre: the ensemble's kappa spread and magnification
    // percentiles, in order.
    let h = s
        .hover(&ViewOptions::default(), 300.0, 300.0)
        .unwrap()
        .expect("on the map");
    let e = h.ensemble.expect("the ensemble's values");
    assert_eq!(e.members, 2);
    assert!(e.kappa_std >= 0.0);
    assert!(
        e.magnification_p16 <= e.magnification_p50 && e.magnification_p50 <= e.magnification_p84
    );
    assert_eq!(e.z_source, h.z_source);
    // Another z_s redraws the curves; the percentiles stay at theirs and say so.
    s.set_z_source(4.0).unwrap();
    let h = s
        .hover(&ViewOptions::default(), 300.0, 300.0)
        .unwrap()
        .unwrap();
    assert_eq!(h.ensemble.unwrap().z_source, e.z_source);
    assert_ne!(h.z_source, e.z_source);
    // A new run replaces the result and its ensemble.
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    assert!(s.ensemble().is_none());
    assert!(s
        .hover(&ViewOptions::default(), 300.0, 300.0)
        .unwrap()
        .unwrap()
        .ensemble
        .is_none());
}
