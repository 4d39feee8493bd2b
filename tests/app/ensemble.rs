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

/// The teaching session with a combined ensemble of `members` (seed 7) on maps of `pixels`,
/// as the app makes it.
fn with_ensemble(members: usize, pixels: usize) -> Session {
    let mut s = teaching_session();
    s.set_field("reconstruct.products.pixels", json!(pixels))
        .unwrap();
    s.set_field("ensemble.members", json!(members)).unwrap();
    s.set_field("ensemble.seed", json!(7)).unwrap();
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let plan = s.ensemble_plan().unwrap().unwrap();
    let runs = (1..=members)
        .map(|k| {
            s.ensemble_member(&plan, k, &mut |_| Control::Continue)
                .unwrap()
        })
        .collect();
    s.set_ensemble(&plan, runs, true).unwrap();
    s
}

/// Largest difference of two maps relative to `f32` rounding of the first's values.
fn worst_in_f32_steps(a: &wslap::Map, b: &wslap::Map) -> f64 {
    assert_eq!(a.geometry, b.geometry);
    a.data
        .iter()
        .zip(&b.data)
        .map(|(p, q)| (p - q).abs() / (p.abs() * f64::from(f32::EPSILON)).max(f64::MIN_POSITIVE))
        .fold(0.0, f64::max)
}

/// A project keeps the ensemble: after save and open, the same record (members, intervals,
/// note), the statistics maps to `f32` precision, the same read-out, spread view and files.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn an_ensemble_survives_save_and_open() {
    // The app's maps (APP_MAP_PIXELS), to measure what a project stores for them.
    let s = with_ensemble(3, wslap::app::APP_MAP_PIXELS);
    let text = s.project_json().unwrap();
    let mut t = Session::new();
    let report = t.open_project(&text, "p.json").unwrap();
    assert_eq!(report.result, "restored", "{}", report.message);
    assert!(
        report.message.contains("ensemble of 3 members restored"),
        "{}",
        report.message
    );
    let (a, b) = (s.ensemble().unwrap(), t.ensemble().expect("the ensemble"));
    assert_eq!(a.members, b.members);
    assert_eq!(
        a.einstein_radius_interval_arcsec,
        b.einstein_radius_interval_arcsec
    );
    assert_eq!(a.mass_within_interval_msun, b.mass_within_interval_msun);
    assert_eq!((&a.note, &a.status, a.seed), (&b.note, &b.status, b.seed));
    let (ma, mb) = (a.maps.as_ref().unwrap(), b.maps.as_ref().unwrap());
    // Stored as f32: each value within one f32 rounding (half an epsilon, relative).
    const F32_STEPS: f64 = 0.5;
    for (what, p, q) in [
        ("kappa_mean", &ma.kappa_mean, &mb.kappa_mean),
        ("kappa_std", &ma.kappa_std, &mb.kappa_std),
        ("magnif_p16", &ma.magnif_p16, &mb.magnif_p16),
        ("magnif_p50", &ma.magnif_p50, &mb.magnif_p50),
        ("magnif_p84", &ma.magnif_p84, &mb.magnif_p84),
    ] {
        let worst = worst_in_f32_steps(p, q);
        assert!(worst <= F32_STEPS, "{what}: {worst} f32 epsilons off");
    }
    // The stored size of the app's 256 x 256 maps: five maps of f32 in base64.
    let p: serde_json::Value = serde_json::from_str(&text).unwrap();
    let stored = &p["result"]["ensemble"];
    assert_eq!(stored["geometry"]["pixels"], 256);
    let maps_chars = stored["maps_f32_base64"].as_str().unwrap().len();
    assert_eq!(maps_chars, (5 * 256 * 256 * 4_usize).div_ceil(3) * 4);
    eprintln!(
        "stored ensemble of 3 members: {} bytes of JSON, {maps_chars} of them the maps; \
         project {} bytes",
        stored.to_string().len(),
        text.len()
    );
    // What the page shows of it: caption intervals, read-out, spread view, files.
    let sum = |s: &Session| -> serde_json::Value {
        serde_json::from_str(&s.result().unwrap().summary_json().unwrap()).unwrap()
    };
    let (sa, sb) = (sum(&s), sum(&t));
    for key in [
        "einstein_radius_interval_arcsec",
        "mass_within_interval_msun",
        "ensemble_members",
    ] {
        assert_eq!(sa[key], sb[key], "{key}");
    }
    let at = |s: &Session| {
        s.hover(&ViewOptions::default(), 300.0, 300.0)
            .unwrap()
            .unwrap()
            .ensemble
            .expect("the ensemble's values")
    };
    let (ea, eb) = (at(&s), at(&t));
    assert_eq!(ea.members, eb.members);
    const READOUT_RTOL: f64 = 1e-6;
    for (p, q) in [
        (ea.magnification_p16, eb.magnification_p16),
        (ea.magnification_p50, eb.magnification_p50),
        (ea.magnification_p84, eb.magnification_p84),
        (ea.kappa_std, eb.kappa_std),
    ] {
        assert!((p - q).abs() <= READOUT_RTOL * p.abs().max(1e-6), "{p} {q}");
    }
    assert!(t
        .spread_view(&ViewOptions::default())
        .unwrap()
        .png
        .starts_with(PNG_MAGIC));
    let names = |s: &Session| -> Vec<String> {
        s.ensemble_files()
            .unwrap()
            .into_iter()
            .map(|(n, _)| n)
            .collect()
    };
    assert_eq!(names(&s), names(&t));
    // Saved again, the reopened project keeps it as it was read.
    let again: serde_json::Value = serde_json::from_str(&t.project_json().unwrap()).unwrap();
    assert_eq!(again["result"]["ensemble"], *stored);
}

/// A project saved before projects kept ensembles opens without one; a stored ensemble that
/// does not read or does not fit the result is dropped with a message, the project opens.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn an_old_or_corrupt_stored_ensemble_still_opens_the_project() {
    let s = with_ensemble(2, 64);
    let p: serde_json::Value = serde_json::from_str(&s.project_json().unwrap()).unwrap();
    let open = |p: &serde_json::Value| {
        let mut t = Session::new();
        let report = t.open_project(&p.to_string(), "p.json").unwrap();
        assert_eq!(report.result, "restored", "{}", report.message);
        (t, report.message)
    };
    let mut old = p.clone();
    old["result"].as_object_mut().unwrap().remove("ensemble");
    let (t, message) = open(&old);
    assert!(t.ensemble().is_none());
    assert!(!message.contains("ensemble"), "{message}");
    let corrupt = |path: &[&str], value: serde_json::Value| {
        let mut q = p.clone();
        let mut at = &mut q["result"]["ensemble"];
        for key in path {
            at = &mut at[*key];
        }
        *at = value;
        q
    };
    let maps = p["result"]["ensemble"]["maps_f32_base64"].as_str().unwrap();
    // The stored maps with a NaN as value `index` (map after map).
    let nan_at = |index: usize| {
        use base64::Engine as _;
        let b64 = base64::engine::general_purpose::STANDARD;
        let mut raw = b64.decode(maps).unwrap();
        raw[4 * index..4 * index + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        corrupt(&["maps_f32_base64"], json!(b64.encode(raw)))
    };
    let pixels = p["result"]["ensemble"]["geometry"]["pixels"]
        .as_u64()
        .unwrap() as usize;
    // Kept with its intervals only (maps too large to keep), it stays so when saved again.
    let mut intervals_only = p.clone();
    intervals_only["result"]["ensemble"]
        .as_object_mut()
        .unwrap()
        .remove("maps_f32_base64");
    let (t, message) = open(&intervals_only);
    assert!(message.contains("(its intervals only"), "{message}");
    let again: serde_json::Value = serde_json::from_str(&t.project_json().unwrap()).unwrap();
    assert_eq!(
        again["result"]["ensemble"],
        intervals_only["result"]["ensemble"]
    );
    let (u, _) = open(&again);
    assert_eq!(
        u.ensemble().unwrap().einstein_radius_interval_arcsec,
        t.ensemble().unwrap().einstein_radius_interval_arcsec
    );
    assert!(u.ensemble().unwrap().maps.is_none());
    // A magnification need not be finite (at a critical curve): the ensemble is kept.
    let (t, message) = open(&nan_at(3 * pixels * pixels + 5));
    assert!(t.ensemble().is_some(), "{message}");
    assert!(
        message.contains("ensemble of 2 members restored"),
        "{message}"
    );
    for (case, q, why) in [
        (
            "kappa not finite",
            nan_at(7),
            "kappa maps is not a finite number",
        ),
        ("not an object", corrupt(&[], json!("x")), "does not read"),
        (
            "no members",
            corrupt(&["record", "members"], json!([])),
            "no members",
        ),
        (
            "not base64",
            corrupt(&["maps_f32_base64"], json!("!!!!")),
            "not base64",
        ),
        (
            "cut short",
            corrupt(&["maps_f32_base64"], json!(&maps[..maps.len() / 8 * 4])),
            "bytes, not the",
        ),
        (
            "another map",
            corrupt(&["geometry", "pixels"], json!(128)),
            "the result's of",
        ),
    ] {
        let (t, message) = open(&q);
        assert!(t.ensemble().is_none(), "{case}");
        assert!(
            message.contains("stored ensemble was dropped") && message.contains(why),
            "{case}: {message}"
        );
        // The rest of the result is there.
        assert!(t.result().unwrap().reconstruction().is_some(), "{case}");
    }
}

/// An ensemble of an "auto" run whose chosen map was crowded: no member uses the candidate
/// passed over for it, each records its own map's crowding, and a member whose first map is
/// crowded moves on to the next candidates of its own draw's ranking as the main run does.
/// The setting's finer grid crowds every system (`crowding_auto_session`). Natively only: an
/// "auto" run with its folds takes minutes in a wasm test.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn ensemble_members_pass_over_crowded_maps() {
    use wslap::Candidate;
    let mut s = crate::fixtures::crowding_auto_session();
    s.set_field("ensemble.members", json!(6)).unwrap();
    s.set_field("ensemble.seed", json!(3)).unwrap();
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let plan = s.ensemble_plan().unwrap().unwrap();
    let choice = plan.strength_choice.as_ref().expect("auto");
    let passed: Vec<Candidate> = choice.crowded_maps.iter().map(|p| p.candidate).collect();
    assert!(!passed.is_empty(), "{choice:?}");
    let runs: Vec<_> = (1..=plan.members())
        .map(|k| {
            s.ensemble_member(&plan, k, &mut |_| Control::Continue)
                .unwrap()
        })
        .collect();
    let used = |r: &EnsembleMember| Candidate {
        regulariser: r.regulariser.unwrap(),
        strength: r.strength.unwrap(),
        cells: r.cells,
    };
    let mut moved = 0;
    for (draw, run) in plan.draws.iter().zip(&runs) {
        let r = &run.record;
        assert!(!passed.contains(&used(r)), "member {}: {r:?}", r.member);
        assert!(draw.then.iter().all(|c| !passed.contains(c)), "{draw:?}");
        let crowding = r.crowding.expect("recorded");
        // Over the systems it fitted: those it left out test it. The app's box says the
        // members that kept a crowded map from `crowded`, not from the rule again.
        assert_eq!(crowding.systems, draw.fitted.len());
        assert_eq!(
            r.crowded,
            crowding.distrusted(),
            "member {}: {r:?}",
            r.member
        );
        if r.crowded_maps.is_empty() {
            // Its first map stood, so it was not crowded.
            assert!(!crowding.distrusted(), "member {}: {r:?}", r.member);
            assert_eq!(used(r).strength, draw.strength.unwrap());
        } else {
            // It fitted its own candidate, then its draw's next ones in order, and kept the
            // first uncrowded map, else the least crowded (its own on a tie): the others are
            // listed in the order fitted.
            moved += 1;
            let own = Candidate {
                regulariser: draw.regulariser.unwrap(),
                strength: draw.strength.unwrap(),
                cells: draw.cells,
            };
            let tried: Vec<Candidate> = r.crowded_maps.iter().map(|p| p.candidate).collect();
            let expected: Vec<Candidate> = std::iter::once(own)
                .chain(draw.then.iter().copied())
                .filter(|c| *c != used(r))
                .take(tried.len())
                .collect();
            assert_eq!(tried, expected, "{r:?}");
            assert!(r.crowded_maps.iter().all(|p| p.crowding.distrusted()));
        }
    }
    eprintln!(
        "members that moved off a crowded map: {moved} of {}",
        runs.len()
    );
    // The path this test is for: some member's own first map was crowded.
    assert!(moved > 0, "no member moved");
    s.set_ensemble(&plan, runs, true).unwrap();
    let json: serde_json::Value = serde_json::from_str(&s.ensemble_json().unwrap()).unwrap();
    assert!(json["members"][0]["crowding"]["systems"].is_u64(), "{json}");
}
